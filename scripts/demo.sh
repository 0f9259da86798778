#!/usr/bin/env bash
# The main job: trace a real scene (../shared/scenes/bunny.obj, 69,630 triangles) with the
# library's closest-hit compiled for the pbrt layout (destructor and constructor specialization,
# lo, Cranelift JIT), check the hits against the runtime's reference traversal, and print the
# figures (build, pack and trace time, Mrays/s, bytes). Also prints the tree IR of closest-hit.
# Installs what is missing first. SCION_SCENE and SCION_LAYOUT (pbrt, ptr, pbrt-align16,
# pbrt-soaos) pick another scene or layout; extra arguments go to the JIT's `scion trace`.
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
echo "== scion trace: $scene, $layout layout, Cranelift JIT" >&2
target/release/scion trace --scene "$scene" --layout "$layout" --backend jit --rays primary --n 65536 \
  -o target/demo-jit.hits "$@"
echo "== scion trace: the same rays through the runtime's Rust reference" >&2
target/release/scion trace --scene "$scene" --backend reference --rays primary --n 65536 --runs 1 \
  -o target/demo-reference.hits > /dev/null
if cmp -s target/demo-jit.hits target/demo-reference.hits; then
  echo "hits: identical to the reference traversal (target/demo-jit.hits)"
else
  echo "hits: DIFFER from the reference traversal" >&2
  exit 1
fi
