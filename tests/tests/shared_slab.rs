//! The shared slab (paper §8.3, layout catalog §7), a reference of several components packed
//! and traced end to end: `lit-tests/Inputs/shared_slab.scion` (16-byte nodes keeping one axis
//! and two planes; the reference `(I, lo, hi)` carries the node's box, the root's from the
//! scene box `build root` stores) built by its generated builder and traced by the library's
//! closest hit through the C entries, by Cranelift and LLVM -O3, and by the GPU kernels emulated
//! on the CPU (`scion_host::gpu_emu`). Its boxes are the parents'
//! with one plane replaced, so they enclose the true boxes: every hit equals the reference
//! traversal over those reconstructed boxes (computed here the way the build chooses the axis)
//! bit for bit, and the reference over the true boxes except where one of the two pruned the
//! other's better hit by the documented rounding exception (`why_pruned`, `why_pruned_with`).

use crate::c_entries;

use scion_host::gpu_emu::EmulatedGpu;
use scion_host::jit::{Codegen, LoOptions};
use scion_host::mem_interp::Program;
use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::{Aabb, Vec3};
use scion_runtime::reference::prelude::distmin_of;
use scion_runtime::reference::{
    closest_hit_tree_stats, closest_hit_with, why_pruned, why_pruned_with, TraversalStats,
};
use scion_tests::cases::{hard_and_real, mixed_rays, TreeKind};

/// The library's closest hit with `layout` of the shared slab files.
fn program(layout: &str) -> Program {
    c_entries::program(
        &[
            "library/algorithms/closest_hit.scion",
            "lit-tests/Inputs/shared_slab.scion",
        ],
        layout,
        "closest_hit",
    )
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

#[test]
fn shared_slab_is_packed_and_traced_like_the_reference() {
    traced_like_the_reference("SharedSlab");
}

/// The same nodes with the box carried by `parent.` (the compiler widens the reference with
/// the parent's index, axis and planes): the same boxes, so the same hits.
#[test]
fn shared_slab_with_parent_is_packed_and_traced_like_the_reference() {
    traced_like_the_reference("SharedSlabParent");
}

fn traced_like_the_reference(layout: &str) {
    // 2048 entries: the carried reference takes 96 bytes of the thread's stack per entry.
    let lo = c_entries::host_lo_stack(&program(layout), 2048);
    let nodes: Vec<u64> = lo
        .entry
        .buffers
        .iter()
        .filter(|b| b.name == "nodes")
        .map(|b| b.stride)
        .collect();
    assert_eq!(nodes, [16], "{:?}", lo.entry.buffers);
    let (mut compared, mut exceptions, mut visits) = (0, 0, (0u64, 0u64));
    // The C entries by Cranelift and LLVM, and the GPU kernels emulated on the CPU.
    let gpu = EmulatedGpu::compile_program(
        &program(layout),
        &LoOptions {
            stack_size: Some(2048),
            opt_level: 3,
            dsl_opt: true,
            target: scion_compiler::abi::EntryTarget::Gpu,
        },
        Codegen::Llvm(3),
        2,
    )
    .and_then(EmulatedGpu::into_pipeline)
    .unwrap();
    for engine in ["cranelift", "llvm", "gpu-emulated"] {
        let code = match engine {
            "cranelift" => Some(Codegen::Cranelift.backend().jit(&lo.module).unwrap()),
            "llvm" => Some(Codegen::Llvm(3).backend().jit(&lo.module).unwrap()),
            _ => None,
        };
        for (i, scene) in hard_and_real(&["teapot", "suzanne"]).iter().enumerate() {
            for kind in [TreeKind::Sah4, TreeKind::Median] {
                let tree = kind.build(scene);
                if tree.is_empty() {
                    continue;
                }
                let boxes = slab_boxes(&tree);
                let rays = mixed_rays(scene, i as u64);
                let hits = match &code {
                    Some(code) => {
                        c_entries::closest_hits(&lo, code.as_ref(), &tree, "closest_hit", &rays)
                    }
                    None => {
                        let packed = gpu.pack(&tree, tree.stats().depth).unwrap();
                        let on_device = gpu.upload_rays(&rays).unwrap();
                        gpu.trace(&packed, &on_device).unwrap().hits
                    }
                };
                for (k, (ray, got)) in rays.iter().zip(&hits).enumerate() {
                    let (mut s_slab, mut s_box) =
                        (TraversalStats::default(), TraversalStats::default());
                    let want = closest_hit_with(&tree, ray, &mut s_slab, |r, i, tmax| {
                        distmin_of(r, &boxes[i as usize], tmax)
                    });
                    let exact = closest_hit_tree_stats(&tree, ray, &mut s_box);
                    assert!(
                        got.bit_eq(&want),
                        "{engine} {} {kind:?} ray {k} {ray:?}: {got:?}, the reference over \
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
        "{layout}: {compared} rays, {exceptions} differing from the exact boxes by the rounding exception; \
         nodes visited: slab {} vs exact boxes {} ({:.1} %)",
        visits.0,
        visits.1,
        100.0 * visits.0 as f64 / visits.1 as f64
    );
}
