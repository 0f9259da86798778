//! Logical BVHs and their builders: triangles -> [`LogicalTree`] (architecture §5).
//!
//! [`logical`] holds the tree form every generated constructor reads; [`sah_binned`],
//! [`median`] and [`fcpw`] (FCPW's binned surface-area builder) build it; [`chain`] builds a maximally deep tree for stack-limit tests;
//! [`wide`] collapses it to four- or eight-wide nodes.
//!
//! The top-down builders are deterministic: the same input gives the same tree, bit for bit,
//! whatever the number of threads. Large ranges (at least [`PARALLEL_MIN`] primitives) build
//! their two subtrees with `rayon::join` and concatenate them in pre-order; smaller ranges run
//! sequentially with an explicit work stack, so even very deep trees never overflow the call
//! stack. Nodes come out in depth-first pre-order: root 0, left child = parent + 1.

pub mod chain;
pub mod collapse;
pub mod dop14;
pub mod fcpw;
pub mod fill;
pub mod logical;
pub mod median;
pub mod oriented;
pub mod reinsert;
pub mod sah_binned;
pub mod schema;
pub mod wide;

pub use chain::{build_caterpillar, DeepSide};
pub use fcpw::{build_fcpw, FcpwOptions};
pub use logical::{
    LogicalNode, LogicalTree, TreeStats, DEFAULT_MAX_LEAF, KIND_INTERIOR, KIND_LEAF, NO_NODE,
};
pub use median::build_median;
pub use sah_binned::{build_sah_binned, SahOptions};

use crate::geom::{Aabb, Vec3};
use crate::primitive::Primitive;

/// Ranges with at least this many primitives build their subtrees in parallel.
pub const PARALLEL_MIN: usize = 16 * 1024;

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

/// Box of the primitives and box of their centroids.
fn range_bounds(items: &[Item]) -> (Aabb, Aabb) {
    let mut b = Aabb::EMPTY;
    let mut c = Aabb::EMPTY;
    for it in items {
        b = b.union(it.bounds);
        c = c.grow(it.centroid);
    }
    (b, c)
}

/// Splits `items` at its median along `axis`, ordering by (centroid, id) so that the result
/// is unique. Returns the left count.
pub(crate) fn median_split(items: &mut [Item], axis: usize) -> usize {
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |a, b| {
        a.centroid
            .axis(axis)
            .total_cmp(&b.centroid.axis(axis))
            .then(a.id.cmp(&b.id))
    });
    mid
}

/// A builder's rule: given a range of items (to partition in place), its box, its centroid box
/// and its depth (the root's is 0), make a leaf or split after `k` items (`0 < k < len`).
pub(crate) trait Decide: Sync {
    fn decide(&self, items: &mut [Item], bounds: Aabb, cbounds: Aabb, depth: usize) -> Decision;
}

/// Builds the tree over `tris` with the rule `rule` (see the module documentation).
pub(crate) fn build_top_down<P: Primitive>(tris: &[P], rule: &impl Decide) -> LogicalTree<P> {
    if tris.is_empty() {
        return LogicalTree::empty();
    }
    let mut items: Vec<Item> = tris
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let bounds = t.bounds();
            Item {
                bounds,
                centroid: bounds.center(),
                id: t.id(),
                index: i as u32,
            }
        })
        .collect();
    let nodes = build_range(&mut items, 0, 0, rule);
    let primitives = items.iter().map(|it| tris[it.index as usize]).collect();
    LogicalTree {
        nodes,
        root: 0,
        primitives,
    }
}

fn checked_split(left: usize, n: usize) -> usize {
    assert!(
        left > 0 && left < n,
        "builder split {left} of {n} primitives"
    );
    left
}

/// The pre-order nodes of the subtree over `items` at depth `depth`, whose first item is
/// primitive `base` of the final order; child indices are relative to the returned vector.
fn build_range(
    items: &mut [Item],
    base: usize,
    depth: usize,
    rule: &impl Decide,
) -> Vec<LogicalNode> {
    let n = items.len();
    if n < PARALLEL_MIN {
        return build_sequential(items, base, depth, rule);
    }
    let (bounds, cbounds) = range_bounds(items);
    match rule.decide(items, bounds, cbounds, depth) {
        Decision::Leaf => vec![LogicalNode::leaf(bounds, base as u32, n as u32)],
        Decision::Split(left) => {
            let left = checked_split(left, n);
            let (l_items, r_items) = items.split_at_mut(left);
            let (l, r) = rayon::join(
                || build_range(l_items, base, depth + 1, rule),
                || build_range(r_items, base + left, depth + 1, rule),
            );
            let mut nodes = Vec::with_capacity(1 + l.len() + r.len());
            nodes.push(LogicalNode::interior(bounds, 1, (1 + l.len()) as u32));
            let shift = |mut node: LogicalNode, by: usize| {
                if !node.is_leaf() {
                    node.child = node.child.map(|c| c + by as u32);
                }
                node
            };
            nodes.extend(l.iter().map(|&x| shift(x, 1)));
            let by = 1 + l.len();
            nodes.extend(r.iter().map(|&x| shift(x, by)));
            nodes
        }
    }
}

/// [`build_range`] on one thread with an explicit stack (same pre-order).
fn build_sequential(
    items: &mut [Item],
    base: usize,
    depth: usize,
    rule: &impl Decide,
) -> Vec<LogicalNode> {
    // (begin, end, parent, side, depth), relative to `items`.
    let mut stack: Vec<(usize, usize, u32, usize, usize)> =
        vec![(0, items.len(), NO_NODE, 0, depth)];
    let mut nodes: Vec<LogicalNode> = Vec::new();
    while let Some((begin, end, parent, side, depth)) = stack.pop() {
        let me = nodes.len() as u32;
        if parent != NO_NODE {
            nodes[parent as usize].child[side] = me;
        }
        let range = &mut items[begin..end];
        let (bounds, cbounds) = range_bounds(range);
        match rule.decide(range, bounds, cbounds, depth) {
            Decision::Leaf => nodes.push(LogicalNode::leaf(
                bounds,
                (base + begin) as u32,
                (end - begin) as u32,
            )),
            Decision::Split(left) => {
                let left = checked_split(left, end - begin);
                nodes.push(LogicalNode::interior(bounds, NO_NODE, NO_NODE));
                stack.push((begin + left, end, me, 1, depth + 1));
                stack.push((begin, begin + left, me, 0, depth + 1));
            }
        }
    }
    nodes
}
