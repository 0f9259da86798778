//! Which `lo` loads read a layout buffer that the function never writes, for the code
//! generators that turn a vector's lanes loaded one word at a time into one vector load
//! (`scion-clif`'s `loads`, `scion-llvm`'s `groups`): such a word reads the same wherever the
//! load is placed, so four consecutive ones may be read again as one 16-byte load.
//!
//! A layout buffer's base is a `lo.load` marked `global` (from the buffer table the entry
//! points receive, `mem-to-lo`); an address inside it is that base plus `lo.ptr_add`s.

use super::Op as L;
use crate::attr::Attr;
use crate::entity::{FuncId, ValueId};
use crate::module::{Module, ValueDef};
use crate::op::OpKind;

/// Whether `v` is an address inside a layout buffer: a buffer's base (a `global` load) plus
/// offsets.
pub fn in_layout(m: &Module, mut v: ValueId) -> bool {
    for _ in 0..64 {
        let Some(op) = m.def_op(v) else { return false };
        let o = &m.ops[op];
        match o.kind {
            OpKind::Lo(L::PtrAdd) => v = o.operands[0],
            OpKind::Lo(L::Load) => return o.attr("global") == Some(&Attr::Bool(true)),
            _ => return false,
        }
    }
    false
}

/// Whether function `f` stores into a layout buffer (a build does; a traversal does not).
pub fn writes_layout(m: &Module, f: FuncId) -> bool {
    m.regions[m.funcs[f].body].blocks.iter().any(|&b| {
        m.blocks[b].ops.iter().any(|&op| {
            let o = &m.ops[op];
            o.kind == OpKind::Lo(L::Store) && in_layout(m, o.operands[0])
        })
    })
}

/// `v`, or when it is the argument of a block entered by one branch, what that branch passes
/// (followed again while it is such an argument): the value an inlined call's parameter stands
/// for.
pub fn passed_value(m: &Module, mut v: ValueId) -> ValueId {
    for _ in 0..16 {
        let ValueDef::BlockArg(b, i) = m.values[v].def else {
            break;
        };
        let Some(region) = m.blocks[b].parent else {
            break;
        };
        let mut passed = None;
        let mut branches = 0;
        for &pb in &m.regions[region].blocks {
            let Some(&t) = m.blocks[pb].ops.last() else {
                continue;
            };
            for s in m.ops[t].successors.iter().filter(|s| s.block == b) {
                branches += 1;
                passed = s.args.get(i as usize).copied();
            }
        }
        match (branches, passed) {
            (1, Some(x)) => v = x,
            _ => break,
        }
    }
    v
}
