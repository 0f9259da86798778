//! `--builders`: the trees the builders make, compared with the traversal held fixed: Scion's
//! binned SAH with and without its insertion-based optimization and its leaf collapse for runs
//! of four (`scion_runtime::bvh::collapse`), and the peers'. Each peer's
//! binary BVH over the workload's triangles is read back as a logical tree
//! (`scion_bench::foreign_tree`), and for Scion's binned SAH tree and each of them the table gives
//! the node counts, depth, the SAH cost (traversal and triangle cost 1, relative to the root's
//! area: `scion_runtime::bvh::TreeStats`) and the work of the runtime's reference traversal (the
//! library's closest hit: box tests, nodes, triangles, and leaf runs of up to four) per ray on
//! the workload's rays. Embree's tree is not exposed by its API.

use crate::{obvhs_peer, tinybvh_peer};
use scion_bench::Workload;
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::{build_sah_binned, SahOptions};
use scion_runtime::reference::closest_hits_tree_stats;
use std::fmt::Write as _;

/// The table (markdown).
pub fn report(w: &Workload, driver: &BatchDriver) -> Result<String, String> {
    let one = SahOptions {
        block: 1,
        ..SahOptions::default()
    };
    let plain = SahOptions {
        reinsertion_passes: 0,
        ..one
    };
    let trees = [
        (
            "Scion binned SAH without reinsertion",
            build_sah_binned(&w.triangles, &plain),
        ),
        (
            "Scion binned SAH + reinsertion",
            build_sah_binned(&w.triangles, &one),
        ),
        (
            "Scion binned SAH + reinsertion + leaves collapsed for runs of four (default)",
            build_sah_binned(&w.triangles, &SahOptions::default()),
        ),
        (
            "tinybvh BVH::Build (binned SAH)",
            tinybvh_peer::logical_tree(&w.triangles)?,
        ),
        (
            "obvhs medium_build (PLOC + reinsertion)",
            obvhs_peer::logical_tree(&w.triangles)?,
        ),
    ];
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Scene {} ({} triangles), {} {} rays; the library's closest hit (reference traversal) on each tree.\n",
        w.scene,
        w.triangles.len(),
        w.rays.len(),
        w.kind.name()
    );
    let _ = writeln!(
        s,
        "| builder | nodes | leaves | largest leaf | depth | SAH cost | box tests/ray | nodes visited/ray | triangle tests/ray | leaf runs/ray |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let per = |x: u64| x as f64 / w.rays.len().max(1) as f64;
    for (name, tree) in &trees {
        tree.validate_with_cap(usize::MAX)
            .map_err(|e| format!("{name}: {e}"))?;
        let st = tree.stats();
        let k = closest_hits_tree_stats(tree, &w.rays, driver);
        let _ = writeln!(
            s,
            "| {name} | {} | {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} |",
            st.nodes,
            st.leaves,
            st.max_leaf,
            st.depth,
            st.sah_cost,
            per(k.boxes_tested),
            per(k.nodes_visited),
            per(k.triangles_tested),
            per(k.leaf_runs)
        );
    }
    Ok(s)
}
