//! `cargo bench -p scion-bench --bench strands -- [OPTIONS]`: closest hit on hair (paper §8.2)
//! through Scion's hair BVH over strand segments (`library/layouts/hair_bvh_strands.scion`,
//! traced by `closest_hit_strands`, compiled by LLVM -O3 and Cranelift; with the runtime's rule
//! for oriented nodes, and axis-aligned only) against the runtime's four-wide reference and
//! Embree 3's flat linear curves (the same ribbons facing the ray, Embree's own BVH and curve
//! test), on one strand scene and one ray set, in one interleaved run by the paper's method
//! (`scion_bench::race`). Every contender traces the same segments and rays on the same threads.
//! Prints a markdown table; ratios are to the reference row, and hits are compared with it
//! (Embree's curve test rounds differently, so its `t` differ in the last bits: the "same
//! segment" column is the one to read for it).
//!
//! Options: `--scene FILE.hair` (default: `scion strands generate`'s default head of hair,
//! 64,000 segments, made in memory), `--rays primary|secondary` (primary), `--n N` (65536),
//! `--seed S` (1), `--threads T` (1), `--leaf N` (Scion's leaves of at most N segments: 7, the
//! hair BVH's count bits).

#[path = "peers/embree_peer.rs"]
mod embree_peer;

use scion_bench::{outcome_rows, race, Contender, RayKind};
use scion_host::entries::{Entries, PackedEntries};
use scion_host::jit::Codegen;
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::oriented::OrientedOptions;
use scion_runtime::bvh::wide::collapse;
use scion_runtime::bvh::{build_sah_binned, LogicalTree, SahOptions};
use scion_runtime::geom::Ray;
use scion_runtime::primitive::Segment;
use scion_runtime::query::{primary_rays_n, secondary_rays};
use scion_runtime::reference::closest_hit_wide;
use scion_runtime::scene::strands::{generate, load_hair, StrandOptions, StrandScene};
use scion_runtime::timing::TimingPlan;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

struct Args {
    scene: Option<PathBuf>,
    rays: RayKind,
    n: usize,
    seed: u64,
    threads: usize,
    leaf: usize,
}

fn parse() -> Result<Args, String> {
    let mut a = Args {
        scene: None,
        rays: RayKind::Primary,
        n: 65536,
        seed: 1,
        threads: 1,
        leaf: 7,
    };
    scion_bench::parse_flags(|flag, value| {
        let num = |s: String| scion_bench::flag_number(flag, &s);
        match flag {
            "--scene" => a.scene = Some(PathBuf::from(value()?)),
            "--rays" => a.rays = RayKind::parse(&value()?)?,
            "--n" => a.n = num(value()?)? as usize,
            "--seed" => a.seed = num(value()?)?,
            "--threads" => a.threads = num(value()?)? as usize,
            "--leaf" => a.leaf = (num(value()?)? as usize).clamp(1, 255),
            other => return Err(format!("unknown option `{other}`")),
        }
        Ok(())
    })?;
    Ok(a)
}

/// The hair BVH over strands compiled by `codegen`, packed with the orientation rule
/// `oriented` (the pack time is the setup), traced through its batch entry.
fn scion<'a>(
    name: &str,
    entries: &'a Entries,
    tree: &LogicalTree<Segment>,
    oriented: &OrientedOptions,
    driver: &'a BatchDriver,
) -> Result<Contender<'a>, String> {
    let packed: PackedEntries = entries.pack_oriented(tree, oriented)?;
    let bytes = packed.bytes();
    let setup = packed.pack_time;
    Ok(Contender {
        name: name.into(),
        bytes: Some(bytes),
        setup,
        subset: None,
        trace: Box::new(move |rays: &[Ray]| {
            entries
                .closest_hits(&packed, rays, driver)
                .map_err(|e| e.to_string())
        }),
    })
}

fn run(a: &Args) -> Result<(), String> {
    let scene: StrandScene = match &a.scene {
        Some(p) => load_hair(p).map_err(|e| e.to_string())?,
        None => generate(&StrandOptions::default()),
    };
    if scene.segments.is_empty() {
        return Err("the scene has no segments".into());
    }
    let driver = BatchDriver::new(a.threads)?;
    let b = scene.bounds();
    let rays = match a.rays {
        RayKind::Primary => primary_rays_n(b, a.n as u64, a.seed).ok_or("no rays")?,
        RayKind::Secondary => secondary_rays(b, a.n, a.seed),
    };
    let tree = build_sah_binned(
        &scene.segments,
        &SahOptions {
            max_leaf: a.leaf,
            ..SahOptions::default()
        },
    );
    let wide = collapse::<4>(&tree);
    let program = scion_host::library::resolve("hair-bvh-strands", None)?.program;
    eprintln!("strands: compiling the hair BVH over strands");
    let llvm = Entries::compile(&program, Codegen::Llvm(3), None)?;
    let clif = Entries::compile(&program, Codegen::Cranelift, None)?;
    let aligned = OrientedOptions {
        max_area_ratio: 0.0,
    };
    eprintln!("strands: building Embree's flat curves");
    let start = Instant::now();
    let wide_ref = &wide;
    let prims = &tree.primitives;
    let drv = &driver;
    let mut contenders = vec![
        Contender {
            name: "reference (4-wide)".into(),
            bytes: None,
            setup: start.elapsed(),
            subset: None,
            trace: Box::new(move |rays: &[Ray]| {
                Ok(drv.map(rays, |r| closest_hit_wide(wide_ref, prims, r)))
            }),
        },
        scion(
            "llvm-O3 hair-bvh-strands",
            &llvm,
            &tree,
            &OrientedOptions::default(),
            &driver,
        )?,
        scion(
            "llvm-O3 hair-bvh-strands, axis-aligned",
            &llvm,
            &tree,
            &aligned,
            &driver,
        )?,
        scion(
            "cranelift hair-bvh-strands",
            &clif,
            &tree,
            &OrientedOptions::default(),
            &driver,
        )?,
        embree_peer::embree_curves(&scene.segments, &driver)?,
    ];
    let outcomes = race(&rays, &mut contenders, &TimingPlan::PAPER, |p| {
        eprintln!("strands: {p}")
    })?;
    println!(
        "Strand scene {} ({} segments), {} {} rays, {} thread(s).\n",
        scene.name,
        scene.segments.len(),
        rays.len(),
        a.rays.name(),
        driver.threads()
    );
    print!("{}", outcome_rows(&outcomes, "same segment"));
    Ok(())
}

fn main() -> ExitCode {
    match parse().and_then(|a| run(&a)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("strands: error: {e}");
            ExitCode::FAILURE
        }
    }
}
