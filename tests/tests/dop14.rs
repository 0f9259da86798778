//! The DOP-14 case study (paper §8.1, layout catalog §5) packed and traced end to end:
//! `library/layouts/dop14_split.scion` (the hot half of a node in one array, the diagonal slabs
//! in a second) built by its generated builder from the runtime's DOP-14s
//! (`scion_runtime::bvh::dop14`, outward rounded) and traced by
//! `library/algorithms/closest_hit_dop14.scion` through the C entries, by Cranelift and LLVM -O3.
//! Every hit equals the runtime's DOP traversal (`closest_hit_dop14_stats`, the same test in
//! Rust) bit for bit, and the AABB traversal's hits (the diagonal test is conservative); the
//! DOP traversal visits fewer nodes than the AABB one.

use crate::c_entries;

use scion_host::jit::Codegen;
use scion_host::mem_interp::Program;
use scion_runtime::bvh::dop14::node_dops;
use scion_runtime::reference::{closest_hit_dop14_stats, closest_hit_tree_stats, TraversalStats};
use scion_tests::cases::{hard_and_real, mixed_rays, TreeKind};

fn program() -> Program {
    c_entries::program(
        &[
            "library/algorithms/closest_hit_dop14.scion",
            "library/layouts/dop14_split.scion",
        ],
        "DopSplit",
        "closest_hit_dop14",
    )
}

#[test]
fn dop14_split_is_packed_and_traced_like_the_reference() {
    let lo = c_entries::host_lo(&program());
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
        for (i, scene) in hard_and_real(&["teapot", "suzanne"]).iter().enumerate() {
            for kind in [TreeKind::Sah4, TreeKind::Median] {
                let tree = kind.build(scene);
                if tree.is_empty() {
                    continue;
                }
                let dops = node_dops(&tree);
                let rays = mixed_rays(scene, i as u64);
                let hits =
                    c_entries::closest_hits(&lo, code.as_ref(), &tree, "closest_hit_dop14", &rays);
                for (k, (ray, got)) in rays.iter().zip(&hits).enumerate() {
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
