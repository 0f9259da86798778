//! The one-to-one correspondences between `tree` and `lo` operations and types that
//! `mem-to-lo` relies on.

use scion_ir::lo::Op as L;
use scion_ir::tree::Op as T;

/// The unsigned integer type of the same width (for unsigned comparisons and shifts).
pub(super) fn unsigned(t: scion_ir::types::IntTy) -> scion_ir::types::IntTy {
    use scion_ir::types::IntTy::*;
    match t {
        I8 | U8 => U8,
        I16 | U16 => U16,
        I32 | U32 => U32,
        I64 | U64 => U64,
    }
}

/// The `lo` op of a `tree` arithmetic or bitwise op (`tree.not` otherwise).
pub(super) fn lo_of(k: T) -> L {
    match k {
        T::Add => L::Add,
        T::Sub => L::Sub,
        T::Mul => L::Mul,
        T::Div => L::Div,
        T::Rem => L::Rem,
        T::And => L::And,
        T::Or => L::Or,
        T::Xor => L::Xor,
        T::Shl => L::Shl,
        T::Shr => L::Shr,
        T::Neg => L::Neg,
        T::BitNot => L::BitNot,
        _ => L::Not,
    }
}
