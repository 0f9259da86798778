//! The layout-free reference for closest-hit ray tracing (paper Figure 4,
//! `library/algorithms/closest_hit.scion`): rays and triangles -> [`Hit`]s, bit for bit what
//! every unquantized layout must return (architecture §6).
//!
//! Two versions with the same arithmetic ([`super::prelude`]):
//! - [`closest_hit_brute`] tests every triangle;
//! - [`closest_hit_tree`] traverses a [`LogicalTree`] exactly as the Scion algorithm does, node
//!   for node and in the same order: `best` starts at `(ray.tmax, u32::MAX)`; the root is
//!   visited iff the ray meets its box before `best.t`; a visited interior node tests both
//!   children's boxes (`distmin(slab_ray(ray), child, best.t)`), skips those that return
//!   `+inf`, and visits the nearer first (the left one on equal distances); a node reached with
//!   entry distance `d > best.t` is skipped (prune on `>` only); a leaf tests its primitives
//!   in order.
//!
//! Tie rule (language notes, "Results and ties"): the smallest `t` wins, and on equal `t` the
//! smallest original primitive id. With it, the result does not depend on the order in which
//! triangles are tested, so brute force and traversal agree whenever pruning never drops the
//! node holding the answer (see docs/runtime.md for the one known exception: rays lying exactly
//! in a box face with a zero direction lane).
//!
//! Results are normalized with [`Hit::from_best`]: a miss is `(+inf, u32::MAX)` whatever the
//! ray's `tmax`.

use super::prelude::{distmin_of, slab_interval, slab_ray};
use crate::batch::BatchDriver;
use crate::bvh::LogicalTree;
use crate::geom::{Hit, Ray, Triangle};
use crate::primitive::Primitive;

/// Counters of one traversal, for comparing layouts' and traversals' work (e.g. extra visits of
/// quantized layouts, paper §9). Each counts what the algorithm does, so generated code that
/// visits the same nodes counts the same.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraversalStats {
    /// Ray-box tests (the root's, and both children's at every visited interior node).
    pub boxes_tested: u64,
    /// Nodes visited (reached with an entry distance `<= best.t`).
    pub nodes_visited: u64,
    /// Nodes skipped when reached because `best.t` had dropped below their entry distance.
    pub nodes_pruned: u64,
    /// Ray-triangle tests.
    pub triangles_tested: u64,
    /// Runs of up to four of a leaf's triangles (`ceil(n / 4)` per leaf visited): the four-lane
    /// tests of the library's closest hit (library/algorithms/closest_hit.scion), which tests
    /// a leaf's triangles four at a time.
    pub leaf_runs: u64,
    /// The most entries ever pending on the traversal stack (the largest over the traversals
    /// added): generated code with a stack of `n` entries overflows exactly when this exceeds
    /// `n`.
    pub max_pending: u64,
}

impl TraversalStats {
    /// Adds another traversal's counters.
    pub fn add(&mut self, o: &TraversalStats) {
        self.boxes_tested += o.boxes_tested;
        self.nodes_visited += o.nodes_visited;
        self.nodes_pruned += o.nodes_pruned;
        self.triangles_tested += o.triangles_tested;
        self.leaf_runs += o.leaf_runs;
        self.max_pending = self.max_pending.max(o.max_pending);
    }
}

/// A LIFO of `(node, entry distance)`: 64 entries inline (no allocation for ordinary trees),
/// then a heap spill for deeper ones, so the reference has no depth limit.
struct NodeStack {
    inline: [(u32, f32); 64],
    len: usize,
    spill: Vec<(u32, f32)>,
}

impl NodeStack {
    fn new() -> NodeStack {
        NodeStack {
            inline: [(0, 0.0); 64],
            len: 0,
            spill: Vec::new(),
        }
    }

    #[inline]
    fn push(&mut self, node: u32, d: f32) {
        if self.len < self.inline.len() {
            self.inline[self.len] = (node, d);
            self.len += 1;
        } else {
            self.spill.push((node, d));
        }
    }

    fn len(&self) -> usize {
        self.len + self.spill.len()
    }

    #[inline]
    fn pop(&mut self) -> Option<(u32, f32)> {
        // Spilled entries were pushed last, so they come off first.
        if let Some(e) = self.spill.pop() {
            return Some(e);
        }
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        Some(self.inline[self.len])
    }
}

/// The algorithm's update of `best` by one primitive (a block of triangles by its nearest).
#[inline]
pub(crate) fn consider<P: Primitive>(ray: &Ray, prim: &P, best: &mut (f32, u32)) {
    let (d, id) = prim.hit(ray);
    if d < f32::INFINITY && (d < best.0 || (d == best.0 && id < best.1)) {
        *best = (d, id);
    }
}

/// Closest hit by testing every triangle.
pub fn closest_hit_brute<P: Primitive>(triangles: &[P], ray: &Ray) -> Hit {
    let mut best = (ray.tmax, u32::MAX);
    for tri in triangles {
        consider(ray, tri, &mut best);
    }
    Hit::from_best(best.0, best.1)
}

/// Closest hit by traversing the logical tree (see the module documentation).
pub fn closest_hit_tree<P: Primitive>(tree: &LogicalTree<P>, ray: &Ray) -> Hit {
    closest_hit_tree_stats(tree, ray, &mut TraversalStats::default())
}

/// [`closest_hit_tree`] that also counts its work into `stats`.
pub fn closest_hit_tree_stats<P: Primitive>(
    tree: &LogicalTree<P>,
    ray: &Ray,
    stats: &mut TraversalStats,
) -> Hit {
    let bounds = |i: u32| tree.nodes[i as usize].aabb();
    closest_hit_with(tree, ray, stats, |r, i, tmax| {
        distmin_of(r, &bounds(i), tmax)
    })
}

/// The traversal of [`closest_hit_tree_stats`] with another bounding volume test:
/// `distmin(r, node, tmax)` is node `node`'s entry distance, or `+inf` when the ray misses it
/// before `tmax` (never NaN).
pub fn closest_hit_with<P: Primitive>(
    tree: &LogicalTree<P>,
    ray: &Ray,
    stats: &mut TraversalStats,
    distmin: impl Fn(&super::prelude::SlabRay, u32, f32) -> f32,
) -> Hit {
    let mut best = (ray.tmax, u32::MAX);
    if tree.is_empty() {
        return Hit::from_best(best.0, best.1);
    }
    let r = slab_ray(ray);
    stats.boxes_tested += 1;
    let d = distmin(&r, tree.root, best.0);
    if d == f32::INFINITY {
        // (distmin is a number or +inf, never NaN: it returns `enter` only when `enter <= exit`.)
        return Hit::from_best(best.0, best.1);
    }
    // An explicit stack replays the recursion's order as generated code does
    // (`recursion-to-stack`): of two children to visit, the farther is pushed and the nearer
    // visited at once; a node without a child to visit pops the next entry.
    let mut stack = NodeStack::new();
    let (mut i, mut d) = (tree.root, d);
    loop {
        let mut next = None;
        if d <= best.0 {
            stats.nodes_visited += 1;
            let node = &tree.nodes[i as usize];
            if node.is_leaf() {
                let prims = tree.leaf_primitives(node);
                stats.leaf_runs += prims.len().div_ceil(4) as u64;
                for tri in prims {
                    stats.triangles_tested += 1;
                    consider(ray, tri, &mut best);
                }
            } else {
                let [left, right] = node.child;
                stats.boxes_tested += 2;
                let dl = distmin(&r, left, best.0);
                let dr = distmin(&r, right, best.0);
                next = match (dl < f32::INFINITY, dr < f32::INFINITY) {
                    (true, true) => {
                        // The nearer first; the left one on equal distances.
                        let (near, far) = if dr < dl {
                            ((right, dr), (left, dl))
                        } else {
                            ((left, dl), (right, dr))
                        };
                        stack.push(far.0, far.1);
                        stats.max_pending = stats.max_pending.max(stack.len() as u64);
                        Some(near)
                    }
                    (true, false) => Some((left, dl)),
                    (false, true) => Some((right, dr)),
                    (false, false) => None,
                };
            }
        } else {
            stats.nodes_pruned += 1;
        }
        match next.or_else(|| stack.pop()) {
            Some((n, nd)) => (i, d) = (n, nd),
            None => break,
        }
    }
    Hit::from_best(best.0, best.1)
}

/// Closest hit over `tree` bounded by the DOP-14s `dops` (one per node,
/// [`crate::bvh::dop14::node_dops`]): [`closest_hit_with`] and the prelude's DOP test
/// (`library/algorithms/closest_hit_dop14.scion`).
pub fn closest_hit_dop14_stats(
    tree: &LogicalTree,
    dops: &[crate::bvh::dop14::Dop14],
    ray: &Ray,
    stats: &mut TraversalStats,
) -> Hit {
    closest_hit_with(tree, ray, stats, |r, i, tmax| {
        super::prelude::distmin_dop14(ray, r, &dops[i as usize], tmax)
    })
}

/// Why the traversal of `tree` could not reach primitive `prim` at distance `t`: the first
/// node on the path from the root to the leaf holding `prim` whose box test fails
/// (`!(enter <= exit)`) or whose entry distance exceeds `t` (`enter > t`), as
/// `(node, enter, exit)`. `None` when every node on the path admits `t` (then a traversal
/// must find the hit) or when no leaf holds `prim`.
///
/// This is the diagnosis of a brute-force/traversal mismatch: the prelude's slab test and its
/// Moller-Trumbore test round differently, so for a triangle lying in a box face the computed
/// entry distance can exceed the computed hit distance by an ulp and pruning on
/// `enter > best.t` then drops the node (docs/runtime.md, "Brute force and traversal").
pub fn why_pruned(tree: &LogicalTree, ray: &Ray, prim: u32, t: f32) -> Option<(u32, f32, f32)> {
    why_pruned_with(tree, ray, prim, t, |i| tree.nodes[i as usize].aabb())
}

/// [`why_pruned`] for a traversal of `tree` over other boxes (`bounds(node)`: the boxes a layout
/// reconstructs or decodes, which enclose the tree's own).
pub fn why_pruned_with(
    tree: &LogicalTree,
    ray: &Ray,
    prim: u32,
    t: f32,
    bounds: impl Fn(u32) -> crate::geom::Aabb,
) -> Option<(u32, f32, f32)> {
    why_pruned_in(tree, ray, |p: &Triangle| p.id == prim, t, bounds)
}

/// [`why_pruned_with`] over a tree of any primitive: `holds(p)` says which primitive holds the
/// hit (a [`crate::primitive::Triangle4`] holds the triangles of its lanes).
pub fn why_pruned_in<P: Primitive>(
    tree: &LogicalTree<P>,
    ray: &Ray,
    holds: impl Fn(&P) -> bool,
    t: f32,
    bounds: impl Fn(u32) -> crate::geom::Aabb,
) -> Option<(u32, f32, f32)> {
    if tree.is_empty() {
        return None;
    }
    // Depth-first search for the path to the leaf holding the hit.
    let mut path: Vec<(u32, usize)> = vec![(tree.root, 0)];
    while let Some(&(i, next)) = path.last() {
        let node = &tree.nodes[i as usize];
        if node.is_leaf() {
            if tree.leaf_primitives(node).iter().any(&holds) {
                break;
            }
            path.pop();
        } else if next < 2 {
            path.last_mut().expect("non-empty").1 += 1;
            path.push((node.child[next], 0));
            continue;
        } else {
            path.pop();
        }
        // Resume the parent.
    }
    path.iter().find_map(|&(i, _)| {
        let (enter, exit) = slab_interval(ray, &bounds(i));
        let meets = enter <= exit; // false when either is NaN
        (!meets || enter > t).then_some((i, enter, exit))
    })
}

/// Closest hits of all `rays` by tree traversal, in parallel blocks of 64 (see
/// [`BatchDriver`]).
pub fn closest_hits_tree<P: Primitive>(
    tree: &LogicalTree<P>,
    rays: &[Ray],
    driver: &BatchDriver,
) -> Vec<Hit> {
    driver.map(rays, |r| closest_hit_tree(tree, r))
}

/// The counters of tracing all `rays` through `tree` (in parallel blocks of 64, summed; the
/// deepest stack is the largest): the work per ray that `scion trace --stats` reports.
pub fn closest_hits_tree_stats<P: Primitive>(
    tree: &LogicalTree<P>,
    rays: &[Ray],
    driver: &BatchDriver,
) -> TraversalStats {
    sum_stats(rays, driver, |r, s| {
        closest_hit_tree_stats(tree, r, s);
    })
}

/// `count` run on every ray in parallel blocks of 64, the counters summed (the deepest stack is
/// the largest).
pub(crate) fn sum_stats(
    rays: &[Ray],
    driver: &BatchDriver,
    count: impl Fn(&Ray, &mut TraversalStats) + Sync,
) -> TraversalStats {
    let total = std::sync::Mutex::new(TraversalStats::default());
    driver.run(rays.len(), |begin, end| {
        let mut s = TraversalStats::default();
        for r in &rays[begin..end] {
            count(r, &mut s);
        }
        total.lock().unwrap_or_else(|p| p.into_inner()).add(&s);
    });
    total.into_inner().unwrap_or_else(|p| p.into_inner())
}

/// Closest hits of all `rays` by brute force, in parallel blocks of 64.
pub fn closest_hits_brute<P: Primitive>(
    triangles: &[P],
    rays: &[Ray],
    driver: &BatchDriver,
) -> Vec<Hit> {
    driver.map(rays, |r| closest_hit_brute(triangles, r))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{build_median, build_sah_binned, SahOptions};
    use crate::geom::{Triangle, Vec3};
    use crate::scene::gen;

    #[test]
    fn tie_goes_to_the_smaller_id_in_every_order() {
        let s = gen::duplicated(&gen::one_triangle(), 5);
        let r = Ray::new(Vec3::new(0.25, 0.25, 1.0), Vec3::new(0.0, 0.0, -1.0));
        let mut reversed = s.triangles.clone();
        reversed.reverse();
        let expected = Hit { t: 1.0, prim: 0 };
        assert_eq!(closest_hit_brute(&s.triangles, &r), expected);
        assert_eq!(closest_hit_brute(&reversed, &r), expected);
        let t = build_median(&reversed);
        assert_eq!(closest_hit_tree(&t, &r), expected);
    }

    #[test]
    fn miss_is_normalized_and_empty_tree_misses() {
        let s = gen::one_triangle();
        let mut r = Ray::new(Vec3::new(5.0, 5.0, 1.0), Vec3::new(0.0, 0.0, -1.0));
        r.tmax = 10.0;
        assert_eq!(closest_hit_brute(&s.triangles, &r), Hit::MISS);
        let t = build_sah_binned(&s.triangles, &SahOptions::default());
        assert_eq!(closest_hit_tree(&t, &r), Hit::MISS);
        assert_eq!(
            closest_hit_tree(&LogicalTree::<Triangle>::empty(), &r),
            Hit::MISS
        );
    }

    #[test]
    fn pruning_skips_far_nodes() {
        let s = gen::quad_grid(8, 8);
        let t = build_sah_binned(&s.triangles, &SahOptions::default());
        let r = Ray::new(Vec3::new(3.5, 3.25, 1.0), Vec3::new(0.0, 0.0, -1.0));
        let mut st = TraversalStats::default();
        let h = closest_hit_tree_stats(&t, &r, &mut st);
        assert!(h.is_hit());
        assert_eq!(h, closest_hit_brute(&s.triangles, &r));
        assert!(st.triangles_tested < s.len() as u64 / 4, "{st:?}");
        assert_eq!(why_pruned(&t, &r, h.prim, h.t), None);
        // A hit distance before the box entry is reported as pruned at the root.
        let (node, enter, _) = why_pruned(&t, &r, h.prim, 0.5).unwrap();
        assert_eq!((node, enter), (t.root, 1.0));
    }
}
