#!/usr/bin/env bash
# The eight-wide layouts against Embree and tinybvh's BVH8_CPU on every library scene: primary
# and secondary rays, one thread (issue 15's table), by the paper's method (1 warm-up round,
# 9 interleaved rounds, mean of the middle 5), every contender on the same triangles, rays and
# thread in the same run (`cargo bench -p scion-bench --bench peers`, built for this CPU as in
# scripts/bench-peers.sh). Writes the summary, with the date, commit, machine and versions, into
# docs/benchmarks.md between `<!-- bench-wide:begin -->` and `<!-- bench-wide:end -->`, and the
# raw rows to target/bench-wide/rows.tsv.
#
# Usage: scripts/bench-wide.sh [SCENE_NAME...]
#   Environment: SCION_SCENES (default: the repository's scenes/), BENCH_N (rays per run,
#   default 65536), BENCH_THREADS (default 1), BENCH_NO_DOC=1 (do not touch docs/benchmarks.md).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh >/dev/null
scenes=$(cd "${SCION_SCENES:-scenes}" && pwd)
. scripts/bench-lib.sh
n=${BENCH_N:-65536}
threads=${BENCH_THREADS:-1}
out=target/bench-wide
mkdir -p "$out"
rows="$out/rows.tsv"
: > "$rows"
if [ $# -gt 0 ]; then
  names=("$@")
else
  names=("${LIBRARY_SCENES[@]}")
fi
for s in "${names[@]}"; do
  scene_file "$s" > /dev/null || exit 2
done

export CARGO_TARGET_DIR=target/bench-native
export RUSTFLAGS="-C target-cpu=native"
echo "bench-wide: building the benchmark (target-cpu=native)" >&2
bench=$(peers_bench)

total=$(( ${#names[@]} * 2 ))
k=0
for s in "${names[@]}"; do
  for rays in primary secondary; do
    k=$((k + 1))
    echo "bench-wide: [$k/$total] $s, $rays rays, $threads thread(s)" >&2
    "$bench" --scene "$(scene_file "$s")" --rays "$rays" --n "$n" --threads "$threads" \
      --layouts "pbrt,bvh8,bvh8-q8-ci,bvh8-tri4" --interp-rays 0 --peers embree,tinybvh-bvh8 \
      --tsv "$rows" > "$out/$s-$rays.md" 2> "$out/$s-$rays.log"
  done
done

python3 scripts/bench_wide_table.py "$rows" "$n" > "$out/summary.md"
cat "$out/summary.md"
if [ "${BENCH_NO_DOC:-0}" != 1 ]; then
  python3 scripts/bench_wide_table.py --into docs/benchmarks.md "$out/summary.md"
  echo "bench-wide: docs/benchmarks.md updated" >&2
fi
