#!/usr/bin/env bash
# Installs what Scion needs on a fresh Debian 12 machine when it is missing, and prints what it
# found. Safe to run again: it installs nothing that is already there.
#   - LLVM 22 tools (lit, FileCheck, not, llvm-objdump) from Debian: the lit test suite runs on
#     them.
#   - LLVM 22 development files (llvm-config, libLLVM, and the Polly, zlib and zstd libraries
#     llvm-config names): the LLVM backend (compiler/backend-llvm, through inkwell/llvm-sys)
#     links against them; .cargo/config.toml points llvm-sys at /usr/lib/llvm-22.
#   - MLIR 22's tools (mlir-opt, mlir-translate; Debian's mlir-22-tools): the tests of
#     `scionc --emit=mlir` give its output to MLIR's verifier and lower it to LLVM IR.
#   - g++ and make: the test suite builds and runs the C++ example (examples/cpp).
#   - On x86-64: the AArch64 cross C compiler (gcc-aarch64-linux-gnu, libc6-dev-arm64-cross)
#     and qemu-user: the test suite runs the AArch64 code scionc emits under qemu.
#   - NVIDIA's PTX assembler `ptxas` (CUDA 13.5, from the Python package registry's
#     nvidia-cuda-nvcc wheel, only the one binary, into ~/.cache/scion): the lit suite assembles
#     the emitted PTX for sm_75..sm_90 with it, so PTX is checked on machines without a GPU.
#     A ptxas already on PATH, in /usr/local/cuda/bin or named by $SCION_PTXAS is used instead.
#   - The Rust toolchain is expected on the machine (cargo, rustc); we do not install it.
set -euo pipefail

need_apt=()
[ -x /usr/lib/llvm-22/bin/lit ] || need_apt+=(llvm-22-tools)
[ -x /usr/bin/FileCheck-22 ] || need_apt+=(llvm-22-tools)
[ -x /usr/lib/llvm-22/bin/llvm-config ] || need_apt+=(llvm-22-dev)
[ -x /usr/lib/llvm-22/bin/mlir-opt ] || need_apt+=(mlir-22-tools)
[ -e /usr/lib/llvm-22/lib/libPolly.a ] || need_apt+=(libpolly-22-dev)
dpkg -s zlib1g-dev >/dev/null 2>&1 || need_apt+=(zlib1g-dev)
dpkg -s libzstd-dev >/dev/null 2>&1 || need_apt+=(libzstd-dev)
command -v python3 >/dev/null || need_apt+=(python3)
# The C++ example's test (tests/tests/cpp_example.rs) builds examples/cpp with make and g++.
command -v g++ >/dev/null || need_apt+=(g++)
command -v make >/dev/null || need_apt+=(make)
# The peers benchmark (bench/benches/peers/embree_peer.rs) links Embree 3, Debian's libembree3.
[ -e /usr/include/embree3/rtcore.h ] || need_apt+=(libembree-dev)
# ptxas: the same places lit-tests/lit.cfg.py and scion_cuda::ptxas::find look in. It comes
# from the Python package registry through pip (Debian's python3 may lack pip: python3-pip).
PTXAS_VERSION=13.5.37
ptxas_cache="${HOME}/.cache/scion/cuda-${PTXAS_VERSION}/bin/ptxas"
find_ptxas() {
  local p
  for p in "${SCION_PTXAS:-}" "$(command -v ptxas || true)" /usr/local/cuda/bin/ptxas "$ptxas_cache"; do
    if [ -n "$p" ] && [ -x "$p" ]; then echo "$p"; return; fi
  done
}
if [ -z "$(find_ptxas)" ] && ! python3 -m pip --version >/dev/null 2>&1; then need_apt+=(python3-pip); fi
# AArch64 code is run, not only disassembled (tests/tests/aarch64_qemu.rs): a cross C compiler
# with the arm64 C library links it with tests/replay/replay.c, and qemu-user runs it.
# (Installed without recommends: qemu-user's would register binfmt handlers on the machine.)
need_cross=()
if [ "$(uname -m)" = x86_64 ]; then
  command -v aarch64-linux-gnu-gcc >/dev/null || need_cross+=(gcc-aarch64-linux-gnu)
  dpkg -s libc6-dev-arm64-cross >/dev/null 2>&1 || need_cross+=(libc6-dev-arm64-cross)
  command -v qemu-aarch64 >/dev/null || need_cross+=(qemu-user)
fi

if [ ${#need_apt[@]} -gt 0 ] || [ ${#need_cross[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -q >/dev/null
fi
if [ ${#need_apt[@]} -gt 0 ]; then
  pkgs=$(printf '%s\n' "${need_apt[@]}" | sort -u | tr '\n' ' ')
  echo "setup: installing ${pkgs}(Debian packages)" >&2
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q $pkgs >/dev/null
fi
if [ ${#need_cross[@]} -gt 0 ]; then
  echo "setup: installing ${need_cross[*]} (Debian packages, without recommends)" >&2
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${need_cross[@]}" >/dev/null
fi

if ! command -v cargo >/dev/null; then
  echo "setup: cargo not found; install the Rust toolchain (rustup) first" >&2
  exit 1
fi
ptxas=$(find_ptxas)
if [ -z "$ptxas" ]; then
  echo "setup: installing ptxas ${PTXAS_VERSION} (nvidia-cuda-nvcc wheel, Python package registry) into ${ptxas_cache%/bin/ptxas}" >&2
  tmp=$(mktemp -d)
  if python3 -m pip download -q --no-deps --only-binary=:all: -d "$tmp" "nvidia-cuda-nvcc==${PTXAS_VERSION}" >&2 &&
     python3 - "$tmp" "$ptxas_cache" <<'PY'
import glob, os, sys, zipfile
tmp, dest = sys.argv[1], sys.argv[2]
wheel = glob.glob(os.path.join(tmp, "*.whl"))[0]
with zipfile.ZipFile(wheel) as z:
    name = next(n for n in z.namelist() if n.endswith("/bin/ptxas"))
    os.makedirs(os.path.dirname(dest), exist_ok=True)
    with z.open(name) as src, open(dest + ".part", "wb") as out:
        out.write(src.read())
os.chmod(dest + ".part", 0o755)
os.replace(dest + ".part", dest)
PY
  then
    ptxas=$ptxas_cache
  else
    echo "setup: WARNING: could not install ptxas; the lit tests that assemble PTX will be UNSUPPORTED" >&2
  fi
  rm -rf "$tmp"
fi
[ -n "$ptxas" ] && ptxas_note=", ptxas $("$ptxas" --version | sed -n 's/.*release \([0-9.]*\).*/\1/p')" || ptxas_note=", no ptxas"

echo "setup: ok ($(cargo --version), lit $(/usr/lib/llvm-22/bin/lit --version 2>&1 | head -1), LLVM $(/usr/lib/llvm-22/bin/llvm-config --version)${ptxas_note})" >&2
