//! Insertion-based optimization of a built tree (Bittner, Hapala and Havran 2013, "Fast
//! insertion-based optimization of bounding volume hierarchies"): the step that takes a binned
//! SAH tree to the quality of the peers' builders (obvhs refines its PLOC trees the same way).
//!
//! A top-down builder decides each split from its own node's primitives only, so it leaves
//! nodes whose box is much larger than their children's (typically where long thin triangles
//! cross a split plane). Each pass takes the interior nodes that are worst by Bittner's measure
//! (the node's area times its area over the sum and over the smaller of its children's areas),
//! a fraction of the tree at a time; removes each such node `N` with its parent (the sibling
//! takes the parent's place); and reinserts `N`'s two subtrees, each as the sibling of the node
//! where it costs the least: the area of the new parent plus the growth of every ancestor's
//! area, found by branch and bound from the root. Removed nodes are reused as the new parents,
//! so the tree keeps its node count; leaves (and their primitives) are never changed. A
//! reinsertion is kept only when it lowers the sum of the interior nodes' areas (the SAH cost's
//! interior part; a journal of the nodes it changed measures and undoes it), so the tree only
//! improves. Passes repeat, at most `passes` times, while each lowers that sum by more than
//! [`MIN_GAIN`] of it. Boxes stay exact unions (recomputed up the path after every change), and the
//! result is put back in depth-first pre-order (root 0, left child = parent + 1).
//!
//! Deterministic: sequential, with ties broken by node number.

use super::{LogicalNode, LogicalTree, NO_NODE};
use crate::geom::Aabb;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// A pass is followed by another only when it lowered the summed interior area by more than
/// this fraction.
pub const MIN_GAIN: f64 = 0.005;

/// Fraction of the interior nodes removed and reinserted per pass.
const BATCH: f64 = 0.02;

/// The tree as the optimizer edits it: nodes of the logical tree plus parents, and a journal
/// of the first old state of every node changed since [`Editable::begin`], so that one
/// reinsertion can be measured and undone.
struct Editable {
    nodes: Vec<LogicalNode>,
    parent: Vec<u32>,
    root: u32,
    journal: Vec<(u32, LogicalNode, u32)>,
    logged: Vec<bool>,
    old_root: u32,
}

fn area(b: &[f32; 6]) -> f64 {
    Aabb::from_array(*b).half_area()
}

fn union(a: &[f32; 6], b: &[f32; 6]) -> [f32; 6] {
    Aabb::from_array(*a).union(Aabb::from_array(*b)).to_array()
}

impl Editable {
    fn children(&self, n: u32) -> [u32; 2] {
        self.nodes[n as usize].child
    }

    fn is_leaf(&self, n: u32) -> bool {
        self.nodes[n as usize].is_leaf()
    }

    fn bounds(&self, n: u32) -> [f32; 6] {
        self.nodes[n as usize].bounds
    }

    /// Records node `n`'s state before its first change since [`Editable::begin`].
    fn log(&mut self, n: u32) {
        if !self.logged[n as usize] {
            self.logged[n as usize] = true;
            self.journal
                .push((n, self.nodes[n as usize], self.parent[n as usize]));
        }
    }

    fn set_parent(&mut self, n: u32, p: u32) {
        self.log(n);
        self.parent[n as usize] = p;
    }

    /// Starts a change that [`Editable::delta`] measures and [`Editable::undo`] reverts.
    fn begin(&mut self) {
        for &(n, ..) in &self.journal {
            self.logged[n as usize] = false;
        }
        self.journal.clear();
        self.old_root = self.root;
    }

    /// How much the change since [`Editable::begin`] changed the sum of interior areas (the
    /// interior nodes stay the same set: removed nodes are reused as interior ones).
    fn delta(&self) -> f64 {
        self.journal
            .iter()
            .filter(|(_, old, _)| !old.is_leaf())
            .map(|&(n, old, _)| area(&self.bounds(n)) - area(&old.bounds))
            .sum()
    }

    /// Reverts the change since [`Editable::begin`].
    fn undo(&mut self) {
        for &(n, node, parent) in self.journal.iter().rev() {
            self.nodes[n as usize] = node;
            self.parent[n as usize] = parent;
        }
        self.root = self.old_root;
    }

    /// Recomputes the boxes from `n` up to the root.
    fn refit(&mut self, mut n: u32) {
        while n != NO_NODE {
            if !self.is_leaf(n) {
                let [a, b] = self.children(n);
                let u = union(&self.bounds(a), &self.bounds(b));
                if u == self.bounds(n) {
                    break;
                }
                self.log(n);
                self.nodes[n as usize].bounds = u;
            }
            n = self.parent[n as usize];
        }
    }

    /// Replaces child `old` of `p` (or the root, when `p` is `NO_NODE`) by `new`.
    fn replace_child(&mut self, p: u32, old: u32, new: u32) {
        if p == NO_NODE {
            self.root = new;
        } else {
            self.log(p);
            let c = &mut self.nodes[p as usize].child;
            let k = usize::from(c[1] == old);
            c[k] = new;
        }
        self.set_parent(new, p);
    }

    /// Sum of the interior nodes' areas (the SAH cost's interior part, up to a constant).
    fn interior_area(&self) -> f64 {
        (0..self.nodes.len() as u32)
            .filter(|&n| !self.is_leaf(n))
            .map(|n| area(&self.bounds(n)))
            .sum()
    }

    /// Bittner's inefficiency of interior node `n`.
    fn badness(&self, n: u32) -> f64 {
        let [a, b] = self.children(n);
        let (an, aa, ab) = (
            area(&self.bounds(n)),
            area(&self.bounds(a)),
            area(&self.bounds(b)),
        );
        let sum = (aa + ab).max(f64::MIN_POSITIVE);
        let min = aa.min(ab).max(f64::MIN_POSITIVE);
        an * (an / sum) * (an / min)
    }

    /// The node whose sibling subtree `x` costs least to become, by branch and bound.
    fn best_sibling(&self, x: u32) -> u32 {
        let bx = self.bounds(x);
        let ax = area(&bx);
        let mut best = (f64::INFINITY, self.root);
        // (lower bound of the total cost under this node, induced cost above it, node)
        let mut heap = BinaryHeap::new();
        heap.push(Candidate {
            bound: ax,
            induced: 0.0,
            node: self.root,
        });
        while let Some(c) = heap.pop() {
            if c.bound >= best.0 {
                break;
            }
            let b = self.bounds(c.node);
            let merged = area(&union(&b, &bx));
            let total = c.induced + merged;
            if total < best.0 || (total == best.0 && c.node < best.1) {
                best = (total, c.node);
            }
            if self.is_leaf(c.node) {
                continue;
            }
            let induced = c.induced + merged - area(&b);
            if induced + ax < best.0 {
                for k in self.children(c.node) {
                    heap.push(Candidate {
                        bound: induced + ax,
                        induced,
                        node: k,
                    });
                }
            }
        }
        best.1
    }

    /// Makes `x` the sibling of `y` under the (detached) interior node `p`.
    fn insert(&mut self, x: u32, y: u32, p: u32) {
        let gp = self.parent[y as usize];
        self.replace_child(gp, y, p);
        self.log(p);
        self.nodes[p as usize].child = [y, x];
        // `p`'s box is stale (it was removed elsewhere): recompute it whatever it holds.
        self.nodes[p as usize].bounds = union(&self.bounds(y), &self.bounds(x));
        self.set_parent(y, p);
        self.set_parent(x, p);
        self.refit(gp);
    }

    /// Removes interior node `n` (not the root) and its parent, and reinserts `n`'s children;
    /// keeps the change only when it lowers the sum of interior areas.
    fn reinsert(&mut self, n: u32) {
        let p = self.parent[n as usize];
        if p == NO_NODE || self.is_leaf(n) {
            return;
        }
        self.begin();
        let [pa, pb] = self.children(p);
        let sibling = if pa == n { pb } else { pa };
        let g = self.parent[p as usize];
        self.replace_child(g, p, sibling);
        self.refit(g);
        let [a, b] = self.children(n);
        for (x, spare) in [(a, n), (b, p)] {
            self.set_parent(x, NO_NODE);
            let y = self.best_sibling(x);
            self.insert(x, y, spare);
        }
        if self.delta() >= 0.0 {
            self.undo();
        }
    }

    /// One pass: the worst `BATCH` of the interior nodes (all but the root) reinserted.
    fn pass(&mut self) {
        let mut worst: Vec<(f64, u32)> = (0..self.nodes.len() as u32)
            .filter(|&n| !self.is_leaf(n) && n != self.root)
            .map(|n| (self.badness(n), n))
            .collect();
        let order = |a: &(f64, u32), b: &(f64, u32)| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1));
        let k = ((worst.len() as f64 * BATCH).ceil() as usize).clamp(1, worst.len().max(1));
        if worst.len() > k {
            worst.select_nth_unstable_by(k, order);
            worst.truncate(k);
        }
        worst.sort_by(order);
        for &(_, n) in &worst {
            if n != self.root && self.parent[n as usize] != NO_NODE {
                self.reinsert(n);
            }
        }
    }
}

/// A node to look at in [`Editable::best_sibling`] (a min-heap on `bound`, then node).
struct Candidate {
    bound: f64,
    induced: f64,
    node: u32,
}

impl PartialEq for Candidate {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Candidate {}
impl PartialOrd for Candidate {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Candidate {
    fn cmp(&self, o: &Self) -> Ordering {
        o.bound.total_cmp(&self.bound).then(o.node.cmp(&self.node))
    }
}

/// Optimizes `tree` in place by at most `passes` passes (see the module documentation).
pub fn optimize<P: crate::primitive::Primitive>(tree: &mut LogicalTree<P>, passes: usize) {
    if tree.is_empty() || passes == 0 || tree.nodes.len() < 7 {
        return;
    }
    let mut parent = vec![NO_NODE; tree.nodes.len()];
    for (i, n) in tree.nodes.iter().enumerate() {
        if !n.is_leaf() {
            for c in n.child {
                parent[c as usize] = i as u32;
            }
        }
    }
    let count = tree.nodes.len();
    let mut e = Editable {
        nodes: std::mem::take(&mut tree.nodes),
        parent,
        root: tree.root,
        journal: Vec::new(),
        logged: vec![false; count],
        old_root: tree.root,
    };
    // Every kept reinsertion lowers the cost, so passes only improve the tree; they stop when
    // one gains too little.
    let mut cost = e.interior_area();
    for _ in 0..passes {
        e.pass();
        let now = e.interior_area();
        let gain = (cost - now) / cost.max(f64::MIN_POSITIVE);
        cost = now;
        if gain <= MIN_GAIN {
            break;
        }
    }
    // Back to depth-first pre-order from the root.
    let mut nodes = Vec::with_capacity(e.nodes.len());
    let mut stack = vec![(e.root, NO_NODE, 0usize)];
    while let Some((n, parent, k)) = stack.pop() {
        let at = nodes.len() as u32;
        if parent != NO_NODE {
            let c: &mut LogicalNode = &mut nodes[parent as usize];
            c.child[k] = at;
        }
        let node = e.nodes[n as usize];
        nodes.push(node);
        if !node.is_leaf() {
            stack.push((node.child[1], at, 1));
            stack.push((node.child[0], at, 0));
        }
    }
    tree.nodes = nodes;
    tree.root = 0;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{build_sah_binned, SahOptions};
    use crate::scene::gen;

    fn plain(tris: &[crate::geom::Triangle]) -> LogicalTree {
        let o = SahOptions {
            reinsertion_passes: 0,
            block: 1,
            ..SahOptions::default()
        };
        build_sah_binned(tris, &o)
    }

    /// The leaves as sets of primitive ids, sorted (what optimization must not change).
    fn leaves(t: &LogicalTree) -> Vec<Vec<u32>> {
        let mut out: Vec<Vec<u32>> = t
            .nodes
            .iter()
            .filter(|n| n.is_leaf())
            .map(|n| {
                let mut ids: Vec<u32> = t.leaf_primitives(n).iter().map(|p| p.id).collect();
                ids.sort_unstable();
                ids
            })
            .collect();
        out.sort();
        out
    }

    #[test]
    fn optimization_keeps_leaves_and_lowers_the_sah_cost() {
        for s in [
            gen::random_soup(2000, 0.3, 7),
            gen::slivers(400),
            gen::axis_planes(12),
        ] {
            let before = plain(&s.triangles);
            let mut after = before.clone();
            optimize(&mut after, 32);
            after
                .validate()
                .unwrap_or_else(|e| panic!("{}: {e}", s.name));
            assert_eq!(leaves(&after), leaves(&before), "{}", s.name);
            assert_eq!(after.nodes.len(), before.nodes.len());
            assert!(
                after.stats().sah_cost <= before.stats().sah_cost,
                "{}",
                s.name
            );
            // Pre-order: root 0, an interior node's left child right after it.
            assert_eq!(after.root, 0);
            for (i, n) in after.nodes.iter().enumerate() {
                if !n.is_leaf() {
                    assert_eq!(n.child[0] as usize, i + 1);
                }
            }
            // Deterministic.
            let mut again = before.clone();
            optimize(&mut again, 32);
            assert_eq!(again.nodes, after.nodes);
        }
        // Axis-aligned planks of very different lengths, as in CAD and architecture scenes:
        // the top-down build leaves room to gain.
        let tris = planks(800);
        let before = plain(&tris);
        let mut after = before.clone();
        optimize(&mut after, 32);
        assert!(
            after.stats().sah_cost < 0.9 * before.stats().sah_cost,
            "{} -> {}",
            before.stats().sah_cost,
            after.stats().sah_cost
        );
    }

    /// `n` thin triangles along the axes, of lengths from 1/20 to all of the unit cube.
    fn planks(n: u32) -> Vec<crate::geom::Triangle> {
        use crate::geom::{Triangle, Vec3};
        let mut rng = crate::rng::SplitMix64::new(5);
        (0..n)
            .map(|i| {
                let p = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
                let len = 0.05 + 0.95 * rng.next_f32();
                let (a, b) = match i % 3 {
                    0 => (Vec3::new(len, 0.0, 0.0), Vec3::new(0.0, 0.01, 0.0)),
                    1 => (Vec3::new(0.0, len, 0.0), Vec3::new(0.0, 0.0, 0.01)),
                    _ => (Vec3::new(0.0, 0.0, len), Vec3::new(0.01, 0.0, 0.0)),
                };
                Triangle::new(p, p + a, p + b, i)
            })
            .collect()
    }

    #[test]
    fn tiny_and_empty_trees_are_left_alone() {
        let mut t = LogicalTree::<crate::geom::Triangle>::empty();
        optimize(&mut t, 8);
        assert!(t.is_empty());
        let s = gen::one_triangle();
        let before = plain(&s.triangles);
        let mut t = before.clone();
        optimize(&mut t, 8);
        assert_eq!(t.nodes, before.nodes);
    }
}
