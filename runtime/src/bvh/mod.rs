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

/// One primitive as the top-down builders move it around: its box, its centroid, its
/// original id (for unique median orders) and its index in the input.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Item {
    pub bounds: Aabb,
    pub centroid: Vec3,
    pub id: u32,
    pub index: u32,
}

/// Shared machinery of the top-down builders: the primitives as [`Item`]s, partitioned in
/// place so that each node owns a contiguous range (sequential memory access), and pre-order
/// node emission.
pub(crate) struct TopDown<'a> {
    pub tris: &'a [Triangle],
    pub items: Vec<Item>,
}

impl<'a> TopDown<'a> {
    pub fn new(tris: &'a [Triangle]) -> TopDown<'a> {
        let items = tris
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let bounds = t.bounds();
                Item {
                    bounds,
                    centroid: bounds.center(),
                    id: t.id,
                    index: i as u32,
                }
            })
            .collect();
        TopDown { tris, items }
    }

    /// Box of the primitives and box of their centroids over `items[begin..end]`.
    pub fn range_bounds(&self, begin: usize, end: usize) -> (Aabb, Aabb) {
        let mut b = Aabb::EMPTY;
        let mut c = Aabb::EMPTY;
        for it in &self.items[begin..end] {
            b = b.union(it.bounds);
            c = c.grow(it.centroid);
        }
        (b, c)
    }

    /// Splits `items[begin..end]` at its median along `axis`, ordering by (centroid, id) so
    /// that the result is unique. Returns the left count.
    pub fn median_split(&mut self, begin: usize, end: usize, axis: usize) -> usize {
        let mid = (end - begin) / 2;
        self.items[begin..end].select_nth_unstable_by(mid, |a, b| {
            a.centroid
                .axis(axis)
                .total_cmp(&b.centroid.axis(axis))
                .then(a.id.cmp(&b.id))
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
        let primitives = self
            .items
            .iter()
            .map(|it| self.tris[it.index as usize])
            .collect();
        LogicalTree {
            nodes,
            root: 0,
            primitives,
        }
    }
}
