//! `cargo bench -p scion-bench --bench peers -- [OPTIONS]`: closest-hit throughput of Scion's
//! generated code (Cranelift and LLVM -O3, layouts pbrt and ptr) against the runtime's Rust reference
//! traversal and the peer libraries obvhs (BVH2, CWBVH; Rust), Embree 3 (the system's
//! libembree3; C++) and tinybvh (BVH, BVH8_CPU; C++ through tinybvh-rs), on one scene and one
//! ray set, in one interleaved run by the paper's method (see `scion_bench`). Every contender
//! traces the same triangles and rays on the same threads (the batch driver's). Prints a
//! markdown table; every ratio is to the reference row, measured in the same rounds.
//!
//! Options: `--scene PATH` (default: `bunny.obj` of `$SCION_SCENES` or `../shared/scenes`),
//! `--rays primary|secondary` (default primary), `--n N` (65536), `--seed S` (1),
//! `--threads T` (1), `--layouts a,b` (pbrt,ptr), `--interp-rays N` (1024: the interpreter traces
//! only the first N rays; 0 leaves it out), `--peers a,b` (which peer libraries run, in this
//! order after the reference: `obvhs-bvh2,obvhs-cwbvh,embree,tinybvh-bvh2,tinybvh-bvh8`, all by
//! default; `--peers ''` runs none). `tinybvh-bvh8` needs a build with the `avx2` target feature
//! (`RUSTFLAGS="-C target-feature=+avx2,+fma"`, see `tinybvh_peer`); without it the row is left
//! out with a note.

mod embree_peer;
mod obvhs_peer;
mod tinybvh_peer;

use scion_bench::{race, table, Contender, RayKind, Workload};
use scion_host::contract::{LayoutCode, Packed};
use scion_host::jit::{Codegen, JitClosestHit};
use scion_host::mem_interp::LIBRARY_LAYOUTS;
use scion_host::oracle::ClosestHit;
use scion_runtime::batch::BatchDriver;
use scion_runtime::reference::closest_hits_tree;
use scion_runtime::timing::TimingPlan;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

struct Args {
    scene: PathBuf,
    rays: RayKind,
    n: usize,
    seed: u64,
    threads: usize,
    layouts: Vec<String>,
    interp_rays: usize,
    peers: Vec<String>,
}

/// The peer libraries `--peers` can name, in the order their rows come.
const PEERS: [&str; 5] = [
    "obvhs-bvh2",
    "obvhs-cwbvh",
    "embree",
    "tinybvh-bvh2",
    "tinybvh-bvh8",
];

fn default_scene() -> PathBuf {
    let dir = std::env::var_os("SCION_SCENES").map_or_else(
        || PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/scenes")),
        PathBuf::from,
    );
    dir.join("bunny.obj")
}

fn parse() -> Result<Args, String> {
    let mut a = Args {
        scene: default_scene(),
        rays: RayKind::Primary,
        n: 65536,
        seed: 1,
        threads: 1,
        layouts: vec!["pbrt".into(), "ptr".into()],
        interp_rays: 1024,
        peers: PEERS.map(str::to_string).to_vec(),
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        // `cargo bench` passes `--bench` to every harness-less benchmark.
        if flag == "--bench" {
            continue;
        }
        let mut value = || it.next().ok_or(format!("{flag} needs a value"));
        let num = |s: String| {
            s.parse::<u64>()
                .map_err(|_| format!("{flag}: `{s}` is not a number"))
        };
        match flag.as_str() {
            "--scene" => a.scene = PathBuf::from(value()?),
            "--rays" => a.rays = RayKind::parse(&value()?)?,
            "--n" => a.n = num(value()?)? as usize,
            "--seed" => a.seed = num(value()?)?,
            "--threads" => a.threads = num(value()?)? as usize,
            "--layouts" => a.layouts = value()?.split(',').map(str::to_string).collect(),
            "--interp-rays" => a.interp_rays = num(value()?)? as usize,
            "--peers" => {
                let list = value()?;
                a.peers = list
                    .split(',')
                    .filter(|p| !p.is_empty())
                    .map(str::to_string)
                    .collect();
                if let Some(p) = a.peers.iter().find(|p| !PEERS.contains(&p.as_str())) {
                    return Err(format!(
                        "--peers: unknown peer `{p}` (known: {})",
                        PEERS.join(",")
                    ));
                }
            }
            _ => {
                return Err(format!(
                    "unknown option `{flag}` (see the header of bench/benches/peers/main.rs)"
                ))
            }
        }
    }
    Ok(a)
}

fn progress(s: &str) {
    eprintln!("peers: {s}");
}

/// A layout's generated code as a contender: packed once (the pack time is its setup), then
/// traced through the batch entry.
fn layout_contender<'a>(
    name: String,
    code: Box<dyn LayoutCode>,
    w: &'a Workload,
    driver: &'a BatchDriver,
) -> Result<Contender<'a>, String> {
    let packed = Packed::new(code.as_ref(), &w.tree)?;
    Ok(Contender {
        name,
        bytes: Some(packed.bytes()),
        setup: packed.pack_time,
        subset: None,
        trace: Box::new(move |rays| {
            packed
                .trace(code.as_ref(), rays, driver)
                .map_err(|f| f.to_string())
        }),
    })
}

fn run(a: &Args) -> Result<(), String> {
    progress(&format!("loading {}", a.scene.display()));
    let w = Workload::load(&a.scene, a.rays, a.n, a.seed)?;
    let driver = BatchDriver::new(a.threads)?;
    let tree_bytes = std::mem::size_of_val(w.tree.nodes.as_slice())
        + std::mem::size_of_val(w.tree.primitives.as_slice());
    let mut contenders = vec![Contender {
        name: "reference".into(),
        bytes: Some(tree_bytes),
        setup: std::time::Duration::ZERO,
        subset: None,
        trace: Box::new(|rays| Ok(closest_hits_tree(&w.tree, rays, &driver))),
    }];
    // The peer libraries, in `PEERS` order whatever the order of `--peers`.
    let tris = w.triangles.as_slice();
    for peer in PEERS.iter().filter(|p| a.peers.iter().any(|q| q == *p)) {
        progress(&format!("building the {peer} structure"));
        match *peer {
            "obvhs-bvh2" => contenders.push(obvhs_peer::bvh2(tris, &driver)),
            "obvhs-cwbvh" => contenders.push(obvhs_peer::cwbvh(tris, &driver)),
            "embree" => contenders.push(embree_peer::embree(tris, &driver)?),
            "tinybvh-bvh2" => contenders.push(tinybvh_peer::bvh2(tris, &driver)?),
            _ => match tinybvh_peer::bvh8_cpu(tris, &driver) {
                Some(c) => contenders.push(c?),
                None => progress(
                    "  left out: tinybvh-rs exposes BVH8_CPU's traversal only to builds with the \
                     avx2 target feature (RUSTFLAGS=\"-C target-feature=+avx2,+fma\")",
                ),
            },
        }
    }
    for layout in &a.layouts {
        let stem = layout.replace('-', "_");
        let Some(&(stem, lname, _)) = LIBRARY_LAYOUTS.iter().find(|l| l.0 == stem) else {
            return Err(format!("unknown library layout `{layout}`"));
        };
        progress(&format!("compiling and packing {layout} (Cranelift)"));
        let t = Instant::now();
        let jit = JitClosestHit::compile(stem, lname, None)?;
        progress(&format!("  compiled in {:.3} s", t.elapsed().as_secs_f64()));
        contenders.push(layout_contender(
            format!("cranelift {layout}"),
            Box::new(jit),
            &w,
            &driver,
        )?);
        progress(&format!("compiling and packing {layout} (LLVM -O3)"));
        let t = Instant::now();
        let llvm = JitClosestHit::compile_with(stem, lname, None, 3, Codegen::Llvm(3))?;
        progress(&format!("  compiled in {:.3} s", t.elapsed().as_secs_f64()));
        contenders.push(layout_contender(
            format!("llvm-O3 {layout}"),
            Box::new(llvm),
            &w,
            &driver,
        )?);
    }
    if a.interp_rays > 0 {
        let interp = ClosestHit::compile(1)?;
        let threads = a.threads;
        let w = &w;
        contenders.push(Contender {
            name: format!(
                "interpreter (first {} rays)",
                a.interp_rays.min(w.rays.len())
            ),
            bytes: None,
            setup: std::time::Duration::ZERO,
            subset: Some(a.interp_rays),
            trace: Box::new(move |rays| interp.trace_all(&w.tree, rays, threads)),
        });
    }
    let outcomes = race(&w.rays, &mut contenders, &TimingPlan::PAPER, progress)?;
    drop(contenders);
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!(
        "Machine: {cores} CPUs, {cpu}. Method: 1 warm-up round, 9 interleaved rounds, mean of the middle 5.\n"
    );
    print!("{}", table(&w, a.threads, &outcomes));
    Ok(())
}

fn main() -> ExitCode {
    match parse().and_then(|a| run(&a)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("peers: error: {e}");
            ExitCode::FAILURE
        }
    }
}
