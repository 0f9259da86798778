#!/usr/bin/env bash
# Speedup of the DSL optimizations (paper §7.3: mem-inline, const-fold, mem-cse, dce) on the
# Cranelift JIT and on LLVM -O3: `scion trace --backend jit|llvm --opt-level 3` against the same
# with `--no-dsl-opt` (the -O3 pipeline without the tree/mem optimizations; specialization,
# lowering, lo-inline and the code generator's own optimizations stay), for layouts pbrt and
# ptr, by the paper's method (`--runs 9`: 1 warm-up, 9 runs, mean of the middle 5), primary and secondary
# rays (n = 65536, seed 1), one thread. Each pair's hit files are compared byte for byte (the
# optimizations must not change a bit). Writes a markdown table to standard output.
#
# Usage: scripts/bench-dslopt.sh [SCENES_DIR] [SCENE_NAME...]
#   SCENES_DIR defaults to $SCION_SCENES or the repository's scenes/; the default scenes are bunny and
#   engine. BACKENDS (default "jit llvm") picks the code generators. Builds the release `scion`
#   first.
set -euo pipefail
cd "$(dirname "$0")/.."
scenes=${1:-${SCION_SCENES:-scenes}}
. scripts/bench-lib.sh
shift || true
cargo build --release -q -p scion-cli
scion=target/release/scion
n=65536
seed=1
threads=1
if [ $# -gt 0 ]; then names=("$@"); else names=(bunny engine); fi
read -r -a backends <<< "${BACKENDS:-jit llvm}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# Mrays/s of one `scion trace` run: scene, rays, backend, layout, extra flag, hits file stem.
mrays() {
  "$scion" trace --scene "$1" --rays "$2" --n "$n" --seed "$seed" --threads "$threads" --runs 9 \
    --backend "$3" --layout "$4" --opt-level 3 $5 -o "$tmp/$6.bin" 2>/dev/null |
    awk '/^throughput/ { print $2 }'
}

cpu=$(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //')
echo "Date: $(date -u '+%Y-%m-%d %H:%M UTC'); machine: $(nproc) CPUs, $cpu; commit $(git rev-parse --short HEAD)."
echo "Rays: n = $n, seed $seed; binned SAH + reinsertion + leaves collapsed for runs of four, leaves <= 15; $threads thread; --runs 9 (mean of the middle 5 of 9 after a warm-up)."
echo
echo "| scene | rays | layout | backend | -O3 --no-dsl-opt Mrays/s | -O3 Mrays/s | speedup | hits identical |"
echo "|---|---|---|---|---:|---:|---:|---|"
for name in "${names[@]}"; do
  obj=$(scene_file "$name") || exit 1
  for rays in primary secondary; do
    for layout in pbrt ptr; do
      for backend in "${backends[@]}"; do
        base=$(mrays "$obj" "$rays" "$backend" "$layout" --no-dsl-opt base)
        opt=$(mrays "$obj" "$rays" "$backend" "$layout" "" opt)
        same=no
        cmp -s "$tmp/base.bin" "$tmp/opt.bin" && same=yes
        speedup=$(awk -v a="$opt" -v b="$base" 'BEGIN { if (b > 0) printf "%.2f", a / b; else print "-" }')
        echo "| $name | $rays | $layout | $backend | $base | $opt | ${speedup}x | $same |"
      done
    done
  done
done
