//! The logical tree: the layout-free binary BVH that every generated constructor reads
//! (architecture §5, paper §3 "logical view" and §7.1 constructor specialization).
//!
//! Form: flat arrays, C ABI. `nodes[i]` is a [`LogicalNode`]; `root` indexes `nodes`;
//! `primitives` is the scene's triangles reordered so that each leaf's primitives are the
//! contiguous range `[prim_offset, prim_offset + prim_count)`, each keeping its original `id`.
//! Nodes may come in any order (builders here emit depth-first pre-order, left before right,
//! so the root is node 0 and an interior node's left child is the next node).
//!
//! Canonical unused fields: an interior node has `prim_offset = prim_count = 0`; a leaf has
//! `child = [NO_NODE, NO_NODE]`. An empty scene is the tree with no nodes, no primitives and
//! `root = NO_NODE`.
//!
//! [`LogicalTree::validate`] checks the whole contract; [`LogicalTree::stats`] summarizes.

use crate::geom::{Aabb, Triangle};
use crate::primitive::Primitive;

/// `kind` of an interior node.
pub const KIND_INTERIOR: u32 = 0;
/// `kind` of a leaf.
pub const KIND_LEAF: u32 = 1;
/// "No node": the root of an empty tree and the children of a leaf.
pub const NO_NODE: u32 = u32::MAX;
/// The shared leaf-size cap (language notes, "Logical trees": several layouts keep the count
/// in 4 bits).
pub const DEFAULT_MAX_LEAF: usize = 15;

/// One node of the logical tree, as generated code reads it (44 bytes, `#[repr(C)]`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogicalNode {
    /// [`KIND_INTERIOR`] or [`KIND_LEAF`].
    pub kind: u32,
    /// `[lo.x, lo.y, lo.z, hi.x, hi.y, hi.z]`: exactly the union of the children's boxes
    /// (interior) or of the primitives' corners (leaf).
    pub bounds: [f32; 6],
    /// Left and right child (interior); `[NO_NODE, NO_NODE]` for a leaf.
    pub child: [u32; 2],
    /// First primitive of a leaf in [`LogicalTree::primitives`]; 0 for an interior node.
    pub prim_offset: u32,
    /// Number of primitives of a leaf (`1..=cap`); 0 for an interior node.
    pub prim_count: u32,
}

impl LogicalNode {
    /// An interior node.
    pub fn interior(bounds: Aabb, left: u32, right: u32) -> LogicalNode {
        LogicalNode {
            kind: KIND_INTERIOR,
            bounds: bounds.to_array(),
            child: [left, right],
            prim_offset: 0,
            prim_count: 0,
        }
    }

    /// A leaf holding `primitives[offset..offset + count]`.
    pub fn leaf(bounds: Aabb, offset: u32, count: u32) -> LogicalNode {
        LogicalNode {
            kind: KIND_LEAF,
            bounds: bounds.to_array(),
            child: [NO_NODE, NO_NODE],
            prim_offset: offset,
            prim_count: count,
        }
    }

    /// True for a leaf.
    pub fn is_leaf(&self) -> bool {
        self.kind == KIND_LEAF
    }

    /// The node's box.
    pub fn aabb(&self) -> Aabb {
        Aabb::from_array(self.bounds)
    }
}

/// A logical BVH over primitives `P` (triangles unless said otherwise; see the module
/// documentation for the contract).
#[derive(Clone, Debug, PartialEq)]
pub struct LogicalTree<P: Primitive = Triangle> {
    /// The nodes, in any order.
    pub nodes: Vec<LogicalNode>,
    /// Index of the root in `nodes`, [`NO_NODE`] for the empty tree.
    pub root: u32,
    /// The primitives, reordered so that every leaf's are contiguous.
    pub primitives: Vec<P>,
}

/// Summary numbers of a tree.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TreeStats {
    /// All nodes.
    pub nodes: usize,
    /// Interior nodes.
    pub interior: usize,
    /// Leaves.
    pub leaves: usize,
    /// Nodes on the longest root-to-leaf path (1 for a single leaf, 0 for the empty tree).
    pub depth: usize,
    /// Primitives.
    pub primitives: usize,
    /// Largest leaf.
    pub max_leaf: usize,
    /// Traversal stack a left-first traversal needs: the most left edges on any root-to-node
    /// path, i.e. the most right children pending at once when a traversal descends into the
    /// left child and pushes the right one (0 for a single leaf). A fixed stack of this many
    /// entries never overflows on this tree (a traversal that pushes both children needs one
    /// more).
    pub stack_needed: usize,
    /// SAH cost with traversal and intersection costs 1: the sum over interior nodes of
    /// `area / root area` plus the sum over leaves of `count * area / root area`.
    pub sah_cost: f64,
}

impl<P: Primitive> LogicalTree<P> {
    /// The tree of an empty scene.
    pub fn empty() -> LogicalTree<P> {
        LogicalTree {
            nodes: Vec::new(),
            root: NO_NODE,
            primitives: Vec::new(),
        }
    }

    /// True for the tree of an empty scene.
    pub fn is_empty(&self) -> bool {
        self.root == NO_NODE
    }

    /// The root's box (`[lo.x, lo.y, lo.z, hi.x, hi.y, hi.z]`), `None` for the empty tree.
    pub fn root_box(&self) -> Option<[f32; 6]> {
        self.nodes.get(self.root as usize).map(|n| n.bounds)
    }

    /// The same tree with every node's box replaced by `f` of it: the tree a layout that
    /// stores boxes differently (quantized) really traverses.
    pub fn map_boxes(&self, f: impl Fn(&[f32; 6]) -> [f32; 6]) -> LogicalTree<P> {
        let mut out = self.clone();
        for n in &mut out.nodes {
            n.bounds = f(&n.bounds);
        }
        out
    }

    /// The primitives of leaf `node`.
    pub fn leaf_primitives(&self, node: &LogicalNode) -> &[P] {
        let start = node.prim_offset as usize;
        &self.primitives[start..start + node.prim_count as usize]
    }

    /// Validates with the shared leaf cap [`DEFAULT_MAX_LEAF`].
    pub fn validate(&self) -> Result<(), String> {
        self.validate_with_cap(DEFAULT_MAX_LEAF)
    }

    /// Checks the contract: root and child indices in range, every node reached exactly once
    /// from the root (so the graph is a tree: acyclic, unshared, no orphans), canonical unused
    /// fields, leaves of `1..=cap` primitives whose ranges cover every primitive exactly once,
    /// finite primitives with distinct ids below `u32::MAX`, and every node's bounds equal to
    /// the `f32` min/max union of its children's bounds or of its primitives' corners.
    /// Returns the first problem found.
    pub fn validate_with_cap(&self, cap: usize) -> Result<(), String> {
        let n = self.nodes.len();
        if n == 0 {
            if self.root != NO_NODE {
                return Err(format!("tree has no nodes but root is {}", self.root));
            }
            if !self.primitives.is_empty() {
                return Err(format!(
                    "tree has no nodes but {} primitives",
                    self.primitives.len()
                ));
            }
            return Ok(());
        }
        if self.root as usize >= n {
            return Err(format!("root {} out of range ({n} nodes)", self.root));
        }
        self.check_primitives()?;
        let mut seen = vec![false; n];
        let mut covered = vec![false; self.primitives.len()];
        let mut stack = vec![self.root];
        while let Some(i) = stack.pop() {
            if std::mem::replace(&mut seen[i as usize], true) {
                return Err(format!(
                    "node {i} is reached twice (a cycle or a shared subtree)"
                ));
            }
            let node = &self.nodes[i as usize];
            match node.kind {
                KIND_INTERIOR => {
                    if node.prim_offset != 0 || node.prim_count != 0 {
                        return Err(format!("interior node {i} has prim_offset/prim_count set"));
                    }
                    let mut union = Aabb::EMPTY;
                    for c in node.child {
                        if c as usize >= n {
                            return Err(format!("node {i}: child {c} out of range ({n} nodes)"));
                        }
                        union = union.union(self.nodes[c as usize].aabb());
                        stack.push(c);
                    }
                    check_bounds(i, node, union, "its children's")?;
                }
                KIND_LEAF => {
                    if node.child != [NO_NODE, NO_NODE] {
                        return Err(format!("leaf {i} has children {:?}", node.child));
                    }
                    let count = node.prim_count as usize;
                    if count == 0 || count > cap {
                        return Err(format!(
                            "leaf {i} holds {count} primitives (allowed 1..={cap})"
                        ));
                    }
                    let start = node.prim_offset as usize;
                    if start + count > self.primitives.len() {
                        return Err(format!(
                            "leaf {i}: primitives {start}..{} out of range ({} primitives)",
                            start + count,
                            self.primitives.len()
                        ));
                    }
                    let mut union = Aabb::EMPTY;
                    for (k, c) in covered[start..start + count].iter_mut().enumerate() {
                        if std::mem::replace(c, true) {
                            return Err(format!(
                                "primitive {} is in more than one leaf (again in leaf {i})",
                                start + k
                            ));
                        }
                        union = union.union(self.primitives[start + k].bounds());
                    }
                    check_bounds(i, node, union, "its primitives'")?;
                }
                other => return Err(format!("node {i} has unknown kind {other}")),
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

    fn check_primitives(&self) -> Result<(), String> {
        let mut ids: Vec<u32> = Vec::with_capacity(self.primitives.len());
        for (k, t) in self.primitives.iter().enumerate() {
            if !t.is_finite() {
                return Err(format!(
                    "primitive {k} (id {}) has a non-finite coordinate",
                    t.id()
                ));
            }
            if t.id() == u32::MAX {
                return Err(format!("primitive {k} has the reserved id u32::MAX"));
            }
            ids.push(t.id());
        }
        ids.sort_unstable();
        if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
            return Err(format!("id {} is used by two primitives", w[0]));
        }
        Ok(())
    }

    /// Node counts, depth, largest leaf, stack need and SAH cost. Meant for valid trees; on an
    /// invalid one it stops after as many visits as there are nodes (so a cycle cannot hang
    /// it) and skips out-of-range children.
    pub fn stats(&self) -> TreeStats {
        let mut s = TreeStats {
            primitives: self.primitives.len(),
            ..TreeStats::default()
        };
        if self.is_empty() {
            return s;
        }
        let Some(root) = self.nodes.get(self.root as usize) else {
            return s;
        };
        let root_area = root.aabb().half_area();
        let rel = |b: Aabb| {
            if root_area > 0.0 {
                b.half_area() / root_area
            } else {
                1.0
            }
        };
        let mut stack = vec![(self.root, 1usize, 0usize)];
        while let Some((i, depth, lefts)) = stack.pop() {
            let Some(node) = self.nodes.get(i as usize) else {
                continue;
            };
            if s.nodes == self.nodes.len() {
                break;
            }
            s.nodes += 1;
            s.depth = s.depth.max(depth);
            s.stack_needed = s.stack_needed.max(lefts);
            if node.is_leaf() {
                s.leaves += 1;
                s.max_leaf = s.max_leaf.max(node.prim_count as usize);
                s.sah_cost += node.prim_count as f64 * rel(node.aabb());
            } else {
                s.interior += 1;
                s.sah_cost += rel(node.aabb());
                stack.push((node.child[1], depth + 1, lefts));
                stack.push((node.child[0], depth + 1, lefts + 1));
            }
        }
        s
    }
}

fn check_bounds(i: u32, node: &LogicalNode, union: Aabb, what: &str) -> Result<(), String> {
    // `==` on f32: exact, and -0.0 equals 0.0 (f32 min/max may pick either zero).
    if node.bounds != union.to_array() {
        return Err(format!(
            "node {i}: bounds {:?} are not the union of {what} bounds {:?}",
            node.bounds,
            union.to_array()
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vec3;

    fn tri(x: f32, id: u32) -> Triangle {
        Triangle::new(
            Vec3::new(x, 0.0, 0.0),
            Vec3::new(x + 1.0, 0.0, 0.0),
            Vec3::new(x, 1.0, 0.0),
            id,
        )
    }

    fn two_leaves() -> LogicalTree {
        let prims = vec![tri(0.0, 5), tri(2.0, 3)];
        let b0 = prims[0].bounds();
        let b1 = prims[1].bounds();
        LogicalTree {
            nodes: vec![
                LogicalNode::interior(b0.union(b1), 1, 2),
                LogicalNode::leaf(b0, 0, 1),
                LogicalNode::leaf(b1, 1, 1),
            ],
            root: 0,
            primitives: prims,
        }
    }

    #[test]
    fn node_is_44_bytes() {
        assert_eq!(std::mem::size_of::<LogicalNode>(), 44);
    }

    #[test]
    fn valid_tree_and_stats() {
        let t = two_leaves();
        t.validate().unwrap();
        let s = t.stats();
        assert_eq!(
            (s.nodes, s.interior, s.leaves, s.depth, s.max_leaf),
            (3, 1, 2, 2, 1)
        );
        LogicalTree::<Triangle>::empty().validate().unwrap();
        assert_eq!(LogicalTree::<Triangle>::empty().stats().depth, 0);
    }

    #[test]
    fn each_violation_is_reported() {
        let mut t = two_leaves();
        t.nodes[0].child[1] = 1;
        t.nodes[0].bounds = t.nodes[1].bounds;
        assert!(t.validate().unwrap_err().contains("reached twice"));

        let mut t = two_leaves();
        t.nodes[0].child[1] = 0;
        assert!(t.validate().unwrap_err().contains("reached twice"));

        let mut t = two_leaves();
        t.nodes[0].child[1] = 9;
        assert!(t.validate().unwrap_err().contains("out of range"));

        let mut t = two_leaves();
        t.nodes[0].bounds[3] += 1.0;
        assert!(t.validate().unwrap_err().contains("not the union"));

        let mut t = two_leaves();
        t.nodes[2].bounds[0] -= 0.5;
        assert!(t.validate().unwrap_err().contains("not the union"));

        let mut t = two_leaves();
        t.nodes[2].prim_offset = 0;
        t.nodes[2].bounds = t.nodes[1].bounds;
        t.nodes[0].bounds = t.nodes[1].bounds;
        assert!(t.validate().unwrap_err().contains("more than one leaf"));

        let mut t = two_leaves();
        t.nodes[2].prim_count = 0;
        assert!(t.validate().unwrap_err().contains("allowed 1..=15"));

        let mut t = two_leaves();
        t.primitives[1].id = 5;
        assert!(t.validate().unwrap_err().contains("used by two"));

        let mut t = two_leaves();
        t.nodes.push(t.nodes[1]);
        assert!(t.validate().unwrap_err().contains("not reachable"));

        let mut t = two_leaves();
        t.primitives.push(tri(9.0, 7));
        assert!(t.validate().unwrap_err().contains("in no leaf"));

        let mut t = two_leaves();
        t.nodes[1].kind = 7;
        assert!(t.validate().unwrap_err().contains("unknown kind"));

        let mut t = LogicalTree::<Triangle>::empty();
        t.root = 0;
        assert!(t.validate().is_err());
        assert_eq!(t.stats().nodes, 0);

        // stats() terminates on a cycle.
        let mut t = two_leaves();
        t.nodes[0].child[1] = 0;
        assert!(t.stats().nodes <= 3);
    }
}
