//! Differential tests: every backend's closest hits equal the runtime's reference traversal bit
//! for bit (same `t` bits, same primitive id), and brute force except where pruning provably
//! drops the brute-force hit (docs/runtime.md, "Brute force and traversal"). A quantized layout
//! (`pbrt_q16`, `sg_eq`) traverses wider, conservative boxes, which can break a tie in `t` differently
//! or keep a grazing hit that the exact boxes prune; its reference is the traversal of the tree
//! with the decoded boxes (`scion_host::quantized`), and brute force is checked the same way.
//!
//! The test is a table: one row per (scene, tree, ray kind, backend). [`BACKENDS`] lists the
//! backends; a new backend (the JIT of a layout) is one more entry there and one more
//! `BackendKind` variant. The LLVM rows (`BackendKind::Llvm`, -O3) cover every library layout
//! on the same scenes and hard cases as the Cranelift rows, and so do the rows of the GPU pipeline
//! emulated on the CPU (`BackendKind::GpuEmulated`: pbrt, ptr, pbrt_q16, sg_eq). Scenes: the generated hard cases
//! (always) and the real scenes of
//! the repository's `scenes/` (or `SCION_SCENES`; a missing folder fails; those over 20 k
//! triangles only in release builds). The interpreters are slow, so real scenes get few rays (release: 128
//! primary and 64 secondary, plus 64 axis and 64 feature rays on scenes under 50 k triangles;
//! debug builds a quarter of that), and each interpreter only a row's first rays
//! (`Backend::max_rays`: 64 for the tree-level interpreters, 32 at the mem level, every row
//! still). The mem-level interpreter packs a tree once for all the rows that trace it.

use crate::common;

use scion_host::backend::{Backend, BackendKind};
use scion_host::contract::LayoutBackend;
use scion_host::jit::JitClosestHit;
use scion_host::mem_interp::{library_layouts, MemInterpBackend};
use scion_host::oracle::tree_depth;
use scion_host::quantized::{Boxes, DecodedTree};
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::{Hit, Ray};
use scion_runtime::reference::{closest_hits_brute, closest_hits_tree};
use scion_runtime::scene::{gen, Scene};
use scion_tests::cases::{compare, real_scene, scenes_dir, RayKind, TreeKind, REAL_SCENES};
use std::time::Instant;

/// The backends under test, each compared with the reference on every (scene, tree, rays).
const BACKENDS: &[BackendKind] = &[
    BackendKind::Reference,
    BackendKind::Interp(0),
    BackendKind::Interp(1),
    // The full DSL pipeline (mem-inline, const-fold, mem-cse, dce) at the tree level.
    BackendKind::Interp(3),
    // The GPU pipeline emulated on the CPU: the kernels of `scion trace --device gpu` compiled
    // for the host, packed and traced by scion-cuda's own pipeline (the four layouts the GPU
    // check runs; docs/gpu.md).
    BackendKind::GpuEmulated {
        stem: "pbrt",
        stack: JIT_STACK,
    },
    BackendKind::GpuEmulated {
        stem: "ptr",
        stack: JIT_STACK,
    },
    BackendKind::GpuEmulated {
        stem: "pbrt_q16",
        stack: JIT_STACK,
    },
    BackendKind::GpuEmulated {
        stem: "sg_eq",
        stack: JIT_STACK,
    },
];

/// The backends of [`BACKENDS`] and the layouts run through the runtime contract: the
/// hand-written `flat32` of `common`, and closest hit specialized to each library layout that
/// (every one; the quantized `pbrt_q16` and `sg_eq` against the reference traversal of their decoded boxes,
/// `Boxes::decoded_tree`), run by the interpreter at the mem level (scenes up to 2 k triangles,
/// the first 32 rays of each row: `Backend::max_rays`) and compiled by the Cranelift JIT (every
/// scene).
fn backends() -> Vec<Box<dyn Backend>> {
    let mut all: Vec<Box<dyn Backend>> = BACKENDS
        .iter()
        .map(|b| b.instantiate(2).unwrap_or_else(|e| panic!("{b:?}: {e}")))
        .collect();
    all.push(Box::new(
        LayoutBackend::new(Box::new(common::Flat32), 2).expect("threads"),
    ));
    // Closest hit specialized to each library layout, interpreted at the mem level.
    for &(stem, name, _) in library_layouts() {
        // Debug builds interpret slowly: pbrt only.
        if release() || stem == "pbrt" {
            let b = MemInterpBackend::new(stem, name, 2).unwrap_or_else(|e| panic!("{stem}: {e}"));
            all.push(Box::new(b));
        }
    }
    // The same, lowered to `lo` and compiled by Cranelift: every layout, every row, with
    // a stack of 256 entries so that the deepest hard case (depth 69) is compared too (the
    // default 64 and its overflow status are tested in tests/jit.rs and the CLI tests).
    for &(stem, name, _) in library_layouts() {
        let code = JitClosestHit::compile(stem, name, Some(JIT_STACK))
            .unwrap_or_else(|e| panic!("jit {stem}: {e}"));
        all.push(Box::new(
            LayoutBackend::new(Box::new(code), 2).expect("threads"),
        ));
    }
    // And by LLVM's JIT at -O3: every layout, the same stack.
    for &(stem, _, _) in library_layouts() {
        let b = BackendKind::Llvm {
            stem,
            stack: JIT_STACK,
        };
        all.push(b.instantiate(2).unwrap_or_else(|e| panic!("{b:?}: {e}")));
    }
    all
}

/// Entries of the JIT rows' traversal stack.
const JIT_STACK: u32 = 256;

/// Where a row's scene comes from.
#[derive(Clone, Copy, Debug)]
enum SceneSource {
    /// The repository's `scenes/NAME.obj.gz`.
    Real(&'static str),
    /// Position in `scene::gen::hard_cases()`.
    Hard(usize),
}

/// One row of the table, without its backend (every backend runs on every row).
#[derive(Clone, Copy, Debug)]
struct Row {
    scene: SceneSource,
    tree: TreeKind,
    rays: RayKind,
    n: usize,
    seed: u64,
}

fn release() -> bool {
    !cfg!(debug_assertions)
}

/// The rows: every hard case with SAH and median trees and all four ray kinds (128 rays each
/// in release, 32 in debug); every real scene (small ones in debug builds) with an SAH tree
/// (also SAH-4 and median under 2 k triangles), primary and secondary rays, plus axis and
/// feature rays under 50 k triangles.
fn rows() -> Vec<Row> {
    let mut rows = Vec::new();
    // Debug builds interpret about 20 times slower: half the rays, small real scenes only.
    let k = if release() { 4 } else { 1 };
    for (i, _) in gen::hard_cases().iter().enumerate() {
        for tree in [TreeKind::Sah15, TreeKind::Median] {
            for rays in [
                RayKind::Primary,
                RayKind::Secondary,
                RayKind::Axis,
                RayKind::Features,
            ] {
                rows.push(Row {
                    scene: SceneSource::Hard(i),
                    tree,
                    rays,
                    n: 32 * k,
                    seed: 7 + i as u64,
                });
            }
        }
    }
    assert!(
        scenes_dir().is_some(),
        "no real scenes: the repository's scenes/ folder is missing, or SCION_SCENES names a \
         folder without them"
    );
    for info in REAL_SCENES {
        let (name, tris) = (info.name, info.triangles);
        if tris > 20_000 && !release() {
            println!("SKIPPED in debug builds: {name} ({tris} triangles)");
            continue;
        }
        let small = tris < 50_000;
        let mut kinds = vec![(RayKind::Primary, 32 * k), (RayKind::Secondary, 16 * k)];
        if small {
            kinds.push((RayKind::Axis, 16 * k));
            kinds.push((RayKind::Features, 16 * k));
        }
        let mut trees = vec![TreeKind::Sah15];
        if tris < 2_000 {
            trees.push(TreeKind::Sah4);
            trees.push(TreeKind::Median);
        }
        for &tree in &trees {
            for &(rays, n) in &kinds {
                rows.push(Row {
                    scene: SceneSource::Real(name),
                    tree,
                    rays,
                    n,
                    seed: 42,
                });
            }
        }
    }
    rows
}

fn load(src: SceneSource, hard: &[Scene]) -> Scene {
    match src {
        SceneSource::Real(name) => real_scene(name).unwrap_or_else(|e| panic!("{e}")),
        SceneSource::Hard(i) => hard[i].clone(),
    }
}

#[test]
fn backends_agree_with_the_reference() {
    let start = Instant::now();
    let backends = backends();
    let driver = BatchDriver::new(2).unwrap();
    let hard = gen::hard_cases();
    let rows = rows();
    let mut failures = Vec::new();
    let (mut compared, mut hits, mut pruned, mut overflows) = (0usize, 0usize, 0usize, 0usize);
    // Consecutive rows share a scene and a tree: load and build once.
    let mut current: Option<(String, TreeKind, Scene, LogicalTree)> = None;
    for row in &rows {
        let key = format!("{:?}", row.scene);
        if current
            .as_ref()
            .is_none_or(|(k, t, _, _)| *k != key || *t != row.tree)
        {
            let scene = load(row.scene, &hard);
            let tree = row.tree.build(&scene);
            tree.validate_with_cap(15)
                .unwrap_or_else(|e| panic!("{key} {:?}: invalid tree: {e}", row.tree));
            current = Some((key, row.tree, scene, tree));
        }
        let (_, _, scene, tree) = current.as_ref().expect("set above");
        let rays: Vec<Ray> = row.rays.rays(scene, row.n, row.seed);
        let tree_ref = closest_hits_tree(tree, &rays, &driver);
        let brute = closest_hits_brute(&scene.triangles, &rays, &driver);
        // A quantized layout's reference: the traversal of the tree with its decoded boxes.
        let mut decoded: Vec<(Boxes, LogicalTree, Vec<Hit>)> = Vec::new();
        for b in &backends {
            if b.max_triangles().is_some_and(|m| scene.len() > m) {
                continue;
            }
            // An interpreter gets the row's first rays only (every layout and ray kind still).
            let n = b.max_rays().map_or(rays.len(), |m| m.min(rays.len()));
            let what = format!(
                "{} {:?} {:?} x{} {}",
                scene.name,
                row.tree,
                row.rays,
                n,
                b.name()
            );
            let got = match b.trace(&scene.triangles, tree, &rays[..n]) {
                Ok(g) => g,
                Err(e) => {
                    // A bounded stack may overflow on a tree deeper than it, and must say so.
                    let deep = b.stack_limit().is_some_and(|l| tree_depth(tree) > l);
                    if deep && e.contains("stack overflow") {
                        overflows += 1;
                        println!("stack overflow (tree depth {}): {what}", tree_depth(tree));
                    } else {
                        failures.push(format!("{what}: {e}"));
                    }
                    continue;
                }
            };
            let boxes = b.boxes();
            let (tree, tree_ref) = if boxes == Boxes::Exact {
                (tree, &tree_ref)
            } else {
                if !decoded.iter().any(|d| d.0 == boxes) {
                    let t = boxes.decoded_tree(tree).into_owned();
                    let r = closest_hits_tree(&t, &rays, &driver);
                    decoded.push((boxes, t, r));
                }
                let d = decoded.iter().find(|d| d.0 == boxes).expect("pushed above");
                (&d.1, &d.2)
            };
            match compare(&what, tree, &rays[..n], &got, &tree_ref[..n], &brute[..n]) {
                Ok(a) => {
                    compared += a.rays;
                    hits += a.hits;
                    pruned += a.pruned;
                }
                Err(e) => failures.push(e),
            }
        }
    }
    println!(
        "{} rows x {} backends: {compared} rays compared, {hits} hits, {pruned} explained by \
         pruning, {overflows} rows with a reported stack overflow on a deep tree, {:.1} s",
        rows.len(),
        backends.len(),
        start.elapsed().as_secs_f64()
    );
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
    assert!(hits > 0, "no row hit anything: the rays miss every scene");
}

/// The oracle's own failure modes are errors, not panics or wrong results.
#[test]
fn oracle_reports_bad_programs() {
    let bad = scion_host::oracle::ClosestHit::compile_source(
        "bad.scion",
        "func closest_hit(ray: Ray, bvh: BVH, best: mut (f32, u32)) = nope",
        1,
    );
    let e = bad.err().expect("an undefined name is a compile error");
    assert!(e.contains("error"), "{e}");
    let none = scion_host::oracle::ClosestHit::compile_source(
        "other.scion",
        "func other(x: f32) -> f32 = x",
        0,
    );
    assert!(none.err().expect("no closest_hit").contains("closest_hit"));
}

/// The empty scene: every ray misses, without running the program.
#[test]
fn empty_scene_misses() {
    let p = scion_host::oracle::ClosestHit::compile(1).unwrap();
    let tree = LogicalTree::<scion_runtime::geom::Triangle>::empty();
    let rays = vec![Ray::new(
        scion_runtime::geom::Vec3::new(0.0, 0.0, 0.0),
        scion_runtime::geom::Vec3::new(0.0, 0.0, 1.0),
    )];
    let hits = p.trace_all(&tree, &rays, 2).unwrap();
    assert!(hits[0].bit_eq(&scion_runtime::geom::Hit::MISS));
}

/// The harness catches a wrong backend: the tie rule reversed (largest id wins on equal `t`)
/// differs from the reference on duplicated triangles, and `compare` says where.
#[test]
fn a_wrong_tie_rule_is_caught() {
    use scion_host::oracle::{ClosestHit, CLOSEST_HIT};
    let mutated = CLOSEST_HIT.replace("h[1] < best[1]", "h[1] > best[1]");
    assert_ne!(mutated, CLOSEST_HIT, "the mutation must apply");
    let p = ClosestHit::compile_source("mutated.scion", &mutated, 1).unwrap();
    let scene = gen::duplicated(&gen::quad_grid(4, 4), 3);
    let tree = TreeKind::Sah15.build(&scene);
    let rays = RayKind::Primary.rays(&scene, 64, 1);
    let driver = BatchDriver::sequential();
    let tree_ref = closest_hits_tree(&tree, &rays, &driver);
    let brute = closest_hits_brute(&scene.triangles, &rays, &driver);
    let got = p.trace_all(&tree, &rays, 1).unwrap();
    let e = compare("mutated", &tree, &rays, &got, &tree_ref, &brute).unwrap_err();
    assert!(e.contains("reference traversal"), "{e}");
}

/// An interpreter failure names the ray by its index in the whole batch, whatever thread ran
/// it.
#[test]
fn interpreter_errors_name_the_ray() {
    use scion_host::oracle::{ClosestHit, CLOSEST_HIT};
    use scion_runtime::geom::Vec3;
    let mutated = CLOSEST_HIT.replace("best = h;", "best = (h[0], h[1] / (h[1] - h[1]));");
    assert_ne!(mutated, CLOSEST_HIT, "the mutation must apply");
    let p = ClosestHit::compile_source("div0.scion", &mutated, 0).unwrap();
    let scene = gen::one_triangle();
    let tree = TreeKind::Sah15.build(&scene);
    let c = scene.bounds().center();
    let away = Ray::new(Vec3::new(1e3, 1e3, 1e3), Vec3::new(1.0, 0.0, 0.0));
    let mut rays = vec![away; 8];
    // Rays 5 and 7 hit the triangle from both sides of its plane.
    let n = {
        let t = &scene.triangles[0];
        (t.p1 - t.p0).cross(t.p2 - t.p0)
    };
    rays[5] = Ray::new(c + n, n * -1.0);
    rays[7] = rays[5];
    let e = p.trace_all(&tree, &rays, 2).unwrap_err();
    assert!(e.starts_with("ray 5: "), "{e}");
    assert!(e.contains("division by zero"), "{e}");
}

/// The mem-level interpreter keeps the last tree it packed for the next traces (the table's
/// rows share trees); a trace of another tree packs that one, and going back packs the first
/// again: every trace equals the reference of its own tree.
#[test]
fn the_mem_interpreter_traces_the_tree_it_is_given() {
    let b = MemInterpBackend::new("pbrt", "LinearBVH", 2).expect("compiles");
    let driver = BatchDriver::new(1).unwrap();
    let scenes = [gen::random_soup(200, 0.1, 3), gen::random_soup(200, 0.1, 4)];
    let trees: Vec<LogicalTree> = scenes.iter().map(|s| TreeKind::Sah4.build(s)).collect();
    let rays = RayKind::Secondary.rays(&scenes[0], 24, 9);
    for k in [0, 1, 0, 0, 1] {
        let got = b.trace(&scenes[k].triangles, &trees[k], &rays).unwrap();
        let want = closest_hits_tree(&trees[k], &rays, &driver);
        let same = got
            .iter()
            .zip(&want)
            .all(|(g, w)| g.t.to_bits() == w.t.to_bits() && g.prim == w.prim);
        assert!(same, "tree {k}: {got:?} against {want:?}");
    }
    let hits = |k: usize| closest_hits_tree(&trees[k], &rays, &driver);
    assert!(
        hits(0).iter().zip(hits(1)).any(|(a, b)| a.prim != b.prim),
        "the two trees give the same hits: the test cannot tell them apart"
    );
}
