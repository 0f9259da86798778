#!/usr/bin/env bash
# Installs what Scion needs on a fresh Debian 12 machine when it is missing, and prints what it
# found. Safe to run again: it installs nothing that is already there.
#   - LLVM 22 tools (lit, FileCheck, not, llvm-objdump) from Debian: the lit test suite runs on
#     them.
#   - LLVM 22 development files (llvm-config, libLLVM, and the Polly, zlib and zstd libraries
#     llvm-config names): the LLVM backend (compiler/backend-llvm, through inkwell/llvm-sys)
#     links against them; .cargo/config.toml points llvm-sys at /usr/lib/llvm-22.
#   - g++ and make: the test suite builds and runs the C++ example (examples/cpp).
#   - The Rust toolchain is expected on the machine (cargo, rustc); we do not install it.
set -euo pipefail

need_apt=()
[ -x /usr/lib/llvm-22/bin/lit ] || need_apt+=(llvm-22-tools)
[ -x /usr/bin/FileCheck-22 ] || need_apt+=(llvm-22-tools)
[ -x /usr/lib/llvm-22/bin/llvm-config ] || need_apt+=(llvm-22-dev)
[ -e /usr/lib/llvm-22/lib/libPolly.a ] || need_apt+=(libpolly-22-dev)
dpkg -s zlib1g-dev >/dev/null 2>&1 || need_apt+=(zlib1g-dev)
dpkg -s libzstd-dev >/dev/null 2>&1 || need_apt+=(libzstd-dev)
command -v python3 >/dev/null || need_apt+=(python3)
# The C++ example's test (tests/tests/cpp_example.rs) builds examples/cpp with make and g++.
command -v g++ >/dev/null || need_apt+=(g++)
command -v make >/dev/null || need_apt+=(make)

if [ ${#need_apt[@]} -gt 0 ]; then
  pkgs=$(printf '%s\n' "${need_apt[@]}" | sort -u | tr '\n' ' ')
  echo "setup: installing ${pkgs}(Debian packages)" >&2
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -q >/dev/null
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q $pkgs >/dev/null
fi

if ! command -v cargo >/dev/null; then
  echo "setup: cargo not found; install the Rust toolchain (rustup) first" >&2
  exit 1
fi
echo "setup: ok ($(cargo --version), lit $(/usr/lib/llvm-22/bin/lit --version 2>&1 | head -1), LLVM $(/usr/lib/llvm-22/bin/llvm-config --version))" >&2
