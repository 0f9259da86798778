//! Wide BVHs: a binary [`LogicalTree`] collapsed to at most `W` children per node (the logical
//! form of the four- and eight-wide layouts; layout catalog §2.1 "Eight-wide" and §4 "Wide
//! builders").
//!
//! Form: a wide node stores its children's boxes and references, as Embree's and the catalog's
//! wide nodes do; a child is an interior node (an index into [`WideTree::nodes`]), a leaf (a
//! range of the binary tree's primitives, which the wide tree shares unchanged) or an empty slot
//! (box [`Aabb::EMPTY`]). Occupied slots come first. The root is a [`WideChild`] with the scene's
//! box, so a scene of one leaf needs no node.
//!
//! Collapse (Embree style): a wide node starts from the two children of a binary interior node
//! and, while it has fewer than `W` children, opens the interior child with the largest surface
//! area (the first such slot on equal areas), putting its left child in its slot and its right
//! child after it. Each remaining interior child becomes a wide node in turn, in depth-first
//! pre-order (the root node is 0). Leaves stay the binary tree's leaves, so the primitive order
//! and the leaf cap carry over, and every child box is exactly a binary node's box.

use super::logical::{LogicalTree, NO_NODE};
use crate::geom::Aabb;
use crate::primitive::Primitive;

/// One child slot of a wide node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WideChild {
    /// No child (the slot's box is [`Aabb::EMPTY`]).
    Empty,
    /// The wide node `nodes[i]`.
    Node(u32),
    /// The primitives `[offset, offset + count)` of the tree's primitive array.
    Leaf {
        /// First primitive.
        offset: u32,
        /// Number of primitives (at least 1).
        count: u32,
    },
}

/// A node of `W` child slots: boxes and references, occupied slots first.
#[derive(Clone, Debug, PartialEq)]
pub struct WideNode<const W: usize> {
    /// The children's boxes ([`Aabb::EMPTY`] for an empty slot).
    pub bounds: [Aabb; W],
    /// The children.
    pub children: [WideChild; W],
}

impl<const W: usize> WideNode<W> {
    /// The occupied slots.
    pub fn len(&self) -> usize {
        self.children
            .iter()
            .take_while(|c| **c != WideChild::Empty)
            .count()
    }

    /// True when no slot is occupied (never the case in a built tree).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A wide BVH over the primitives of the binary tree it was collapsed from.
#[derive(Clone, Debug, PartialEq)]
pub struct WideTree<const W: usize> {
    /// Interior nodes, root first (depth-first pre-order).
    pub nodes: Vec<WideNode<W>>,
    /// The root: [`WideChild::Empty`] for an empty scene, a leaf for a one-leaf scene.
    pub root: WideChild,
    /// The scene's box (the binary root's), [`Aabb::EMPTY`] for an empty scene.
    pub root_bounds: Aabb,
}

/// Summary numbers of a wide tree.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WideStats {
    /// Interior nodes.
    pub nodes: usize,
    /// Leaves.
    pub leaves: usize,
    /// Occupied child slots over all slots of all nodes (1.0 when every slot is used).
    pub occupancy: f64,
    /// Nodes on the longest path from the root node to a node (0 without nodes).
    pub depth: usize,
}

/// Collapses `tree` into a tree of at most `W` children per node (`2 <= W <= 64`).
pub fn collapse<const W: usize>(tree: &LogicalTree<impl Primitive>) -> WideTree<W> {
    assert!(
        (2..=64).contains(&W),
        "a wide tree has 2 to 64 children per node"
    );
    let mut out = WideTree {
        nodes: Vec::new(),
        root: WideChild::Empty,
        root_bounds: Aabb::EMPTY,
    };
    if tree.is_empty() {
        return out;
    }
    let root = &tree.nodes[tree.root as usize];
    out.root_bounds = root.aabb();
    if root.is_leaf() {
        out.root = WideChild::Leaf {
            offset: root.prim_offset,
            count: root.prim_count,
        };
        return out;
    }
    out.root = WideChild::Node(0);
    // Depth-first pre-order: a node is numbered when it is popped, and its interior children
    // are pushed last slot first, so the first child's subtree is numbered next.
    let mut work: Vec<(u32, Option<(u32, usize)>)> = vec![(tree.root, None)];
    while let Some((bin, parent)) = work.pop() {
        let id = out.nodes.len() as u32;
        if let Some((p, k)) = parent {
            out.nodes[p as usize].children[k] = WideChild::Node(id);
        }
        let mut node = empty_node::<W>();
        let mut interior = Vec::new();
        for (k, &c) in open(tree, bin, W).iter().enumerate() {
            let n = &tree.nodes[c as usize];
            node.bounds[k] = n.aabb();
            node.children[k] = if n.is_leaf() {
                WideChild::Leaf {
                    offset: n.prim_offset,
                    count: n.prim_count,
                }
            } else {
                interior.push((c, k));
                // Patched when the child's node is numbered.
                WideChild::Node(NO_NODE)
            };
        }
        out.nodes.push(node);
        for &(c, k) in interior.iter().rev() {
            work.push((c, Some((id, k))));
        }
    }
    out
}

fn empty_node<const W: usize>() -> WideNode<W> {
    WideNode {
        bounds: [Aabb::EMPTY; W],
        children: [WideChild::Empty; W],
    }
}

/// The binary nodes that become the children of the wide node made from interior `bin`.
pub(crate) fn open<P: Primitive>(tree: &LogicalTree<P>, bin: u32, width: usize) -> Vec<u32> {
    let mut slots: Vec<u32> = tree.nodes[bin as usize].child.to_vec();
    while slots.len() < width {
        let mut best: Option<(usize, f64)> = None;
        for (k, &c) in slots.iter().enumerate() {
            let n = &tree.nodes[c as usize];
            if n.is_leaf() {
                continue;
            }
            let a = n.aabb().half_area();
            if best.is_none_or(|(_, b)| a > b) {
                best = Some((k, a));
            }
        }
        let Some((k, _)) = best else {
            break;
        };
        let [l, r] = tree.nodes[slots[k] as usize].child;
        slots[k] = l;
        slots.insert(k + 1, r);
    }
    slots
}

impl<const W: usize> WideTree<W> {
    /// True for the tree of an empty scene.
    pub fn is_empty(&self) -> bool {
        self.root == WideChild::Empty
    }

    /// Checks the tree against the binary `tree` it was collapsed from: every node reached once
    /// from the root, occupied slots first with at least two per node, every occupied slot's
    /// box the exact union of what it holds, leaves of at least one primitive covering each of
    /// `tree`'s primitives exactly once. Returns the first problem found.
    pub fn validate<P: Primitive>(&self, tree: &LogicalTree<P>) -> Result<(), String> {
        let mut covered = vec![false; tree.primitives.len()];
        let mut seen = vec![false; self.nodes.len()];
        let mut stack: Vec<(WideChild, Aabb, String)> =
            vec![(self.root, self.root_bounds, "the root".to_string())];
        while let Some((child, bounds, at)) = stack.pop() {
            match child {
                WideChild::Empty => {
                    if !self.nodes.is_empty() || !tree.primitives.is_empty() {
                        return Err(format!("{at} is empty in a non-empty tree"));
                    }
                }
                WideChild::Leaf { offset, count } => {
                    let (start, end) = (offset as usize, offset as usize + count as usize);
                    if count == 0 || end > tree.primitives.len() {
                        return Err(format!(
                            "{at}: leaf {start}..{end} is empty or out of range"
                        ));
                    }
                    let mut union = Aabb::EMPTY;
                    for (p, c) in covered.iter_mut().enumerate().take(end).skip(start) {
                        if std::mem::replace(c, true) {
                            return Err(format!("primitive {p} is in two leaves (again at {at})"));
                        }
                        union = union.union(tree.primitives[p].bounds());
                    }
                    if union != bounds {
                        return Err(format!(
                            "{at}: box {bounds:?} is not its primitives' {union:?}"
                        ));
                    }
                }
                WideChild::Node(i) => {
                    let Some(node) = self.nodes.get(i as usize) else {
                        return Err(format!("{at}: node {i} out of range"));
                    };
                    if std::mem::replace(&mut seen[i as usize], true) {
                        return Err(format!("node {i} is reached twice"));
                    }
                    let n = node.len();
                    if n < 2 {
                        return Err(format!("node {i} has {n} children"));
                    }
                    let mut union = Aabb::EMPTY;
                    for k in 0..W {
                        let c = node.children[k];
                        if k >= n {
                            if c != WideChild::Empty || node.bounds[k] != Aabb::EMPTY {
                                return Err(format!(
                                    "node {i}: slot {k} after an empty slot is used"
                                ));
                            }
                            continue;
                        }
                        union = union.union(node.bounds[k]);
                        stack.push((c, node.bounds[k], format!("node {i} slot {k}")));
                    }
                    if union != bounds {
                        return Err(format!(
                            "{at}: box {bounds:?} is not its children's {union:?}"
                        ));
                    }
                }
            }
        }
        if let Some(i) = seen.iter().position(|s| !s) {
            return Err(format!("node {i} is not reachable from the root"));
        }
        if let Some(p) = covered.iter().position(|c| !c) {
            return Err(format!("primitive {p} is in no leaf"));
        }
        Ok(())
    }

    /// Nodes, leaves, slot occupancy and depth.
    pub fn stats(&self) -> WideStats {
        let mut s = WideStats {
            nodes: self.nodes.len(),
            ..WideStats::default()
        };
        let mut used = 0usize;
        for n in &self.nodes {
            used += n.len();
            s.leaves += n
                .children
                .iter()
                .filter(|c| matches!(c, WideChild::Leaf { .. }))
                .count();
        }
        if matches!(self.root, WideChild::Leaf { .. }) {
            s.leaves += 1;
        }
        if !self.nodes.is_empty() {
            s.occupancy = used as f64 / (self.nodes.len() * W) as f64;
        }
        let mut stack = match self.root {
            WideChild::Node(i) => vec![(i, 1usize)],
            _ => Vec::new(),
        };
        while let Some((i, d)) = stack.pop() {
            s.depth = s.depth.max(d);
            for c in &self.nodes[i as usize].children {
                if let WideChild::Node(j) = c {
                    stack.push((*j, d + 1));
                }
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{build_sah_binned, SahOptions};
    use crate::geom::Triangle;
    use crate::scene::gen;

    #[test]
    fn every_hard_case_collapses_to_a_valid_tree() {
        for scene in gen::hard_cases() {
            let tree = build_sah_binned(&scene.triangles, &SahOptions::default());
            let w4 = collapse::<4>(&tree);
            let w8 = collapse::<8>(&tree);
            w4.validate(&tree)
                .unwrap_or_else(|e| panic!("{}: W=4: {e}", scene.name));
            w8.validate(&tree)
                .unwrap_or_else(|e| panic!("{}: W=8: {e}", scene.name));
            let binary = tree.stats();
            // A wide node replaces at least one binary interior node, so there are never more.
            // (Wider is not always fewer: 1024 leaves in a balanced binary tree make 341 4-wide
            // nodes but 585 8-wide ones, 512 of them with two leaves, as 2^10 = 8^3 * 2.)
            assert!(w4.nodes.len() <= binary.interior.max(1), "{}", scene.name);
            assert!(w8.nodes.len() <= binary.interior.max(1), "{}", scene.name);
            assert_eq!(w4.stats().leaves, binary.leaves, "{}", scene.name);
            assert_eq!(w8.stats().leaves, binary.leaves, "{}", scene.name);
            // Greedy opening: a node with a free slot has only leaves left to open.
            for n in &w8.nodes {
                if n.len() < 8 {
                    assert!(
                        n.children.iter().all(|c| !matches!(c, WideChild::Node(_))),
                        "{}",
                        scene.name
                    );
                }
            }
        }
    }

    #[test]
    fn nodes_fill_up_and_come_in_pre_order() {
        let scene = gen::quad_grid(32, 32);
        // Leaves of one triangle (costed one at a time, so not collapsed).
        let one = SahOptions {
            block: 1,
            ..SahOptions::default()
        };
        let tree = build_sah_binned(&scene.triangles, &one);
        let w = collapse::<8>(&tree);
        let s = w.stats();
        // 1024 leaves: 1 + 8 + 64 nodes of 8 children, then 512 nodes of two leaves.
        assert_eq!((s.nodes, s.leaves, s.depth), (585, 1024, 4), "{s:?}");
        assert_eq!(w.root, WideChild::Node(0));
        // Pre-order: every interior child has a larger number than its parent, and the first
        // interior child of a node is the next node.
        for (i, n) in w.nodes.iter().enumerate() {
            let kids: Vec<u32> = n
                .children
                .iter()
                .filter_map(|c| match c {
                    WideChild::Node(j) => Some(*j),
                    _ => None,
                })
                .collect();
            assert!(kids.iter().all(|&j| j as usize > i));
            if let Some(&first) = kids.first() {
                assert_eq!(first as usize, i + 1);
            }
        }
    }

    #[test]
    fn small_scenes() {
        let empty = collapse::<8>(&LogicalTree::<Triangle>::empty());
        assert!(empty.is_empty() && empty.nodes.is_empty());
        empty.validate(&LogicalTree::<Triangle>::empty()).unwrap();
        let one = gen::one_triangle();
        let tree = build_sah_binned(&one.triangles, &SahOptions::default());
        let w = collapse::<4>(&tree);
        assert_eq!(
            w.root,
            WideChild::Leaf {
                offset: 0,
                count: 1
            }
        );
        assert!(w.nodes.is_empty());
        w.validate(&tree).unwrap();
    }

    #[test]
    fn the_largest_child_is_opened_first() {
        use crate::bvh::LogicalNode;
        use crate::geom::{Triangle, Vec3};
        // root = (A, B): A holds two wide-apart triangles (a large box), B two close ones.
        let tri = |x: f32, size: f32, id: u32| Triangle {
            p0: Vec3::new(x, 0.0, 0.0),
            p1: Vec3::new(x + size, 0.0, 0.0),
            p2: Vec3::new(x, size, 0.0),
            id,
        };
        let primitives = vec![
            tri(0.0, 4.0, 0),
            tri(10.0, 4.0, 1),
            tri(20.0, 1.0, 2),
            tri(22.0, 1.0, 3),
        ];
        let leaf = |k: usize| LogicalNode::leaf(primitives[k].bounds(), k as u32, 1);
        let (l0, l1, l2, l3) = (leaf(0), leaf(1), leaf(2), leaf(3));
        let a = LogicalNode::interior(l0.aabb().union(l1.aabb()), 2, 3);
        let b = LogicalNode::interior(l2.aabb().union(l3.aabb()), 5, 6);
        let root = LogicalNode::interior(a.aabb().union(b.aabb()), 1, 4);
        let tree = LogicalTree {
            nodes: vec![root, a, l0, l1, b, l2, l3],
            root: 0,
            primitives,
        };
        tree.validate().unwrap();
        let w3 = collapse::<3>(&tree);
        w3.validate(&tree).unwrap();
        assert_eq!(
            w3.nodes[0].children,
            [
                WideChild::Leaf {
                    offset: 0,
                    count: 1
                },
                WideChild::Leaf {
                    offset: 1,
                    count: 1
                },
                WideChild::Node(1)
            ]
        );
        assert_eq!(w3.nodes[1].len(), 2);
        // With four slots both are opened: four leaves under one node.
        let w4 = collapse::<4>(&tree);
        assert_eq!(w4.nodes.len(), 1);
        assert_eq!(w4.stats().occupancy, 1.0);
    }
}
