//! Closest hit over a wide tree ([`WideTree`], the logical form of the four- and eight-wide
//! layouts): the reference that a wide traversal written in Scion must match node for node.
//!
//! The order generalizes the binary traversal's ([`super::closest_hit`]): `best` starts at
//! `(ray.tmax, u32::MAX)`; the root is visited iff the ray meets the scene's box before
//! `best.t`; a visited interior node tests the boxes of all its occupied slots
//! (`distmin(slab_ray(ray), box, best.t)`), drops those that return `+inf`, and visits the
//! rest nearest first (lower slot first on equal distances): the nearest at once, the others
//! pushed farthest first; a child reached with entry distance `d > best.t` is skipped; a leaf
//! tests its primitives in order. With the tie rule the hits equal the binary traversal's and
//! brute force's (see `closest_hit` for the one known exception, rays lying in a box face).

use super::closest_hit::{consider, sum_stats, TraversalStats};
use super::prelude::{distmin_of, slab_ray};
use crate::batch::BatchDriver;
use crate::bvh::wide::{WideChild, WideTree};
use crate::geom::{Hit, Ray};
use crate::primitive::Primitive;

/// Closest hit of `ray` over `tree`, whose leaves index `primitives` (the binary tree's
/// reordered primitives it was collapsed from).
pub fn closest_hit_wide<const W: usize>(
    tree: &WideTree<W>,
    primitives: &[impl Primitive],
    ray: &Ray,
) -> Hit {
    closest_hit_wide_stats(tree, primitives, ray, &mut TraversalStats::default())
}

/// [`closest_hit_wide`] that also counts its work into `stats` (an interior node's box tests
/// are its occupied slots; leaves count as visited nodes, as in the binary traversal).
pub fn closest_hit_wide_stats<const W: usize>(
    tree: &WideTree<W>,
    primitives: &[impl Primitive],
    ray: &Ray,
    stats: &mut TraversalStats,
) -> Hit {
    let mut best = (ray.tmax, u32::MAX);
    if tree.is_empty() {
        return Hit::from_best(best.0, best.1);
    }
    let r = slab_ray(ray);
    stats.boxes_tested += 1;
    let d = distmin_of(&r, &tree.root_bounds, best.0);
    if d == f32::INFINITY {
        return Hit::from_best(best.0, best.1);
    }
    let mut stack: Vec<(WideChild, f32)> = Vec::with_capacity(64);
    let (mut child, mut d) = (tree.root, d);
    loop {
        let mut next = None;
        if d <= best.0 {
            stats.nodes_visited += 1;
            match child {
                WideChild::Empty => {}
                WideChild::Leaf { offset, count } => {
                    stats.leaf_runs += u64::from(count).div_ceil(4);
                    let start = offset as usize;
                    for tri in &primitives[start..start + count as usize] {
                        stats.triangles_tested += 1;
                        consider(ray, tri, &mut best);
                    }
                }
                WideChild::Node(i) => {
                    let node = &tree.nodes[i as usize];
                    let n = node.len();
                    stats.boxes_tested += n as u64;
                    // (distance, slot) of the children the ray meets before `best`.
                    let mut hits: [(f32, usize); W] = [(f32::INFINITY, 0); W];
                    let mut m = 0;
                    for k in 0..n {
                        let dk = distmin_of(&r, &node.bounds[k], best.0);
                        if dk < f32::INFINITY {
                            hits[m] = (dk, k);
                            m += 1;
                        }
                    }
                    // Nearest first, lower slot on ties (distances are numbers, never NaN).
                    hits[..m].sort_unstable_by(|a, b| {
                        a.0.partial_cmp(&b.0)
                            .unwrap_or(std::cmp::Ordering::Equal)
                            .then(a.1.cmp(&b.1))
                    });
                    for &(dk, k) in hits[1..m.max(1)].iter().rev() {
                        stack.push((node.children[k], dk));
                    }
                    stats.max_pending = stats.max_pending.max(stack.len() as u64);
                    if m > 0 {
                        next = Some((node.children[hits[0].1], hits[0].0));
                    }
                }
            }
        } else {
            stats.nodes_pruned += 1;
        }
        match next.or_else(|| stack.pop()) {
            Some((c, cd)) => (child, d) = (c, cd),
            None => break,
        }
    }
    Hit::from_best(best.0, best.1)
}

/// The counters of tracing all `rays` through `tree` (in parallel blocks of 64, summed; the
/// deepest stack is the largest), as [`super::closest_hits_tree_stats`] for binary trees.
pub fn closest_hits_wide_stats<const W: usize>(
    tree: &WideTree<W>,
    primitives: &[impl Primitive],
    rays: &[Ray],
    driver: &BatchDriver,
) -> TraversalStats {
    sum_stats(rays, driver, |r, s| {
        closest_hit_wide_stats(tree, primitives, r, s);
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::wide::collapse;
    use crate::bvh::{build_sah_binned, LogicalTree, SahOptions};
    use crate::query::rays::{axis_rays, primary_rays_n, secondary_rays};
    use crate::reference::{
        closest_hit_brute, closest_hit_tree, closest_hit_tree_stats, why_pruned,
    };
    use crate::scene::gen;

    /// Every wide hit is brute force's, except where the binary tree's own box tests drop the
    /// node holding it (the documented exception, which the wide tree may or may not share:
    /// it tests a subset of the same boxes).
    fn check<const W: usize>(tree: &LogicalTree, rays: &[Ray], name: &str) -> TraversalStats {
        let wide = collapse::<W>(tree);
        wide.validate(tree)
            .unwrap_or_else(|e| panic!("{name}: W={W}: {e}"));
        let mut stats = TraversalStats::default();
        for (i, ray) in rays.iter().enumerate() {
            let got = closest_hit_wide_stats(&wide, &tree.primitives, ray, &mut stats);
            let brute = closest_hit_brute(&tree.primitives, ray);
            if got != brute {
                assert!(
                    brute.is_hit() && why_pruned(tree, ray, brute.prim, brute.t).is_some(),
                    "{name}: W={W}: ray {i}: wide {got:?}, brute force {brute:?}, binary {:?}",
                    closest_hit_tree(tree, ray)
                );
            }
        }
        stats
    }

    #[test]
    fn wide_hits_are_brute_force_hits_on_every_hard_case() {
        for scene in gen::hard_cases() {
            let tree = build_sah_binned(&scene.triangles, &SahOptions::default());
            let b = scene.bounds();
            let mut rays = secondary_rays(b, 300, 7);
            rays.extend(axis_rays(b, 300, 8));
            rays.extend(primary_rays_n(b, 300, 9).unwrap_or_default());
            check::<2>(&tree, &rays, &scene.name);
            check::<4>(&tree, &rays, &scene.name);
            check::<8>(&tree, &rays, &scene.name);
        }
    }

    #[test]
    fn two_wide_is_the_binary_traversal() {
        // With two slots nothing is opened: the same nodes in the same order.
        let scene = gen::random_soup(400, 0.1, 3);
        let tree = build_sah_binned(&scene.triangles, &SahOptions::default());
        for ray in secondary_rays(scene.bounds(), 200, 5) {
            let (mut a, mut b) = (TraversalStats::default(), TraversalStats::default());
            let wide = collapse::<2>(&tree);
            let h = closest_hit_wide_stats(&wide, &tree.primitives, &ray, &mut a);
            assert_eq!(h, closest_hit_tree_stats(&tree, &ray, &mut b));
            assert_eq!(a, b);
        }
    }

    #[test]
    fn wider_nodes_test_more_boxes_in_fewer_visits() {
        let scene = gen::random_soup(2000, 0.05, 11);
        let tree = build_sah_binned(&scene.triangles, &SahOptions::default());
        let rays = secondary_rays(scene.bounds(), 500, 2);
        let s2 = check::<2>(&tree, &rays, "soup");
        let s4 = check::<4>(&tree, &rays, "soup");
        let s8 = check::<8>(&tree, &rays, "soup");
        assert!(s8.nodes_visited < s4.nodes_visited && s4.nodes_visited < s2.nodes_visited);
        assert!(s8.boxes_tested > s2.boxes_tested, "{s2:?} {s8:?}");
        // The same leaves hold the answers: triangle tests do not grow with the width.
        assert!(s8.triangles_tested <= s2.triangles_tested, "{s2:?} {s8:?}");
    }
}
