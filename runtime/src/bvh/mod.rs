//! Logical BVHs and their builders: triangles -> [`LogicalTree`] (architecture §5).
//!
//! [`logical`] holds the tree form every generated constructor reads; [`sah_binned`] and
//! [`median`] build it; [`chain`] builds a maximally deep tree for stack-limit tests. Both builders are sequential and deterministic (the same input gives
//! the same tree, bit for bit, on every run and machine) and emit nodes in depth-first
//! pre-order with an explicit work stack, so even very deep trees never overflow the call
//! stack.

pub mod chain;
pub mod logical;
pub mod median;
pub mod sah_binned;

pub use chain::{build_caterpillar, DeepSide};
pub use logical::{
    LogicalNode, LogicalTree, TreeStats, DEFAULT_MAX_LEAF, KIND_INTERIOR, KIND_LEAF, NO_NODE,
};
pub use median::build_median;
pub use sah_binned::{build_sah_binned, SahOptions};

use crate::geom::{Aabb, Triangle, Vec3};

/// What a builder decides for one range of primitives.
pub(crate) enum Decision {
    /// Make a leaf of the whole range.
    Leaf,
    /// Split the range after this many primitives (already partitioned in place).
    Split(usize),
}

/// Shared machinery of the top-down builders: per-primitive boxes and centroids, the index
/// permutation, and pre-order node emission.
pub(crate) struct TopDown<'a> {
    pub tris: &'a [Triangle],
    pub boxes: Vec<Aabb>,
    pub centroids: Vec<Vec3>,
    /// A permutation of `0..tris.len()`; each node owns a contiguous range of it.
    pub order: Vec<u32>,
}

impl<'a> TopDown<'a> {
    pub fn new(tris: &'a [Triangle]) -> TopDown<'a> {
        let boxes: Vec<Aabb> = tris.iter().map(Triangle::bounds).collect();
        let centroids = boxes.iter().map(|b| b.center()).collect();
        TopDown {
            tris,
            boxes,
            centroids,
            order: (0..tris.len() as u32).collect(),
        }
    }

    /// Box of the primitives and box of their centroids over `order[begin..end]`.
    pub fn range_bounds(&self, begin: usize, end: usize) -> (Aabb, Aabb) {
        let mut b = Aabb::EMPTY;
        let mut c = Aabb::EMPTY;
        for &i in &self.order[begin..end] {
            b = b.union(self.boxes[i as usize]);
            c = c.grow(self.centroids[i as usize]);
        }
        (b, c)
    }

    /// Splits `order[begin..end]` at its median along `axis`, ordering by (centroid, id) so
    /// that the result is unique. Returns the left count.
    pub fn median_split(&mut self, begin: usize, end: usize, axis: usize) -> usize {
        let mid = (end - begin) / 2;
        let (cen, tris) = (&self.centroids, self.tris);
        self.order[begin..end].select_nth_unstable_by(mid, |&a, &b| {
            cen[a as usize][axis]
                .total_cmp(&cen[b as usize][axis])
                .then(tris[a as usize].id.cmp(&tris[b as usize].id))
        });
        mid
    }

    /// Builds the tree top-down: `decide(self, begin, end, bounds, centroid_bounds)` either
    /// makes a leaf or partitions the range in place and returns the left count (in
    /// `1..count`). Nodes are emitted in pre-order (root 0, left child = parent + 1).
    pub fn build(
        mut self,
        mut decide: impl FnMut(&mut TopDown<'a>, usize, usize, Aabb, Aabb) -> Decision,
    ) -> LogicalTree {
        let n = self.tris.len();
        if n == 0 {
            return LogicalTree::empty();
        }
        // (begin, end, parent, side)
        let mut stack: Vec<(usize, usize, u32, usize)> = vec![(0, n, NO_NODE, 0)];
        let mut nodes: Vec<LogicalNode> = Vec::new();
        while let Some((begin, end, parent, side)) = stack.pop() {
            let me = nodes.len() as u32;
            if parent != NO_NODE {
                nodes[parent as usize].child[side] = me;
            }
            let (bounds, cbounds) = self.range_bounds(begin, end);
            match decide(&mut self, begin, end, bounds, cbounds) {
                Decision::Leaf => {
                    nodes.push(LogicalNode::leaf(
                        bounds,
                        begin as u32,
                        (end - begin) as u32,
                    ));
                }
                Decision::Split(left) => {
                    assert!(
                        left > 0 && left < end - begin,
                        "builder split {left} of {} primitives",
                        end - begin
                    );
                    nodes.push(LogicalNode::interior(bounds, NO_NODE, NO_NODE));
                    stack.push((begin + left, end, me, 1));
                    stack.push((begin, begin + left, me, 0));
                }
            }
        }
        let primitives = self.order.iter().map(|&i| self.tris[i as usize]).collect();
        LogicalTree {
            nodes,
            root: 0,
            primitives,
        }
    }
}
