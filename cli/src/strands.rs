//! `scion strands`: hair and fur scenes (paper §8.2). `generate` writes a seeded head of hair as
//! a `.hair` file (`scion_runtime::scene::strands`, docs/formats.md); `trace` loads a `.hair`
//! file, builds the binned-SAH tree over its segments, packs it into a layout over `Segment`s
//! (`hair-bvh-strands` by default) with the generated builder, traces closest-hit rays with the
//! generated traversal, times it by the paper's method and checks every hit against the
//! runtime's four-wide reference over the same collapse (or, where that reference's rounding
//! pruned it, brute force's hit).

use std::path::PathBuf;
use std::time::Instant;

use clap::{Args, Subcommand};
use scion_host::entries::Entries;
use scion_host::jit::Codegen;
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::oriented::OrientedOptions;
use scion_runtime::bvh::wide::collapse;
use scion_runtime::bvh::{build_sah_binned, SahOptions};
use scion_runtime::geom::Ray;
use scion_runtime::query::{primary_rays_n, secondary_rays};
use scion_runtime::reference::{closest_hit_brute, closest_hit_wide};
use scion_runtime::scene::strands::{generate_polylines, hair_bytes, load_hair, StrandOptions};

use crate::io::outln;
use crate::trace::{progress, secs, significant, timed};
use crate::{CliError, RaysArg, RunBackend};

/// Arguments of `scion strands`.
#[derive(Args, Debug)]
pub struct StrandsArgs {
    #[command(subcommand)]
    pub command: StrandsCommand,
}

/// What `scion strands` does.
#[derive(Subcommand, Debug)]
pub enum StrandsCommand {
    /// Write a seeded head of hair as a `.hair` file: strands rooted on a unit sphere, grown
    /// outward, pulled down and curled; the same options write the same bytes (SplitMix64;
    /// the angles through the platform's sin and cos).
    Generate(GenerateArgs),
    /// Trace closest-hit rays through a `.hair` scene with a layout over strand segments, timed
    /// and checked against the reference.
    Trace(StrandTraceArgs),
}

/// Arguments of `scion strands generate`.
#[derive(Args, Debug)]
pub struct GenerateArgs {
    /// Number of strands.
    #[arg(long, default_value_t = 4000, value_parser = clap::value_parser!(u32).range(1..=10_000_000))]
    pub strands: u32,
    /// Segments per strand (a `.hair` file holds at most 65,535).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=65_535))]
    pub segments: u32,
    /// Radius at a strand's root (it tapers to a fifth at the tip); the head's radius is 1.
    #[arg(long, default_value_t = 0.004)]
    pub radius: f32,
    /// The random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The `.hair` file to write.
    #[arg(short = 'o', long = "output", value_name = "FILE.hair")]
    pub output: PathBuf,
}

/// Arguments of `scion strands trace`.
#[derive(Args, Debug)]
pub struct StrandTraceArgs {
    /// The strand scene: a `.hair` file (Cem Yuksel's format, plain or gzip-compressed).
    #[arg(long, value_name = "FILE.hair")]
    pub scene: PathBuf,
    /// A layout whose leaves hold `Segment`s (`scion layouts --primitive Segment`), or a
    /// `.scion` file.
    #[arg(
        long,
        default_value = "hair-bvh-strands",
        value_name = "NAME|PATH.scion"
    )]
    pub layout: String,
    /// The code generator.
    #[arg(long, value_enum, default_value = "llvm")]
    pub backend: RunBackend,
    /// Primary rays (a camera framing the scene) or secondary rays (origins in its box,
    /// directions uniform on the sphere).
    #[arg(long, value_enum, default_value = "primary")]
    pub rays: RaysArg,
    /// Number of rays.
    #[arg(long, default_value_t = 1 << 16, value_parser = clap::value_parser!(u64).range(1..=1 << 30))]
    pub n: u64,
    /// The rays' random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Largest leaf of the binned-SAH tree (the hair BVH's references count up to 7).
    #[arg(long, default_value_t = 7, value_parser = clap::value_parser!(u32).range(1..=255))]
    pub leaf_size: u32,
    /// Which interior nodes below the root are oriented (`OBBNode`s): where their children's
    /// oriented boxes have at most this fraction of the surface of their axis-aligned boxes
    /// (0: none, the tree is axis-aligned; `inf`: every one). The default is the runtime's.
    #[arg(long, default_value_t = OrientedOptions::default().max_area_ratio, value_name = "RATIO")]
    pub max_area_ratio: f64,
    /// Threads (0: one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Timed runs after one warm-up (the paper's method: 9, dropping the 2 fastest and slowest).
    #[arg(long, default_value_t = 9, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub runs: u32,
}

/// Runs `scion strands`.
pub fn run(args: &StrandsArgs) -> Result<(), CliError> {
    match &args.command {
        StrandsCommand::Generate(a) => generate(a),
        StrandsCommand::Trace(a) => trace(a),
    }
}

fn generate(args: &GenerateArgs) -> Result<(), CliError> {
    if !(args.radius.is_finite() && args.radius >= 0.0) {
        return Err(CliError::usage(format!(
            "--radius {}: a radius is a finite number at least 0",
            args.radius
        )));
    }
    let options = StrandOptions {
        strands: args.strands,
        segments: args.segments,
        radius: args.radius,
        seed: args.seed,
    };
    let lines = generate_polylines(&options);
    let info = format!(
        "scion strands generate --strands {} --segments {} --radius {} --seed {}",
        args.strands, args.segments, args.radius, args.seed
    );
    let bytes = hair_bytes(&lines, &info).map_err(CliError::new)?;
    std::fs::write(&args.output, &bytes)
        .map_err(|e| CliError::new(format!("cannot write {}: {e}", args.output.display())))?;
    outln!(
        "wrote {} ({} strands, {} segments, {} bytes)",
        args.output.display(),
        args.strands,
        u64::from(args.strands) * u64::from(args.segments),
        bytes.len()
    );
    Ok(())
}

fn trace(args: &StrandTraceArgs) -> Result<(), CliError> {
    crate::io::check_threads(args.threads)?;
    let resolved = scion_host::library::resolve(&args.layout, None)
        .map_err(|e| CliError::usage(e).note("scion layouts --primitive Segment lists them"))?;
    if resolved.primitive != "Segment" {
        return Err(CliError::usage(format!(
            "--layout {}: its leaves hold `{}`s; a strand scene needs a layout over `Segment`s",
            args.layout, resolved.primitive
        ))
        .note("scion layouts --primitive Segment lists them"));
    }
    let codegen = match args.backend {
        RunBackend::Jit => Codegen::Cranelift,
        RunBackend::Llvm => Codegen::Llvm(3),
    };
    progress(&format!("compiling `{}`", resolved.program.layout));
    let entries = Entries::compile(&resolved.program, codegen, None).map_err(CliError::new)?;

    progress(&format!("loading {}", args.scene.display()));
    let t = Instant::now();
    let scene = load_hair(&args.scene)
        .map_err(|e| CliError::new(format!("cannot load the strand scene: {e}")))?;
    let load_time = t.elapsed();
    let bounds = scene.bounds();
    if scene.segments.is_empty() {
        return Err(CliError::new(format!(
            "{}: the scene has no segments, so there is no box to aim rays at",
            args.scene.display()
        )));
    }
    let t = Instant::now();
    let tree = build_sah_binned(
        &scene.segments,
        &SahOptions {
            max_leaf: args.leaf_size as usize,
            // The hair traversal tests a leaf's segments one at a time.
            block: 1,
            ..SahOptions::default()
        },
    );
    let build_time = t.elapsed();
    progress(&format!(
        "packing the tree into layout `{}`",
        resolved.program.layout
    ));
    if args.max_area_ratio.is_nan() || args.max_area_ratio < 0.0 {
        return Err(CliError::usage(format!(
            "--max-area-ratio {}: a ratio at least 0 (inf: every node)",
            args.max_area_ratio
        )));
    }
    let oriented = OrientedOptions {
        max_area_ratio: args.max_area_ratio,
    };
    let packed = entries.pack_oriented(&tree, &oriented).map_err(|e| {
        CliError::new(format!("layout `{}`: {e}", resolved.program.layout))
            .note("the hair BVH's references count at most 7 segments per leaf (--leaf-size)")
    })?;
    let rays: Vec<Ray> = match args.rays {
        RaysArg::Primary => primary_rays_n(bounds, args.n, args.seed)
            .ok_or_else(|| CliError::usage("--n: 1 to 2^30 rays"))?,
        RaysArg::Secondary => secondary_rays(bounds, args.n as usize, args.seed),
        RaysArg::Axis => scion_runtime::query::axis_rays(bounds, args.n as usize, args.seed),
    };
    let driver = BatchDriver::new(args.threads).map_err(CliError::new)?;
    progress(&format!("tracing {} rays", rays.len()));
    let (hits, timing) = timed(args.runs, || {
        entries
            .closest_hits(&packed, &rays, &driver)
            .map_err(|e| CliError::new(format!("layout `{}`: {e}", resolved.program.layout)))
    })?;
    // The check: the four-wide reference over the same collapse, bit for bit; where it
    // differs, the hit must be brute force's (the reference's rounding exception).
    let wide = collapse::<4>(&tree);
    let mismatch = rays.iter().zip(&hits).position(|(ray, got)| {
        let want = closest_hit_wide(&wide, &tree.primitives, ray);
        !(got.bit_eq(&want) || got.bit_eq(&closest_hit_brute(&scene.segments, ray)))
    });
    let stats = tree.stats();
    let bytes = packed.bytes();
    let hit_count = hits.iter().filter(|h| h.is_hit()).count();
    outln!("scene        {}", args.scene.display());
    outln!("segments     {}", scene.segments.len());
    outln!(
        "nodes        {} binary ({} leaves of at most {}, depth {}, SAH cost {:.2})",
        stats.nodes,
        stats.leaves,
        args.leaf_size,
        stats.depth,
        stats.sah_cost
    );
    outln!("load time    {}", secs(load_time));
    outln!("build time   {}", secs(build_time));
    outln!(
        "layout       {}: {bytes} bytes ({:.1} per segment), packed in {}",
        resolved.program.layout,
        bytes as f64 / scene.segments.len() as f64,
        secs(packed.pack_time)
    );
    outln!(
        "rays         {} {} (seed {})",
        rays.len(),
        args.rays.name(),
        args.seed
    );
    outln!(
        "backend      {} on {} threads",
        match codegen {
            Codegen::Cranelift => "jit (Cranelift)",
            _ => "llvm -O3",
        },
        driver.threads()
    );
    outln!("trace time   {}", secs(timing.mean));
    outln!(
        "throughput   {} Mrays/s ({:.1} ns/ray)",
        significant(timing.queries_per_second(rays.len()) / 1e6),
        timing.ns_per_query(rays.len())
    );
    outln!("hits         {hit_count} of {} rays", rays.len());
    match mismatch {
        None => {
            outln!(
                "check        identical to the reference on all {} rays",
                rays.len()
            );
            Ok(())
        }
        Some(k) => Err(CliError::new(format!(
            "ray {k} ({:?}): the generated traversal's hit {:?} is neither the reference's nor \
             brute force's",
            rays[k], hits[k]
        ))),
    }
}
