#!/usr/bin/env bash
# Composes a large scene from a library scene (issue 17's lucy-scale run: the Lucy statue of
# the paper has 28 M triangles, and no such mesh is at hand): COPIES copies of NAME's OBJ on a
# grid (as near a cube as COPIES allows, each copy's box 5 % apart from the next), written as
# one OBJ, the copies' vertices shared within each copy, face indices shifted per copy. The
# copies do not overlap, so rays see a city of statues rather than one dense blob.
#
# Usage: scripts/compose-scene.sh NAME COPIES OUT.obj      e.g. dragon 32 target/scenes/lucy-scale.obj
#   (32 dragons: 27,881,792 triangles; 1.3 GB of OBJ text.)
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/bench-lib.sh
[ $# -eq 3 ] || { echo "usage: $0 NAME COPIES OUT.obj" >&2; exit 2; }
name=$1 copies=$2 out=$3
[[ "$copies" =~ ^[1-9][0-9]*$ ]] || { echo "$0: COPIES must be a positive count, not '$copies'" >&2; exit 2; }
src=$(scene_file "$name")
mkdir -p "$(dirname "$out")"
cat_src() { case "$src" in *.gz) gzip -dc "$src" ;; *) cat "$src" ;; esac; }
# Pass 1: the box and the vertex count; pass 2: the copies.
read -r nv minx miny minz maxx maxy maxz < <(cat_src | awk '
  $1 == "v" { n++; for (i = 0; i < 3; i++) { x = $(i + 2) + 0;
    if (n == 1 || x < lo[i]) lo[i] = x; if (n == 1 || x > hi[i]) hi[i] = x } }
  END { printf "%d %.9g %.9g %.9g %.9g %.9g %.9g\n", n, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2] }')
[ "$nv" -gt 0 ] || { echo "$0: $src has no vertices" >&2; exit 1; }
echo "# ${copies} copies of ${name} (${src}) on a grid, by scripts/compose-scene.sh" > "$out"
for ((k = 0; k < copies; k++)); do
  cat_src | awk -v k="$k" -v copies="$copies" -v nv="$nv" \
      -v ex="$(awk -v a="$minx" -v b="$maxx" 'BEGIN { print (b - a) * 1.05 }')" \
      -v ey="$(awk -v a="$miny" -v b="$maxy" 'BEGIN { print (b - a) * 1.05 }')" \
      -v ez="$(awk -v a="$minz" -v b="$maxz" 'BEGIN { print (b - a) * 1.05 }')" '
    BEGIN { side = int(copies ^ (1 / 3) + 0.999999); if (side < 1) side = 1;
            gx = k % side; gy = int(k / side) % side; gz = int(k / (side * side)) }
    $1 == "v" { printf "v %.9g %.9g %.9g\n", $2 + gx * ex, $3 + gy * ey, $4 + gz * ez; next }
    $1 == "f" { printf "f"; for (i = 2; i <= NF; i++) { split($i, p, "/"); printf " %d", p[1] + k * nv } printf "\n" }
  ' >> "$out"
done
echo "$out: $copies copies of $name ($((copies * nv)) vertices)" >&2
