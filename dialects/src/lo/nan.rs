//! Where a backend may skip the canonicalization of an arithmetic NaN. Input: the blocks of a
//! `lo` function; output: the float results whose NaN payload nothing can observe.
//!
//! `lo` float `add sub mul div rem` (and the directed `add_rd` .. `mul_ru`) produce the
//! canonical quiet NaN ([`crate::tree::scalar`]):
//! the interpreters canonicalize after every such op, the backends with a compare and a
//! select. That is needed only where the payload can be seen. A use that is another float
//! `add sub mul div rem` or a compare ([`payload_blind_use`]) sees only whether its operand is
//! a NaN: its own result is a NaN exactly when an operand is (or the operation is invalid),
//! whatever the payloads, and is itself canonicalized before anything observes it (or again
//! only seen by such uses). Every other use (store, return, call or branch argument, bitcast,
//! conversion, `select`, `min`/`max`, `neg`/`abs`, `sqrt`, `fma`, ...) may pass the payload
//! on, so a result with such a use is canonicalized.

use crate::entity::{BlockId, OpId, ValueId};
use crate::lo::Op as L;
use crate::module::Module;
use crate::op::OpKind;
use crate::types::Type;
use rustc_hash::FxHashSet;

/// A set of values (the result of [`payload_blind_results`]).
pub type ValueSet = FxHashSet<ValueId>;

/// True for the uses that see only whether an operand is a NaN: float `add sub mul div rem`
/// and compares.
pub fn payload_blind_use(m: &Module, op: OpId) -> bool {
    let o = &m.ops[op];
    match o.kind {
        OpKind::Lo(L::Add | L::Sub | L::Mul | L::Div | L::Rem) => o
            .results
            .first()
            .is_some_and(|&r| matches!(m.types.get(m.values[r].ty), Type::Float(_))),
        OpKind::Lo(L::Cmp | L::AddRd | L::AddRu | L::MulRd | L::MulRu) => true,
        _ => false,
    }
}

/// The float `add sub mul div rem` results in `blocks` (a function's body) whose every use is
/// a [`payload_blind_use`]: a backend may leave their NaNs as the hardware made them and
/// still agree bit for bit with the interpreters.
pub fn payload_blind_results(m: &Module, blocks: &[BlockId]) -> ValueSet {
    let mut arith = FxHashSet::default();
    let mut observed = FxHashSet::default();
    for &b in blocks {
        for &op in &m.blocks[b].ops {
            let o = &m.ops[op];
            if matches!(
                o.kind,
                OpKind::Lo(L::Add | L::Sub | L::Mul | L::Div | L::Rem)
                    | OpKind::Lo(L::AddRd | L::AddRu | L::MulRd | L::MulRu)
            ) {
                arith.extend(o.results.iter().copied());
            }
            if !payload_blind_use(m, op) {
                observed.extend(o.operands.iter().copied());
            }
            for s in &o.successors {
                observed.extend(s.args.iter().copied());
            }
        }
    }
    arith.retain(|v| !observed.contains(v));
    arith
}
