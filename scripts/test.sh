#!/usr/bin/env bash
# The whole test suite: Rust unit and integration tests, the parser/sema robustness run and the
# lit suite (run from cargo through compiler/tests/lit.rs). Installs what is missing first.
# Then the compiler once more without its code generators (no LLVM, no Cranelift linked): the
# front end, the IR and every pass must build and pass their tests on their own.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
cargo test --workspace --release
cargo test -p scion-compiler --no-default-features
