//! Writes a rays file and the reference hits for a scene, and times the reference traversal
//! by the paper's method.
//!
//! ```text
//! cargo run --release -p scion-runtime --example reference -- SCENE OUT_PREFIX \
//!     [primary W H | secondary N] [--seed S] [--threads T] [--max-leaf L]
//! ```
//!
//! `SCENE` is an OBJ path or the name of a real scene (`bunny`: scenes/bunny.obj.gz).
//! Writes `OUT_PREFIX.rays` and `OUT_PREFIX.hits` (docs/formats.md) and prints the tree's
//! statistics and the timing (mean of the middle 5 of 9 runs, per ray and per second).

use std::process::ExitCode;

use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::{build_sah_binned, SahOptions};
use scion_runtime::query::{primary_rays, secondary_rays, write_hits, write_rays};
use scion_runtime::reference::closest_hits_tree;
use scion_runtime::scene::{load_obj, manifest};
use scion_runtime::timing::measure;

fn parse<T: std::str::FromStr>(what: &str, v: Option<&String>) -> Result<T, String> {
    let v = v.ok_or_else(|| format!("missing {what}"))?;
    v.parse().map_err(|_| format!("bad {what}: `{v}`"))
}

fn run(args: &[String]) -> Result<(), String> {
    let mut rest: Vec<String> = Vec::new();
    let (mut seed, mut threads, mut max_leaf) = (1u64, 0usize, 15usize);
    let mut i = 0;
    while i < args.len() {
        match args[i].as_str() {
            "--seed" => seed = parse("seed", args.get(i + 1))?,
            "--threads" => threads = parse("thread count", args.get(i + 1))?,
            "--max-leaf" => max_leaf = parse("leaf size", args.get(i + 1))?,
            _ => {
                rest.push(args[i].clone());
                i += 1;
                continue;
            }
        }
        i += 2;
    }
    let [scene_path, prefix, kind, tail @ ..] = rest.as_slice() else {
        return Err(
            "usage: reference SCENE.obj OUT_PREFIX [primary W H | secondary N] \
                    [--seed S] [--threads T] [--max-leaf L]"
                .into(),
        );
    };
    // A bare name (`bunny`) means that real scene from the repository's scenes/.
    let scene_path = manifest::resolve(std::path::Path::new(scene_path))?;
    let scene = load_obj(&scene_path).map_err(|e| e.to_string())?;
    let bounds = scene.bounds();
    let rays = match kind.as_str() {
        "primary" => primary_rays(
            bounds,
            parse("width", tail.first())?,
            parse("height", tail.get(1))?,
            seed,
        ),
        "secondary" => secondary_rays(bounds, parse("ray count", tail.first())?, seed),
        other => return Err(format!("unknown ray kind `{other}` (primary or secondary)")),
    };
    let options = SahOptions {
        max_leaf,
        ..SahOptions::default()
    };
    let tree = build_sah_binned(&scene.triangles, &options);
    tree.validate_with_cap(max_leaf)?;
    let driver = BatchDriver::new(threads)?;
    let hits = closest_hits_tree(&tree, &rays, &driver);
    let timing = measure(|| {
        std::hint::black_box(closest_hits_tree(&tree, &rays, &driver));
    });
    write_rays(format!("{prefix}.rays"), &rays).map_err(|e| e.to_string())?;
    write_hits(format!("{prefix}.hits"), &hits).map_err(|e| e.to_string())?;
    let s = tree.stats();
    println!(
        "{}: {} triangles; tree: {} nodes, depth {}, stack {}, SAH cost {:.1}",
        scene.name,
        scene.len(),
        s.nodes,
        s.depth,
        s.stack_needed,
        s.sah_cost
    );
    println!(
        "{} {kind} rays, {} hits; {} threads: {:.1} ns/ray, {:.2} Mrays/s (raw ms: {})",
        rays.len(),
        hits.iter().filter(|h| h.is_hit()).count(),
        driver.threads(),
        timing.ns_per_query(rays.len()),
        timing.queries_per_second(rays.len()) / 1e6,
        timing
            .raw
            .iter()
            .map(|d| format!("{:.2}", d.as_secs_f64() * 1e3))
            .collect::<Vec<_>>()
            .join(" ")
    );
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
