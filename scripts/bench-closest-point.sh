#!/usr/bin/env bash
# Closest points against parry3d and FCPW (issue 16): on each library scene, the points of
# `scion run --algorithm closest-point` (uniform in the scene's box), one thread each, the paper's
# timing method (1 warm-up, 9 runs, the middle 5 averaged), in the same run:
#   - Scion: library/algorithms/closest_point.scion's closest_point_query over pbrt and
#     closest_point8.scion's closest_point8 over the eight-wide bvh8, on Scion's binned SAH
#     tree, and closest_point_query over pbrt on FCPW's tree (runtime/src/bvh/fcpw.rs, the
#     paper's set-up), LLVM -O3 (bench/benches/closest_point.rs, through their C entries on one
#     thread);
#   - parry3d 0.31 (crate): its TriMesh's point projection, in the same process;
#   - FCPW (Python package `fcpw`, its C++ core; installed with numpy when missing): its
#     surface-area BVH, vectorized and scalar, `find_closest_points` over all points, pinned to
#     one core with `taskset -c 0` (it runs queries on every core otherwise);
# and each side's answers on the first 2048 points against float64 brute force (the largest
# distance error; answers naming another triangle than float64's at a distance more than 1e-6
# of the scene's size away from it). Writes the table into docs/benchmarks.md between
# `<!-- bench-closest-point:begin -->` and `<!-- bench-closest-point:end -->` (BENCH_NO_DOC=1:
# print only).
#
# With PEER_CSV=FILE, also appends the peers' rows to the peers file FILE (the columns of
# `scion_runtime::timing::PEER_FIELDS`), each anchored to Scion's pbrt (LLVM -O3) measured by the
# same benchmark binary, for `scion explore --peers` (scripts/explore-docs.sh): parry3d from the
# same run, FCPW from its own process just before it.
#
# Usage: scripts/bench-closest-point.sh [SCENE_NAME...]   (default: the ten library scenes)
#   Environment: BENCH_N (points, default 65536), BENCH_RUNS (9), PEER_CSV (none),
#   BENCH_NO_DOC=1 (print only).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/bench-lib.sh
./scripts/setup.sh >/dev/null
python3 -c 'import numpy, fcpw' 2>/dev/null || {
  echo "bench-closest-point: installing numpy and fcpw (Python packages)" >&2
  python3 -m pip install --quiet numpy fcpw
}
command -v taskset >/dev/null || { echo "bench-closest-point: taskset (util-linux) is needed" >&2; exit 1; }
cargo bench -q -p scion-bench --bench closest_point --no-run 2>/dev/null
target=${CARGO_TARGET_DIR:-target}
bin=$(ls -t "$target"/release/deps/closest_point-* | grep -v '\.d$' | head -1)
out=$target/bench-closest-point
mkdir -p "$out"
n=${BENCH_N:-65536}
runs=${BENCH_RUNS:-9}
if [ $# -gt 0 ]; then names=("$@"); else names=("${LIBRARY_SCENES[@]}"); fi

table=$out/table.md
{
  cpu=$(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //')
  fcpw=$(python3 -c 'import importlib.metadata as m; print(m.version("fcpw"))')
  echo "Measured $(date -u '+%Y-%m-%d %H:%M UTC') on $cpu, $(nproc) CPUs; commit $(git rev-parse --short HEAD); $n points per scene (seed 1); 1 thread; Scion pbrt and bvh8 on its binned SAH tree and pbrt on FCPW's tree, LLVM -O3; parry3d 0.31; FCPW $fcpw (pip); the paper's method ($runs runs); \`scripts/bench-closest-point.sh\`."
  echo
  echo "| scene | triangles | Scion pbrt Mq/s | Scion bvh8 Mq/s | Scion pbrt, FCPW's tree Mq/s | parry3d Mq/s | FCPW vectorized Mq/s | FCPW scalar Mq/s | pbrt / fastest peer | bvh8 / fastest peer | pbrt on FCPW's tree / fastest peer | largest error vs float64 (Scion, parry3d, FCPW) | wrong triangles (Scion, parry3d, FCPW) |"
  echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|"
  for name in "${names[@]}"; do
    f=$(scene_file "$name")
    "$bin" --scene "$f" --n "$n" --inputs "$out"
    fv=$(taskset -c 0 python3 bench/fcpw/fcpw_closest.py "$out/tris.bin" "$out/points.bin" "$runs" "$out/fcpw.out" | awk '{ print $3 }')
    fs=$(taskset -c 0 python3 bench/fcpw/fcpw_closest.py "$out/tris.bin" "$out/points.bin" "$runs" "$out/fcpw-scalar.out" scalar | awk '{ print $3 }')
    "$bin" --scene "$f" --n "$n" --runs "$runs" --peer "fcpw=$out/fcpw.out" > "$out/run.txt"
    if [ -n "${PEER_CSV:-}" ]; then
      [ -f "$PEER_CSV" ] || echo "scene,kind,queries,n,threads,peer,bytes,triangles,ns_per_query,anchor,anchor_ns_per_query" > "$PEER_CSV"
      awk -v s="$name" -v n="$n" -v fv="$fv" -v fs="$fs" '
        $1 == "triangles" { t = $2 } $1 == "scion_ms" { sm[$2] = $3 } $1 == "parry_ms" { pm = $2 }
        END {
          ns = 1e6 / n; a = sm["pbrt"] * ns
          printf "%s,closest-point,points,%d,1,parry3d,,%d,%.4f,llvm-O3 pbrt,%.4f\n", s, n, t, pm * ns, a
          printf "%s,closest-point,points,%d,1,fcpw,,%d,%.4f,llvm-O3 pbrt,%.4f\n", s, n, t, fv * ns, a
          printf "%s,closest-point,points,%d,1,fcpw scalar,,%d,%.4f,llvm-O3 pbrt,%.4f\n", s, n, t, fs * ns, a
        }' "$out/run.txt" >> "$PEER_CSV"
    fi
    awk -v s="$name" -v n="$n" -v fv="$fv" -v fs="$fs" '
      $1 == "triangles" { t = $2 } $1 == "scion_ms" { sm[$2] = $3 } $1 == "parry_ms" { pm = $2 }
      $1 == "scion_layouts_differ" && $2 != 0 { print "bench-closest-point: the layouts differ on " $2 " answers" > "/dev/stderr"; bad = 1 }
      $1 == "scion:bvh8_error" { se = $2; sw = $4 "/" $6 } $1 == "parry_error" { pe = $2; pw = $4 "/" $6 }
      $1 == "fcpw_error" { fe = $2; fw = $4 "/" $6 }
      END {
        q = n / 1000.0
        best = pm; if (fv < best) best = fv; if (fs < best) best = fs
        if (bad) exit 1
        printf "| %s | %d | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.2f | %.2f | %.2f | %s, %s, %s | %s, %s, %s |\n",
          s, t, q / sm["pbrt"], q / sm["bvh8"], q / sm["pbrt@fcpw"], q / pm, q / fv, q / fs, best / sm["pbrt"], best / sm["bvh8"], best / sm["pbrt@fcpw"], se, pe, fe, sw, pw, fw
      }' "$out/run.txt"
  done
} > "$table"
cat "$table"
doc_table "$table" bench-closest-point
