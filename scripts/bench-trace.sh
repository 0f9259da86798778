#!/usr/bin/env bash
# Throughput of `scion trace --backend jit` (layouts pbrt and ptr) against the runtime's Rust
# reference traversal, by the paper's method (`--runs 9`: 1 warm-up, 9 runs, mean of the middle
# 5), on every scene of the scenes folder, primary and secondary rays (n = 65536, seed 1), on 1
# and 2 threads. Writes a markdown table (with the date, machine and commit) to standard output.
#
# Usage: scripts/bench-trace.sh [SCENES_DIR] [SCENE_NAME...]
#   SCENES_DIR defaults to $SCION_SCENES or the repository's scenes/; with names, only those scenes
#   (file stems) are measured, in that order. Builds the release `scion` first.
set -euo pipefail
cd "$(dirname "$0")/.."
scenes=${1:-${SCION_SCENES:-scenes}}
. scripts/bench-lib.sh
shift || true
cargo build --release -q -p scion-cli
scion=target/release/scion
n=65536
seed=1

if [ $# -gt 0 ]; then
  names=("$@")
else
  names=()
  for f in "$scenes"/*.obj "$scenes"/*.obj.gz; do
    [ -f "$f" ] || continue
    name=$(basename "$f"); name=${name%.gz}; names+=("${name%.obj}")
  done
fi

# Mrays/s of one `scion trace` run.
mrays() {
  "$scion" trace --scene "$1" --rays "$2" --n "$n" --seed "$seed" --threads "$3" --runs 9 \
    --backend "$4" ${5:+--layout "$5"} 2>/dev/null |
    awk '/^throughput/ { print $2 }'
}

cpu=$(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //')
echo "Date: $(date -u '+%Y-%m-%d %H:%M UTC'); machine: $(nproc) CPUs, $cpu; commit $(git rev-parse --short HEAD)."
echo "Rays: n = $n, seed $seed; binned SAH + reinsertion + leaves collapsed for runs of four, leaves <= 15; --runs 9 (mean of the middle 5 of 9 after a warm-up)."
echo
echo "| scene | triangles | rays | threads | reference Mrays/s | jit pbrt Mrays/s | pbrt / ref | jit ptr Mrays/s | ptr / ref |"
echo "|---|---:|---|---:|---:|---:|---:|---:|---:|"
for name in "${names[@]}"; do
  obj=$(scene_file "$name") || exit 1
  tris=$("$scion" trace --scene "$obj" --n 1 --runs 1 2>/dev/null | awk '/^triangles/ { print $2 }')
  for rays in primary secondary; do
    for threads in 1 2; do
      ref=$(mrays "$obj" "$rays" "$threads" reference "")
      pbrt=$(mrays "$obj" "$rays" "$threads" jit pbrt)
      ptr=$(mrays "$obj" "$rays" "$threads" jit ptr)
      ratio() { awk -v a="$1" -v b="$2" 'BEGIN { if (b > 0) printf "%.2f", a / b; else print "-" }'; }
      echo "| $name | $tris | $rays | $threads | $ref | $pbrt | $(ratio "$pbrt" "$ref") | $ptr | $(ratio "$ptr" "$ref") |"
    done
  done
done
