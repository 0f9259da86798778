#!/usr/bin/env bash
# Makes the strand scene of the hair BVH case study (paper §8.2; `scenes/` has only triangle
# meshes, and no hair model of the paper's is at hand): a head of hair as a `.hair` file (Cem
# Yuksel's format, docs/formats.md), by `scion strands generate`, seeded, so the same options
# give the same bytes (the angles go through the platform's sin and cos). The procedure
# (scion_runtime::scene::strands::generate):
# STRANDS roots uniform on the unit sphere above z = -0.3; each strand SEGMENTS straight pieces
# of a length drawn in 0.6..1.2, grown from the surface normal, pulled down by a gravity that
# grows along the strand and turned by a per-strand curl; radius RADIUS at the root tapering to
# a fifth at the tip; all drawn from SplitMix64 seeded by SEED.
#
# Usage: scripts/make-strands.sh [OUT.hair]       (default target/scenes/head.hair)
#   STRANDS=4000 SEGMENTS=16 RADIUS=0.004 SEED=1 (the defaults: 64,000 segments, 1.1 MB)
# Then: target/release/scion strands trace --scene OUT.hair [--rays secondary] [--backend jit]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-target/scenes/head.hair}
[ -x target/release/scion ] || cargo build -q --release -p scion-cli
mkdir -p "$(dirname "$out")"
target/release/scion strands generate --strands "${STRANDS:-4000}" --segments "${SEGMENTS:-16}" \
  --radius "${RADIUS:-0.004}" --seed "${SEED:-1}" -o "$out"
sha256sum "$out"
