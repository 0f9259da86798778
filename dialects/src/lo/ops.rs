//! The op kinds of the `lo` dialect and their static properties (name, purity, terminator).
//!
//! `lo` is a scalar SSA control-flow graph (design note §5): every value is a scalar (`i1`,
//! `i8`..`u64`, `f32`, `f64`) or a `ptr`. Signedness stays part of the integer types, so `div`,
//! `rem`, `shr`, `cast` and `cmp` read it from their operand types, exactly as in `tree`. Each
//! variant documents its operands, attributes, successors and results; [`super::verify`] checks
//! what is written here.

/// One `lo` operation kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Op {
    /// `lo.const {value}` `() -> T`: an integer, float or `i1` constant (`ptr`: an integer
    /// address, normally 0).
    Const,
    /// `lo.add` `(T, T) -> T`: wrapping integer or round-to-nearest float addition.
    Add,
    /// `lo.sub` `(T, T) -> T`.
    Sub,
    /// `lo.mul` `(T, T) -> T`.
    Mul,
    /// `lo.div` `(T, T) -> T`: integer division truncates toward zero (by zero: undefined).
    Div,
    /// `lo.rem` `(T, T) -> T`: the sign follows the dividend; floats: C `fmod`.
    Rem,
    /// `lo.neg` `(T) -> T`: integer negation or float sign flip (bits kept).
    Neg,
    /// `lo.and` `(T, T) -> T`, integers or `i1`.
    And,
    /// `lo.or` `(T, T) -> T`.
    Or,
    /// `lo.xor` `(T, T) -> T`.
    Xor,
    /// `lo.shl` `(T, U) -> T`: the amount is taken modulo the width.
    Shl,
    /// `lo.shr` `(T, U) -> T`: arithmetic on signed, logical on unsigned types.
    Shr,
    /// `lo.bitnot` `(T) -> T`, integers.
    BitNot,
    /// `lo.not` `(i1) -> i1`.
    Not,
    /// `lo.cmp {pred}` `(T, T) -> i1`: `eq ne lt le gt ge`, ordered on floats except `ne`.
    Cmp,
    /// `lo.select` `(i1, T, T) -> T`.
    Select,
    /// `lo.cast` `(A) -> B`: value conversion between scalars (integer widen/narrow, int to
    /// float, float to int saturating with NaN to 0, float widen/narrow, to `i1` is `!= 0`).
    Cast,
    /// `lo.bitcast` `(A) -> B`: reinterpretation between scalars of equal width.
    Bitcast,
    /// `lo.min` `(T, T) -> T`: integer minimum, or float `minNum`: the non-NaN operand when
    /// one is NaN, else the smaller, the first operand on ties (`min(+0, -0) = +0`).
    Min,
    /// `lo.max` `(T, T) -> T`: as `min`, the larger.
    Max,
    /// `lo.abs` `(T) -> T`: integer (wrapping) or float (clears the sign bit).
    Abs,
    /// `lo.sqrt` `(T) -> T`, floats, correctly rounded.
    Sqrt,
    /// `lo.floor` `(T) -> T`, floats.
    Floor,
    /// `lo.ceil` `(T) -> T`, floats.
    Ceil,
    /// `lo.trunc` `(T) -> T`, floats.
    Trunc,
    /// `lo.fma` `(T, T, T) -> T`: `a * b + c` rounded once.
    Fma,
    /// `lo.next_up` `(T) -> T`, floats: the next float toward `+inf` (NaN and `+inf` stay;
    /// `±0` gives the smallest positive subnormal).
    NextUp,
    /// `lo.next_down` `(T) -> T`: the next float toward `-inf`.
    NextDown,
    /// `lo.add_rd` `(f32, f32) -> f32`: addition rounded toward `-inf`
    /// ([`crate::tree::directed`]: exact IEEE directed rounding, canonical NaN).
    AddRd,
    /// `lo.add_ru` `(f32, f32) -> f32`: addition rounded toward `+inf`.
    AddRu,
    /// `lo.mul_rd` `(f32, f32) -> f32`: multiplication rounded toward `-inf`.
    MulRd,
    /// `lo.mul_ru` `(f32, f32) -> f32`: multiplication rounded toward `+inf`.
    MulRu,
    /// `lo.popcount` `(T) -> T`, integers: the number of one bits.
    Popcount,
    /// `lo.clz` `(T) -> T`, integers: leading zero bits within the width (the width for 0).
    Clz,
    /// `lo.ctz` `(T) -> T`, integers: trailing zero bits (the width for 0).
    Ctz,
    /// `lo.load {offset}` `(ptr) -> T`: the scalar at `ptr + offset` (little-endian). A `ptr`
    /// load may carry `global = true`: it reads a layout buffer's address from the buffer table
    /// (`mem.buffer`). The runtime always allocates buffers in the device's global memory, so a
    /// GPU backend may use global-space accesses through it; and nothing writes the table while
    /// generated code runs, so a CPU backend may treat the load as a pure value (hoist it out of
    /// loops). The interpreter ignores it.
    Load,
    /// `lo.store {offset}` `(ptr, T) -> ()`.
    Store,
    /// `lo.ptr_add` `(ptr, integer) -> ptr`: byte offset, sign-extended for signed types,
    /// zero-extended for unsigned ones.
    PtrAdd,
    /// `lo.stack_slot {size, align}` `() -> ptr`: a fresh `size`-byte slot in the function's
    /// frame, valid until the function returns.
    StackSlot,
    /// `lo.global_id` `() -> u64`: the index of the GPU thread running this code in a
    /// one-dimensional launch (`blockIdx.x * blockDim.x + threadIdx.x`). Only GPU targets
    /// (`nvptx64`) give it a meaning: CPU backends and the interpreter reject it.
    GlobalId,
    /// `lo.call {callee = @f}` `(args...) -> (results...)`.
    Call,
    /// `lo.br` `() -> ()` with one successor.
    Br,
    /// `lo.cond_br` `(i1) -> ()` with two successors: taken when true, when false.
    CondBr,
    /// `lo.return` `(values...) -> ()`: the function's results.
    Return,
}

impl Op {
    /// Every op, in declaration order.
    pub const ALL: [Op; 44] = [
        Op::Const,
        Op::Add,
        Op::Sub,
        Op::Mul,
        Op::Div,
        Op::Rem,
        Op::Neg,
        Op::And,
        Op::Or,
        Op::Xor,
        Op::Shl,
        Op::Shr,
        Op::BitNot,
        Op::Not,
        Op::Cmp,
        Op::Select,
        Op::Cast,
        Op::Bitcast,
        Op::Min,
        Op::Max,
        Op::Abs,
        Op::Sqrt,
        Op::Floor,
        Op::Ceil,
        Op::Trunc,
        Op::Fma,
        Op::NextUp,
        Op::NextDown,
        Op::AddRd,
        Op::AddRu,
        Op::MulRd,
        Op::MulRu,
        Op::Popcount,
        Op::Clz,
        Op::Ctz,
        Op::Load,
        Op::Store,
        Op::PtrAdd,
        Op::StackSlot,
        Op::GlobalId,
        Op::Call,
        Op::Br,
        Op::CondBr,
        Op::Return,
    ];

    /// The name without the dialect prefix (`add`).
    pub fn mnemonic(self) -> &'static str {
        match self {
            Op::Const => "const",
            Op::Add => "add",
            Op::Sub => "sub",
            Op::Mul => "mul",
            Op::Div => "div",
            Op::Rem => "rem",
            Op::Neg => "neg",
            Op::And => "and",
            Op::Or => "or",
            Op::Xor => "xor",
            Op::Shl => "shl",
            Op::Shr => "shr",
            Op::BitNot => "bitnot",
            Op::Not => "not",
            Op::Cmp => "cmp",
            Op::Select => "select",
            Op::Cast => "cast",
            Op::Bitcast => "bitcast",
            Op::Min => "min",
            Op::Max => "max",
            Op::Abs => "abs",
            Op::Sqrt => "sqrt",
            Op::Floor => "floor",
            Op::Ceil => "ceil",
            Op::Trunc => "trunc",
            Op::Fma => "fma",
            Op::NextUp => "next_up",
            Op::NextDown => "next_down",
            Op::AddRd => "add_rd",
            Op::AddRu => "add_ru",
            Op::MulRd => "mul_rd",
            Op::MulRu => "mul_ru",
            Op::Popcount => "popcount",
            Op::Clz => "clz",
            Op::Ctz => "ctz",
            Op::Load => "load",
            Op::Store => "store",
            Op::PtrAdd => "ptr_add",
            Op::StackSlot => "stack_slot",
            Op::GlobalId => "global_id",
            Op::Call => "call",
            Op::Br => "br",
            Op::CondBr => "cond_br",
            Op::Return => "return",
        }
    }

    /// The op with mnemonic `s`.
    pub fn from_mnemonic(s: &str) -> Option<Op> {
        Op::ALL.iter().copied().find(|op| op.mnemonic() == s)
    }

    /// True for ops that end a block.
    pub fn is_terminator(self) -> bool {
        matches!(self, Op::Br | Op::CondBr | Op::Return)
    }

    /// True for ops whose only effect is their results. `load` is not: it may trap and its
    /// value depends on stores; `stack_slot` is, since an unused slot can go.
    pub fn is_pure(self) -> bool {
        !matches!(
            self,
            Op::Load | Op::Store | Op::Call | Op::Br | Op::CondBr | Op::Return
        )
    }

    /// True for the binary ops `(T, T) -> T` whose scalar semantics are `tree`'s.
    pub fn is_binary(self) -> bool {
        matches!(
            self,
            Op::Add
                | Op::Sub
                | Op::Mul
                | Op::Div
                | Op::Rem
                | Op::And
                | Op::Or
                | Op::Xor
                | Op::Shl
                | Op::Shr
        )
    }

    /// The `tree` op with the same scalar semantics, for the ops `lo` shares with `tree`.
    pub fn tree_equivalent(self) -> Option<crate::tree::Op> {
        use crate::tree::Op as T;
        Some(match self {
            Op::Add => T::Add,
            Op::Sub => T::Sub,
            Op::Mul => T::Mul,
            Op::Div => T::Div,
            Op::Rem => T::Rem,
            Op::Neg => T::Neg,
            Op::And => T::And,
            Op::Or => T::Or,
            Op::Xor => T::Xor,
            Op::Shl => T::Shl,
            Op::Shr => T::Shr,
            Op::BitNot => T::BitNot,
            Op::Not => T::Not,
            _ => return None,
        })
    }

    /// For the directed-rounding ops: whether it multiplies (else adds), and the direction.
    pub fn directed(self) -> Option<(bool, crate::tree::directed::Round)> {
        use crate::tree::directed::Round;
        Some(match self {
            Op::AddRd => (false, Round::Down),
            Op::AddRu => (false, Round::Up),
            Op::MulRd => (true, Round::Down),
            Op::MulRu => (true, Round::Up),
            _ => return None,
        })
    }

    /// The directed-rounding op for `mul` (else `add`) in direction `dir`.
    pub fn with_rounding(mul: bool, dir: crate::tree::directed::Round) -> Op {
        use crate::tree::directed::Round;
        match (mul, dir) {
            (false, Round::Down) => Op::AddRd,
            (false, Round::Up) => Op::AddRu,
            (true, Round::Down) => Op::MulRd,
            (true, Round::Up) => Op::MulRu,
        }
    }

    /// True for the float-only unary intrinsics.
    pub fn is_float_unary(self) -> bool {
        matches!(
            self,
            Op::Sqrt | Op::Floor | Op::Ceil | Op::Trunc | Op::NextUp | Op::NextDown
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for op in Op::ALL {
            assert_eq!(Op::from_mnemonic(op.mnemonic()), Some(op));
        }
        assert_eq!(Op::from_mnemonic("nope"), None);
    }
}
