#!/usr/bin/env bash
# The main job at this stage: compile the library's closest-hit traversal against the pbrt layout
# and print its `tree` IR. Installs what is missing first.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
cargo run --release -q -p scion-compiler --bin scionc -- --emit=tree \
  library/algorithms/closest_hit.scion library/layouts/pbrt.scion "$@"
