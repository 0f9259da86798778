//! The builtins of the `tree` and `mem` levels: one list, with each builtin's name and type rule.
//!
//! `tree.intrinsic {name = "min"}` names one of these; the text form keeps the name, and every
//! consumer reads it back through [`Intrinsic::of`], so an unknown name is one error in one
//! place. The enum is matched exhaustively by everything that gives a builtin a meaning, so a
//! new builtin cannot be added without its semantics:
//!
//! * the type rule: [`Intrinsic::check`] (used by the `tree` verifier);
//! * the interpreter: `crate::interp::intrinsics::eval`;
//! * the lowering to `lo`: `scion_compiler`'s `mem_to_lo/intrinsics.rs` and `mem_to_lo/quant.rs`;
//! * the front end: `scion_compiler`'s `sema::typed::Builtin` wraps an [`Intrinsic`] for every
//!   builtin that is one (the rest, `clamp`, `insert` and `append`, are sugar over these or
//!   build-language operations), and types each in `sema/builtins.rs`.
//!
//! Every builtin here has an interpreter meaning and a `lo` form, except [`Intrinsic::SetInsert`]
//! (sets exist in the traversal language and the interpreter; the compiler reports them) and
//! [`Intrinsic::Len`] of a plain array (only views have a length at run time).

use crate::entity::TypeId;
use crate::module::Module;
use crate::op::Operation;
use crate::types::{FloatTy, IntTy, Type};

macro_rules! intrinsics {
    ($($(#[doc = $doc:literal])* $v:ident = $name:literal,)*) => {
        /// A builtin of the `tree` and `mem` levels (see the module documentation).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Intrinsic {
            $($(#[doc = $doc])* $v,)*
        }

        impl Intrinsic {
            /// Every builtin, in declaration order.
            pub const ALL: &'static [Intrinsic] = &[$(Intrinsic::$v,)*];

            /// The name in `tree.intrinsic {name = ...}` and in the traversal language.
            pub fn name(self) -> &'static str {
                match self {
                    $(Intrinsic::$v => $name,)*
                }
            }
        }
    };
}

intrinsics! {
    /// `abs(x)`: absolute value, lane-wise (numbers).
    Abs = "abs",
    /// `min(a, b)`: lane-wise; on floats IEEE 754 minNum (a NaN operand yields the other).
    Min = "min",
    /// `max(a, b)`: lane-wise; on floats IEEE 754 maxNum.
    Max = "max",
    /// `sqrt(x)`: correctly rounded square root, lane-wise (floats).
    Sqrt = "sqrt",
    /// `rsqrt(x)`: `1 / sqrt(x)` with two roundings, lane-wise (floats).
    Rsqrt = "rsqrt",
    /// `floor(x)`, lane-wise (floats).
    Floor = "floor",
    /// `ceil(x)`, lane-wise (floats).
    Ceil = "ceil",
    /// `trunc(x)`: rounds toward zero, lane-wise (floats).
    Trunc = "trunc",
    /// `fma(a, b, c)`: `a * b + c` rounded once, lane-wise (floats).
    Fma = "fma",
    /// `fadd_rd(a, b)`: `a + b` rounded toward -inf (`f32` lanes).
    FaddRd = "fadd_rd",
    /// `fadd_ru(a, b)`: `a + b` rounded toward +inf (`f32` lanes).
    FaddRu = "fadd_ru",
    /// `fsub_rd(a, b)`: `a - b` rounded toward -inf (`f32` lanes).
    FsubRd = "fsub_rd",
    /// `fsub_ru(a, b)`: `a - b` rounded toward +inf (`f32` lanes).
    FsubRu = "fsub_ru",
    /// `fmul_rd(a, b)`: `a * b` rounded toward -inf (`f32` lanes).
    FmulRd = "fmul_rd",
    /// `fmul_ru(a, b)`: `a * b` rounded toward +inf (`f32` lanes).
    FmulRu = "fmul_ru",
    /// `with_axis(v, k, x)`: `v` with lane `k` replaced by `x` (a `k` outside the lanes changes
    /// nothing).
    WithAxis = "with_axis",
    /// `popcount(x)`: set bits, lane-wise (integers).
    Popcount = "popcount",
    /// `clz(x)`: leading zero bits, lane-wise (integers; the width for 0).
    Clz = "clz",
    /// `ctz(x)`: trailing zero bits, lane-wise (integers; the width for 0).
    Ctz = "ctz",
    /// `isnan(x)`: `x != x`, lane-wise (floats to `i1` lanes).
    IsNan = "isnan",
    /// `dot(a, b)`: lane products summed left to right, unfused (float vectors).
    Dot = "dot",
    /// `length(v)`: `sqrt(dot(v, v))` (float vectors).
    Length = "length",
    /// `cross(a, b)`: the 3-lane cross product `a[i]*b[j] - a[j]*b[i]`.
    Cross = "cross",
    /// `normalize(v)`: each lane divided by `length(v)` (float vectors).
    Normalize = "normalize",
    /// `hmin(v)`: the lanes folded left to right by `min`.
    Hmin = "hmin",
    /// `hmax(v)`: the lanes folded left to right by `max`.
    Hmax = "hmax",
    /// `hsum(v)`: the lanes summed left to right.
    Hsum = "hsum",
    /// `len(a)`: the element count of an array, view or set, as the result's integer type.
    Len = "len",
    /// `sort(a)`: the elements of a fixed array in ascending order; elements are numbers or
    /// tuples of numbers, compared by `<` component by component (lexicographically).
    Sort = "sort",
    /// `set_insert(s, x)`: the set `s` with `x` added.
    SetInsert = "set_insert",
    /// `frame_origin(lo)`: the quantization frame's origin below `lo` (`f32` vectors; layout
    /// catalog §2.4).
    FrameOrigin = "frame_origin",
    /// `frame_step(origin, hi, m)`: the frame's step for codes `0..=m` (`f32` vectors).
    FrameStep = "frame_step",
    /// `quant_lo(v, origin, step, m)`: the largest code whose plane is at or below `v` (`u32`
    /// lanes).
    QuantLo = "quant_lo",
    /// `quant_hi(v, origin, step, m)`: the smallest code whose plane is at or above `v` (`u32`
    /// lanes).
    QuantHi = "quant_hi",
    /// `sg_bins(wlo, whi, m)`: the bin width of a snapped-grid frame with `m` bins (catalog
    /// §3.8).
    SgBins = "sg_bins",
    /// `sg_code_up(v, wlo, whi, m)`: the bins from `wlo` up to low plane `v` (`u32` lanes).
    SgCodeUp = "sg_code_up",
    /// `sg_code_down(v, wlo, whi, m)`: the bins from `whi` down to high plane `v` (`u32` lanes).
    SgCodeDown = "sg_code_down",
}

impl Intrinsic {
    /// The builtin named `name`.
    pub fn from_name(name: &str) -> Option<Intrinsic> {
        Intrinsic::ALL.iter().copied().find(|i| i.name() == name)
    }

    /// The builtin a `tree.intrinsic` op names, or why it names none.
    pub fn of(o: &Operation) -> Result<Intrinsic, String> {
        let name = o
            .str_attr("name")
            .ok_or("`tree.intrinsic` needs a string `name`")?;
        Intrinsic::from_name(name).ok_or_else(|| format!("unknown intrinsic `{name}`"))
    }

    /// Whether the result has the first operand's type and every operand is lane-wise with it
    /// (`min`, `sqrt`, `fadd_rd`, `with_axis`, ...): what a layout expression may call without
    /// a type of its own to give.
    pub fn keeps_first_type(self) -> bool {
        use Intrinsic::*;
        matches!(
            self,
            Abs | Min
                | Max
                | Sqrt
                | Rsqrt
                | Floor
                | Ceil
                | Trunc
                | Fma
                | FaddRd
                | FaddRu
                | FsubRd
                | FsubRu
                | FmulRd
                | FmulRu
                | WithAxis
                | Popcount
                | Clz
                | Ctz
        )
    }

    /// Checks this builtin on operands of types `args` giving `result`.
    pub fn check(self, m: &Module, args: &[TypeId], result: TypeId) -> Result<(), String> {
        use Intrinsic::*;
        let name = self.name();
        let t = &m.types;
        let show = |ty: TypeId| t.display(ty).to_string();
        let is_float = |ty: TypeId| t.as_float(t.scalar_of(ty)).is_some();
        let is_int = |ty: TypeId| t.as_int(t.scalar_of(ty)).is_some();
        let is_numeric = |ty: TypeId| is_float(ty) || is_int(ty);
        let float_vec = |ty: TypeId| t.lanes(ty).is_some() && is_float(ty);
        let is_f32 = |ty: TypeId| matches!(t.get(t.scalar_of(ty)), Type::Float(FloatTy::F32));
        let f32_vec = |ty: TypeId| t.lanes(ty).is_some() && is_f32(ty);
        let all_same = |n: usize| args.len() == n && args.iter().all(|&a| a == result);
        let ok = match self {
            Abs | Min | Max => all_same(self.arity()) && is_numeric(result),
            Sqrt | Rsqrt | Floor | Ceil | Trunc | Fma => all_same(self.arity()) && is_float(result),
            FaddRd | FaddRu | FsubRd | FsubRu | FmulRd | FmulRu => all_same(2) && is_f32(result),
            WithAxis => {
                args.len() == 3
                    && args[0] == result
                    && t.lanes(result).is_some()
                    && t.as_int(args[1]).is_some()
                    && t.scalar_of(result) == args[2]
            }
            Popcount | Clz | Ctz => all_same(1) && is_int(result),
            IsNan => args.first().is_some_and(|&a| {
                is_float(a)
                    && t.lanes(a) == t.lanes(result)
                    && matches!(t.get(t.scalar_of(result)), Type::Bool)
            }),
            Dot => {
                args.len() == 2
                    && args[0] == args[1]
                    && float_vec(args[0])
                    && t.scalar_of(args[0]) == result
            }
            Length => args.len() == 1 && float_vec(args[0]) && t.scalar_of(args[0]) == result,
            Cross => all_same(2) && float_vec(result) && t.lanes(result) == Some(3),
            Normalize => all_same(1) && float_vec(result),
            Hmin | Hmax | Hsum => {
                args.len() == 1 && t.lanes(args[0]).is_some() && t.scalar_of(args[0]) == result
            }
            Sort => {
                let scalar = |ty: TypeId| is_numeric(ty) && t.lanes(ty).is_none();
                args.len() == 1
                    && args[0] == result
                    && match t.get(result) {
                        Type::Array { elem, len: Some(_) } => match t.get(*elem) {
                            Type::Tuple(cs) => !cs.is_empty() && cs.iter().all(|&c| scalar(c)),
                            _ => scalar(*elem),
                        },
                        _ => false,
                    }
            }
            Len => {
                args.len() == 1
                    && matches!(
                        t.get(args[0]),
                        Type::Array { .. } | Type::Set(_) | Type::View(_)
                    )
                    && t.as_int(result).is_some()
            }
            SetInsert => {
                args.len() == 2 && args[0] == result && *t.get(result) == Type::Set(args[1])
            }
            FrameOrigin => all_same(1) && f32_vec(result),
            FrameStep | SgBins => {
                args.len() == 3
                    && args[0] == result
                    && args[1] == result
                    && f32_vec(result)
                    && t.as_int(args[2]).is_some()
            }
            QuantLo | QuantHi | SgCodeUp | SgCodeDown => {
                args.len() == 4
                    && args[0] == args[1]
                    && args[1] == args[2]
                    && f32_vec(args[0])
                    && t.lanes(result) == t.lanes(args[0])
                    && matches!(t.get(t.scalar_of(result)), Type::Int(IntTy::U32))
                    && t.as_int(args[3]).is_some()
            }
        };
        if args.len() != self.arity() {
            return Err(format!(
                "`{name}` takes {} operands, found {}",
                self.arity(),
                args.len()
            ));
        }
        if ok {
            return Ok(());
        }
        let a: Vec<String> = args.iter().map(|&x| show(x)).collect();
        Err(format!(
            "`{name}` does not apply to ({}) -> {}",
            a.join(", "),
            show(result)
        ))
    }

    /// The number of operands.
    pub fn arity(self) -> usize {
        use Intrinsic::*;
        match self {
            Abs | Sqrt | Rsqrt | Floor | Ceil | Trunc | Popcount | Clz | Ctz | IsNan | Length
            | Normalize | Hmin | Hmax | Hsum | Len | Sort | FrameOrigin => 1,
            Min | Max | FaddRd | FaddRu | FsubRd | FsubRu | FmulRd | FmulRu | Dot | Cross
            | SetInsert => 2,
            Fma | WithAxis | FrameStep | SgBins => 3,
            QuantLo | QuantHi | SgCodeUp | SgCodeDown => 4,
        }
    }
}

impl std::fmt::Display for Intrinsic {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::Intrinsic;

    #[test]
    fn names_are_unique_and_round_trip() {
        for &i in Intrinsic::ALL {
            assert_eq!(Intrinsic::from_name(i.name()), Some(i));
        }
        let mut names: Vec<&str> = Intrinsic::ALL.iter().map(|i| i.name()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), Intrinsic::ALL.len());
        for gone in [
            "sin",
            "cos",
            "exp",
            "log",
            "round",
            "some",
            "unwrap",
            "set_empty",
        ] {
            assert_eq!(Intrinsic::from_name(gone), None, "{gone}");
        }
    }
}
