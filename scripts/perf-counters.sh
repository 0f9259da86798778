#!/usr/bin/env bash
# Instructions and (simulated) cache misses per ray of Scion's closest hit and of its peers, on
# one scene, one thread, the same rays: what docs/performance.md explains gaps with.
#
# Hardware counters (`perf stat`) are not available on the development machine (a VM without a
# PMU), so each tracer runs under valgrind's callgrind with its cache and branch simulation
# (instruction counts are exact; cache misses come from its model of this machine's caches).
# The peers benchmark traces one row, once (`--trace-only`), and callgrind counts only that call
# (`--toggle-collect`: loading, building, compiling and the harness are left out; counted, they
# varied by millions of instructions between runs), at two ray counts: the difference divided by
# the difference in rays is the per-ray cost of that row's traversal, without the first rays'
# cold caches. Branch mispredictions come from valgrind's simple branch predictor model, so read
# them as relative, not as this CPU's.
#
# Usage: scripts/perf-counters.sh [SCENE_NAME [RAYS]]   (default: bunny, primary and secondary)
#   Environment: SCION_SCENES (default: the repository's scenes/), PERF_N1 / PERF_N2 (ray counts,
#   default 4096 and 20480), PERF_ROWS (rows to run, below; default all), PERF_ARGS (more
#   options for the peers benchmark, e.g. "--root enters" to count only the rays that enter the
#   root's box, or "--tree obvhs"). Prints a markdown table.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh >/dev/null
scenes=$(cd "${SCION_SCENES:-scenes}" && pwd)
. scripts/bench-lib.sh
need_valgrind
scene=${1:-bunny}
kinds=${2:-primary secondary}
n1=${PERF_N1:-4096}
n2=${PERF_N2:-20480}
# Valgrind runs only part of x86-64: no AVX-512, and not every newer extension a native build
# may use (Zen 3's 256-bit VPCLMULQDQ, which crc32fast picks when the build allows it, stops
# valgrind 3.19 with SIGILL). So on x86-64 the benchmark (and every Rust and C++ peer compiled
# with it) is built for x86-64-v3 (AVX2, FMA, BMI2) in its own folder, whatever the CPU; the JIT
# asks for the CPU valgrind reports, which has none of those either.
if [ "$(uname -m)" = x86_64 ]; then
  export CARGO_TARGET_DIR=target/bench-valgrind
  export RUSTFLAGS="-C target-cpu=x86-64-v3"
  # tinybvh-rs compiles its C++ with -march=native; flags from the environment come last.
  export CFLAGS="-march=x86-64-v3" CXXFLAGS="-march=x86-64-v3"
else
  export CARGO_TARGET_DIR=target/bench-native
  export RUSTFLAGS="-C target-cpu=native"
fi
bench=$(peers_bench)
out=target/perf-counters
mkdir -p "$out"

# row name | --peers | --layouts; PERF_ROWS (a space-separated list of row names with `_` for
# spaces, e.g. "llvm-O3_bvh8 embree") picks some of them.
rows=(
  "llvm-O3 pbrt||pbrt"
  "cranelift pbrt||pbrt"
  "hand-written pbrt|hand-pbrt|"
  "reference||"
  "tinybvh bvh2|tinybvh-bvh2|"
  "obvhs bvh2|obvhs-bvh2|"
  "embree|embree|"
  "llvm-O3 bvh8||bvh8"
  "llvm-O3 bvh8-q8-ci||bvh8-q8-ci"
  "tinybvh bvh8_cpu|tinybvh-bvh8|"
  "llvm-O3 bvh8-tri4||bvh8-tri4"
)
if [ -n "${PERF_ROWS:-}" ]; then
  picked=()
  for row in "${rows[@]}"; do
    name=${row%%|*}
    for want in $PERF_ROWS; do [ "$want" = "${name// /_}" ] && picked+=("$row"); done
  done
  [ ${#picked[@]} -gt 0 ] || { echo "perf-counters: no row named in PERF_ROWS=$PERF_ROWS" >&2; exit 2; }
  rows=("${picked[@]}")
fi

# counts FILE: "instructions D1-misses LL-misses branches mispredicts" from callgrind's
# summary on stderr (its cache and branch simulation, cachegrind's).
counts() {
  awk '/I *refs:/ { gsub(",", "", $4); i = $4 }
       /D1 *misses:/ { gsub(",", "", $4); d = $4 }
       /LLd misses:/ { gsub(",", "", $4); l = $4 }
       /Branches:/ { gsub(",", "", $3); b = $3 }
       /Mispredicts:/ { gsub(",", "", $3); m = $3 }
       END { print i, d, l, b, m }' "$1"
}

echo "| rays | tracer | instructions/ray | branches/ray | mispredicted/ray | L1d misses/ray | LLd misses/ray |"
echo "|---|---|---:|---:|---:|---:|---:|"
for kind in $kinds; do
  for row in "${rows[@]}"; do
    IFS='|' read -r name peers layouts <<<"$row"
    tag=$(echo "$name" | tr ' ' '_')-$kind
    for n in "$n1" "$n2"; do
      # Only the traced call is counted (the bench's `peers_traced_call`): setup, compiling and
      # the harness would add their own run-to-run variation to the difference.
      valgrind --tool=callgrind --cache-sim=yes --branch-sim=yes --callgrind-out-file=/dev/null \
        --collect-atstart=no --toggle-collect='*peers_traced_call*' \
        "$bench" --scene "$(scene_file "$scene")" --rays "$kind" --n "$n" --threads 1 \
        --peers "$peers" --layouts "$layouts" --interp-rays 0 --trace-only "$name" ${PERF_ARGS:-} \
        > "$out/$tag-$n.out" 2> "$out/$tag-$n.err"
    done
    read -r i1 d1 l1 b1 m1 <<<"$(counts "$out/$tag-$n1.err")"
    read -r i2 d2 l2 b2 m2 <<<"$(counts "$out/$tag-$n2.err")"
    awk -v k="$kind" -v name="$name" -v n="$((n2 - n1))" \
      -v i="$((i2 - i1))" -v d="$((d2 - d1))" -v l="$((l2 - l1))" -v b="$((b2 - b1))" -v m="$((m2 - m1))" \
      'BEGIN { printf "| %s | %s | %.0f | %.1f | %.2f | %.1f | %.2f |\n", k, name, i / n, b / n, m / n, d / n, l / n }'
  done
done
