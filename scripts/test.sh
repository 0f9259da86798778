#!/usr/bin/env bash
# The whole test suite: Rust unit and integration tests, the parser/sema robustness run and the
# lit suite (run from cargo through compiler/tests/lit.rs). Installs what is missing first.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
cargo test --workspace --release
