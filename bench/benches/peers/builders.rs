//! `--builders`: the trees the builders make, compared with the traversal held fixed. Each peer's
//! binary BVH over the workload's triangles is read back as a logical tree
//! (`scion_bench::foreign_tree`), and for Scion's binned SAH tree and each of them the table gives
//! the node counts, depth, the SAH cost (traversal and triangle cost 1, relative to the root's
//! area: `scion_runtime::bvh::TreeStats`) and the work of the runtime's reference traversal (the
//! library's closest hit) per ray on the workload's rays. Embree's tree is not exposed by its API.

use crate::{obvhs_peer, tinybvh_peer};
use scion_bench::Workload;
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::LogicalTree;
use scion_runtime::reference::{closest_hit_tree_stats, TraversalStats};
use std::fmt::Write as _;
use std::sync::Mutex;

fn work(tree: &LogicalTree, w: &Workload, driver: &BatchDriver) -> TraversalStats {
    let total = Mutex::new(TraversalStats::default());
    driver.run(w.rays.len(), |begin, end| {
        let mut s = TraversalStats::default();
        for r in &w.rays[begin..end] {
            closest_hit_tree_stats(tree, r, &mut s);
        }
        total.lock().unwrap_or_else(|p| p.into_inner()).add(&s);
    });
    total.into_inner().unwrap_or_else(|p| p.into_inner())
}

/// The table (markdown).
pub fn report(w: &Workload, driver: &BatchDriver) -> Result<String, String> {
    let trees = [
        ("Scion binned SAH (32 bins, leaves <= 15)", w.tree.clone()),
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
        "| builder | nodes | leaves | largest leaf | depth | SAH cost | box tests/ray | nodes visited/ray | triangle tests/ray |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    let per = |x: u64| x as f64 / w.rays.len().max(1) as f64;
    for (name, tree) in &trees {
        tree.validate_with_cap(usize::MAX)
            .map_err(|e| format!("{name}: {e}"))?;
        let st = tree.stats();
        let k = work(tree, w, driver);
        let _ = writeln!(
            s,
            "| {name} | {} | {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} |",
            st.nodes,
            st.leaves,
            st.max_leaf,
            st.depth,
            st.sah_cost,
            per(k.boxes_tested),
            per(k.nodes_visited),
            per(k.triangles_tested)
        );
    }
    Ok(s)
}
