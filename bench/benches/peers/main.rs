//! `cargo bench -p scion-bench --bench peers -- [OPTIONS]`: closest-hit throughput of Scion's
//! generated code (Cranelift and LLVM -O3, layouts pbrt and ptr) against the runtime's Rust reference
//! traversal and the peer libraries obvhs (BVH2, CWBVH; Rust), Embree 3 (the system's
//! libembree3; C++) and tinybvh (BVH, BVH8_CPU; C++ through tinybvh-rs), on one scene and one
//! ray set, in one interleaved run by the paper's method (see `scion_bench`). Every contender
//! traces the same triangles and rays on the same threads (the batch driver's). Prints a
//! markdown table; every ratio is to the reference row, measured in the same rounds.
//!
//! Options: `--scene PATH|NAME` (an OBJ file, or a scene of the repository's `scenes/` by name;
//! default `bunny`),
//! `--rays primary|secondary` (default primary), `--n N` (65536), `--seed S` (1),
//! `--threads T` (1), `--layouts a,b` (pbrt,ptr), `--interp-rays N` (1024: the interpreter traces
//! only the first N rays; 0 leaves it out), `--peers a,b` (which peers run, in this order after
//! the reference: `hand-pbrt` (the hand-written kernel over the pbrt layout's bytes,
//! `scion_bench::pbrt_kernel`), `obvhs-bvh2,obvhs-cwbvh,embree,tinybvh-bvh2,tinybvh-bvh8`; all by
//! default; `--peers ''` runs none), `--tsv PATH` (also append one tab-separated line per row to
//! PATH, the input of scripts/bench-peers.sh), `--peer-csv PATH` (also append the peer
//! libraries' rows to the peers file PATH, each anchored to the LLVM row of the first of
//! `--layouts`: what `scion explore --peers` draws on its plots; see
//! `scion_runtime::timing::PEER_FIELDS`), `--trace-only NAME` (trace only the row NAME, once,
//! untimed: what scripts/perf-counters.sh runs under valgrind), `--builders` (instead of timing,
//! compare the trees of Scion's builder, tinybvh's and obvhs's: SAH cost and the reference
//! traversal's work per ray on each, see `builders`), `--tree scion|tinybvh|obvhs|embree` (the
//! tree the reference, the hand-written kernel and Scion's rows traverse: Scion's binned SAH
//! tree by default, or the one tinybvh's, obvhs's or Embree's builder makes, read back as a
//! logical tree; Embree's through its builder API `rtcBuildBVH`, which also makes the tree of
//! blocks the `Triangle4` layouts traverse, its SAH counting blocks of four, see `embree_tree`;
//! the peers always use their own), `--max-leaf N` (Scion's tree with leaves of at most N
//! primitives, for layouts with narrower counts: the hair BVH's 3 bits hold 7),
//! `--traversal-cost C` (Scion's tree built with the SAH's cost of an interior visit set to
//! `C` triangle tests instead of 1: larger leaves and fewer nodes as `C` grows; for measuring
//! the builder's constants), `--sah-block N` (Scion's tree with its leaves collapsed for a
//! traversal that tests them in runs of `N` primitives instead of 4, `SahOptions::block`; 1
//! leaves the reinserted binned SAH tree as built), `--root enters|misses` (trace only the rays
//! that enter, or that miss, the root's box of the tree Scion's rows traverse, by the prelude's
//! slab test: the time of the rays that descend apart from the time of those that stop at the
//! root, docs/performance.md "Twenty-second session"). `tinybvh-bvh8` needs a build with the `avx2` target feature
//! (`RUSTFLAGS="-C target-feature=+avx2,+fma"`, see `tinybvh_peer`); without it the row is left
//! out with a note.

mod builders;
mod embree_peer;
mod embree_tree;
mod obvhs_peer;
mod scion_rows;
mod tinybvh_peer;

use scion_bench::{peer_csv_rows, race, table, tsv_rows, Contender, RayKind, Workload};
use scion_host::oracle::ClosestHit;
use scion_runtime::batch::BatchDriver;
use scion_runtime::reference::closest_hits_tree;
use scion_runtime::timing::TimingPlan;
use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

struct Args {
    scene: PathBuf,
    rays: RayKind,
    n: usize,
    seed: u64,
    threads: usize,
    layouts: Vec<String>,
    interp_rays: usize,
    peers: Vec<String>,
    tsv: Option<PathBuf>,
    peer_csv: Option<PathBuf>,
    trace_only: Option<String>,
    builders: bool,
    tree: String,
    max_leaf: Option<usize>,
    traversal_cost: Option<f64>,
    sah_block: Option<usize>,
    /// `--root`: keep only the rays that enter (`true`) or miss (`false`) the root's box.
    root: Option<bool>,
}

/// `c`'s trace of `rays`, the one call of `--trace-only` that scripts/perf-counters.sh counts
/// (callgrind's `--toggle-collect=*peers_traced_call*`: not inlined, so that it has a symbol).
#[inline(never)]
fn peers_traced_call(
    c: &mut Contender<'_>,
    rays: &[scion_runtime::geom::Ray],
) -> Result<Vec<scion_runtime::geom::Hit>, String> {
    (c.trace)(std::hint::black_box(rays))
}

/// The peers `--peers` can name, in the order their rows come: the hand-written kernel over
/// the `pbrt` layout's bytes, then the peer libraries.
const PEERS: [&str; 6] = [
    "hand-pbrt",
    "obvhs-bvh2",
    "obvhs-cwbvh",
    "embree",
    "tinybvh-bvh2",
    "tinybvh-bvh8",
];

fn default_scene() -> PathBuf {
    scion_runtime::scene::manifest::resolve(std::path::Path::new("bunny"))
        .unwrap_or_else(|_| PathBuf::from("scenes/bunny.obj.gz"))
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
        tsv: None,
        peer_csv: None,
        trace_only: None,
        builders: false,
        tree: "scion".into(),
        max_leaf: None,
        traversal_cost: None,
        sah_block: None,
        root: None,
    };
    scion_bench::parse_flags(|flag, value| {
        let num = |s: String| scion_bench::flag_number(flag, &s);
        match flag {
            "--scene" => {
                a.scene = scion_runtime::scene::manifest::resolve(&PathBuf::from(value()?))
                    .map_err(|e| format!("--scene: {e}"))?
            }
            "--rays" => a.rays = RayKind::parse(&value()?)?,
            "--n" => a.n = num(value()?)? as usize,
            "--seed" => a.seed = num(value()?)?,
            "--threads" => a.threads = num(value()?)? as usize,
            "--layouts" => {
                a.layouts = value()?
                    .split(',')
                    .filter(|l| !l.is_empty())
                    .map(str::to_string)
                    .collect()
            }
            "--interp-rays" => a.interp_rays = num(value()?)? as usize,
            "--tsv" => a.tsv = Some(PathBuf::from(value()?)),
            "--peer-csv" => a.peer_csv = Some(PathBuf::from(value()?)),
            "--trace-only" => a.trace_only = Some(value()?),
            "--builders" => a.builders = true,
            "--tree" => a.tree = value()?,
            "--max-leaf" => {
                let n = num(value()?)? as usize;
                if n == 0 {
                    return Err("--max-leaf: at least 1 primitive per leaf".into());
                }
                a.max_leaf = Some(n);
            }
            "--traversal-cost" => {
                let v = value()?;
                let c: f64 = v
                    .parse()
                    .map_err(|_| format!("--traversal-cost: `{v}` is not a number"))?;
                if !(c.is_finite() && c > 0.0) {
                    return Err("--traversal-cost: a positive number".into());
                }
                a.traversal_cost = Some(c);
            }
            "--sah-block" => {
                let n = num(value()?)? as usize;
                if n == 0 {
                    return Err("--sah-block: at least 1 primitive per test".into());
                }
                a.sah_block = Some(n);
            }
            "--root" => {
                a.root = Some(match value()?.as_str() {
                    "enters" => true,
                    "misses" => false,
                    v => return Err(format!("--root: `{v}` is neither `enters` nor `misses`")),
                })
            }
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
        Ok(())
    })?;
    Ok(a)
}

fn progress(s: &str) {
    eprintln!("peers: {s}");
}

/// Keeps the rays of `w` that enter the root's box of its tree (`enters`), or those that miss
/// it, by the prelude's slab test (`slab_interval`); an empty selection is an error.
fn keep_by_root(w: &mut Workload, enters: bool) -> Result<(), String> {
    let Some(root) = w.tree.nodes.get(w.tree.root as usize) else {
        return Err("--root: the scene's tree is empty".into());
    };
    let b = root.aabb();
    let before = w.rays.len();
    w.rays.retain(|r| {
        let (t0, t1) = scion_runtime::reference::prelude::slab_interval(r, &b);
        (t0 <= t1) == enters
    });
    let what = if enters { "enter" } else { "miss" };
    if w.rays.is_empty() {
        return Err(format!(
            "--root: not one of the {before} rays would {what} the root's box"
        ));
    }
    progress(&format!(
        "{} of {before} rays {what} the root's box",
        w.rays.len()
    ));
    Ok(())
}

fn run(a: &Args) -> Result<(), String> {
    progress(&format!("loading {}", a.scene.display()));
    let mut w = Workload::load(&a.scene, a.rays, a.n, a.seed)?;
    // The tree the reference, the hand-written kernel and Scion's rows traverse.
    match a.tree.as_str() {
        "scion" => {
            if a.max_leaf.is_some() || a.traversal_cost.is_some() || a.sah_block.is_some() {
                let d = scion_runtime::bvh::SahOptions::default();
                let o = scion_runtime::bvh::SahOptions {
                    max_leaf: a.max_leaf.unwrap_or(d.max_leaf),
                    traversal_cost: a.traversal_cost.unwrap_or(d.traversal_cost),
                    block: a.sah_block.unwrap_or(d.block),
                    ..d
                };
                w.tree = scion_runtime::bvh::build_sah_binned(&w.triangles, &o);
            }
        }
        "tinybvh" => w.tree = tinybvh_peer::logical_tree(&w.triangles)?,
        "obvhs" => w.tree = obvhs_peer::logical_tree(&w.triangles)?,
        "embree" => {
            let leaf = a
                .max_leaf
                .unwrap_or(scion_runtime::bvh::SahOptions::default().max_leaf);
            w.tree = embree_tree::logical_tree(&w.triangles, leaf, 1)?;
            let blocks = embree_tree::logical_tree(
                &w.triangles,
                scion_runtime::triangle4::BLOCK_TREE_MAX_LEAF,
                4,
            )?;
            w.blocks = Some(scion_runtime::triangle4::block_tree(&blocks)?);
        }
        t => {
            return Err(format!(
                "--tree: unknown builder `{t}` (scion, tinybvh, obvhs or embree)"
            ))
        }
    }
    if let Some(enters) = a.root {
        keep_by_root(&mut w, enters)?;
    }
    let driver = BatchDriver::new(a.threads)?;
    let tree_bytes = std::mem::size_of_val(w.tree.nodes.as_slice())
        + std::mem::size_of_val(w.tree.primitives.as_slice());
    if a.builders {
        print!("{}", builders::report(&w, &driver)?);
        return Ok(());
    }
    let want = |p: &str| a.peers.iter().any(|q| q == p);
    // The pbrt layout's bytes for the hand-written kernel (they outlive the contenders).
    let hand_packed = if want("hand-pbrt") {
        progress("packing the pbrt layout for the hand-written kernel");
        Some(scion_rows::pack_pbrt(&w)?)
    } else {
        None
    };
    let mut contenders = vec![Contender {
        name: "reference".into(),
        bytes: Some(tree_bytes),
        setup: std::time::Duration::ZERO,
        subset: None,
        trace: Box::new(|rays| Ok(closest_hits_tree(&w.tree, rays, &driver))),
    }];
    // The peers, in `PEERS` order whatever the order of `--peers`.
    let tris = w.triangles.as_slice();
    for peer in PEERS.iter().filter(|p| want(p)) {
        progress(&format!("building the {peer} structure"));
        match *peer {
            "hand-pbrt" => {
                let packed = hand_packed
                    .as_ref()
                    .ok_or("the pbrt layout was not packed")?;
                contenders.push(scion_rows::hand_pbrt(packed, &driver)?);
            }
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
        contenders.extend(scion_rows::generated(layout, &w, &driver)?);
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
    if let Some(name) = &a.trace_only {
        // One untimed trace of one contender, for counting its instructions and cache misses
        // (scripts/perf-counters.sh runs this under callgrind, collecting in `traced` only).
        let c = contenders
            .iter_mut()
            .find(|c| &c.name == name)
            .ok_or_else(|| format!("--trace-only: no contender `{name}`"))?;
        let hits = peers_traced_call(c, &w.rays)?;
        println!(
            "{name}: traced {} rays, {} hits",
            hits.len(),
            hits.iter().filter(|h| h.is_hit()).count()
        );
        return Ok(());
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
    if let Some(path) = &a.tsv {
        let mut f = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        f.write_all(tsv_rows(&w, a.threads, &outcomes).as_bytes())
            .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    if let Some(path) = &a.peer_csv {
        let anchor = format!(
            "llvm-O3 {}",
            a.layouts.first().map_or("pbrt", String::as_str)
        );
        let rows = peer_csv_rows(&w, a.n, a.threads, &outcomes, &anchor)?;
        let new = !path.exists();
        let mut f = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        if new {
            writeln!(f, "{}", scion_runtime::timing::PEER_FIELDS.join(","))
                .map_err(|e| format!("{}: {e}", path.display()))?;
        }
        f.write_all(rows.as_bytes())
            .map_err(|e| format!("{}: {e}", path.display()))?;
    }
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
