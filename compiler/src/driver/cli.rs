//! Command-line interface of `scionc`: every flag of the planned compiler, documented in
//! `--help`. Flags whose stage is not built yet are accepted by the parser and rejected by
//! [`Options::check_implemented`] with a clear error (code E0901), never ignored silently.

use clap::{Parser, ValueEnum};
use std::path::PathBuf;

/// What `scionc` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Emit {
    /// The parsed program, printed back as canonical Scion source.
    Ast,
    /// The layout-agnostic `tree` dialect (after type checking and well-formedness).
    Tree,
    /// The `mem` dialect: traversals specialized to a layout (destructor specialization).
    Mem,
    /// The `lo` dialect: an SSA control-flow graph with loads and stores.
    Lo,
    /// Cranelift IR.
    Clif,
    /// LLVM IR (optimized at the -O level), for --target.
    Llvm,
    /// Assembly for --target (PTX for nvptx64).
    Asm,
    /// An ELF object file for --target (binary: needs -o when standard output is a terminal).
    Obj,
    /// PTX for NVIDIA GPUs (implies --target=nvptx64).
    Ptx,
    /// A C header for the generated entry points.
    Header,
    /// Upstream MLIR (func, arith, math, cf and llvm's pointers) from the `lo` module, for
    /// MLIR's tools (`mlir-opt` verifies it; docs/backends.md).
    Mlir,
    /// Nothing: check the input and report diagnostics only.
    Check,
}

impl Emit {
    /// True for the outputs made from the `lo` module (`lo`, `clif` and LLVM's).
    pub fn lowers_to_lo(self) -> bool {
        matches!(
            self,
            Emit::Lo | Emit::Clif | Emit::Mlir | Emit::Llvm | Emit::Asm | Emit::Obj | Emit::Ptx
        )
    }

    /// True for the outputs of the LLVM backend.
    pub fn is_llvm(self) -> bool {
        matches!(self, Emit::Llvm | Emit::Asm | Emit::Obj | Emit::Ptx)
    }

    /// The flag value as written.
    pub fn as_str(self) -> &'static str {
        match self {
            Emit::Ast => "ast",
            Emit::Tree => "tree",
            Emit::Mem => "mem",
            Emit::Lo => "lo",
            Emit::Clif => "clif",
            Emit::Llvm => "llvm",
            Emit::Asm => "asm",
            Emit::Obj => "obj",
            Emit::Ptx => "ptx",
            Emit::Header => "header",
            Emit::Mlir => "mlir",
            Emit::Check => "check",
        }
    }
}

/// Code generation targets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Target {
    /// x86-64 (System V).
    #[value(name = "x86_64")]
    X86_64,
    /// 64-bit ARM.
    Aarch64,
    /// NVIDIA GPUs through PTX.
    Nvptx64,
}

/// In-process execution engines.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RunEngine {
    /// The Cranelift JIT.
    Jit,
    /// The reference interpreter.
    Interp,
}

const AFTER_HELP: &str = "\
Inputs:
  The prelude (library/prelude.scion: Ray, AABB, Triangle, BVH and the geometric tests) is
  loaded first, then every FILE in order; all items share one namespace. A layout and its build
  usually sit in one file (library/layouts/pbrt.scion), an algorithm in another
  (library/algorithms/closest_hit.scion).

Examples:
  Print the tree IR of closest-hit, checked against the pbrt layout:
    scionc --emit=tree library/algorithms/closest_hit.scion library/layouts/pbrt.scion
  Only check a layout and report every diagnostic:
    scionc --emit=check library/layouts/ptr.scion
  Show the pass pipeline of -O2 without running it (the lowering to lo and the entry points
  are passes too, so --print-after-all, --stop-after and --time-passes see them):
    scionc -O2 --print-pipeline library/algorithms/closest_hit.scion
    scionc -O3 --emit=asm --layout LinearBVH --entry closest_hit --print-pipeline
  Compare -O3 with and without the DSL optimizations (mem-inline, const-fold, mem-cse, dce, ...):
    scionc -O3 --emit=mem --layout LinearBVH closest_hit.scion pbrt.scion
    scionc -O3 --no-dsl-opt --emit=mem --layout LinearBVH closest_hit.scion pbrt.scion
  Run one pass by name on tree IR and print every step:
    scionc --emit=tree --passes=const-fold,dce --print-after-all FILE.scion
  Compile closest-hit for pbrt to an AArch64 object with LLVM at -O3:
    scionc -O3 --emit=obj --target=aarch64 --layout=LinearBVH -o ch.o \
      library/algorithms/closest_hit.scion library/layouts/pbrt.scion
  The same as PTX for an sm_90 GPU (--cpu=sm_XX picks another):
    scionc -O3 --emit=ptx --layout=LinearBVH library/algorithms/closest_hit.scion \
      library/layouts/pbrt.scion
  Print the C header and the lo entry points of closest-hit over the pbrt layout:
    scionc --emit=header --layout LinearBVH --entry closest_hit \
      library/algorithms/closest_hit.scion library/layouts/pbrt.scion
    scionc --emit=lo --layout LinearBVH --entry closest_hit FILES...

Code generation:
  --emit=llvm|asm|obj|ptx go through LLVM 22: --target=x86_64|aarch64|nvptx64 (default: this
  machine; --emit=ptx sets nvptx64), --cpu=native|<llvm cpu>|sm_XX (default: the
  architecture's baseline, sm_90 on nvptx64), and -O0..-O3 also select LLVM's default<O0..O3>
  pipeline.

Exit status: 0 on success, 1 when the input has errors, 2 on a bad command line, 101 on an
internal compiler error (a bug: please report it with the input).

Not built yet (these say so with error E0901 instead of being ignored):
  --run.";

/// `scionc`: the Scion compiler.
///
/// Compiles tree traversals written against a logical BVH (an algebraic data type) to code
/// specialized for a physical layout (a `layout` spec) and its packer (a `build` spec).
#[derive(Debug, Parser)]
#[command(name = "scionc", version, after_help = AFTER_HELP)]
pub struct Options {
    /// Scion source files (.scion), compiled together after the prelude.
    #[arg(value_name = "FILE")]
    pub files: Vec<PathBuf>,

    /// What to produce.
    #[arg(long, value_enum, default_value = "tree", value_name = "KIND")]
    pub emit: Emit,

    /// Write the output here instead of standard output (`-o -` is standard output).
    #[arg(short = 'o', long, value_name = "PATH")]
    pub output: Option<PathBuf>,

    /// Optimization level 0-3: selects the pass pipeline (see --print-pipeline).
    #[arg(short = 'O', value_name = "LEVEL", default_value = "0",
          value_parser = clap::value_parser!(u8).range(0..=3))]
    pub opt_level: u8,

    /// Layout to specialize the traversals for (a `layout` name declared in the inputs).
    #[arg(long, value_name = "NAME")]
    pub layout: Option<String>,

    /// Add the exported C entry points of this algorithm (a function of the inputs taking the
    /// layout's tree) for `--layout`: `scion_L_sizes`, `scion_L_build`, `scion_L_root` and the
    /// batch query `scion_NAME_L` (docs/c-abi.md). Needs `--layout`.
    #[arg(long, value_name = "NAME")]
    pub entry: Option<String>,

    /// Code generation target of --emit=llvm|asm|obj|ptx (default: this machine); with
    /// `--entry`, `nvptx64` also adds the GPU kernels to `--emit=lo`.
    #[arg(long, value_enum, value_name = "TARGET")]
    pub target: Option<Target>,

    /// Target CPU: `native`, an LLVM CPU name, or `sm_XX` for NVPTX.
    #[arg(long, value_name = "CPU")]
    pub cpu: Option<String>,

    /// Run the compiled traversal in process instead of writing output.
    #[arg(long, value_enum, value_name = "ENGINE")]
    pub run: Option<RunEngine>,

    /// Entries of the traversal's fixed software stack (default 64; 512 for a traversal whose
    /// visits push all their calls: eight-wide, best first); overflow is reported.
    #[arg(long, value_name = "N")]
    pub stack_size: Option<u32>,

    /// Do not load the prelude.
    #[arg(long)]
    pub no_prelude: bool,

    /// Load this file as the prelude instead of the built-in library/prelude.scion.
    #[arg(long, value_name = "PATH", conflicts_with = "no_prelude")]
    pub prelude: Option<PathBuf>,

    /// Run exactly these passes (comma-separated names) instead of the -O pipeline.
    #[arg(long, value_name = "P1,P2,...", value_delimiter = ',')]
    pub passes: Option<Vec<String>>,

    /// Leave out the tree/mem (DSL) optimizations of the -O level: mem-inline, const-fold,
    /// mem-cse and dce. The specializations, lowering and backend optimizations stay.
    #[arg(long, conflicts_with = "passes")]
    pub no_dsl_opt: bool,

    /// Print the pass pipeline that would run, then stop.
    #[arg(long)]
    pub print_pipeline: bool,

    /// List every pass with a one-line summary, then stop.
    #[arg(long)]
    pub help_passes: bool,

    /// Print the IR after every pass (to standard error).
    #[arg(long)]
    pub print_after_all: bool,

    /// Print the IR before every pass (to standard error).
    #[arg(long)]
    pub print_before_all: bool,

    /// Stop the pipeline after the named pass and emit the IR at that point.
    #[arg(long, value_name = "PASS")]
    pub stop_after: Option<String>,

    /// Run the IR verifier after every pass (always on in debug builds).
    #[arg(long)]
    pub verify_each: bool,

    /// Print the time each pass took (to standard error).
    #[arg(long)]
    pub time_passes: bool,

    /// Stop after this many errors (0 = no limit).
    #[arg(long, value_name = "N", default_value = "50")]
    pub error_limit: usize,
}

/// A command-line request for a stage that does not exist yet.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NotImplemented {
    /// The flag as the user wrote it.
    pub flag: String,
    /// What will provide it.
    pub planned: &'static str,
}

impl Options {
    /// The output file, or `None` for standard output (no `-o`, or `-o -` as in cc and clang).
    pub fn output_path(&self) -> Option<&std::path::Path> {
        self.output.as_deref().filter(|p| p.as_os_str() != "-")
    }

    /// Rejects flags whose stage is not built yet, naming them.
    pub fn check_implemented(&self) -> Result<(), NotImplemented> {
        let emit_plan = match self.emit {
            Emit::Ast
            | Emit::Tree
            | Emit::Check
            | Emit::Mem
            | Emit::Lo
            | Emit::Clif
            | Emit::Llvm
            | Emit::Asm
            | Emit::Obj
            | Emit::Ptx
            | Emit::Mlir
            | Emit::Header => None,
        };
        if let Some(planned) = emit_plan {
            return Err(NotImplemented {
                flag: format!("--emit={}", self.emit.as_str()),
                planned,
            });
        }
        if self.run.is_some() {
            return Err(NotImplemented {
                flag: "--run".into(),
                planned: "the JIT and the interpreter",
            });
        }
        Ok(())
    }
}

/// Rejects `--target`/`--cpu` with an output that does not use them.
pub fn check_flags(opts: &Options) -> Result<(), scion_ir::diag::Diagnostic> {
    if opts.emit.is_llvm() || opts.emit == Emit::Header {
        return Ok(());
    }
    // With `--entry`, `--target=nvptx64` adds the GPU kernels to `--emit=lo`.
    if opts.emit == Emit::Lo && opts.entry.is_some() && opts.cpu.is_none() {
        return Ok(());
    }
    let flag = match (&opts.target, &opts.cpu) {
        (Some(_), _) => "--target",
        (None, Some(_)) => "--cpu",
        (None, None) => return Ok(()),
    };
    Err(scion_ir::diag::Diagnostic::error(
        "E0920",
        format!("`{flag}` has no effect on `--emit={}`", opts.emit.as_str()),
    )
    .with_note("it selects the machine code of --emit=llvm|asm|obj|ptx"))
}
