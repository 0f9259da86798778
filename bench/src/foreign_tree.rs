//! Another library's binary BVH as a [`LogicalTree`], so that builders can be compared with
//! the traversal held fixed: the SAH cost of each tree by one formula, and the work of the
//! same reference traversal (box tests, nodes visited, triangle tests per ray) on each
//! (`peers --builders`). Input: the triangles, the peer's root and a function giving each node's
//! shape; output: a valid logical tree (pre-order, exact boxes recomputed from the triangles,
//! so rounding in the peer's own boxes does not count).

use scion_runtime::bvh::{LogicalNode, LogicalTree};
use scion_runtime::geom::{Aabb, Triangle};

/// One node of a foreign binary BVH.
pub enum Shape<'s> {
    /// Children (the peer's node numbers), first then second.
    Interior(u32, u32),
    /// The triangles (indices into the scene's triangles) of a leaf.
    Leaf(&'s [u32]),
}

/// The logical tree of the foreign BVH rooted at `root` whose nodes `shape` describes, over
/// `tris`. Errors name a node that is reached twice or a triangle index out of range.
pub fn logical_tree<'s>(
    tris: &[Triangle],
    root: u32,
    shape: impl Fn(u32) -> Shape<'s>,
) -> Result<LogicalTree, String> {
    let mut nodes: Vec<LogicalNode> = Vec::new();
    let mut primitives: Vec<Triangle> = Vec::new();
    // (peer node, index of the parent's child slot to fill: (parent, 0 or 1))
    let mut stack = vec![(root, None::<(usize, usize)>)];
    let mut seen = std::collections::HashSet::new();
    while let Some((peer, slot)) = stack.pop() {
        if !seen.insert(peer) {
            return Err(format!("node {peer} is reached twice"));
        }
        let at = nodes.len();
        if let Some((parent, k)) = slot {
            nodes[parent].child[k] = at as u32;
        }
        let empty = Aabb::new(
            scion_runtime::geom::Vec3::splat(0.0),
            scion_runtime::geom::Vec3::splat(0.0),
        );
        match shape(peer) {
            Shape::Interior(a, b) => {
                nodes.push(LogicalNode::interior(empty, u32::MAX, u32::MAX));
                stack.push((b, Some((at, 1))));
                stack.push((a, Some((at, 0))));
            }
            Shape::Leaf(ids) => {
                let first = primitives.len() as u32;
                for &i in ids {
                    let t = tris
                        .get(i as usize)
                        .ok_or_else(|| format!("node {peer}: triangle {i} out of range"))?;
                    primitives.push(*t);
                }
                nodes.push(LogicalNode::leaf(empty, first, ids.len() as u32));
            }
        }
    }
    // Exact boxes, children before parents (reverse pre-order).
    for i in (0..nodes.len()).rev() {
        let n = nodes[i];
        let b = if n.is_leaf() {
            let ts = &primitives[n.prim_offset as usize..(n.prim_offset + n.prim_count) as usize];
            ts.iter().map(Triangle::bounds).reduce(Aabb::union)
        } else {
            Some(
                nodes[n.child[0] as usize]
                    .aabb()
                    .union(nodes[n.child[1] as usize].aabb()),
            )
        };
        nodes[i].bounds = b
            .ok_or_else(|| format!("an empty leaf at node {i}"))?
            .to_array();
    }
    Ok(LogicalTree {
        nodes,
        root: 0,
        primitives,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use scion_runtime::bvh::{build_sah_binned, SahOptions};
    use scion_runtime::scene::gen;

    #[test]
    fn a_logical_tree_read_back_as_foreign_is_the_same_tree() {
        let s = gen::random_soup(200, 0.1, 3);
        let t = build_sah_binned(&s.triangles, &SahOptions::default());
        // The tree's primitives are its own leaf order; index them as "the scene's".
        let ids: Vec<u32> = (0..t.primitives.len() as u32).collect();
        let back = logical_tree(&t.primitives, t.root, |i| {
            let n = &t.nodes[i as usize];
            if n.is_leaf() {
                let r = n.prim_offset as usize..(n.prim_offset + n.prim_count) as usize;
                Shape::Leaf(&ids[r])
            } else {
                Shape::Interior(n.child[0], n.child[1])
            }
        })
        .unwrap();
        back.validate().unwrap();
        assert_eq!(back.stats().sah_cost, t.stats().sah_cost);
        assert_eq!(back.nodes.len(), t.nodes.len());
        let cyclic = logical_tree(&t.primitives, 0, |_| Shape::Interior(0, 0));
        assert!(cyclic.unwrap_err().contains("twice"));
    }
}
