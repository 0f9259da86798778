//! The generated program does the work the reference counts: closest hit specialized to a
//! library layout, run by the `mem` interpreter with its calls counted, calls
//! `closest_hit_node` once per node it reaches, `distmin` (the four-lane slab test over the
//! prepared ray) once per root box test and `distmin_pair` (a node's two children on eight
//! lanes) once per two box tests, and `hit_lanes` (four triangles at once) once per run of up to four of a
//! leaf's triangles, exactly as often as `scion_runtime::reference::closest_hit_tree_stats`
//! counts nodes visited and skipped, box tests and leaf runs on the tree the layout traverses (decoded boxes for a quantized
//! layout). So `scion trace --stats`, which reports the reference's counters, reports what the
//! generated code does, node for node.

use scion_host::mem_interp::{library_layouts, MemClosestHit};
use scion_host::quantized::DecodedTree;
use scion_runtime::reference::{closest_hit_tree_stats, TraversalStats};
use scion_runtime::scene::gen;
use scion_tests::cases::{RayKind, TreeKind};

#[test]
fn generated_code_visits_what_the_reference_counts() {
    let scene = gen::random_soup(300, 0.08, 21);
    let tree = TreeKind::Sah4.build(&scene);
    let mut rays = RayKind::Primary.rays(&scene, 100, 3);
    rays.extend(RayKind::Secondary.rays(&scene, 100, 4));
    rays.extend(RayKind::Axis.rays(&scene, 50, 5));
    for &(stem, name, boxes) in library_layouts()
        .iter()
        .filter(|l| ["pbrt", "ptr", "pbrt_q16"].contains(&l.0))
    {
        let program = MemClosestHit::compile(stem, name).unwrap();
        let calls = program.call_profile(&tree, &rays).unwrap();
        let count = |f: &str| calls.iter().find(|c| c.0 == f).map_or(0, |c| c.1);
        let mut want = TraversalStats::default();
        let traversed = boxes.decoded_tree(&tree);
        for r in &rays {
            closest_hit_tree_stats(&traversed, r, &mut want);
        }
        assert!(
            want.triangles_tested > 0 && want.nodes_pruned > 0,
            "{stem}: {want:?}"
        );
        assert_eq!(
            count("closest_hit_node"),
            want.nodes_visited + want.nodes_pruned,
            "{stem}: nodes reached ({calls:?})"
        );
        // The root's box test is `distmin` of `SlabLanes` (numbered `distmin.2` among the
        // prelude's overloads; any `distmin` counts), a node's two children's one
        // `distmin_pair`.
        let box_tests: u64 = calls
            .iter()
            .filter(|c| c.0 == "distmin" || c.0.starts_with("distmin."))
            .map(|c| c.1)
            .sum::<u64>()
            + 2 * count("distmin_pair");
        assert_eq!(box_tests, want.boxes_tested, "{stem}: box tests");
        assert_eq!(count("hit_lanes"), want.leaf_runs, "{stem}: leaf runs");
    }
}
