//! Typing of builtin functions (`docs/language.md`, "Builtins").
//!
//! Input: a builtin and its argument types. Output: its result type, or a diagnostic naming
//! the argument it cannot take. Builtins are generic over a small class of types (numbers,
//! floats, float vectors), so they are typed here rather than given one signature each.

use super::errors::SemaError;
use super::infer::Checker;
use super::ops::{Class, Progress};
use super::typed::{Builtin, Intrinsic};
use super::types::{Prim, Ty};
use scion_ir::diag::Span;

/// The class of types a builtin argument must belong to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Want {
    /// Integers, floats and numeric vectors.
    Numeric,
    /// Integers and integer vectors.
    Integer,
    /// Floats and float vectors.
    Float,
    /// Float vectors.
    FloatVec,
    /// `f32` vectors (the quantization builtins).
    F32Vec,
    /// `f32` and `f32` vectors (directed rounding).
    F32,
    /// 3-lane float vectors.
    FloatVec3,
    /// Any vector.
    Vector,
    /// Vectors of numbers.
    NumericVector,
    /// Arrays, slices and sets.
    Collection,
    /// Sets.
    Set,
    /// Fixed arrays of numbers or of tuples of numbers (`sort`).
    Sortable,
}

impl Want {
    fn describe(self) -> &'static str {
        match self {
            Want::Numeric => "a number or a numeric vector",
            Want::Integer => "an integer or an integer vector",
            Want::Float => "a float or a float vector",
            Want::FloatVec => "a float vector",
            Want::F32Vec => "an f32 vector",
            Want::F32 => "an f32 or an f32 vector",
            Want::FloatVec3 => "a 3-lane float vector",
            Want::Vector => "a vector",
            Want::NumericVector => "a numeric vector",
            Want::Collection => "an array, slice or set",
            Want::Set => "a set",
            Want::Sortable => "a fixed array of numbers or of tuples of numbers",
        }
    }
}

impl Checker<'_> {
    /// `Some(ok)` once `t` is known enough to tell whether it belongs to `want`.
    fn belongs(&self, t: &Ty, want: Want) -> Option<bool> {
        let s = self.shallow(t);
        if s == Ty::Error {
            return Some(true);
        }
        let class = self.class(&s);
        if class == Class::Unknown {
            return None;
        }
        Some(match want {
            Want::Numeric => {
                matches!(class, Class::Int | Class::Float)
                    || matches!(s, Ty::Vector(p, _) if p.is_numeric())
            }
            Want::Integer => class == Class::Int || matches!(s, Ty::Vector(p, _) if p.is_int()),
            Want::Float => class == Class::Float || matches!(s, Ty::Vector(p, _) if p.is_float()),
            Want::FloatVec => matches!(s, Ty::Vector(p, _) if p.is_float()),
            Want::F32Vec => matches!(s, Ty::Vector(Prim::F32, _)),
            // A float literal not yet typed may still become f32; an integer one cannot.
            Want::F32 if matches!(s, Ty::Var(_)) => {
                if class == Class::Float {
                    return None;
                }
                false
            }
            Want::F32 => matches!(s, Ty::Prim(Prim::F32) | Ty::Vector(Prim::F32, _)),
            Want::FloatVec3 => matches!(s, Ty::Vector(p, 3) if p.is_float()),
            Want::Vector => matches!(s, Ty::Vector(..)),
            Want::NumericVector => matches!(s, Ty::Vector(p, _) if p.is_numeric()),
            Want::Collection => matches!(s, Ty::Array(..) | Ty::Slice(_) | Ty::Set(_)),
            Want::Set => matches!(s, Ty::Set(_)),
            Want::Sortable => match s {
                Ty::Array(e, _) => {
                    let number = |t: &Ty| matches!(self.class(t), Class::Int | Class::Float);
                    match self.shallow(&e) {
                        Ty::Tuple(cs) => !cs.is_empty() && cs.iter().all(number),
                        e => number(&e),
                    }
                }
                _ => false,
            },
        })
    }

    pub(super) fn solve_builtin(
        &mut self,
        kind: Builtin,
        args: &[(Ty, Span)],
        result: &Ty,
        span: Span,
        force: bool,
    ) -> Progress {
        use Intrinsic::*;
        let name = kind.name();
        if matches!(kind, Builtin::Select | Builtin::Any | Builtin::All) {
            return self.solve_lane_builtin(kind, args, result, force);
        }
        let intrinsic = match kind {
            Builtin::Intrinsic(i) => Some(i),
            _ => None,
        };
        // The class of the first argument, how many leading arguments share its type, and which
        // arguments are integers of any type.
        let all = args.len();
        let (want, shared, ints): (Want, usize, &[usize]) = match kind {
            Builtin::Clamp => (Want::Numeric, all, &[]),
            // Typed by `solve_lane_builtin` above.
            Builtin::Select | Builtin::Any | Builtin::All => (Want::Vector, 0, &[]),
            Builtin::Append => (Want::Collection, 1, &[]),
            Builtin::Insert => (Want::Set, 1, &[]),
            Builtin::Intrinsic(i) => match i {
                Min | Max | Abs => (Want::Numeric, all, &[]),
                Sqrt | Rsqrt | Floor | Ceil | Trunc | Fma | IsNan => (Want::Float, all, &[]),
                Popcount | Clz | Ctz => (Want::Integer, all, &[]),
                FaddRd | FaddRu | FsubRd | FsubRu | FmulRd | FmulRu => (Want::F32, all, &[]),
                Dot | Length | Normalize => (Want::FloatVec, all, &[]),
                Hmin | Hmax | Hsum => (Want::NumericVector, all, &[]),
                FrameOrigin => (Want::F32Vec, all, &[]),
                Cross => (Want::FloatVec3, all, &[]),
                FrameStep | SgBins => (Want::F32Vec, 2, &[2]),
                QuantLo | QuantHi | SgCodeUp | SgCodeDown => (Want::F32Vec, 3, &[3]),
                WithAxis => (Want::Vector, 1, &[1]),
                Len => (Want::Collection, 1, &[]),
                Sort => (Want::Sortable, all, &[]),
                // Sets are grown with `insert`, which `Builtin::traversal` offers instead.
                SetInsert => (Want::Set, 1, &[]),
            },
        };
        let Some((first, first_span)) = args.first().cloned() else {
            return Progress::Done;
        };
        for (t, s) in args.iter().take(shared).skip(1) {
            self.expect(t, &first, *s, "the builtin's other arguments");
        }
        for &i in ints {
            let Some((k, ks)) = args.get(i).cloned() else {
                continue;
            };
            match self.class(&k) {
                Class::Unknown if !force => return Progress::Wait,
                Class::Int | Class::Unknown => {
                    let v = self.fresh(super::unify::VarKind::Int);
                    self.unify(&k, &v).ok();
                }
                _ => {
                    let ty = self.show(&k);
                    self.error(SemaError::BuiltinArg {
                        name: name.to_string(),
                        ty,
                        expected: "an integer",
                        span: ks,
                    });
                }
            }
        }
        if force && matches!(want, Want::F32) && self.class(&first) == Class::Float {
            // Only f32 fits: an untyped float literal becomes one.
            self.unify(&first, &Ty::Prim(Prim::F32)).ok();
        }
        match self.belongs(&first, want) {
            None if !force => return Progress::Wait,
            None => {
                self.error(SemaError::CannotInfer {
                    what: "builtin's argument",
                    span,
                });
                self.unify(result, &Ty::Error).ok();
                return Progress::Done;
            }
            Some(false) => {
                let ty = self.show(&first);
                self.error(SemaError::BuiltinArg {
                    name: name.to_string(),
                    ty,
                    expected: want.describe(),
                    span: first_span,
                });
                self.unify(result, &Ty::Error).ok();
                return Progress::Done;
            }
            Some(true) => {}
        }
        if intrinsic == Some(Abs)
            && matches!(self.shallow(&first), Ty::Prim(p) if p.is_unsigned_int())
        {
            let ty = self.show(&first);
            self.error(SemaError::BuiltinArg {
                name: name.to_string(),
                ty,
                expected: "a signed number",
                span: first_span,
            });
        }
        let elem = match self.shallow(&first) {
            Ty::Vector(p, _) => Ty::Prim(p),
            Ty::Array(e, _) | Ty::Slice(e) | Ty::Set(e) => *e,
            _ => Ty::Error,
        };
        let out = match intrinsic {
            Some(Dot | Length | Hmin | Hmax | Hsum) => elem,
            Some(Len) => Ty::Prim(Prim::U32),
            Some(IsNan) => match self.shallow(&first) {
                Ty::Vector(_, n) => Ty::Vector(Prim::Bool, n),
                _ => Ty::Prim(Prim::Bool),
            },
            _ if kind == Builtin::Insert => {
                let (x, xs) = args[1].clone();
                self.expect(&x, &elem, xs, "the set's element type");
                Ty::unit()
            }
            Some(WithAxis) => {
                let (x, xs) = args[2].clone();
                self.expect(&x, &elem, xs, "the vector's element type");
                first
            }
            Some(QuantLo | QuantHi | SgCodeUp | SgCodeDown) => match self.shallow(&first) {
                Ty::Vector(_, n) => Ty::Vector(Prim::U32, n),
                _ => Ty::Error,
            },
            _ => first,
        };
        self.unify(result, &out).ok();
        Progress::Done
    }

    /// `select(c, a, b)` (`c` a `bool`, or a `bool` vector as wide as `a`; `a` and `b` of one
    /// type, the result's), `any(m)` and `all(m)` (`m` a `bool` vector; the result `bool`).
    fn solve_lane_builtin(
        &mut self,
        kind: Builtin,
        args: &[(Ty, Span)],
        result: &Ty,
        force: bool,
    ) -> Progress {
        let name = kind.name();
        let Some((c, cs)) = args.first().cloned() else {
            return Progress::Done;
        };
        let c = self.shallow(&c);
        if self.class(&c) == Class::Unknown && !force {
            return Progress::Wait;
        }
        let lanes = match c {
            Ty::Vector(Prim::Bool, n) => Some(n),
            Ty::Error => return Progress::Done,
            _ if kind == Builtin::Select && c == Ty::bool() => None,
            _ => {
                let ty = self.show(&c);
                self.error(SemaError::BuiltinArg {
                    name: name.to_string(),
                    ty,
                    expected: if kind == Builtin::Select {
                        "a `bool` or a `bool` vector (a lane-wise comparison of vectors)"
                    } else {
                        "a `bool` vector (a lane-wise comparison of vectors)"
                    },
                    span: cs,
                });
                self.unify(result, &Ty::Error).ok();
                return Progress::Done;
            }
        };
        if kind != Builtin::Select {
            self.unify(result, &Ty::bool()).ok();
            return Progress::Done;
        }
        let [_, (a, a_span), (b, b_span)] = args else {
            return Progress::Done;
        };
        if let Some(n) = lanes {
            let a = self.shallow(a);
            match a {
                Ty::Vector(_, m) if m == n => {}
                Ty::Error => {}
                _ if self.class(&a) == Class::Unknown && !force => {
                    return Progress::Wait;
                }
                _ => {
                    let ty = self.show(&a);
                    self.error(SemaError::BuiltinArg {
                        name: name.to_string(),
                        ty,
                        expected: "a vector with as many lanes as the condition",
                        span: *a_span,
                    });
                    self.unify(result, &Ty::Error).ok();
                    return Progress::Done;
                }
            }
        }
        self.expect(b, a, *b_span, "`select`'s first value");
        self.unify(result, a).ok();
        Progress::Done
    }
}
