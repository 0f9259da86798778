//! Filling a schema: [`LogicalBytes::fill`] writes a built [`LogicalTree`] into logical nodes
//! of a [`Schema`]'s shape (node for node for a binary tree type, collapsed to the schema's
//! arity otherwise, oriented nodes where [`super::oriented::fit`] orients them).

use super::dop14::{node_dops, Dop14};
use super::logical::{LogicalTree, NO_NODE};
use super::oriented::{fit, OrientedNode, OrientedOptions};
use super::schema::{Role, Schema, SHARED};
use crate::geom::{Aabb, Vec3};
use crate::primitive::Primitive;

/// A tree's logical nodes in a schema's form (the primitives they index are the tree's).
#[derive(Clone, Debug, Default)]
pub struct LogicalBytes {
    /// The nodes' storage: `node_count * node_size` bytes from `start`, 8 bytes of slack so
    /// that `start` is 8-aligned.
    storage: Vec<u8>,
    /// Where the nodes start in `storage`.
    start: usize,
    /// Bytes per node.
    pub node_size: usize,
    /// Number of nodes.
    pub node_count: usize,
    /// The root's index, [`NO_NODE`] for the empty tree.
    pub root: u32,
}

/// One node before encoding.
struct Node {
    kind: u32,
    bounds: Aabb,
    /// The node's DOP-14 (only computed when the schema has a DOP field).
    dop: Dop14,
    children: Vec<(u32, Aabb)>,
    /// The oriented form of an interior node of the oriented variant.
    obb: Option<OrientedNode>,
    prims: (u32, u32),
}

impl LogicalBytes {
    /// The nodes as bytes.
    pub fn nodes(&self) -> &[u8] {
        &self.storage[self.start..self.start + self.node_count * self.node_size]
    }

    /// `tree` in `schema`'s form; an error names a schema the runtime cannot fill (see
    /// [`Schema::validate`]) or a tree too large for `u32` indices. A schema with an
    /// oriented interior variant orients nodes by [`OrientedOptions::default`].
    pub fn fill<P: Primitive>(
        tree: &LogicalTree<P>,
        schema: &Schema,
    ) -> Result<LogicalBytes, String> {
        Self::fill_oriented(tree, schema, &OrientedOptions::default())
    }

    /// [`LogicalBytes::fill`] with the rule for orienting nodes ([`super::oriented::fit`]).
    pub fn fill_oriented<P: Primitive>(
        tree: &LogicalTree<P>,
        schema: &Schema,
        oriented: &OrientedOptions,
    ) -> Result<LogicalBytes, String> {
        schema.validate()?;
        if schema.primitive != P::TYPE_NAME {
            return Err(format!(
                "`{}` holds `{}` primitives, and this tree's are `{}`s",
                schema.adt,
                schema.primitive,
                P::TYPE_NAME
            ));
        }
        let wants_dop = schema
            .fields
            .iter()
            .any(|f| f.role == Role::Dop14Bounds as u32);
        let dops = if wants_dop {
            node_dops(tree)
        } else {
            vec![Dop14::EMPTY; tree.nodes.len()]
        };
        let (nodes, root) = if tree.is_empty() {
            (Vec::new(), NO_NODE)
        } else if schema.arity == 2 && schema.oriented().is_none() {
            (binary_nodes(tree, schema, &dops), tree.root)
        } else {
            wide_nodes(tree, schema, &dops, oriented)
        };
        if nodes.len() >= NO_NODE as usize {
            return Err(format!(
                "{} logical nodes do not fit u32 indices",
                nodes.len()
            ));
        }
        let size = schema.node_size as usize;
        let mut storage = vec![0u8; nodes.len() * size + 8];
        let start = (8 - storage.as_ptr() as usize % 8) % 8;
        for (i, n) in nodes.iter().enumerate() {
            let at = start + i * size;
            encode(&mut storage[at..at + size], n, schema);
        }
        Ok(LogicalBytes {
            storage,
            start,
            node_size: size,
            node_count: nodes.len(),
            root,
        })
    }
}

fn binary_nodes<P: Primitive>(tree: &LogicalTree<P>, schema: &Schema, dops: &[Dop14]) -> Vec<Node> {
    tree.nodes
        .iter()
        .zip(dops)
        .map(|(n, &dop)| {
            if n.is_leaf() {
                Node {
                    kind: schema.leaf,
                    bounds: n.aabb(),
                    dop,
                    children: Vec::new(),
                    obb: None,
                    prims: (n.prim_offset, n.prim_count),
                }
            } else {
                Node {
                    kind: schema.interior,
                    bounds: n.aabb(),
                    dop,
                    children: n
                        .child
                        .iter()
                        .map(|&c| (c, tree.nodes[c as usize].aabb()))
                        .collect(),
                    obb: None,
                    prims: (0, 0),
                }
            }
        })
        .collect()
}

/// Collapsed to `schema.arity` slots: interior nodes in pre-order (the root first), then the
/// leaves, then one empty leaf per empty slot. With an oriented variant, each interior node
/// that [`fit`] orients takes it.
fn wide_nodes<P: Primitive>(
    tree: &LogicalTree<P>,
    schema: &Schema,
    dops: &[Dop14],
    oriented: &OrientedOptions,
) -> (Vec<Node>, u32) {
    let width = schema.arity as usize;
    let root = &tree.nodes[tree.root as usize];
    let leaf = |n: &super::LogicalNode, i: u32| Node {
        kind: schema.leaf,
        bounds: n.aabb(),
        dop: dops[i as usize],
        children: Vec::new(),
        obb: None,
        prims: (n.prim_offset, n.prim_count),
    };
    if root.is_leaf() {
        return (vec![leaf(root, tree.root)], 0);
    }
    // Pass 1: interior nodes in pre-order with their binary children.
    let mut interior: Vec<(u32, Vec<u32>)> = Vec::new();
    let mut work = vec![tree.root];
    while let Some(bin) = work.pop() {
        let slots = super::wide::open(tree, bin, width);
        for &c in slots.iter().rev() {
            if !tree.nodes[c as usize].is_leaf() {
                work.push(c);
            }
        }
        interior.push((bin, slots));
    }
    // Numbering: interior nodes 0.., leaves after them in slot order.
    let mut index = vec![NO_NODE; tree.nodes.len()];
    for (i, (bin, _)) in interior.iter().enumerate() {
        index[*bin as usize] = i as u32;
    }
    let mut nodes: Vec<Node> = Vec::with_capacity(interior.len() * 2);
    let mut leaves: Vec<Node> = Vec::new();
    let mut next = interior.len() as u32;
    for (bin, slots) in &interior {
        let mut children = Vec::with_capacity(width);
        for &c in slots {
            let n = &tree.nodes[c as usize];
            if n.is_leaf() {
                index[c as usize] = next;
                next += 1;
                leaves.push(leaf(n, c));
            }
            children.push((index[c as usize], n.aabb()));
        }
        // The root stays axis-aligned (catalog §6: AABB nodes near the root), so every
        // oriented node has an axis-aligned ancestor whose exit distance bounds its hits.
        let obb = schema
            .oriented()
            .filter(|_| *bin != tree.root)
            .and_then(|v| Some((v, fit(tree, slots, oriented)?)));
        nodes.push(Node {
            kind: obb.as_ref().map_or(schema.interior, |o| o.0),
            bounds: tree.nodes[*bin as usize].aabb(),
            dop: dops[*bin as usize],
            children,
            obb: obb.map(|o| o.1),
            prims: (0, 0),
        });
    }
    nodes.extend(leaves);
    // Each empty slot gets its own empty leaf, so the logical tree stays a tree and a layout
    // that places a record per leaf has room for every one (`node_count` bounds placements).
    let mut empties = 0;
    for node in nodes.iter_mut().take(interior.len()) {
        while node.children.len() < width {
            node.children.push((next + empties, Aabb::EMPTY));
            empties += 1;
        }
    }
    nodes.extend((0..empties).map(|_| Node {
        kind: schema.leaf,
        bounds: Aabb::EMPTY,
        dop: Dop14::EMPTY,
        children: Vec::new(),
        obb: None,
        prims: (0, 0),
    }));
    (nodes, 0)
}

fn put(bytes: &mut [u8], at: usize, v: &[u8]) {
    bytes[at..at + v.len()].copy_from_slice(v);
}

fn put_box(bytes: &mut [u8], at: usize, b: Aabb) {
    for (k, x) in b.to_array().iter().enumerate() {
        put(bytes, at + 4 * k, &x.to_le_bytes());
    }
}

fn encode(bytes: &mut [u8], n: &Node, schema: &Schema) {
    put(bytes, 0, &n.kind.to_le_bytes());
    for f in &schema.fields {
        if f.variant != SHARED && f.variant != n.kind {
            continue;
        }
        let at = f.offset as usize;
        match Role::from_u32(f.role) {
            Some(Role::Bounds) => put_box(bytes, at, n.bounds),
            Some(Role::ChildBounds) => {
                for k in 0..f.count as usize {
                    let b = n
                        .children
                        .get(f.slot as usize + k)
                        .map_or(Aabb::EMPTY, |c| c.1);
                    put_box(bytes, at + 24 * k, b);
                }
            }
            Some(Role::Children) => {
                for k in 0..f.count as usize {
                    let c = n.children.get(f.slot as usize + k).map_or(NO_NODE, |c| c.0);
                    put(bytes, at + 4 * k, &c.to_le_bytes());
                }
            }
            Some(Role::PrimCount) => {
                let c = u64::from(n.prims.1).to_le_bytes();
                put(bytes, at, &c[..f.width as usize]);
            }
            Some(Role::PrimOffset) => put(bytes, at, &n.prims.0.to_le_bytes()),
            Some(Role::ChildObbs) => {
                for k in 0..f.count as usize {
                    let at = at + 60 * k;
                    let slot = f.slot as usize + k;
                    let (cols, b) = match &n.obb {
                        Some(o) if slot < o.boxes.len() => {
                            ([0, 1, 2].map(|j| o.orientation.column(j)), o.boxes[slot])
                        }
                        _ => ([Vec3::splat(0.0); 3], Aabb::EMPTY),
                    };
                    for (j, c) in cols.iter().enumerate() {
                        for (l, x) in c.to_array().iter().enumerate() {
                            put(bytes, at + 12 * j + 4 * l, &x.to_le_bytes());
                        }
                    }
                    put_box(bytes, at + 36, b);
                }
            }
            Some(Role::Dop14Bounds) => {
                for (k, x) in n.dop.to_array().iter().enumerate() {
                    put(bytes, at + 4 * k, &x.to_le_bytes());
                }
            }
            None => {}
        }
    }
}
