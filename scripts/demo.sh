#!/usr/bin/env bash
# The main job: trace a real scene (../shared/scenes/bunny.obj, 69,630 triangles) with the
# library's closest-hit compiled for the pbrt layout (destructor and constructor specialization,
# lo, then machine code twice: LLVM -O3 and the Cranelift JIT), check the hits of both against
# the runtime's reference traversal, and print the figures (build, pack and trace time, Mrays/s,
# bytes). Also prints the tree IR of closest-hit. Installs what is missing first. SCION_SCENE and
# SCION_LAYOUT (pbrt, ptr, pbrt-align16, pbrt-soaos) pick another scene or layout; extra
# arguments go to both `scion trace` runs.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
scene="${SCION_SCENE:-../shared/scenes/bunny.obj}"
layout="${SCION_LAYOUT:-pbrt}"
cargo build --release -q -p scion-compiler -p scion-cli
echo "== scionc --emit=tree: closest-hit (paper Figure 4), first lines" >&2
target/release/scionc --emit=tree library/algorithms/closest_hit.scion library/layouts/pbrt.scion \
  > target/demo-closest-hit.tree
awk '/^func @closest_hit/,/^}/' target/demo-closest-hit.tree | sed -n 1,12p
echo "   ... (whole module: target/demo-closest-hit.tree)"
echo "== scion trace: the runtime's Rust reference traversal (the hits to match)" >&2
target/release/scion trace --scene "$scene" --backend reference --rays primary --n 65536 --runs 1 \
  -o target/demo-reference.hits > /dev/null
for backend in llvm jit; do
  case $backend in
    llvm) what="LLVM -O3 (in-process JIT, host CPU)" ;;
    jit) what="Cranelift JIT" ;;
  esac
  echo "== scion trace: $scene, $layout layout, $what" >&2
  target/release/scion trace --scene "$scene" --layout "$layout" --backend "$backend" --rays primary \
    --n 65536 -o "target/demo-$backend.hits" "$@"
  if cmp -s "target/demo-$backend.hits" target/demo-reference.hits; then
    echo "hits: identical to the reference traversal (target/demo-$backend.hits)"
  else
    echo "hits: DIFFER from the reference traversal ($backend)" >&2
    exit 1
  fi
done
