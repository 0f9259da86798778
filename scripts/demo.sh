#!/usr/bin/env bash
# The main job: trace a real scene (scenes/bunny.obj.gz, 69,630 triangles) with the
# library's closest-hit compiled for the pbrt layout (destructor and constructor specialization,
# lo, then machine code twice: LLVM -O3 and the Cranelift JIT), check the hits of both against
# the runtime's reference traversal, and print the figures (build, pack and trace time, Mrays/s,
# bytes). Also prints the tree IR of closest-hit. Installs what is missing first. SCION_SCENE (a
# path or a scene name of scenes/) and SCION_LAYOUT (pbrt, ptr, pbrt-align16, pbrt-soaos,
# pbrt-q16, sg-eq) pick another scene or layout; extra arguments go to both `scion trace` runs.
# Outputs go to target/demo/ (the binaries come from $CARGO_TARGET_DIR when it is set).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
scene="${SCION_SCENE:-bunny}"
layout="${SCION_LAYOUT:-pbrt}"
bin="${CARGO_TARGET_DIR:-target}/release"
out=target/demo
mkdir -p "$out"
cargo build --release -q -p scion-compiler -p scion-cli
echo "== scionc --emit=tree: closest-hit (paper Figure 4), first lines" >&2
"$bin/scionc" --emit=tree library/algorithms/closest_hit.scion library/layouts/pbrt.scion \
  > "$out/closest-hit.tree"
awk '/^func @closest_hit/,/^}/' "$out/closest-hit.tree" | sed -n 1,12p
echo "   ... (whole module: $out/closest-hit.tree)"
echo "== scion trace: the runtime's Rust reference traversal (the hits to match)" >&2
"$bin/scion" trace --scene "$scene" --backend reference --rays primary --n 65536 --runs 1 \
  -o "$out/reference.hits" > /dev/null
for backend in llvm jit; do
  case $backend in
    llvm) what="LLVM -O3 (in-process JIT, host CPU)" ;;
    jit) what="Cranelift JIT" ;;
  esac
  echo "== scion trace: $scene, $layout layout, $what" >&2
  "$bin/scion" trace --scene "$scene" --layout "$layout" --backend "$backend" --rays primary \
    --n 65536 -o "$out/$backend.hits" "$@"
  if cmp -s "$out/$backend.hits" "$out/reference.hits"; then
    echo "hits: identical to the reference traversal ($out/$backend.hits)"
  else
    echo "hits: DIFFER from the reference traversal ($backend)" >&2
    exit 1
  fi
done
