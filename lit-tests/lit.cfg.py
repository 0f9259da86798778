# lit configuration for Scion's FileCheck tests.
#
# Run through cargo (compiler/tests/lit.rs passes the tool paths), or by hand:
#   /usr/lib/llvm-22/bin/lit -v lit-tests --param scionc=target/release/scionc
import os
import lit.formats

config.name = "scion"
config.test_format = lit.formats.ShTest(execute_external=True)
config.suffixes = [".scion", ".tree", ".mem", ".lo"]
config.excludes = ["Inputs", "lit.cfg.py"]
config.test_source_root = os.path.dirname(__file__)
config.test_exec_root = os.path.join(config.test_source_root, "Output")

repo = os.path.dirname(config.test_source_root)
llvm_bin = lit_config.params.get("llvm_bin", "/usr/lib/llvm-22/bin")


def tool(name, default):
    path = lit_config.params.get(name, default)
    if not os.path.exists(path):
        lit_config.fatal(f"{name} not found at {path}: build it (cargo build --release) or pass --param {name}=PATH")
    return path


scionc = tool("scionc", os.path.join(repo, "target", "release", "scionc"))
filecheck = lit_config.params.get("filecheck", "/usr/bin/FileCheck-22")
if not os.path.exists(filecheck):
    filecheck = os.path.join(llvm_bin, "FileCheck")

config.substitutions.append(("%scionc", scionc))
config.substitutions.append(("%library", os.path.join(repo, "library")))
config.substitutions.append(("FileCheck", filecheck + " --enable-var-scope"))
scion_opt = lit_config.params.get("scion_opt", os.path.join(repo, "target", "release", "scion-opt"))
config.substitutions.append(("%scion-opt", scion_opt))

# MLIR's tools (Debian's mlir-22-tools, which scripts/setup.sh installs): the tests of
# --emit=mlir say `REQUIRES: mlir-opt`.
mlir_opt = os.path.join(llvm_bin, "mlir-opt")
if os.access(mlir_opt, os.X_OK):
    config.available_features.add("mlir-opt")
    config.substitutions.append(("%mlir-opt", mlir_opt))
    config.substitutions.append(("%mlir-translate", os.path.join(llvm_bin, "mlir-translate")))
    config.substitutions.append(("%lli", os.path.join(llvm_bin, "lli")))
else:
    lit_config.note("mlir-opt not found: the --emit=mlir tests are UNSUPPORTED (scripts/setup.sh installs mlir-22-tools)")

# `not` and `count` come from LLVM's tools.
config.environment["PATH"] = os.pathsep.join([llvm_bin, config.environment.get("PATH", os.environ.get("PATH", ""))])
config.environment["NO_COLOR"] = "1"

# NVIDIA's PTX assembler, looked for where scripts/setup.sh (which installs it) and
# scion_cuda::ptxas look: --param ptxas, $SCION_PTXAS, PATH, /usr/local/cuda/bin, then the copy
# setup.sh puts in ~/.cache/scion. Tests that assemble PTX say `REQUIRES: ptxas`; without it
# they are UNSUPPORTED, not passed.
import shutil

ptxas_candidates = [
    lit_config.params.get("ptxas"),
    os.environ.get("SCION_PTXAS"),
    shutil.which("ptxas"),
    "/usr/local/cuda/bin/ptxas",
    os.path.expanduser("~/.cache/scion/cuda-13.5.37/bin/ptxas"),
]
ptxas = next((p for p in ptxas_candidates if p and os.access(p, os.X_OK)), None)
if ptxas:
    config.available_features.add("ptxas")
    config.substitutions.append(("%ptxas", ptxas))
else:
    lit_config.note("ptxas not found: the tests that assemble PTX are UNSUPPORTED (scripts/setup.sh installs it)")
