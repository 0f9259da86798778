//! `const-fold`: evaluates `tree` arithmetic, bitwise, comparison, cast and select ops whose
//! operands are scalar constants, replacing each by a `tree.const` (level: any → same).
//!
//! ```text
//! %0 = "tree.const"() {value = 1.5} : () -> f32
//! %1 = "tree.const"() {value = 2.0} : () -> f32
//! %2 = "tree.add"(%0, %1) : (f32, f32) -> f32
//! // becomes
//! %2 = "tree.const"() {value = 3.5} : () -> f32
//! ```
//!
//! Semantics are the IR's, exactly: integers wrap in two's complement at their width, shift
//! amounts are taken modulo the width, `shr` is arithmetic on signed types; integer division or
//! remainder by zero is left unfolded; floats compute in their own precision with IEEE
//! round-to-nearest (`f32` ops in `f32`, never through `f64`), `rem` is C `fmod`; ordered
//! comparisons are false on NaN and `ne` is true; float-to-integer casts saturate (NaN gives 0);
//! a cast to `i1` is `!= 0`. A NaN produced by arithmetic becomes the canonical quiet NaN (IEEE
//! leaves payloads open); `neg` and `bitcast` keep bits exactly. `f16` is not folded. The
//! replaced ops' results are aliased to the new constants; `dce` then removes the dead operands.
//! A `tree.if` on a constant condition is replaced by the ops of the region it would run, when
//! that region ends with `tree.yield`.

use crate::attr::{Attr, CANONICAL_NAN_BITS};
use crate::builder::{Builder, InsertPoint, OpSpec};
use crate::entity::{OpId, TypeId, ValueId};
use crate::module::Module;
use crate::op::OpKind;
use crate::pass::{Pass, PassCx, PassError};
use crate::rewrite;
use crate::tree::{CmpPred, Op};
use crate::types::{FloatTy, IntTy, Type};
use crate::walk;
use rustc_hash::FxHashMap;

/// The `const-fold` pass.
#[derive(Default)]
pub struct ConstFold;

impl Pass for ConstFold {
    fn name(&self) -> &'static str {
        "const-fold"
    }

    fn summary(&self) -> &'static str {
        "Evaluate tree arithmetic, comparisons and casts on scalar constants (exact IEEE semantics)"
    }

    fn run(&mut self, m: &mut Module, _cx: &mut PassCx) -> Result<bool, PassError> {
        let mut changed = false;
        for f in m.func_order.clone() {
            let mut consts: FxHashMap<ValueId, Attr> = FxHashMap::default();
            for op in walk::func_ops(m, f, walk::Order::Pre) {
                let o = &m.ops[op];
                if o.kind.is_tree(Op::Const) {
                    if let Some(a) = o.attr("value") {
                        consts.insert(o.results[0], a.clone());
                    }
                    continue;
                }
                if o.kind.is_tree(Op::If) && o.parent.is_some() {
                    if let Some(Attr::Bool(c)) = o.operands.first().and_then(|v| consts.get(v)) {
                        changed |= fold_if(m, op, *c);
                    }
                    continue;
                }
                match fold_op(m, op, &consts) {
                    Some(Folded::Const(attr)) => {
                        let res = m.ops[op].results[0];
                        let ty = m.values[res].ty;
                        let span = m.span(op);
                        let mut b = Builder::new(m);
                        b.set_insertion_point(InsertPoint::Before(op));
                        b.set_span(span);
                        let new = b.insert(
                            OpSpec::new(Op::Const)
                                .attr("value", attr.clone())
                                .results(&[ty]),
                        );
                        let v = m.ops[new].results[0];
                        consts.insert(res, attr.clone());
                        consts.insert(v, attr);
                        rewrite::replace_op(m, op, &[v]);
                        changed = true;
                    }
                    Some(Folded::Alias(v)) => {
                        let res = m.ops[op].results[0];
                        if let Some(a) = consts.get(&v).cloned() {
                            consts.insert(res, a);
                        }
                        rewrite::replace_op(m, op, &[v]);
                        changed = true;
                    }
                    None => {}
                }
            }
        }
        Ok(changed)
    }
}

/// Replaces `tree.if` with a constant condition by the ops of the region it would run, when
/// that region ends with `tree.yield` (one ending with `tree.return` is left alone, as the rest
/// of the enclosing block would become dead). Returns whether it changed anything.
fn fold_if(m: &mut Module, op: OpId, cond: bool) -> bool {
    let Some(&region) = m.ops[op].regions.get(if cond { 0 } else { 1 }) else {
        return false;
    };
    let ends_in_yield = m.regions[region]
        .blocks
        .first()
        .and_then(|&b| m.blocks[b].ops.last())
        .is_some_and(|&t| m.ops[t].kind.is_tree(Op::Yield));
    if !ends_in_yield {
        return false;
    }
    let Some(term) = rewrite::inline_region_before(m, region, op, &[]) else {
        return false;
    };
    let yielded = m.ops[term].operands.clone();
    rewrite::replace_op(m, op, &yielded);
    true
}

/// What an op folds to.
#[derive(Clone, Debug, PartialEq)]
pub enum Folded {
    /// A new constant of the op's result type.
    Const(Attr),
    /// An existing value (e.g. a `select` with a constant condition).
    Alias(ValueId),
}

/// A scalar constant with its type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scalar {
    /// `i1`
    Bool(bool),
    /// An integer, normalized to its type's range.
    Int(i128, IntTy),
    /// An `f32`.
    F32(f32),
    /// An `f64`.
    F64(f64),
}

impl Scalar {
    /// Reads constant `a` of type `ty`; `None` for non-scalar or `f16` types.
    pub fn from_attr(m: &Module, a: &Attr, ty: TypeId) -> Option<Scalar> {
        Some(match (m.types.get(ty), a) {
            (Type::Bool, Attr::Bool(b)) => Scalar::Bool(*b),
            (Type::Int(it), Attr::Int(v)) => Scalar::Int(it.wrap(*v), *it),
            (Type::Float(FloatTy::F32), Attr::Float(bits)) => {
                Scalar::F32(f64::from_bits(*bits) as f32)
            }
            (Type::Float(FloatTy::F64), Attr::Float(bits)) => Scalar::F64(f64::from_bits(*bits)),
            _ => return None,
        })
    }

    /// The attribute holding this constant.
    pub fn to_attr(self) -> Attr {
        match self {
            Scalar::Bool(b) => Attr::Bool(b),
            Scalar::Int(v, _) => Attr::Int(v),
            Scalar::F32(x) => Attr::Float((x as f64).to_bits()),
            Scalar::F64(x) => Attr::Float(x.to_bits()),
        }
    }

    /// The raw bits (two's complement for integers).
    fn bits(self) -> u64 {
        match self {
            Scalar::Bool(b) => b as u64,
            Scalar::Int(v, _) => v as u64,
            Scalar::F32(x) => x.to_bits() as u64,
            Scalar::F64(x) => x.to_bits(),
        }
    }
}

fn canon32(x: f32) -> Scalar {
    Scalar::F32(if x.is_nan() {
        f32::from_bits(0x7fc0_0000)
    } else {
        x
    })
}

fn canon64(x: f64) -> Scalar {
    Scalar::F64(if x.is_nan() {
        f64::from_bits(CANONICAL_NAN_BITS)
    } else {
        x
    })
}

/// What `op` folds to given the constants known so far, if anything.
pub fn fold_op(m: &Module, op: OpId, consts: &FxHashMap<ValueId, Attr>) -> Option<Folded> {
    let o = &m.ops[op];
    let OpKind::Tree(kind) = o.kind;
    if o.results.len() != 1 {
        return None;
    }
    let result_ty = m.values[o.results[0]].ty;
    if kind == Op::Select {
        let c = consts.get(o.operands.first()?)?;
        return match c {
            Attr::Bool(true) => Some(Folded::Alias(*o.operands.get(1)?)),
            Attr::Bool(false) => Some(Folded::Alias(*o.operands.get(2)?)),
            _ => None,
        };
    }
    let args: Option<Vec<Scalar>> = o
        .operands
        .iter()
        .map(|&v| Scalar::from_attr(m, consts.get(&v)?, m.values[v].ty))
        .collect();
    let args = args?;
    let out = match (kind, args.as_slice()) {
        (
            Op::Add
            | Op::Sub
            | Op::Mul
            | Op::Div
            | Op::Rem
            | Op::And
            | Op::Or
            | Op::Xor
            | Op::Shl
            | Op::Shr,
            [a, b],
        ) => binary(kind, *a, *b)?,
        (Op::Neg, [a]) => match *a {
            Scalar::Int(v, t) => Scalar::Int(t.wrap(-v), t),
            Scalar::F32(x) => Scalar::F32(-x),
            Scalar::F64(x) => Scalar::F64(-x),
            Scalar::Bool(_) => return None,
        },
        (Op::BitNot, [a]) => match *a {
            Scalar::Int(v, t) => Scalar::Int(t.wrap(!v), t),
            Scalar::Bool(b) => Scalar::Bool(!b),
            _ => return None,
        },
        (Op::Not, [Scalar::Bool(b)]) => Scalar::Bool(!b),
        (Op::Cmp, [a, b]) => {
            Scalar::Bool(compare(CmpPred::from_name(o.str_attr("pred")?)?, *a, *b)?)
        }
        (Op::Cast, [a]) => cast(*a, m.types.get(result_ty))?,
        (Op::Bitcast, [a]) => bitcast(*a, m.types.get(result_ty))?,
        _ => return None,
    };
    Some(Folded::Const(out.to_attr()))
}

fn binary(kind: Op, a: Scalar, b: Scalar) -> Option<Scalar> {
    Some(match (a, b) {
        (Scalar::Int(x, t), Scalar::Int(y, u)) => {
            let v = match kind {
                Op::Add => x + y,
                Op::Sub => x - y,
                Op::Mul => x.wrapping_mul(y),
                Op::Div if y == 0 => return None,
                Op::Div => x / y,
                Op::Rem if y == 0 => return None,
                Op::Rem => x % y,
                Op::And => x & y,
                Op::Or => x | y,
                Op::Xor => x ^ y,
                Op::Shl => x << (u.wrap(y) as u128 as u32 % t.bits()),
                Op::Shr => x >> (u.wrap(y) as u128 as u32 % t.bits()),
                _ => return None,
            };
            if t != u && !matches!(kind, Op::Shl | Op::Shr) {
                return None;
            }
            Scalar::Int(t.wrap(v), t)
        }
        (Scalar::Bool(x), Scalar::Bool(y)) => Scalar::Bool(match kind {
            Op::And => x & y,
            Op::Or => x | y,
            Op::Xor => x ^ y,
            _ => return None,
        }),
        (Scalar::F32(x), Scalar::F32(y)) => canon32(match kind {
            Op::Add => x + y,
            Op::Sub => x - y,
            Op::Mul => x * y,
            Op::Div => x / y,
            Op::Rem => x % y,
            _ => return None,
        }),
        (Scalar::F64(x), Scalar::F64(y)) => canon64(match kind {
            Op::Add => x + y,
            Op::Sub => x - y,
            Op::Mul => x * y,
            Op::Div => x / y,
            Op::Rem => x % y,
            _ => return None,
        }),
        _ => return None,
    })
}

fn compare(pred: CmpPred, a: Scalar, b: Scalar) -> Option<bool> {
    use std::cmp::Ordering;
    let ord: Option<Ordering> = match (a, b) {
        (Scalar::Int(x, _), Scalar::Int(y, _)) => Some(x.cmp(&y)),
        (Scalar::Bool(x), Scalar::Bool(y)) => Some(x.cmp(&y)),
        (Scalar::F32(x), Scalar::F32(y)) => x.partial_cmp(&y),
        (Scalar::F64(x), Scalar::F64(y)) => x.partial_cmp(&y),
        _ => return None,
    };
    // `None` is an unordered (NaN) comparison: only `ne` holds.
    Some(match (pred, ord) {
        (CmpPred::Ne, None) => true,
        (_, None) => false,
        (CmpPred::Eq, Some(o)) => o == Ordering::Equal,
        (CmpPred::Ne, Some(o)) => o != Ordering::Equal,
        (CmpPred::Lt, Some(o)) => o == Ordering::Less,
        (CmpPred::Le, Some(o)) => o != Ordering::Greater,
        (CmpPred::Gt, Some(o)) => o == Ordering::Greater,
        (CmpPred::Ge, Some(o)) => o != Ordering::Less,
    })
}

/// `as`: value conversion to the scalar type `to`.
pub fn cast(a: Scalar, to: &Type) -> Option<Scalar> {
    Some(match (a, to) {
        (Scalar::Bool(b), Type::Bool) => Scalar::Bool(b),
        (Scalar::Int(v, _), Type::Bool) => Scalar::Bool(v != 0),
        (Scalar::F32(x), Type::Bool) => Scalar::Bool(x != 0.0),
        (Scalar::F64(x), Type::Bool) => Scalar::Bool(x != 0.0),
        (Scalar::Bool(b), Type::Int(t)) => Scalar::Int(b as i128, *t),
        (Scalar::Int(v, _), Type::Int(t)) => Scalar::Int(t.wrap(v), *t),
        (Scalar::F32(x), Type::Int(t)) => {
            Scalar::Int(float_to_int(x as f64, x.is_nan(), *t, Some(x)), *t)
        }
        (Scalar::F64(x), Type::Int(t)) => Scalar::Int(float_to_int(x, x.is_nan(), *t, None), *t),
        (Scalar::Bool(b), Type::Float(FloatTy::F32)) => Scalar::F32(b as u8 as f32),
        (Scalar::Bool(b), Type::Float(FloatTy::F64)) => Scalar::F64(b as u8 as f64),
        (Scalar::Int(v, _), Type::Float(FloatTy::F32)) => Scalar::F32(v as f32),
        (Scalar::Int(v, _), Type::Float(FloatTy::F64)) => Scalar::F64(v as f64),
        (Scalar::F32(x), Type::Float(FloatTy::F32)) => Scalar::F32(x),
        (Scalar::F32(x), Type::Float(FloatTy::F64)) => Scalar::F64(x as f64),
        (Scalar::F64(x), Type::Float(FloatTy::F32)) => Scalar::F32(x as f32),
        (Scalar::F64(x), Type::Float(FloatTy::F64)) => Scalar::F64(x),
        _ => return None,
    })
}

/// Saturating float-to-integer conversion (Rust's `as`): NaN gives 0. `narrow` is the `f32`
/// source when there is one, converted directly so no double rounding can occur.
fn float_to_int(x: f64, nan: bool, t: IntTy, narrow: Option<f32>) -> i128 {
    if nan {
        return 0;
    }
    macro_rules! conv {
        ($ty:ty) => {
            match narrow {
                Some(f) => f as $ty as i128,
                None => x as $ty as i128,
            }
        };
    }
    match t {
        IntTy::I8 => conv!(i8),
        IntTy::I16 => conv!(i16),
        IntTy::I32 => conv!(i32),
        IntTy::I64 => conv!(i64),
        IntTy::U8 => conv!(u8),
        IntTy::U16 => conv!(u16),
        IntTy::U32 => conv!(u32),
        IntTy::U64 => conv!(u64),
    }
}

/// `to`: reinterpretation of the bits as the scalar type `to` of the same width.
pub fn bitcast(a: Scalar, to: &Type) -> Option<Scalar> {
    let width = match a {
        Scalar::Bool(_) => 1,
        Scalar::Int(_, t) => t.bits(),
        Scalar::F32(_) => 32,
        Scalar::F64(_) => 64,
    };
    let bits = a.bits()
        & if width == 64 {
            u64::MAX
        } else {
            (1u64 << width) - 1
        };
    Some(match to {
        Type::Bool if width == 1 => Scalar::Bool(bits != 0),
        Type::Int(t) if t.bits() == width => Scalar::Int(t.wrap(bits as i128), *t),
        Type::Float(FloatTy::F32) if width == 32 => Scalar::F32(f32::from_bits(bits as u32)),
        Type::Float(FloatTy::F64) if width == 64 => Scalar::F64(f64::from_bits(bits)),
        _ => return None,
    })
}
