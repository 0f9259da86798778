//! The DOP-14 case study (paper §8.1, layout catalog §5) packed and traced end to end:
//! `library/layouts/dop14_split.scion` (the hot half of a node in one array, the diagonal slabs
//! in a second) built by its generated builder from the runtime's DOP-14s
//! (`scion_runtime::bvh::dop14`, outward rounded) and traced by
//! `library/algorithms/closest_hit_dop14.scion` through the C entries, by Cranelift and LLVM -O3.
//! Every hit equals the runtime's DOP traversal (`closest_hit_dop14_stats`, the same test in
//! Rust) bit for bit, and the AABB traversal's hits (the diagonal test is conservative); the
//! DOP traversal visits fewer nodes than the AABB one.

// Calling the generated C entry points needs unsafe (each call carries its SAFETY note).
#![allow(unsafe_code)]

use scion_compiler::abi::EntryTarget;
use scion_host::contract::LogicalTreeView;
use scion_host::jit::{program_lo, Codegen, LoOptions};
use scion_host::mem_interp::Program;
use scion_runtime::bvh::dop14::node_dops;
use scion_runtime::bvh::schema::LogicalBytes;
use scion_runtime::geom::{Hit, Ray};
use scion_runtime::reference::{closest_hit_dop14_stats, closest_hit_tree_stats, TraversalStats};
use scion_runtime::scene::{gen, Scene};
use scion_tests::cases::{real_scene, RayKind, TreeKind};
use std::path::PathBuf;

type SizesFn = unsafe extern "C" fn(*const LogicalTreeView, *mut u64);
type BuildFn = unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> i32;
type RootFn = unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> u32;
type BatchFn =
    unsafe extern "C" fn(*const *const u8, *const Ray, *mut (f32, u32), u64, u64, u32) -> i32;

fn program() -> Program {
    let lib = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../library");
    let read = |rel: &str| std::fs::read_to_string(lib.join(rel)).expect(rel);
    Program {
        files: vec![
            (
                "closest_hit_dop14.scion".to_string(),
                read("algorithms/closest_hit_dop14.scion"),
            ),
            (
                "dop14_split.scion".to_string(),
                read("layouts/dop14_split.scion"),
            ),
        ],
        layout: "DopSplit".to_string(),
        algorithm: "closest_hit_dop14".to_string(),
    }
}

fn aligned(size: usize) -> (Vec<u8>, usize) {
    let bytes = vec![0u8; size + 128];
    let off = bytes.as_ptr().align_offset(64);
    (bytes, off)
}

fn scenes() -> Vec<Scene> {
    let mut scenes = gen::hard_cases();
    for name in ["teapot", "suzanne"] {
        if let Ok(s) = real_scene(name) {
            scenes.push(s);
        }
    }
    scenes
}

#[test]
fn dop14_split_is_packed_and_traced_like_the_reference() {
    let lo = program_lo(
        &program(),
        &LoOptions {
            stack_size: Some(4096),
            opt_level: 3,
            dsl_opt: true,
            target: EntryTarget::Host,
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    // The node group's two arrays are two buffers of 32-byte records.
    let nodes: Vec<(&str, u64)> = lo
        .entry
        .buffers
        .iter()
        .filter(|b| b.name.starts_with("nodes"))
        .map(|b| (b.name.as_str(), b.stride))
        .collect();
    assert_eq!(nodes.len(), 2, "{:?}", lo.entry.buffers);
    assert!(nodes.iter().all(|n| n.1 == 32), "{nodes:?}");
    let mut visits = (0u64, 0u64);
    let mut compared = 0;
    for codegen in [Codegen::Cranelift, Codegen::Llvm(3)] {
        let code = codegen.backend().jit(&lo.module).unwrap();
        let f = |name: &str| {
            code.function_ptr(name)
                .unwrap_or_else(|| panic!("no `@{name}`"))
        };
        for (i, scene) in scenes().iter().enumerate() {
            for kind in [TreeKind::Sah4, TreeKind::Median] {
                let tree = kind.build(scene);
                if tree.is_empty() {
                    continue;
                }
                let dops = node_dops(&tree);
                let mut rays = RayKind::Secondary.rays(scene, 300, i as u64);
                rays.extend(RayKind::Primary.rays(scene, 256, i as u64));
                rays.extend(RayKind::Axis.rays(scene, 100, i as u64));
                rays.extend(RayKind::Features.rays(scene, 200, 0));
                let bytes = LogicalBytes::fill(&tree, &lo.entry.logical).unwrap();
                let view = LogicalTreeView::new(&tree, &bytes).unwrap();
                let mut hits = vec![(0f32, 0u32); rays.len()];
                for (h, r) in hits.iter_mut().zip(&rays) {
                    *h = (r.tmax, u32::MAX);
                }
                // SAFETY: the entries have docs/c-abi.md's signatures for a `u32` reference; the
                // view describes the live tree; every buffer has the size `sizes` gave and is
                // 64-byte aligned; `rays` and `hits` have `n` elements of the 32-byte query and
                // the 8-byte (f32, u32) result.
                unsafe {
                    let sizes = std::mem::transmute::<*const u8, SizesFn>(f("scion_DopSplit_sizes"));
                    let build = std::mem::transmute::<*const u8, BuildFn>(f("scion_DopSplit_build"));
                    let root = std::mem::transmute::<*const u8, RootFn>(f("scion_DopSplit_root"));
                    let batch = std::mem::transmute::<*const u8, BatchFn>(f(
                        "scion_closest_hit_dop14_DopSplit",
                    ));
                    let mut sz = vec![0u64; lo.entry.buffers.len()];
                    sizes(&view, sz.as_mut_ptr());
                    let mut bufs: Vec<(Vec<u8>, usize)> =
                        sz.iter().map(|&s| aligned(s as usize)).collect();
                    let table: Vec<*mut u8> =
                        bufs.iter_mut().map(|(b, o)| b.as_mut_ptr().add(*o)).collect();
                    assert_eq!(build(&view, table.as_ptr()), 0, "build");
                    let ctable: Vec<*const u8> = table.iter().map(|&p| p as *const u8).collect();
                    let r = root(&view, table.as_ptr());
                    let n = rays.len() as u64;
                    assert_eq!(
                        batch(ctable.as_ptr(), rays.as_ptr(), hits.as_mut_ptr(), 0, n, r),
                        0,
                        "batch status"
                    );
                }
                for (k, (ray, got)) in rays.iter().zip(&hits).enumerate() {
                    let got = Hit::from_best(got.0, got.1);
                    let mut s_dop = TraversalStats::default();
                    let mut s_box = TraversalStats::default();
                    let want = closest_hit_dop14_stats(&tree, &dops, ray, &mut s_dop);
                    let aabb = closest_hit_tree_stats(&tree, ray, &mut s_box);
                    assert!(
                        got.bit_eq(&want),
                        "{codegen:?} {} {kind:?} ray {k} {ray:?}: {got:?}, the DOP reference {want:?}",
                        scene.name
                    );
                    assert!(
                        want.bit_eq(&aabb),
                        "{} {kind:?} ray {k} {ray:?}: DOP {want:?}, AABB {aabb:?}",
                        scene.name
                    );
                    visits.0 += s_dop.nodes_visited;
                    visits.1 += s_box.nodes_visited;
                    compared += 1;
                }
            }
        }
    }
    assert!(compared > 20_000, "{compared} rays");
    assert!(
        visits.0 < visits.1,
        "the DOP traversal visits {} nodes, the AABB one {}",
        visits.0,
        visits.1
    );
    eprintln!(
        "{compared} rays; nodes visited: DOP {} vs AABB {} ({:.1} %)",
        visits.0,
        visits.1,
        100.0 * visits.0 as f64 / visits.1 as f64
    );
}
