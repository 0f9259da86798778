#!/usr/bin/env bash
# Collision against FCL (issue 16): every library scene against its copy turned by (60°, 70°,
# 10°) about the centre of its box, one thread, the paper's timing method (1 warm-up, 9 runs,
# the middle 5 averaged) on each side, in the same run:
#   - Scion: `scion run --algorithm collide` (library/algorithms/collide.scion over the pbrt
#     layout, LLVM -O3; binned SAH trees, leaves of up to 15 triangles; the explicit-stack
#     `collide` and the `collide_recursive` variant, calls on the machine stack as FCL, whose
#     pairs must be the same);
#   - FCL 0.7 (Debian's libfcl-dev, installed when missing): bench/fcl/fcl_collide.cpp with OBBRSS
#     and with AABB bounding volumes (its default builder: mean split, one triangle per leaf),
#     built with g++ -O3 here, on the same triangles (bench/src/bin/collide_inputs.rs).
# Each side's pairs are compared: the table says whether the three sets are equal, and if not,
# how many pairs only Scion or only FCL reports and how many of those the separating-axis test
# in float64 finds colliding (bench/src/bin/collide_f64.rs: the oracle of who is right). Writes the table into docs/benchmarks.md between
# `<!-- bench-collide:begin -->` and `<!-- bench-collide:end -->` (BENCH_NO_DOC=1: print only).
#
# Usage: scripts/bench-collide.sh [SCENE_NAME...]   (default: the ten library scenes)
#   Environment: BENCH_RUNS (timed runs, default 9), BENCH_LAYOUT (default pbrt).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/bench-lib.sh
./scripts/setup.sh >/dev/null
if [ ! -e /usr/include/fcl/fcl.h ]; then
  echo "bench-collide: installing libfcl-dev (Debian package)" >&2
  sudo=""; [ "$(id -u)" -eq 0 ] || sudo=sudo
  $sudo apt-get update -q >/dev/null
  $sudo apt-get install -y -q libfcl-dev >/dev/null
fi
cargo build --release -q -p scion-cli -p scion-bench --bin collide_inputs --bin collide_f64
target=${CARGO_TARGET_DIR:-target}
bin="$target/release/scion"
out=$target/bench-collide
mkdir -p "$out"
g++ -O3 -std=c++17 -I/usr/include/eigen3 bench/fcl/fcl_collide.cpp -lfcl -o "$out/fcl_collide"
runs=${BENCH_RUNS:-9}
layout=${BENCH_LAYOUT:-pbrt}
if [ $# -gt 0 ]; then names=("$@"); else names=("${LIBRARY_SCENES[@]}"); fi

table=$out/table.md
{
  cpu=$(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //')
  fcl=$(dpkg-query -W -f='${Version}' libfcl-dev 2>/dev/null || echo "?")
  echo "Measured $(date -u '+%Y-%m-%d %H:%M UTC') on $cpu, $(nproc) CPUs; commit $(git rev-parse --short HEAD); FCL $fcl (g++ -O3); Scion \`$layout\`, LLVM -O3; 1 thread; the paper's method ($runs runs); \`scripts/bench-collide.sh\`."
  echo
  echo "| scene | triangles | pairs (Scion) | Scion ms | Scion recursive ms | FCL OBBRSS ms | FCL AABB ms | faster FCL / Scion | faster FCL / Scion recursive | pairs equal to FCL's (float64 verdict where not) |"
  echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|"
  for name in "${names[@]}"; do
    f=$(scene_file "$name")
    "$bin" run --algorithm collide --scene "$f" --layout "$layout" --runs "$runs" \
      -o "$out/scion.pairs" > "$out/scion.txt" 2>/dev/null
    tris=$(awk '$1 == "triangles" { print $2 }' "$out/scion.txt")
    pairs=$(awk '$1 == "pairs" { print $2 }' "$out/scion.txt")
    ms=$(awk '$1 == "time" { printf "%.4f", $2 * 1000 }' "$out/scion.txt")
    # The recursive variant (calls on the machine stack, as FCL): the same pairs.
    "$bin" run --algorithm collide_recursive --scene "$f" --layout "$layout" --runs "$runs" \
      -o "$out/scion-rec.pairs" > "$out/scion-rec.txt" 2>/dev/null
    cmp -s "$out/scion.pairs" "$out/scion-rec.pairs" || { echo "bench-collide: $name: the recursive variant's pairs differ" >&2; exit 1; }
    rms=$(awk '$1 == "time" { printf "%.4f", $2 * 1000 }' "$out/scion-rec.txt")
    "$target/release/collide_inputs" "$f" "$out/a.tris" "$out/b.tris"
    "$out/fcl_collide" "$out/a.tris" "$out/b.tris" "$runs" "$out/fcl" > "$out/fcl.txt"
    obb=$(awk '$1 == "fcl-obbrss" { print $5 }' "$out/fcl.txt")
    aabb=$(awk '$1 == "fcl-aabb" { print $5 }' "$out/fcl.txt")
    # Where the sets differ, the float64 test decides (collide_f64).
    same=""
    for bv in obbrss aabb; do
      if cmp -s "$out/scion.pairs" "$out/fcl-$bv.pairs"; then v=yes
      else v=$("$target/release/collide_f64" "$out/a.tris" "$out/b.tris" "$out/scion.pairs" "$out/fcl-$bv.pairs" | sed 's/the peer/FCL/'); fi
      same="${same:+$same; }$bv: $v"
    done
    awk -v n="$name" -v t="$tris" -v p="$pairs" -v s="$ms" -v r="$rms" -v o="$obb" -v a="$aabb" -v same="$same" \
      'BEGIN { f = (o < a ? o : a); printf "| %s | %s | %s | %.3f | %.3f | %.3f | %.3f | %.2f | %.2f | %s |\n", n, t, p, s, r, o, a, f / s, f / r, same }'
  done
} > "$table"
cat "$table"
doc_table "$table" bench-collide
