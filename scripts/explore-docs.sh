#!/usr/bin/env bash
# The design-space exploration of the docs (issue 17), in one command: `scion explore` over the
# library's ten scenes × every library layout × closest hit with primary and secondary rays and
# closest points (65,536 each, one thread, LLVM -O3, the paper's method), its results in
# docs/explore/results.csv (resumable: a rerun measures only what is missing; delete the file to
# measure again); the peer libraries of the peers benchmark (Embree, tinybvh's BVH2 and
# BVH8_CPU, obvhs's BVH2 and CWBVH, the hand-written pbrt kernel) on the same scenes and rays,
# and those of scripts/bench-closest-point.sh (parry3d, FCPW) on the same points, each with
# Scion's pbrt layout in the same run, in docs/explore/peers.csv (also resumable);
# the Pareto (peers as reference points) and speed-against-error plots of every context, SVG
# and PNG, and their index in docs/explore/; and the summary table of docs/benchmarks.md
# ("Design-space exploration", between `<!-- explore:begin -->` and `<!-- explore:end -->`;
# BENCH_NO_DOC=1: print only).
#
# Usage: scripts/explore-docs.sh [SCENE_NAME...]   (default: the ten library scenes)
#   Environment: EXPLORE_KINDS (closest-hit,closest-point), EXPLORE_SIZES (65536), EXPLORE_RUNS (9),
#   EXPLORE_LAYOUTS (every library layout but hair-bvh, whose 3-bit leaf counts need leaves of
#   at most 7 triangles: `scion trace --layout hair-bvh --leaf-size 7` measures it).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/bench-lib.sh
./scripts/setup.sh >/dev/null
cargo build --release -q -p scion-cli
if [ $# -gt 0 ]; then names=("$@"); else names=("${LIBRARY_SCENES[@]}"); fi
scenes_arg=$(IFS=,; echo "${names[*]}")
out=docs/explore
mkdir -p "$out"
all=$(target/release/scion layouts --names --primitive Triangle | grep -v '^hair-bvh$' | paste -sd, -)
layouts=(--layouts "${EXPLORE_LAYOUTS:-$all}")
kinds=${EXPLORE_KINDS:-closest-hit,closest-point}
target/release/scion explore --scenes "$scenes_arg" "${layouts[@]}" \
  --kinds "$kinds" --sizes "${EXPLORE_SIZES:-65536}" \
  --runs "${EXPLORE_RUNS:-9}" --threads 1 -o "$out/results.csv"

# The peers of every closest-hit context not yet in peers.csv, built for this CPU as
# scripts/bench-peers.sh builds them (tinybvh's BVH8_CPU needs AVX2).
peers_csv="$out/peers.csv"
bench=$(CARGO_TARGET_DIR=target/bench-native RUSTFLAGS="-C target-cpu=native" peers_bench)
for s in "${names[@]}"; do
  for rays in primary secondary; do
    for n in $(tr , ' ' <<<"${EXPLORE_SIZES:-65536}"); do
      [[ $n == *^* ]] && n=$(( ${n%^*} ** ${n#*^} ))
      [ -f "$peers_csv" ] && grep -q "^$s\.obj,closest-hit,$rays,$n,1," "$peers_csv" && continue
      echo "explore-docs: peers on $s, $n $rays rays" >&2
      "$bench" --scene "$(scene_file "$s")" --rays "$rays" --n "$n" --threads 1 \
        --layouts pbrt --interp-rays 0 --peer-csv "$peers_csv" > /dev/null 2> target/explore-peers.log ||
        { cat target/explore-peers.log >&2; exit 1; }
    done
  done
done
# The closest-point peers (parry3d, FCPW) of the scenes not yet in peers.csv, by
# scripts/bench-closest-point.sh (its table in docs/benchmarks.md is left alone).
if [[ ,$kinds, == *,closest-point,* ]]; then
  missing=()
  for s in "${names[@]}"; do
    grep -q "^$s,closest-point,points,65536,1," "$peers_csv" || missing+=("$s")
  done
  if [ ${#missing[@]} -gt 0 ]; then
    echo "explore-docs: closest-point peers on ${missing[*]}" >&2
    BENCH_NO_DOC=1 BENCH_N=65536 PEER_CSV="$peers_csv" scripts/bench-closest-point.sh "${missing[@]}" > /dev/null
  fi
fi
target/release/scion explore --scenes "$scenes_arg" "${layouts[@]}" \
  --kinds "$kinds" --sizes "${EXPLORE_SIZES:-65536}" \
  --runs "${EXPLORE_RUNS:-9}" --threads 1 -o "$out/results.csv" --plots "$out" --peers "$peers_csv"
table=target/explore-summary.md
python3 scripts/explore_summary.py "$out/results.csv" "$peers_csv" > "$table"
cat "$table"
doc_table "$table" explore
