#!/usr/bin/env bash
# Speed against error for every quantized layout of the library (issue 15 item 5), binary and
# eight-wide: per scene and ray kind, its bytes, Mrays/s (LLVM -O3, 1 thread, the paper's 9
# runs) and ratio to its unquantized twin (pbrt for the binary `BVH` layouts, bvh8 for the
# eight-wide `BVH8` ones), how much its decoded boxes inflate (surface area, volume; whether every
# decoded box contains its exact one; for the eight-wide layouts the children's boxes, decoded in
# each node's frame), the extra work per ray they cause against the exact boxes (box tests, node
# visits, triangle tests of the reference traversal, binary or wide), and whether its hits equal
# the twin's (else how many differ: at the same t, nearer than the twin's hit, farther or a
# miss).
# Writes the table into docs/benchmarks.md between `<!-- bench-quantized:begin -->` and
# `<!-- bench-quantized:end -->` (BENCH_NO_DOC=1: print only).
#
# Usage: scripts/bench-quantized.sh [SCENE_NAME...]   (default: the ten library scenes, about
#   17 minutes on 2 cores)
#   Environment: BENCH_N (rays per run, default 65536).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/bench-lib.sh
./scripts/setup.sh >/dev/null
cargo build --release -q -p scion-cli
bin="${CARGO_TARGET_DIR:-target}/release/scion"
n=${BENCH_N:-65536}
out=target/bench-quantized
mkdir -p "$out"
if [ $# -gt 0 ]; then scenes=("$@"); else scenes=("${LIBRARY_SCENES[@]}"); fi
# The quantized layouts of the prelude's BVH and of BVH8, as the registry finds them (boxes not
# exact), with their twins.
layouts=$("$bin" layouts | awk 'NR > 1 && ($3 == "BVH" || $3 == "BVH8") && $5 != "exact" { print $1 }')
twin_of() { case $("$bin" layouts | awk -v l="$1" '$1 == l { print $3 }') in BVH8) echo bvh8;; *) echo pbrt;; esac; }

field() { awk -v k="$1" '$1 == k { print $2 }' "$2"; }
table=$out/table.md
{
  cpu=$(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //')
  echo "Measured $(date -u '+%Y-%m-%d %H:%M UTC') on $cpu, $(nproc) CPUs; commit $(git rev-parse --short HEAD); $n rays per run (seed 1), 1 thread, LLVM -O3, \`scripts/bench-quantized.sh\`."
  echo
  echo "| scene | rays | layout | twin | bytes | Mrays/s | / twin | area x | volume x | conservative | extra box tests | extra nodes | extra triangle tests | hits = twin |"
  echo "|---|---|---|---|---:|---:|---:|---:|---:|---|---:|---:|---:|---|"
  for s in "${scenes[@]}"; do
    for rays in primary secondary; do
      for t in pbrt bvh8; do
        "$bin" trace --scene "$s" --rays "$rays" --n "$n" --threads 1 --backend llvm --layout "$t" \
          -o "$out/$t.hits" > "$out/$t.txt" 2>/dev/null
      done
      for l in $layouts; do
        twin=$(twin_of "$l")
        base=$(field throughput "$out/$twin.txt")
        "$bin" trace --scene "$s" --rays "$rays" --n "$n" --threads 1 --backend llvm --layout "$l" \
          --stats -o "$out/q.hits" > "$out/q.txt" 2>/dev/null
        mrays=$(field throughput "$out/q.txt")
        bytes=$(field structure "$out/q.txt")
        same=$(python3 - "$out/q.hits" "$out/$twin.hits" <<'PY'
import struct, sys
a, b = (open(f, "rb").read() for f in sys.argv[1:3])
n = len(b) // 8
d = [i for i in range(n) if a[8 * i:8 * i + 8] != b[8 * i:8 * i + 8]]
t = lambda x, i: struct.unpack_from("<f", x, 8 * i)[0]
same = sum(1 for i in d if t(a, i) == t(b, i))
nearer = sum(1 for i in d if t(a, i) < t(b, i))
farther = sum(1 for i in d if t(a, i) > t(b, i))
print("yes" if not d else f"{len(d)}: {same} same t, {nearer} nearer, {farther} farther")
PY
)
        awk -v s="$s" -v r="$rays" -v l="$l" -v t="$twin" -v b="$bytes" -v m="$mrays" -v base="$base" -v same="$same" '
          /^boxes / { area = $7; vol = $9; sub(/^x/, "", area); sub(/,$/, "", area); sub(/^x/, "", vol); sub(/;$/, "", vol);
                      cons = ($0 ~ /\(conservative/) ? "yes" : "NO" }
          /^error\/ray/ { bt = $4; nv = $8; tt = $12 }
          END { printf "| %s | %s | %s | %s | %d | %s | %.2f | %s | %s | %s | %s %% | %s %% | %s %% | %s |\n",
                       s, r, l, t, b, m, m / base, area, vol, cons, bt, nv, tt, same }' "$out/q.txt"
      done
    done
  done
} > "$table"
cat "$table"
doc_table "$table" bench-quantized
