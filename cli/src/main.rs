//! `scion`: the command that runs Scion's traversals on scenes (issue 3 item 7, paper §9).
//!
//! `scion trace` loads an OBJ scene, builds its logical tree (binned SAH or median), generates
//! or reads rays, traces them with a backend (the runtime's Rust reference, the `tree`
//! interpreter over the logical tree, brute force, or the JIT of a layout), times the trace by
//! the paper's method, prints sizes and throughput on standard output and writes the hits file
//! (docs/formats.md). Progress goes to standard error. Failures (a missing scene, a NaN in an
//! OBJ file, an unwritable output, standard output closed) are `error:` lines and exit status
//! 1; a bad command line (clap's usage errors, an unknown layout or GPU architecture, `-o` onto
//! an input, too many threads) exits 2. Outputs are checked before the scene is loaded and
//! written whole or not at all (`io`).

mod args_study;
mod bar;
mod collide;
mod explore;
mod gpu;
mod io;
mod list;
mod memory;
mod plot;
mod quant_error;
mod render;
mod results;
mod run;
mod run_gpu;
mod strands;
mod trace;
mod trace_blocks;
mod tune;

pub use args_study::{ExploreArgs, RenderArgs, ShadingArg, TuneArgs, TuneEmit, TuneRays};
use clap::{Parser, Subcommand, ValueEnum};
use std::path::PathBuf;
use std::process::ExitCode;

/// Scion runs ray traversals compiled for a BVH layout on real scenes: it loads an OBJ scene
/// (a path, or a library scene's name such as `bunny`), builds its tree, packs it into the
/// layout, traces rays and reports sizes, times and hits, checked against the reference.
///
/// Exit status: 0 success, 1 a failure (files, scene, compilation, hits that differ), 2 a bad
/// command line.
#[derive(Parser, Debug)]
#[command(
    name = "scion",
    version,
    after_help = "Examples:\n  scion trace --scene bunny --backend llvm\n  scion trace --scene \
                  scenes/fzk_haus.obj.gz --layout pbrt-q16 --backend jit --rays secondary --stats\n  \
                  scion ptx --layout pbrt -o pbrt.ptx\n\nDocs: README.md, docs/runtime.md \
                  (scenes, rays, timing), docs/formats.md (files), docs/gpu.md."
)]
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
    /// Run any algorithm of a known query kind (closest hit, any hit, closest point, collision)
    /// compiled for a layout on a scene, timed by the paper's method and checked against its
    /// reference.
    Run(RunArgs),
    /// List the library's layouts (library/layouts/*.scion): the name --layout takes, the
    /// layout, the sum type it realizes, the closest hit compiled for it, how it stores boxes.
    Layouts(LayoutsArgs),
    /// Render a PNG of a scene through any layout and backend: one primary ray per pixel from
    /// the camera `scion trace` uses, each hit checked against the reference, shaded by the hit
    /// triangle's normal. Every layout that returns the reference's hits draws the same bytes.
    Render(RenderArgs),
    /// Sweep the design space: scenes × query kinds × query sets × sizes × devices and backends
    /// × every library layout with an entry of the kind, timed by the paper's method and
    /// checked, one CSV row per measurement (resumable: a rerun skips what the file has), then
    /// optionally Pareto plots of time against memory, with peer libraries as reference points
    /// (`--peers`), and of speed against error (`--plots DIR`, SVG and PNG).
    Explore(ExploreArgs),
    /// Choose the layout for one scene and query kind ("model only what a scene needs"): every
    /// candidate measured as `scion explore` does, the Pareto frontier of time against memory,
    /// the fastest (or the fastest within a memory budget, or the smallest within a slowdown),
    /// why, and optionally its compiled code (`--emit obj|ptx|header`).
    Tune(TuneArgs),
    /// Hair and fur (paper §8.2): generate a seeded strand scene as a `.hair` file, or trace a
    /// `.hair` scene through a layout over strand segments (`hair-bvh-strands`), timed and
    /// checked against the reference.
    Strands(strands::StrandsArgs),
}

/// The code generators of `scion run`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RunBackend {
    /// Cranelift.
    Jit,
    /// LLVM's JIT at -O3 for this machine's CPU.
    Llvm,
}

/// Arguments of `scion run`.
#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// What to run: a query kind (closest-hit, any-hit, closest-point, collide: the library's
    /// entry of that kind over the layout's tree type: closest_hit, occluded,
    /// closest_point_query, collide), a library function of a known kind
    /// (closest_point_best_first), or `PATH.scion[:FUNCTION]`. A collision runs the scene
    /// against its copy turned by --rotate.
    #[arg(long, value_name = "KIND|FUNCTION|PATH.scion")]
    pub algorithm: String,
    /// The scene: an OBJ file (plain or `.obj.gz`) or a library scene's name.
    #[arg(long, value_name = "PATH.obj|NAME")]
    pub scene: PathBuf,
    /// The layout: a library layout's name (scion layouts) or `PATH.scion[:NAME]`.
    #[arg(long, value_name = "NAME|PATH.scion")]
    pub layout: Option<String>,
    /// The code generator.
    #[arg(long, value_enum, default_value = "llvm")]
    pub backend: RunBackend,
    /// Read the queries from this file instead of generating them: rays (32-byte records) for
    /// hits, points (12-byte records: f32 x, y, z) for closest points (docs/formats.md).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["n", "seed", "rays"])]
    pub queries_file: Option<PathBuf>,
    /// How many queries to generate (points uniform in the scene's box, or rays).
    #[arg(long, default_value_t = 1 << 16, value_parser = clap::value_parser!(u64).range(1..=1 << 32))]
    pub n: u64,
    /// Seed of the query generator.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Which rays to generate for hit queries.
    #[arg(long, value_enum, default_value = "primary")]
    pub rays: RaysArg,
    /// Threads (0 = one per core; at most 8 per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Timed runs (9: the paper's method; 1: one run).
    #[arg(long, default_value_t = 9, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub runs: u32,
    /// Tree builder.
    #[arg(long, value_enum, default_value = "sah")]
    pub builder: BuilderArg,
    /// Largest leaf of the SAH and FCPW builders (1..=15; default 15 for sah, FCPW's 4 for
    /// fcpw; median leaves hold one triangle).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=15))]
    pub leaf_size: Option<u32>,
    /// Where to run: this CPU (with --backend and --threads), an NVIDIA GPU (the algorithm
    /// compiled to PTX, one thread per query, through CUDA) or the GPU's kernels emulated on
    /// this CPU. Every answer is checked against the reference either way. Collision runs on
    /// the CPU only.
    #[arg(long, value_enum, default_value = "cpu")]
    pub device: DeviceArg,
    /// Entries of the traversal's explicit stack (default 64, 512 for a traversal whose visits
    /// push all their calls such as the eight-wide ones; 1024 for a collision, whose
    /// stack holds pairs of subtrees).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1 << 20))]
    pub stack_size: Option<u32>,
    /// Collision: the copy of the scene the scene is tested against is turned by these angles
    /// in degrees about the x, y and z axes through the centre of its box (x first, then y,
    /// then z), as the paper's evaluation does.
    #[arg(long, value_name = "X,Y,Z", default_value = "60,70,10", value_parser = parse_angles)]
    pub rotate: [f64; 3],
    /// Write the result records here: 8 bytes per closest hit (f32 t, u32 id), 4 per any hit
    /// (u32, nonzero when occluded), 20 per closest point (f32 distance, u32 id, f32 x, y, z),
    /// 8 per colliding pair (u32 face id in the scene, u32 in the rotated copy; sorted).
    #[arg(short = 'o', long = "output", value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// Arguments of `scion layouts`.
#[derive(clap::Args, Debug)]
pub struct LayoutsArgs {
    /// Print only the names, one per line.
    #[arg(long)]
    pub names: bool,
    /// Only the layouts `scion trace --device gpu|gpu-emulated` runs: those over triangles
    /// (or blocks of four), each with its closest hit.
    #[arg(long)]
    pub gpu: bool,
    /// Only the layouts a PTX kit holds (`scion ptx`, `--emit-ptx`, `scion-gpu`): the prelude's
    /// `closest_hit` over `BVH`.
    #[arg(long)]
    pub kit: bool,
    /// Only the layouts whose leaves hold this primitive: `Triangle` (meshes, OBJ scenes) or
    /// `Segment` (strands, `.hair` scenes).
    #[arg(long, value_name = "TYPE")]
    pub primitive: Option<String>,
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
    /// Entries of the generated traversal's explicit stack (default 64; 512 for a traversal whose
    /// visits push all their calls, such as the eight-wide ones).
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

impl RaysArg {
    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            RaysArg::Primary => "primary",
            RaysArg::Secondary => "secondary",
            RaysArg::Axis => "axis",
        }
    }
}

/// Tree builders.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum BuilderArg {
    /// Binned SAH (32 bins), leaves of up to `--leaf-size` triangles, then insertion-based
    /// optimization of the tree (Bittner et al. 2013), then leaves collapsed where one leaf
    /// tested four triangles at a time costs less than its subtree (docs/runtime.md).
    Sah,
    /// Median split of the longest axis, one triangle per leaf.
    Median,
    /// FCPW's builder (the paper's closest-point comparison, §9.3.2): binned surface area over
    /// 8 slices of each node's box, leaves of up to `--leaf-size` triangles (default 4), no
    /// leaf cost and no reinsertion (docs/runtime.md).
    Fcpw,
}

impl BuilderArg {
    /// The largest leaf this builder makes with `--leaf-size` (median: 1). FCPW's builder
    /// also makes a larger leaf at its depth limit (62), which no library scene reaches.
    pub fn leaf_size(self, leaf_size: Option<u32>) -> usize {
        match self {
            BuilderArg::Sah => leaf_size.unwrap_or(15) as usize,
            BuilderArg::Fcpw => leaf_size.unwrap_or(4) as usize,
            BuilderArg::Median => 1,
        }
    }

    /// How the tree was built, for reports.
    pub fn describe(self, leaf_size: Option<u32>) -> String {
        let n = self.leaf_size(leaf_size);
        match self {
            BuilderArg::Sah => format!(
                "binned SAH + reinsertion + leaves collapsed for runs of four, leaves <= {n}"
            ),
            BuilderArg::Fcpw => format!("FCPW's binned surface area, leaves <= {n}"),
            BuilderArg::Median => "median, one triangle per leaf".to_string(),
        }
    }
}

/// Arguments of `scion trace`.
#[derive(clap::Args, Debug)]
pub struct TraceArgs {
    /// The scene: an OBJ file (plain or gzip-compressed, `.obj.gz`), or the name of a scene of
    /// the repository's scenes/ folder (teapot, pine, suzanne, balloon, fzk_haus,
    /// sponza_dabrovic, bunny, engine, cruiser_cg57, dragon).
    #[arg(long, value_name = "PATH.obj|NAME")]
    pub scene: PathBuf,
    /// The layout for `--backend jit|llvm|mem-interp`: a library layout's name (a file of
    /// library/layouts with `-` for `_`, e.g. pbrt, pbrt-q16, sg-eq, bvh8, bvh8-q8-ci,
    /// dop14-split, hair-bvh; `scion layouts` lists them all; default pbrt), or any layout file,
    /// `PATH.scion` (`PATH.scion:NAME` when it declares several). `--backend jit|llvm` take
    /// either; mem-interp the library's binary closest-hit layouts; the GPU (`--device`) any
    /// layout over triangles, a PTX kit (`--ptx`, `--emit-ptx`) the binary ones. A layout whose
    /// leaves hold blocks of four triangles (`Triangle4`: bvh8-tri4) traces a tree over blocks:
    /// the binned SAH counting a block as one test, leaves of at most 8 triangles (two blocks;
    /// `--leaf-size`), each leaf's triangles cut into fours. Layout-free backends trace the
    /// logical tree and ignore it.
    #[arg(long, value_name = "NAME|PATH.scion")]
    pub layout: Option<String>,
    /// The closest hit to compile for the layout (`--backend jit|llvm`): a library algorithm
    /// (a file stem of library/algorithms, e.g. closest_hit, or a closest-hit function's name)
    /// or a file, `PATH.scion[:FUNCTION]`. Default: the library's closest hit over the sum type
    /// the layout realizes (closest_hit for BVH, closest_hit8 for BVH8, closest_hit_dop14,
    /// closest_hit_hair).
    #[arg(long, value_name = "NAME|PATH.scion")]
    pub algorithm: Option<String>,
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
    /// Threads (0 = one per core; at most 8 per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Write the hits here (docs/formats.md).
    #[arg(short = 'o', long = "output", value_name = "HITS.bin")]
    pub output: Option<PathBuf>,
    /// Tree builder.
    #[arg(long, value_enum, default_value = "sah")]
    pub builder: BuilderArg,
    /// Largest leaf of the SAH and FCPW builders (1..=15; default 15 for sah, FCPW's 4 for
    /// fcpw; median leaves hold one triangle).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=15))]
    pub leaf_size: Option<u32>,
    /// Timed runs: 9 is the paper's method (1 warm-up, 9 runs, mean of the middle 5); 1 is a
    /// single untimed-warm-up run for quick use; other counts drop (runs - 1) / 4 at each end.
    #[arg(long, default_value_t = 9, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub runs: u32,
    /// Entries of the generated traversal's explicit stack (`--backend jit|llvm`, `--device
    /// gpu|gpu-emulated`; the compiler's `recursion-to-stack:stack-size`, default 64, or 512
    /// where visits push all their calls). A tree too deep for it is an error naming the first
    /// ray that overflowed (on the GPU, the kernel's overflow status).
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
    /// (scionc --no-dsl-opt: mem-inline, const-fold, mem-cse, dce, mem-split-loads, mem-sink), to measure what they gain.
    #[arg(long)]
    pub no_dsl_opt: bool,
    /// Also report the traversal's work per ray: box tests, nodes visited, nodes skipped
    /// because a nearer hit was found first, triangle tests, and the deepest traversal stack.
    /// Counted by the reference traversal of the tree the layout traverses (its decoded boxes
    /// for a quantized layout), which visits the same nodes in the same order as generated
    /// code (the test suite checks the generated program's own counts against it).
    #[arg(long)]
    pub stats: bool,
    /// Do not compare the hits of generated code (`--backend jit|llvm`) with the reference
    /// traversal of the tree the layout traverses (its decoded boxes when quantized; the
    /// eight-wide reference for eight-wide layouts), which `scion trace` does by default.
    #[arg(long)]
    pub no_check: bool,
}

fn main() -> ExitCode {
    let mut cli = Cli::parse();
    let result = match &mut cli.command {
        Command::Trace(args) => preflight(args).and_then(|()| trace::run(args)),
        Command::Layouts(args) => list::run(args),
        Command::Render(args) => preflight_render(args).and_then(|()| render::run(args)),
        Command::Explore(args) => io::check_threads(args.threads).and_then(|()| explore::run(args)),
        Command::Tune(args) => preflight_tune(args).and_then(|()| tune::run(args)),
        Command::Strands(args) => strands::run(args),
        Command::Run(args) => preflight_run(args).and_then(|()| run::run(args)),
        Command::Ptx(args) => check_gpu_cpu(args.cpu.as_deref())
            .and_then(|()| io::check_output("-o", &args.output, &[]))
            .and_then(|()| gpu::run_ptx(args)),
    }
    .and_then(|()| io::finish_stdout());
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", e.message);
            for note in &e.notes {
                eprintln!("  note: {note}");
            }
            ExitCode::from(if e.usage { 2 } else { 1 })
        }
    }
}

/// A `--cpu` for the GPU that LLVM does not know is a bad command line.
fn check_gpu_cpu(cpu: Option<&str>) -> Result<(), CliError> {
    match cpu {
        Some(cpu) => scion_llvm::target::validate_cpu(scion_llvm::Target::Nvptx64, cpu)
            .map_err(|e| CliError::usage(format!("--cpu {cpu}: {}", e.0))),
        None => Ok(()),
    }
}

/// `--rotate X,Y,Z`: three finite angles in degrees.
fn parse_angles(s: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let [x, y, z] = parts[..] else {
        return Err(format!(
            "`{s}`: expected three angles in degrees, as 60,70,10"
        ));
    };
    let angle = |a: &str| match a.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("`{a}` is not a finite angle in degrees")),
    };
    Ok([angle(x)?, angle(y)?, angle(z)?])
}

/// What `scion run` checks before the long work: the scene, the threads, the output.
fn preflight_run(args: &mut RunArgs) -> Result<(), CliError> {
    args.scene = scion_runtime::scene::manifest::resolve(&args.scene)
        .map_err(|e| CliError::new(format!("--scene {}: {e}", args.scene.display())))?;
    io::check_threads(args.threads)?;
    let mut inputs: Vec<(&str, &std::path::Path)> = vec![("--scene", &args.scene)];
    if let Some(q) = &args.queries_file {
        inputs.push(("--queries-file", q));
    }
    if let Some(out) = &args.output {
        io::check_output("-o", out, &inputs)?;
    }
    // Queries (at most a ray's 32 bytes), results (at most 20) and the reference's answers.
    let n = match &args.queries_file {
        Some(path) => std::fs::metadata(path).map_or(0, |m| m.len() / 12),
        None => args.n,
    };
    io::check_memory(&format!("{n} queries and their answers"), n * (32 + 2 * 20))
}

/// What `scion tune` checks first: the scene (resolved to a path), the threads, the output.
fn preflight_tune(args: &mut TuneArgs) -> Result<(), CliError> {
    args.scene = scion_runtime::scene::manifest::resolve(&args.scene)
        .map_err(|e| CliError::new(format!("--scene {}: {e}", args.scene.display())))?;
    io::check_threads(args.threads)?;
    if let Some(out) = &args.output {
        io::check_output("-o", out, &[("--scene", &args.scene)])?;
    }
    Ok(())
}

/// What `scion render` checks before the long work: the scene (a path or a library scene's
/// name), the threads, the image (not the scene, writable), the memory of its rays and hits.
fn preflight_render(args: &mut RenderArgs) -> Result<(), CliError> {
    args.scene = scion_runtime::scene::manifest::resolve(&args.scene)
        .map_err(|e| CliError::new(format!("--scene {}: {e}", args.scene.display())))?;
    io::check_threads(args.threads)?;
    io::check_output("-o", &args.output, &[("--scene", &args.scene)])?;
    let n = u64::from(args.width) * u64::from(args.height);
    io::check_memory(&format!("{n} pixels' rays and hits"), n * (32 + 8 + 3))
}

/// What `scion trace` checks before the long work: the scene (a path or a library scene's
/// name, resolved here), the threads, the outputs (not an input, writable), and the memory
/// the rays and hits need.
fn preflight(args: &mut TraceArgs) -> Result<(), CliError> {
    args.scene = scion_runtime::scene::manifest::resolve(&args.scene)
        .map_err(|e| CliError::new(format!("--scene {}: {e}", args.scene.display())))?;
    io::check_threads(args.threads)?;
    if args.device == DeviceArg::Gpu {
        check_gpu_cpu(args.cpu.as_deref())?;
    }
    let mut inputs: Vec<(&str, &std::path::Path)> = vec![("--scene", &args.scene)];
    if let Some(rays) = &args.rays_file {
        inputs.push(("--rays-file", rays));
    }
    if let Some(ptx) = &args.ptx {
        inputs.push(("--ptx", ptx));
    }
    for (flag, out) in [("-o", &args.output), ("--emit-ptx", &args.emit_ptx)] {
        if let Some(out) = out {
            io::check_output(flag, out, &inputs)?;
        }
    }
    if let (Some(o), Some(e)) = (&args.output, &args.emit_ptx) {
        if o == e {
            return Err(CliError::usage("-o and --emit-ptx name the same file"));
        }
    }
    // The rays, the hits of the checked trace, of a timed run and of the reference.
    let per_ray = std::mem::size_of::<scion_runtime::geom::Ray>() as u64
        + 3 * std::mem::size_of::<scion_runtime::geom::Hit>() as u64;
    let rays = match &args.rays_file {
        Some(path) => std::fs::metadata(path).map_or(0, |m| m.len() / 32),
        None => args.n,
    };
    io::check_memory(&format!("{rays} rays and their hits"), rays * per_ray)
}

/// A user-facing failure: one message and optional notes.
#[derive(Debug)]
pub struct CliError {
    /// What went wrong.
    pub message: String,
    /// What to do about it.
    pub notes: Vec<String>,
    /// A bad command line (exit status 2) rather than a failure (1).
    pub usage: bool,
}

impl CliError {
    /// A failure without notes (exit status 1).
    pub fn new(message: impl Into<String>) -> CliError {
        CliError {
            message: message.into(),
            notes: Vec::new(),
            usage: false,
        }
    }

    /// A bad command line (exit status 2).
    pub fn usage(message: impl Into<String>) -> CliError {
        CliError {
            usage: true,
            ..CliError::new(message)
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
