//! The scalar semantics of the IR, in one place: what `tree` arithmetic, comparisons and
//! conversions compute on one lane. `const-fold` and the interpreter both use these functions,
//! so a folded constant is by construction what the interpreter would compute; backends must
//! match them (the differential tests check that).
//!
//! Integers wrap in two's complement at their width; shift amounts are taken modulo the width;
//! `shr` is arithmetic on signed types; integer division truncates toward zero and division by
//! zero has no result (`None`). Floats compute in their own precision with IEEE
//! round-to-nearest; `rem` is C `fmod`; ordered comparisons are false on NaN and `ne` is true.
//! Float-to-integer casts saturate (NaN gives 0), a cast to `i1` is `!= 0`. A NaN produced by
//! arithmetic is the canonical quiet NaN; `neg` and `bitcast` keep bits. `f16` has no scalar
//! form here.

use super::ops::{CmpPred, Op};
use crate::attr::{Attr, CANONICAL_NAN_BITS};
use crate::entity::TypeId;
use crate::module::Module;
use crate::types::{FloatTy, IntTy, Type};

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

pub(crate) fn canon32(x: f32) -> Scalar {
    Scalar::F32(if x.is_nan() {
        f32::from_bits(0x7fc0_0000)
    } else {
        x
    })
}

pub(crate) fn canon64(x: f64) -> Scalar {
    Scalar::F64(if x.is_nan() {
        f64::from_bits(CANONICAL_NAN_BITS)
    } else {
        x
    })
}

/// A binary op (`add` .. `shr`) on two scalars of one type (the shift amount may be any
/// integer type); `None` for integer division by zero or operands the op does not take.
pub fn binary(kind: Op, a: Scalar, b: Scalar) -> Option<Scalar> {
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

/// `tree.cmp`; `None` for operands of different kinds.
pub fn compare(pred: CmpPred, a: Scalar, b: Scalar) -> Option<bool> {
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

/// A unary op (`neg`, `bitnot`, `not`); `None` for operands the op does not take.
pub fn unary(kind: Op, a: Scalar) -> Option<Scalar> {
    Some(match (kind, a) {
        (Op::Neg, Scalar::Int(v, t)) => Scalar::Int(t.wrap(-v), t),
        (Op::Neg, Scalar::F32(x)) => Scalar::F32(-x),
        (Op::Neg, Scalar::F64(x)) => Scalar::F64(-x),
        (Op::BitNot, Scalar::Int(v, t)) => Scalar::Int(t.wrap(!v), t),
        (Op::BitNot | Op::Not, Scalar::Bool(b)) => Scalar::Bool(!b),
        _ => return None,
    })
}
