//! How a layout stores its boxes, and the logical tree a quantized layout really traverses.
//!
//! A quantized layout (layout catalog §2.4) widens every box to the nearest grid planes, so
//! its traversal visits more nodes and may visit them in another order: where two hits tie
//! in `t`, or where the exact box's slab test prunes a grazing hit that the wider box keeps,
//! its answer can differ from the reference traversal of the exact tree and still be right.
//! Its bit-for-bit reference is the reference traversal of [`Boxes::decoded_tree`]: the
//! logical tree with every box replaced by the decoded box the layout's build writes, computed
//! here with the quantization builtins' reference functions (`scion_ir::tree::quant`).
//! Input: a logical tree; output: the same tree with decoded boxes.

use scion_ir::tree::quant::{decode, frame_origin, frame_step, quant_hi, quant_lo};
use scion_runtime::bvh::LogicalTree;
use std::borrow::Cow;

/// How a layout stores node boxes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Boxes {
    /// The logical tree's `f32` boxes, unchanged.
    Exact,
    /// 16-bit codes against one frame written from the root's box (`pbrt-q16`):
    /// `wlo = frame_origin(root.low)`, `wstep = frame_step(wlo, root.high, 65535)`, each box
    /// `quant_lo(low)` / `quant_hi(high)`, decoded with `fma(q, wstep, wlo)`.
    GlobalQ16,
}

/// The codes' upper bound of [`Boxes::GlobalQ16`].
const Q16: u32 = 65535;

impl Boxes {
    /// The tree whose reference traversal a layout with these boxes must match bit for bit.
    pub fn decoded_tree<'t>(&self, tree: &'t LogicalTree) -> Cow<'t, LogicalTree> {
        match self {
            Boxes::Exact => Cow::Borrowed(tree),
            Boxes::GlobalQ16 => {
                let Some(root) = tree.nodes.get(tree.root as usize) else {
                    return Cow::Borrowed(tree);
                };
                let origin: [f32; 3] = std::array::from_fn(|k| frame_origin(root.bounds[k]));
                let step: [f32; 3] =
                    std::array::from_fn(|k| frame_step(origin[k], root.bounds[k + 3], Q16));
                let mut out = tree.clone();
                for n in &mut out.nodes {
                    for k in 0..3 {
                        let (o, s) = (origin[k], step[k]);
                        let lo = quant_lo(n.bounds[k], o, s, Q16);
                        let hi = quant_hi(n.bounds[k + 3], o, s, Q16);
                        n.bounds[k] = decode(lo, o, s);
                        n.bounds[k + 3] = decode(hi, o, s);
                    }
                }
                Cow::Owned(out)
            }
        }
    }
}
