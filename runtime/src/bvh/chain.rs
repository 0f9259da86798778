//! The caterpillar tree: a valid but maximally deep logical tree, for stack-limit tests of
//! generated traversals (architecture §5: overflow of the fixed traversal stack must be
//! detected). Triangles -> [`LogicalTree`] of depth `n`.
//!
//! Interior node `k` has leaf `k` (primitive `k`, in input order) on one side and the rest of
//! the chain on the other. With the deep side on the left, a left-first traversal pushes one
//! pending right leaf per level, so its stack grows to `n - 1` entries; with the deep side on
//! the right it stays at one entry. Nodes: interior `k` is node `2k`, leaf `k` is node
//! `2k + 1`, the last primitive's leaf is node `2(n - 1)`; the root is node 0.

use super::{LogicalNode, LogicalTree};
use crate::geom::{Aabb, Triangle};

/// Which side of each interior node carries the rest of the chain.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeepSide {
    /// Left: a left-first traversal's stack grows with the depth.
    Left,
    /// Right: a left-first traversal's stack stays small.
    Right,
}

/// Builds the caterpillar tree over `tris` (one primitive per leaf, depth `n`).
pub fn build_caterpillar(tris: &[Triangle], deep: DeepSide) -> LogicalTree {
    let n = tris.len();
    if n == 0 {
        return LogicalTree::empty();
    }
    let mut nodes = vec![LogicalNode::leaf(Aabb::EMPTY, 0, 0); 2 * n - 1];
    let last = 2 * (n - 1);
    nodes[last] = LogicalNode::leaf(tris[n - 1].bounds(), (n - 1) as u32, 1);
    let mut rest = tris[n - 1].bounds();
    for k in (0..n - 1).rev() {
        let b = tris[k].bounds();
        nodes[2 * k + 1] = LogicalNode::leaf(b, k as u32, 1);
        let (leaf, next) = ((2 * k + 1) as u32, (2 * k + 2) as u32);
        rest = b.union(rest);
        nodes[2 * k] = match deep {
            DeepSide::Left => LogicalNode::interior(rest, next, leaf),
            DeepSide::Right => LogicalNode::interior(rest, leaf, next),
        };
    }
    LogicalTree {
        nodes,
        root: 0,
        primitives: tris.to_vec(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::gen;

    #[test]
    fn caterpillar_is_valid_and_as_deep_as_long() {
        let s = gen::random_soup(300, 0.05, 4);
        for deep in [DeepSide::Left, DeepSide::Right] {
            let t = build_caterpillar(&s.triangles, deep);
            t.validate_with_cap(1).unwrap();
            assert_eq!(t.stats().depth, 300);
            let stack = if deep == DeepSide::Left { 299 } else { 1 };
            assert_eq!(t.stats().stack_needed, stack);
        }
        let one = build_caterpillar(&gen::one_triangle().triangles, DeepSide::Left);
        one.validate().unwrap();
        assert!(build_caterpillar(&[], DeepSide::Left).is_empty());
    }
}
