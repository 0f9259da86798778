//! Leaf collapsing by the SAH of a traversal that tests a leaf's primitives in runs of `block`
//! (the library's closest hit tests four triangles at a time): after the top-down build and the
//! insertion-based optimization have made the tree over small leaves, every subtree whose
//! primitives cost less as one leaf than as the subtree becomes that leaf. obvhs collapses its
//! PLOC trees the same way; building with the block's leaf cost from the start instead fixes
//! leaves of up to `block` primitives before the optimization, which never changes leaves
//! (`super::reinsert`), so that thin triangles crossing a split stay grouped in large boxes
//! (sponza's primary rays: 3.37 nodes and 0.87 leaf runs per ray against 2.93 and 0.40;
//! docs/performance.md, "Eighteenth session").
//!
//! Costs, with `A` a node's half surface area: a leaf of `n` primitives `ci * ceil(n / block) *
//! A`, an interior node `ct * A` plus its children's costs. A subtree of at most `max_leaf`
//! primitives whose leaf cost is strictly lower than its cost as a subtree is collapsed (the
//! comparison bottom-up, so a collapsed child counts at its leaf cost). The collapsed leaf's box
//! is the subtree's box (the exact union of its primitives' boxes) and its primitives are the
//! subtree's leaves' in depth-first order, left first. The result is in depth-first pre-order
//! with the primitives reordered to match. Deterministic.

use super::{LogicalNode, LogicalTree, NO_NODE};
use crate::geom::Aabb;

/// The leaf and node costs the collapse compares.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CollapseCost {
    /// Largest leaf the collapse may make.
    pub max_leaf: usize,
    /// Primitives one leaf test takes at once (at least 1).
    pub block: usize,
    /// Cost of visiting an interior node.
    pub traversal_cost: f64,
    /// Cost of one leaf test (of `block` primitives).
    pub intersection_cost: f64,
}

/// Collapses `tree` in place (see the module documentation). Returns the number of subtrees
/// collapsed.
pub fn collapse<P: crate::primitive::Primitive + Clone>(
    tree: &mut LogicalTree<P>,
    cost: &CollapseCost,
) -> usize {
    if tree.is_empty() {
        return 0;
    }
    let block = cost.block.max(1);
    let n = tree.nodes.len();
    // Post-order: children before parents, whatever the node order.
    let mut order = Vec::with_capacity(n);
    let mut stack = vec![(tree.root, false)];
    while let Some((i, expanded)) = stack.pop() {
        let node = &tree.nodes[i as usize];
        if expanded || node.is_leaf() {
            order.push(i);
        } else {
            stack.push((i, true));
            stack.push((node.child[1], false));
            stack.push((node.child[0], false));
        }
    }
    let mut count = vec![0usize; n];
    let mut best = vec![0f64; n];
    let mut merge = vec![false; n];
    let leaf_cost = |k: usize, area: f64| cost.intersection_cost * k.div_ceil(block) as f64 * area;
    for &i in &order {
        let node = &tree.nodes[i as usize];
        let area = Aabb::from_array(node.bounds).half_area();
        if node.is_leaf() {
            count[i as usize] = node.prim_count as usize;
            best[i as usize] = leaf_cost(node.prim_count as usize, area);
        } else {
            let [l, r] = node.child.map(|c| c as usize);
            let k = count[l] + count[r];
            let split = cost.traversal_cost * area + best[l] + best[r];
            count[i as usize] = k;
            best[i as usize] = split;
            if k <= cost.max_leaf && leaf_cost(k, area) < split {
                best[i as usize] = leaf_cost(k, area);
                merge[i as usize] = true;
            }
        }
    }
    // Rebuild in depth-first pre-order, a merged subtree as one leaf.
    let mut nodes: Vec<LogicalNode> = Vec::with_capacity(n);
    let mut prims: Vec<P> = Vec::with_capacity(tree.primitives.len());
    let mut merged = 0;
    let mut stack = vec![(tree.root, NO_NODE, 0usize)];
    while let Some((i, parent, k)) = stack.pop() {
        let at = nodes.len() as u32;
        if parent != NO_NODE {
            nodes[parent as usize].child[k] = at;
        }
        let node = tree.nodes[i as usize];
        if node.is_leaf() || merge[i as usize] {
            merged += usize::from(!node.is_leaf());
            let first = prims.len() as u32;
            // The subtree's leaves, left first.
            let mut inner = vec![i];
            while let Some(j) = inner.pop() {
                let m = &tree.nodes[j as usize];
                if m.is_leaf() {
                    prims.extend_from_slice(tree.leaf_primitives(m));
                } else {
                    inner.push(m.child[1]);
                    inner.push(m.child[0]);
                }
            }
            let bounds = Aabb::from_array(node.bounds);
            nodes.push(LogicalNode::leaf(bounds, first, prims.len() as u32 - first));
        } else {
            nodes.push(node);
            stack.push((node.child[1], at, 1));
            stack.push((node.child[0], at, 0));
        }
    }
    tree.nodes = nodes;
    tree.root = 0;
    tree.primitives = prims;
    merged
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{build_sah_binned, SahOptions};
    use crate::scene::gen;

    /// The SAH cost of `t` with leaves tested in runs of `block` (unnormalized).
    fn block_cost(t: &LogicalTree, block: usize) -> f64 {
        t.nodes
            .iter()
            .map(|n| {
                let a = Aabb::from_array(n.bounds).half_area();
                if n.is_leaf() {
                    (n.prim_count as usize).div_ceil(block) as f64 * a
                } else {
                    a
                }
            })
            .sum()
    }

    #[test]
    fn collapsing_keeps_the_primitives_and_never_raises_the_block_cost() {
        let scene = gen::random_soup(3000, 0.05, 7);
        let one = SahOptions {
            block: 1,
            ..SahOptions::default()
        };
        let plain = build_sah_binned(&scene.triangles, &one);
        for block in [1, 2, 4] {
            let mut t = plain.clone();
            let cost = CollapseCost {
                max_leaf: 15,
                block,
                traversal_cost: 1.0,
                intersection_cost: 1.0,
            };
            let merged = collapse(&mut t, &cost);
            t.validate_with_cap(15).unwrap();
            let mut before: Vec<u32> = plain.primitives.iter().map(|p| p.id).collect();
            let mut after: Vec<u32> = t.primitives.iter().map(|p| p.id).collect();
            before.sort_unstable();
            after.sort_unstable();
            assert_eq!(before, after, "block {block}: the same primitives");
            assert_eq!(merged == 0, t.nodes == plain.nodes, "block {block}");
            assert!(t.stats().leaves <= plain.stats().leaves, "block {block}");
            let (b, a) = (block_cost(&plain, block), block_cost(&t, block));
            assert!(a <= b, "block {block}: cost {b} -> {a}");
            if block == 4 {
                assert!(merged > 0, "runs of four merge some leaves");
                assert!(t.stats().leaves * 10 < plain.stats().leaves * 8);
            }
        }
    }
}
