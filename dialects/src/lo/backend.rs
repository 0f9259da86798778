//! What every backend of `lo` shares, so the Cranelift and LLVM backends translate and call
//! code the same way: the block order they translate in, which declarations a module really
//! calls, and the 64-bit slots their JITs pass arguments and results through.

use crate::entity::BlockId;
use crate::interp::Val;
use crate::module::Module;
use crate::op::OpKind;
use crate::types::{FloatTy, IntTy, Type};
use rustc_hash::FxHashSet;

/// The blocks of a function body (`blocks[0]` is the entry) reachable from the entry, in
/// reverse post-order: every block comes after its dominators, so a one-pass translation sees
/// each value's definition before its uses (block arguments aside).
pub fn reverse_post_order(m: &Module, blocks: &[BlockId]) -> Vec<BlockId> {
    let mut seen = FxHashSet::default();
    let mut post = Vec::new();
    let Some(&entry) = blocks.first() else {
        return post;
    };
    let mut stack = vec![(entry, 0usize)];
    seen.insert(entry);
    while let Some(&mut (b, ref mut i)) = stack.last_mut() {
        let succs: Vec<BlockId> = m.blocks[b]
            .ops
            .last()
            .map(|&o| m.ops[o].successors.iter().map(|s| s.block).collect())
            .unwrap_or_default();
        if let Some(&s) = succs.get(*i) {
            *i += 1;
            if seen.insert(s) {
                stack.push((s, 0));
            }
        } else {
            post.push(b);
            stack.pop();
        }
    }
    post.reverse();
    post
}

/// True when some `lo.call` of `m` names `callee`.
pub fn is_called(m: &Module, callee: &str) -> bool {
    m.ops.iter().any(|(_, o)| {
        o.parent.is_some() && o.kind == OpKind::Lo(super::Op::Call) && o.callee() == Some(callee)
    })
}

/// `v` as the 64-bit slot a JIT passes an argument of type `t` in (the value's bits,
/// zero-extended); `None` when `v` is not a value of `t`.
pub fn to_slot(v: &Val, t: &Type) -> Option<u64> {
    Some(match (v, t) {
        (Val::Bool(b), Type::Bool) => u64::from(*b),
        (Val::Int(x, it), Type::Int(want)) if it == want => *x as u64,
        (Val::Int(x, _), Type::Ptr) => *x as u64,
        (Val::F32(x), Type::Float(FloatTy::F32)) => u64::from(x.to_bits()),
        (Val::F64(x), Type::Float(FloatTy::F64)) => x.to_bits(),
        _ => return None,
    })
}

/// The value of type `t` in the low bits of a JIT's result slot (a `ptr` as a `u64`).
pub fn from_slot(raw: u64, t: &Type) -> Val {
    match t {
        Type::Bool => Val::Bool(raw & 1 != 0),
        Type::Int(it) => {
            let bits = it.bits();
            let masked = if bits == 64 {
                raw
            } else {
                raw & ((1u64 << bits) - 1)
            };
            Val::Int(it.wrap(masked as i128), *it)
        }
        Type::Float(FloatTy::F32) => Val::F32(f32::from_bits(raw as u32)),
        Type::Float(_) => Val::F64(f64::from_bits(raw)),
        _ => Val::Int(raw as i128, IntTy::U64),
    }
}

/// A JIT-compiled trampoline `name$entry(args, results)`: reads one 64-bit slot per parameter
/// from `args` and writes one per result (at least one) through `results`.
pub type Trampoline = extern "C" fn(*const u64, *mut u64);

/// Calls `@name` (parameters `params`, results `results`) through its trampoline `entry` on
/// `args`: the arity and every argument's type are checked before the call.
pub fn call_through_slots(
    name: &str,
    params: &[Type],
    results: &[Type],
    args: &[Val],
    entry: Trampoline,
) -> Result<Vec<Val>, String> {
    if args.len() != params.len() {
        return Err(format!(
            "`@{name}` takes {} arguments, given {}",
            params.len(),
            args.len()
        ));
    }
    let mut slots = Vec::with_capacity(args.len() + 1);
    for (a, t) in args.iter().zip(params) {
        slots.push(
            to_slot(a, t)
                .ok_or_else(|| format!("`@{name}`: argument {a:?} does not have type {t:?}"))?,
        );
    }
    slots.push(0);
    let mut raw = vec![0u64; results.len().max(1)];
    entry(slots.as_ptr(), raw.as_mut_ptr());
    Ok(results
        .iter()
        .zip(raw)
        .map(|(t, r)| from_slot(r, t))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slots_round_trip_and_reject_wrong_types() {
        let cases = [
            (Val::Bool(true), Type::Bool),
            (Val::Int(-3, IntTy::I16), Type::Int(IntTy::I16)),
            (
                Val::Int(u64::MAX as i128, IntTy::U64),
                Type::Int(IntTy::U64),
            ),
            (Val::F32(-0.0), Type::Float(FloatTy::F32)),
            (Val::F64(f64::MIN_POSITIVE), Type::Float(FloatTy::F64)),
        ];
        for (v, t) in cases {
            let raw = to_slot(&v, &t).unwrap();
            assert_eq!(format!("{:?}", from_slot(raw, &t)), format!("{v:?}"));
        }
        assert_eq!(to_slot(&Val::F32(1.0), &Type::Float(FloatTy::F64)), None);
        assert_eq!(
            to_slot(&Val::Int(1, IntTy::U8), &Type::Int(IntTy::U32)),
            None
        );
    }
}
