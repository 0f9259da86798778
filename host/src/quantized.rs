//! The logical tree a layout really traverses. A quantized layout (layout catalog §2.4) widens
//! every box to the nearest grid planes, so its traversal visits more nodes and may visit them
//! in another order: where two hits tie in `t`, or where the exact box's slab test prunes a
//! grazing hit that the wider box keeps, its answer can differ from the reference traversal of
//! the exact tree and still be right. Its bit-for-bit reference is the reference traversal of
//! [`DecodedTree::decoded_tree`]: the logical tree with every box replaced by the decoded box
//! the layout's build writes, computed with the quantization builtins' reference functions
//! ([`scion_ir::tree::quant::Boxes::decoder`], which the GPU runner `scion-gpu` uses too).
//! A wide layout that quantizes each node's children against the node's own frame
//! ([`Boxes::NodeQ8`], [`Boxes::NodeQ16`]) traverses the wide tree with those children's boxes
//! decoded ([`decoded_wide`]).

pub use scion_ir::tree::quant::Boxes;
use scion_runtime::bvh::wide::WideTree;
use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::Aabb;
use std::borrow::Cow;

/// The tree whose reference traversal a layout with these boxes must match bit for bit.
pub trait DecodedTree {
    /// `tree` with the boxes this layout's traversal sees (borrowed when they are exact).
    fn decoded_tree<'t>(&self, tree: &'t LogicalTree) -> Cow<'t, LogicalTree>;
}

impl DecodedTree for Boxes {
    fn decoded_tree<'t>(&self, tree: &'t LogicalTree) -> Cow<'t, LogicalTree> {
        match tree.root_box().and_then(|root| self.decoder(&root)) {
            Some(decode) => Cow::Owned(tree.map_boxes(decode)),
            None => Cow::Borrowed(tree),
        }
    }
}

/// `tree` (a binary tree collapsed to `W` children) with the child boxes a layout with these
/// boxes stores: each node's children decoded in the node's frame
/// (`scion_ir::tree::quant::decode_children`) when it quantizes per node, else unchanged.
pub fn decoded_wide<'t, const W: usize>(
    boxes: Boxes,
    tree: &'t WideTree<W>,
) -> Cow<'t, WideTree<W>> {
    let Some(m) = boxes.node_codes() else {
        return Cow::Borrowed(tree);
    };
    let mut out = tree.clone();
    for n in &mut out.nodes {
        let exact: Vec<[f32; 6]> = n.bounds.iter().map(|b| b.to_array()).collect();
        let decoded = scion_ir::tree::quant::decode_children(&exact, m);
        for (b, d) in n.bounds.iter_mut().zip(decoded) {
            *b = Aabb::from_array(d);
        }
    }
    Cow::Owned(out)
}
