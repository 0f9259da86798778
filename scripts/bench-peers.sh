#!/usr/bin/env bash
# Closest hit against its peers on every library scene: primary and secondary rays, one thread
# and all threads, by the paper's method (1 warm-up round, 9 interleaved rounds, mean of the
# middle 5), every contender on the same triangles, rays and threads in the same run
# (`cargo bench -p scion-bench --bench peers`, see bench/benches/peers/main.rs). Then writes the
# summary table, with the date, commit, machine and versions, into docs/benchmarks.md between
# the markers `<!-- bench-peers:begin -->` and `<!-- bench-peers:end -->`, and the raw rows to
# target/bench-peers/rows.tsv.
#
# The benchmark is built with RUSTFLAGS="-C target-cpu=native" in its own target folder
# (target/bench-native): the JIT compiles Scion's code for this CPU, so the Rust and C++ peers
# get it too (tinybvh's BVH8_CPU needs AVX2 to exist at all).
#
# Usage: scripts/bench-peers.sh [SCENE_NAME...]
#   Environment: SCION_SCENES (default: the repository's scenes/), BENCH_N (rays per run, default 65536),
#   BENCH_THREADS (default "1 all"), BENCH_NO_DOC=1 (do not touch docs/benchmarks.md).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh >/dev/null
scenes=$(cd "${SCION_SCENES:-scenes}" && pwd)
. scripts/bench-lib.sh
n=${BENCH_N:-65536}
all=$(nproc)
threads=${BENCH_THREADS:-1 all}
out=target/bench-peers
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
echo "bench-peers: building the benchmark (target-cpu=native)" >&2
bench=$(peers_bench)

total=$(( ${#names[@]} * 2 * $(wc -w <<<"$threads") ))
k=0
for s in "${names[@]}"; do
  for rays in primary secondary; do
    for t in $threads; do
      [ "$t" = all ] && t=$all
      k=$((k + 1))
      echo "bench-peers: [$k/$total] $s, $rays rays, $t thread(s)" >&2
      "$bench" --scene "$(scene_file "$s")" --rays "$rays" \
        --n "$n" --threads "$t" --layouts pbrt --interp-rays 0 --tsv "$rows" \
        > "$out/$s-$rays-$t.md" 2> "$out/$s-$rays-$t.log"
    done
  done
done

python3 scripts/bench_peers_table.py "$rows" "$n" > "$out/summary.md"
cat "$out/summary.md"
if [ "${BENCH_NO_DOC:-0}" != 1 ]; then
  python3 scripts/bench_peers_table.py --into docs/benchmarks.md "$out/summary.md"
  echo "bench-peers: docs/benchmarks.md updated" >&2
fi
