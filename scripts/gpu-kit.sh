#!/usr/bin/env bash
# Prepares gpu-kit/: everything scripts/gpu-check.sh runs on a GPU machine that has the NVIDIA
# driver but no Rust toolchain (and maybe no LLVM 22): release binaries, the GPU test binaries
# of scion-cuda, PTX kits for pbrt, ptr, pbrt-q16 and sg-eq (so the check also runs where `scion`
# cannot start for lack of libLLVM) and the scenes, gzipped. Run it here, from the repository root; carry
# `gpu-kit` (about 31 MB, git-ignored) to the GPU machine. See docs/gpu.md.
set -euo pipefail
cd "$(dirname "$0")/.."
KIT=${GPU_KIT:-gpu-kit}
rm -rf "$KIT"
mkdir -p "$KIT/bin" "$KIT/tests" "$KIT/ptx"

cargo build --release -p scion-cli -p scion-cuda --bins
cp target/release/scion target/release/scion-gpu "$KIT/bin/"

# The test binaries of scion-cuda (unit tests and tests/*.rs), under their target names.
cargo test --release -p scion-cuda --no-run --message-format=json 2>/dev/null |
  python3 -c '
import json, shutil, sys
kit = sys.argv[1]
for line in sys.stdin:
    try:
        m = json.loads(line)
    except ValueError:
        continue
    exe = m.get("executable")
    if m.get("reason") == "compiler-artifact" and exe and m.get("profile", {}).get("test"):
        name = m["target"]["name"].replace("-", "_")
        kind = m["target"]["kind"][0]
        dest = f"{kit}/tests/{name}" if kind == "test" else f"{kit}/tests/{name}_unit"
        shutil.copy(exe, dest)
        print("test binary", dest)
' "$KIT"

# Every library layout the GPU path runs (the registry: `scion layouts --gpu`: the binary ones,
# the eight-wide ones, the case studies over triangles, bvh8-tri4), the paper's four first;
# their names go to $KIT/LAYOUTS, which gpu-check.sh runs in order within its budget. A PTX kit
# (for scion-gpu, which checks against the binary reference) for those `scion layouts --kit`
# lists; gpu-check.sh's mode scion runs the others through `scion trace --device gpu`.
: > "$KIT/LAYOUTS"
# (hair-bvh is left out, as scripts/explore-docs.sh leaves it out: its 3-bit leaf counts need
# leaves of at most 7 triangles, `scion trace --device gpu --layout hair-bvh --leaf-size 7`.)
kits=$(target/release/scion layouts --kit --names)
for layout in pbrt ptr pbrt-q16 sg-eq $(target/release/scion layouts --gpu --names | grep -vx hair-bvh); do
  grep -qx "$layout" "$KIT/LAYOUTS" && continue
  if echo "$kits" | grep -qx "$layout"; then
    target/release/scion ptx --layout "$layout" -o "$KIT/ptx/$layout.ptx"
  fi
  echo "$layout" >> "$KIT/LAYOUTS"
done
cp scripts/gpu-check.sh "$KIT/"

# The repository's scenes, gzipped as they are (13 MB); gpu-check.sh unpacks them when
# SCION_SCENES names no folder.
mkdir -p "$KIT/scenes"
cp scenes/*.obj.gz "$KIT/scenes/"
git rev-parse HEAD > "$KIT/COMMIT" 2>/dev/null || true
du -sh "$KIT"
echo "gpu-kit ready: carry $KIT, then run: $KIT/gpu-check.sh"
