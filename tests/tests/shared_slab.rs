//! The shared slab (paper §8.3, layout catalog §7), a reference of several components packed
//! and traced end to end: `lit-tests/Inputs/shared_slab.scion` (16-byte nodes keeping one axis
//! and two planes; the reference `(I, lo, hi)` carries the node's box, the root's from the
//! scene box `build root` stores) built by its generated builder and traced by the library's
//! closest hit through the C entries, by Cranelift and LLVM -O3. Its boxes are the parents'
//! with one plane replaced, so they enclose the true boxes: every hit equals the reference
//! traversal over those reconstructed boxes (computed here the way the build chooses the axis)
//! bit for bit, and the reference over the true boxes except where one of the two pruned the
//! other's better hit by the documented rounding exception (`why_pruned`, `why_pruned_with`).

// Calling the generated C entry points needs unsafe (each call carries its SAFETY note).
#![allow(unsafe_code)]

use scion_compiler::abi::EntryTarget;
use scion_host::contract::LogicalTreeView;
use scion_host::jit::{program_lo, Codegen, LoOptions};
use scion_host::mem_interp::Program;
use scion_runtime::bvh::schema::LogicalBytes;
use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::{Aabb, Hit, Ray, Vec3};
use scion_runtime::reference::prelude::distmin_of;
use scion_runtime::reference::{
    closest_hit_tree_stats, closest_hit_with, why_pruned, why_pruned_with, TraversalStats,
};
use scion_runtime::scene::{gen, Scene};
use scion_tests::cases::{real_scene, RayKind, TreeKind};
use std::path::PathBuf;

type SizesFn = unsafe extern "C" fn(*const LogicalTreeView, *mut u64);
type BuildFn = unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> i32;
type RootFn = unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> u32;
type BatchFn =
    unsafe extern "C" fn(*const *const u8, *const Ray, *mut (f32, u32), u64, u64, u32) -> i32;

fn program() -> Program {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let read = |rel: &str| std::fs::read_to_string(root.join(rel)).expect(rel);
    Program {
        files: vec![
            (
                "closest_hit.scion".to_string(),
                read("library/algorithms/closest_hit.scion"),
            ),
            (
                "shared_slab.scion".to_string(),
                read("lit-tests/Inputs/shared_slab.scion"),
            ),
        ],
        layout: "SharedSlab".to_string(),
        algorithm: "closest_hit".to_string(),
    }
}

fn aligned(size: usize) -> (Vec<u8>, usize) {
    let bytes = vec![0u8; size + 128];
    let off = bytes.as_ptr().align_offset(64);
    (bytes, off)
}

/// The boxes the layout reconstructs: the root's is its own (the scene box), a child's its
/// parent's with the plane of the build's axis replaced by the child's own (the layout file's
/// `slab_axis`, in the same `f32` arithmetic).
fn slab_boxes(tree: &LogicalTree) -> Vec<Aabb> {
    let mut boxes = vec![Aabb::EMPTY; tree.nodes.len()];
    if tree.is_empty() {
        return boxes;
    }
    boxes[tree.root as usize] = tree.nodes[tree.root as usize].aabb();
    let mut work = vec![tree.root];
    while let Some(i) = work.pop() {
        let n = &tree.nodes[i as usize];
        if n.is_leaf() {
            continue;
        }
        let [l, r] = n.child;
        let (b, lb, rb) = (
            n.aabb(),
            tree.nodes[l as usize].aabb(),
            tree.nodes[r as usize].aabb(),
        );
        let cut = (b.high - lb.high) + (rb.low - b.low);
        let axis = if cut.x >= cut.y && cut.x >= cut.z {
            0
        } else if cut.y >= cut.z {
            1
        } else {
            2
        };
        let with = |v: Vec3, x: f32| {
            let mut a = v.to_array();
            a[axis] = x;
            Vec3::from_array(a)
        };
        let p = boxes[i as usize];
        boxes[l as usize] = Aabb::new(p.low, with(p.high, lb.high.axis(axis)));
        boxes[r as usize] = Aabb::new(with(p.low, rb.low.axis(axis)), p.high);
        work.extend([l, r]);
    }
    boxes
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
fn shared_slab_is_packed_and_traced_like_the_reference() {
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
    let nodes: Vec<u64> = lo
        .entry
        .buffers
        .iter()
        .filter(|b| b.name == "nodes")
        .map(|b| b.stride)
        .collect();
    assert_eq!(nodes, [16], "{:?}", lo.entry.buffers);
    let (mut compared, mut exceptions, mut visits) = (0, 0, (0u64, 0u64));
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
                let boxes = slab_boxes(&tree);
                let mut rays = RayKind::Secondary.rays(scene, 300, i as u64);
                rays.extend(RayKind::Primary.rays(scene, 256, i as u64));
                rays.extend(RayKind::Axis.rays(scene, 100, i as u64));
                rays.extend(RayKind::Features.rays(scene, 200, 0));
                let bytes = LogicalBytes::fill(&tree, &lo.entry.logical).unwrap();
                let view = LogicalTreeView::new(&tree, &bytes).unwrap();
                let mut hits: Vec<(f32, u32)> = rays.iter().map(|r| (r.tmax, u32::MAX)).collect();
                // SAFETY: the entries have docs/c-abi.md's signatures for a `u32` reference (the
                // placed component); the view describes the live tree; every buffer has the size
                // `sizes` gave and is 64-byte aligned; `rays` and `hits` have `n` elements of the
                // 32-byte query and the 8-byte (f32, u32) result.
                unsafe {
                    let sizes =
                        std::mem::transmute::<*const u8, SizesFn>(f("scion_SharedSlab_sizes"));
                    let build =
                        std::mem::transmute::<*const u8, BuildFn>(f("scion_SharedSlab_build"));
                    let root = std::mem::transmute::<*const u8, RootFn>(f("scion_SharedSlab_root"));
                    let batch = std::mem::transmute::<*const u8, BatchFn>(f(
                        "scion_closest_hit_SharedSlab",
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
                    let (mut s_slab, mut s_box) =
                        (TraversalStats::default(), TraversalStats::default());
                    let want = closest_hit_with(&tree, ray, &mut s_slab, |r, i, tmax| {
                        distmin_of(r, &boxes[i as usize], tmax)
                    });
                    let exact = closest_hit_tree_stats(&tree, ray, &mut s_box);
                    assert!(
                        got.bit_eq(&want),
                        "{codegen:?} {} {kind:?} ray {k} {ray:?}: {got:?}, the reference over \
                         the slab boxes {want:?}",
                        scene.name
                    );
                    if !want.bit_eq(&exact) {
                        // One traversal pruned the other's better hit (smaller t, or equal t
                        // and smaller id) by the rounding exception: that hit's node's entry
                        // distance exceeds its computed t, in the boxes of the one that missed.
                        let slab_better = (want.t, want.prim) < (exact.t, exact.prim);
                        let explained = if slab_better {
                            why_pruned(&tree, ray, want.prim, want.t).is_some()
                        } else {
                            why_pruned_with(&tree, ray, exact.prim, exact.t, |i| boxes[i as usize])
                                .is_some()
                        };
                        assert!(
                            explained,
                            "{} {kind:?} ray {k} {ray:?}: slab {want:?}, exact boxes {exact:?}",
                            scene.name
                        );
                        exceptions += 1;
                    }
                    visits.0 += s_slab.nodes_visited;
                    visits.1 += s_box.nodes_visited;
                    compared += 1;
                }
            }
        }
    }
    assert!(compared > 20_000, "{compared} rays");
    assert!(visits.0 >= visits.1, "looser boxes never visit fewer nodes");
    eprintln!(
        "{compared} rays, {exceptions} differing from the exact boxes by the rounding exception; \
         nodes visited: slab {} vs exact boxes {} ({:.1} %)",
        visits.0,
        visits.1,
        100.0 * visits.0 as f64 / visits.1 as f64
    );
}
