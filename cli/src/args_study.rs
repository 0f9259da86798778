//! The arguments of the commands that study the design space: `scion render` (pictures),
//! `scion explore` (sweeps and plots) and `scion tune` (a layout chosen for a scene).

use crate::{BuilderArg, DeviceArg, RunBackend};
use clap::ValueEnum;
use std::path::PathBuf;

/// What `scion tune` writes for its choice.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum TuneEmit {
    /// A host object file with the entries (x86-64 or AArch64, LLVM -O3).
    Obj,
    /// A PTX kit for `scion trace --device gpu --ptx` and `scion-gpu`.
    Ptx,
    /// The C header of the entries.
    Header,
}

/// Arguments of `scion tune`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  scion tune --scene bunny --algorithm closest-hit\n  scion tune \
                        --scene fzk_haus --algorithm closest-point --max-bytes-per-triangle 40 \
                        --emit obj -o chosen.o"
)]
pub struct TuneArgs {
    /// The scene (a path or a library scene's name).
    #[arg(long, value_name = "PATH.obj|NAME")]
    pub scene: PathBuf,
    /// The query kind: closest-hit, any-hit or closest-point.
    #[arg(long, default_value = "closest-hit")]
    pub algorithm: String,
    /// The rays of a hit kind.
    #[arg(long, value_enum, default_value = "primary")]
    pub rays: TuneRays,
    /// Queries per measurement (`N` or `2^K`).
    #[arg(long, default_value = "65536", value_parser = parse_size)]
    pub n: usize,
    /// The code generator.
    #[arg(long, value_enum, default_value = "llvm")]
    pub backend: RunBackend,
    /// Where the layouts are measured: cpu (with --backend), gpu (an NVIDIA GPU through CUDA),
    /// gpu-emulated (the GPU kernels on this CPU).
    #[arg(long, value_enum, default_value = "cpu")]
    pub device: DeviceArg,
    /// Threads (0: one per core).
    #[arg(long, default_value_t = 1)]
    pub threads: usize,
    /// Timed runs per layout (9: the paper's method).
    #[arg(long, default_value_t = 9, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub runs: u32,
    /// Candidates, comma-separated (default: every library layout with an entry of the kind).
    #[arg(long, value_delimiter = ',')]
    pub layouts: Option<Vec<String>>,
    /// Choose the fastest layout within this many bytes per triangle.
    #[arg(long, value_name = "B")]
    pub max_bytes_per_triangle: Option<f64>,
    /// Choose the smallest layout within this factor of the fastest's time (e.g. 1.1).
    #[arg(long, value_name = "X", value_parser = parse_slowdown)]
    pub max_slowdown: Option<f64>,
    /// Where the measurements are kept (an explore CSV; default a file in the temporary
    /// folder): a second call reuses them.
    #[arg(long, value_name = "RESULTS.csv")]
    pub results: Option<PathBuf>,
    /// Also compile the chosen layout's entries.
    #[arg(long, value_enum)]
    pub emit: Option<TuneEmit>,
    /// Where `--emit` writes.
    #[arg(short = 'o', long = "output", value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// The rays `scion tune` measures with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum TuneRays {
    /// Camera rays.
    Primary,
    /// Rays of uniform origins and directions in the scene's box.
    Secondary,
}

impl TuneRays {
    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            TuneRays::Primary => "primary",
            TuneRays::Secondary => "secondary",
        }
    }
}

pub(crate) fn parse_slowdown(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x >= 1.0 && x.is_finite() => Ok(x),
        _ => Err(format!(
            "`{s}`: a slowdown is a factor of at least 1 (1.1: 10 % slower)"
        )),
    }
}

/// Parses a size: `N` or `2^K`.
pub(crate) fn parse_size(s: &str) -> Result<usize, String> {
    let n = match s.strip_prefix("2^") {
        Some(k) => {
            let k: u32 = k
                .parse()
                .map_err(|_| format!("`{s}`: 2^K needs a whole K"))?;
            if k > 30 {
                return Err(format!("`{s}`: at most 2^30 queries"));
            }
            1usize << k
        }
        None => s
            .parse()
            .map_err(|_| format!("`{s}`: a size is N or 2^K"))?,
    };
    if n == 0 {
        return Err("a size of 0 queries measures nothing".into());
    }
    Ok(n)
}

/// Where `scion explore` measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ExploreDevice {
    /// This CPU, and an NVIDIA GPU when one opens.
    Auto,
    /// This CPU, with each of `--backends`.
    Cpu,
    /// An NVIDIA GPU: the kernels compiled to PTX by LLVM, run through CUDA, timed by CUDA
    /// events.
    Gpu,
    /// The GPU kernels compiled for this CPU and launched as grids of host threads (checks the
    /// GPU path without a GPU; its times are not a GPU's).
    GpuEmulated,
}

/// Arguments of `scion explore`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  scion explore --scenes teapot,bunny --layouts pbrt,pbrt-q16,bvh8 \
                        -o explore.csv --plots docs/explore\n  scion explore --kinds \
                        closest-hit,closest-point --sizes 2^18,2^20 -o all.csv\n\nColumns: \
                        docs/benchmarks.md, \"Design-space exploration\"."
)]
pub struct ExploreArgs {
    /// Scenes, comma-separated (paths or library scene names; default: the ten library scenes).
    #[arg(long, value_delimiter = ',')]
    pub scenes: Option<Vec<String>>,
    /// Layouts, comma-separated library names (default: every library layout; each kind runs
    /// on those with an entry of the kind over their type).
    #[arg(long, value_delimiter = ',')]
    pub layouts: Option<Vec<String>>,
    /// Query kinds, comma-separated: closest-hit, any-hit, closest-point.
    #[arg(long, value_delimiter = ',', default_value = "closest-hit")]
    pub kinds: Vec<String>,
    /// Ray sets of the hit kinds, comma-separated: primary, secondary (closest points use
    /// points uniform in the scene's box).
    #[arg(long, value_delimiter = ',', default_value = "primary,secondary")]
    pub rays: Vec<String>,
    /// Queries per measurement, comma-separated, `N` or `2^K` (the paper sweeps 2^18 to 2^23).
    #[arg(long, value_delimiter = ',', default_value = "65536", value_parser = parse_size)]
    pub sizes: Vec<usize>,
    /// Code generators of the CPU measurements, comma-separated: llvm, jit.
    #[arg(long, value_enum, value_delimiter = ',', default_value = "llvm")]
    pub backends: Vec<RunBackend>,
    /// Devices, comma-separated: cpu (with each of --backends), gpu (an NVIDIA GPU through
    /// CUDA: the `ptx` rows), gpu-emulated (the GPU kernels on this CPU), auto (cpu, and gpu
    /// when one opens).
    #[arg(long, value_enum, value_delimiter = ',', default_value = "auto")]
    pub devices: Vec<ExploreDevice>,
    /// Threads (0: one per core).
    #[arg(long, default_value_t = 1)]
    pub threads: usize,
    /// Timed runs per measurement (9: the paper's method).
    #[arg(long, default_value_t = 9, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub runs: u32,
    /// Tree builder.
    #[arg(long, value_enum, default_value = "sah")]
    pub builder: BuilderArg,
    /// Largest leaf of the SAH and FCPW builders (1..=15; default 15 for sah, 4 for fcpw).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=15))]
    pub leaf_size: Option<u32>,
    /// Entries of the traversals' explicit stacks (default 64, or 512 where visits push all
    /// their calls).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1 << 20))]
    pub stack_size: Option<u32>,
    /// The results CSV: rows are appended; a rerun skips the measurements it has.
    #[arg(
        short = 'o',
        long = "output",
        value_name = "RESULTS.csv",
        default_value = "explore.csv"
    )]
    pub output: PathBuf,
    /// Also draw the plots of every context in the file (SVG and PNG) and their index.md into
    /// DIR.
    #[arg(long, value_name = "DIR")]
    pub plots: Option<PathBuf>,
    /// Peer libraries to draw on the plots: a CSV of their measurements, each with a Scion
    /// layout's in the same run (written by `cargo bench -p scion-bench --bench peers --
    /// --peer-csv FILE` and scripts/bench-closest-point.sh; scripts/explore-docs.sh makes it).
    #[arg(long, value_name = "PEERS.csv", requires = "plots")]
    pub peers: Option<PathBuf>,
}

/// How `scion render` colours a hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ShadingArg {
    /// The hit triangle's normal as a colour (x, y, z from [-1, 1] to red, green, blue).
    Normals,
    /// Grey, lit from the camera (the cosine between the ray and the normal).
    Diffuse,
}

impl ShadingArg {
    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ShadingArg::Normals => "normals",
            ShadingArg::Diffuse => "diffuse",
        }
    }
}

/// Arguments of `scion render`.
#[derive(clap::Args, Debug)]
#[command(
    after_help = "Examples:\n  scion render --scene bunny -o bunny.png\n  scion render \
                        --scene fzk_haus --layout bvh8-q8-ci --shading diffuse --width 1024 \
                        --height 768 -o haus.png"
)]
pub struct RenderArgs {
    /// The scene: an OBJ file (plain or `.obj.gz`) or a library scene's name (teapot, pine,
    /// suzanne, balloon, fzk_haus, sponza_dabrovic, bunny, engine, cruiser_cg57, dragon).
    #[arg(long, value_name = "PATH.obj|NAME")]
    pub scene: PathBuf,
    /// The layout: a library layout's name (`scion layouts`) or `PATH.scion[:NAME]`.
    #[arg(long)]
    pub layout: Option<String>,
    /// The closest hit to run (default: the library's over the layout's type), a function
    /// name or `PATH.scion[:FUNCTION]`.
    #[arg(long)]
    pub algorithm: Option<String>,
    /// The code generator.
    #[arg(long, value_enum, default_value = "llvm")]
    pub backend: RunBackend,
    /// Image width in pixels.
    #[arg(long, default_value_t = 640, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 480, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub height: u32,
    /// How hits are coloured.
    #[arg(long, value_enum, default_value = "normals")]
    pub shading: ShadingArg,
    /// Tree builder.
    #[arg(long, value_enum, default_value = "sah")]
    pub builder: BuilderArg,
    /// Largest leaf of the SAH and FCPW builders (1..=15; default 15 for sah, 4 for fcpw).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=15))]
    pub leaf_size: Option<u32>,
    /// Threads (0: one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Entries of the traversal's explicit stack (default 64, or 512 where visits push all
    /// their calls).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1 << 20))]
    pub stack_size: Option<u32>,
    /// The PNG to write.
    #[arg(short = 'o', long = "output", value_name = "IMAGE.png")]
    pub output: PathBuf,
}
