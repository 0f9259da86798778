//! `scion`: the command that runs Scion's traversals on scenes (issue 3 item 7, paper §9).
//!
//! `scion trace` loads an OBJ scene, builds its logical tree (binned SAH or median), generates
//! or reads rays, traces them with a backend (the runtime's Rust reference, the `tree`
//! interpreter over the logical tree, brute force, or the JIT of a layout), times the trace by
//! the paper's method, prints sizes and throughput on standard output and writes the hits file
//! (docs/formats.md). Progress goes to standard error. User errors (a missing scene, a NaN in an
//! OBJ file, a bad flag) are `error:` lines and exit status 1; clap's usage errors exit 2.

mod gpu;
mod trace;

use clap::{Parser, Subcommand, ValueEnum};
use std::path::PathBuf;
use std::process::ExitCode;

/// Scion: layout-specialized tree traversals.
#[derive(Parser, Debug)]
#[command(name = "scion", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Trace closest-hit rays through a scene and report sizes, times and hits.
    Trace(TraceArgs),
    /// Compile closest hit for a layout to PTX for NVIDIA GPUs (a "PTX kit": the PTX with
    /// comment lines naming the layout and its buffers), to run with `scion trace --device gpu
    /// --ptx` or `scion-gpu` (docs/gpu.md).
    Ptx(PtxArgs),
}

/// Where `scion trace` runs the traversal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum DeviceArg {
    /// This machine's CPU, with `--backend`.
    Cpu,
    /// An NVIDIA GPU: closest hit for `--layout` compiled to PTX by LLVM and run through CUDA,
    /// each hit compared with the reference (`--backend` is not used).
    Gpu,
    /// The GPU path without a GPU: the same kernels (closest hit for `--layout` with the GPU
    /// entry points) compiled for this CPU by LLVM, launched as grids of host threads and
    /// driven by the same packing and tracing code, each hit compared with the reference.
    /// Checks the kernels and the launch protocol, not NVPTX code generation.
    GpuEmulated,
}

/// Arguments of `scion ptx`.
#[derive(clap::Args, Debug)]
pub struct PtxArgs {
    /// The layout (a name from library/layouts: pbrt, ptr, ...).
    #[arg(long, default_value = "pbrt")]
    pub layout: String,
    /// Where to write the PTX kit.
    #[arg(short = 'o', long = "output", value_name = "KIT.ptx")]
    pub output: PathBuf,
    /// The GPU architecture (`sm_XX`; default sm_90).
    #[arg(long, value_name = "sm_XX")]
    pub cpu: Option<String>,
    /// Entries of the generated traversal's explicit stack (default 64).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1 << 20))]
    pub stack_size: Option<u32>,
}

/// The backends of `scion trace`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BackendArg {
    /// The runtime's Rust traversal of the logical tree (the prelude's arithmetic).
    Reference,
    /// The `tree` interpreter running library/algorithms/closest_hit.scion (slow; an oracle).
    Interp,
    /// Every triangle against every ray, no tree.
    Brute,
    /// Closest hit specialized to `--layout` (destructor and constructor specialization),
    /// packed by its generated `@L.build` and run by the interpreter at the mem level (slow; a
    /// check of specialization without the JIT).
    MemInterp,
    /// Generated code for `--layout`, compiled by Cranelift.
    Jit,
    /// Generated code for `--layout`, compiled by LLVM's JIT at -O3 for this machine's CPU.
    Llvm,
}

/// Ray generators.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RaysArg {
    /// A pinhole camera looking at the scene, one jittered ray per pixel.
    Primary,
    /// Origins uniform in the scene's box, directions uniform on the sphere.
    Secondary,
    /// Origins in the box, axis-parallel directions with signed-zero lanes.
    Axis,
}

/// Tree builders.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BuilderArg {
    /// Binned SAH (32 bins), leaves of up to `--leaf-size` triangles, then insertion-based
    /// optimization of the tree (Bittner et al. 2013; docs/runtime.md).
    Sah,
    /// Median split of the longest axis, one triangle per leaf.
    Median,
}

/// Arguments of `scion trace`.
#[derive(clap::Args, Debug)]
pub struct TraceArgs {
    /// The scene: an OBJ file.
    #[arg(long, value_name = "PATH.obj")]
    pub scene: PathBuf,
    /// The layout for `--backend jit|llvm|mem-interp` (a name from library/layouts, e.g. pbrt,
    /// ptr, pbrt-align16, pbrt-soaos, pbrt-q16, sg-eq; default pbrt). Layout-free
    /// backends trace the logical tree and ignore it.
    #[arg(long)]
    pub layout: Option<String>,
    /// Which rays to generate (ignored with --rays-file).
    #[arg(long, value_enum, default_value = "primary")]
    pub rays: RaysArg,
    /// How many rays to generate.
    #[arg(long, default_value_t = 1 << 16, value_parser = clap::value_parser!(u64).range(1..=1 << 32))]
    pub n: u64,
    /// Seed of the ray generator.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Read the rays from this file (docs/formats.md) instead of generating them.
    #[arg(long, value_name = "RAYS.bin", conflicts_with_all = ["rays", "n", "seed"])]
    pub rays_file: Option<PathBuf>,
    /// How to trace.
    #[arg(long, value_enum, default_value = "reference")]
    pub backend: BackendArg,
    /// Threads (0 = one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Write the hits here (docs/formats.md).
    #[arg(short = 'o', long = "output", value_name = "HITS.bin")]
    pub output: Option<PathBuf>,
    /// Tree builder.
    #[arg(long, value_enum, default_value = "sah")]
    pub builder: BuilderArg,
    /// Largest leaf of the SAH builder (1..=15).
    #[arg(long, default_value_t = 15, value_parser = clap::value_parser!(u32).range(1..=15))]
    pub leaf_size: u32,
    /// Timed runs: 9 is the paper's method (1 warm-up, 9 runs, mean of the middle 5); 1 is a
    /// single untimed-warm-up run for quick use; other counts drop (runs - 1) / 4 at each end.
    #[arg(long, default_value_t = 9, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub runs: u32,
    /// Entries of the generated traversal's explicit stack (`--backend jit|llvm`, `--device
    /// gpu|gpu-emulated`; the compiler's `recursion-to-stack:stack-size`, default 64). A tree
    /// too deep for it is an error naming the first ray that overflowed (on the GPU, the
    /// kernel's overflow status).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1 << 20))]
    pub stack_size: Option<u32>,
    /// Where to trace: the CPU (`--backend`), an NVIDIA GPU (`--layout` compiled to PTX,
    /// checked against the reference), or the GPU's kernels emulated on the CPU.
    #[arg(long, value_enum, default_value = "cpu")]
    pub device: DeviceArg,
    /// The CUDA device ordinal for `--device gpu`.
    #[arg(long, default_value_t = 0, value_name = "N")]
    pub gpu: i32,
    /// `--device gpu`: run this PTX kit (from `scion ptx` or `--emit-ptx`) instead of compiling.
    #[arg(long, value_name = "KIT.ptx")]
    pub ptx: Option<PathBuf>,
    /// `--device gpu`: also write the PTX kit that runs to this file.
    #[arg(long, value_name = "KIT.ptx")]
    pub emit_ptx: Option<PathBuf>,
    /// `--device gpu`: the GPU architecture to compile for (`sm_XX`; default: the device's own,
    /// e.g. sm_90 on an H100 or H200).
    #[arg(long, value_name = "sm_XX")]
    pub cpu: Option<String>,
    /// The compiler's tree/mem -O level for `--backend jit|llvm` (scionc -O0..-O3; default 3;
    /// LLVM's own pipeline stays at -O3).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u8).range(0..=3))]
    pub opt_level: u8,
    /// `--backend jit|llvm`: leave out the tree/mem (DSL) optimizations of the -O level
    /// (scionc --no-dsl-opt: mem-inline, const-fold, mem-cse, dce), to measure what they gain.
    #[arg(long)]
    pub no_dsl_opt: bool,
    /// Also report the traversal's work per ray: box tests, nodes visited, nodes skipped
    /// because a nearer hit was found first, triangle tests, and the deepest traversal stack.
    /// Counted by the reference traversal of the tree the layout traverses (its decoded boxes
    /// for a quantized layout), which visits the same nodes in the same order as generated
    /// code (the test suite checks the generated program's own counts against it).
    #[arg(long)]
    pub stats: bool,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Trace(args) => trace::run(args),
        Command::Ptx(args) => gpu::run_ptx(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", e.message);
            for note in &e.notes {
                eprintln!("  note: {note}");
            }
            ExitCode::from(1)
        }
    }
}

/// A user-facing failure: one message and optional notes.
#[derive(Debug)]
pub struct CliError {
    /// What went wrong.
    pub message: String,
    /// What to do about it.
    pub notes: Vec<String>,
}

impl CliError {
    /// An error without notes.
    pub fn new(message: impl Into<String>) -> CliError {
        CliError {
            message: message.into(),
            notes: Vec::new(),
        }
    }

    /// Adds a note.
    pub fn note(mut self, n: impl Into<String>) -> CliError {
        self.notes.push(n.into());
        self
    }
}

impl From<String> for CliError {
    fn from(message: String) -> CliError {
        CliError::new(message)
    }
}
