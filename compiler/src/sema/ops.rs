//! Deferred typing obligations: operators, field access, indexing, slicing, conversions and
//! iteration, solved once the operand types are known (paper §3).
//!
//! Input: obligations created while walking expressions. Output: unifications and side-table
//! entries (widenings), or diagnostics. An obligation whose operands are still unknown waits;
//! `mod.rs` retries waiting obligations until nothing changes, then again with `force` (unify
//! what HM would unify), then after defaulting literals; what still waits is an error.
//!
//! Operator rules: arithmetic on ints, floats and numeric vectors of one type; comparisons give
//! `bool`; `&& || !` on `bool`; bit operations and shifts on integers; an integer operand is
//! implicitly widened to a wider integer of the same signedness (`p_o + nprims` with `u32` and
//! `u16`), recorded in `widenings`.

use super::errors::SemaError;
use super::infer::Checker;
use super::overload::CallOb;
use super::typed::Builtin;
use super::types::Ty;
use super::unify::VarKind;
use crate::syntax::ast::{BinaryOp, NodeId, UnaryOp};
use scion_ir::diag::Span;

/// Where an expression must be an integer (or a `ptr`), in layouts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum IntCheck {
    Discriminant,
    GroupSize,
    GroupBy,
    FromKey,
}

/// A typing rule waiting for its operand types.
#[derive(Clone, Debug)]
pub(super) enum Obligation {
    Field {
        base: Ty,
        name: String,
        result: Ty,
        span: Span,
    },
    Index {
        base: Ty,
        index: Ty,
        literal: Option<u128>,
        result: Ty,
        span: Span,
        index_span: Span,
    },
    Slice {
        base: Ty,
        bounds: [(Ty, Span); 2],
        /// Both bounds when they are literals (checked against an integer's width).
        literal: Option<(u128, u128)>,
        result: Ty,
        span: Span,
    },
    Unary {
        op: UnaryOp,
        operand: Ty,
        result: Ty,
        span: Span,
    },
    Binary {
        op: BinaryOp,
        lhs: (NodeId, Ty, Span),
        rhs: (NodeId, Ty, Span),
        result: Ty,
        span: Span,
    },
    Cast {
        from: Ty,
        to: Ty,
        bits: bool,
        span: Span,
    },
    Elem {
        iter: Ty,
        elem: Ty,
        span: Span,
    },
    Int {
        ty: Ty,
        check: IntCheck,
        span: Span,
    },
    Call(CallOb),
    Builtin {
        kind: Builtin,
        args: Vec<(Ty, Span)>,
        result: Ty,
        span: Span,
    },
}

/// Whether an obligation was settled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Progress {
    Done,
    Wait,
}

/// What an operand is, once its variable bindings are followed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Class {
    Unknown,
    Int,
    Float,
    Other,
}

impl Checker<'_> {
    /// Solves `ob` now or keeps it for later.
    pub(super) fn solve_or_defer(&mut self, ob: Obligation) {
        if self.solve(&ob, false) == Progress::Wait {
            self.pending.push(ob);
        }
    }

    /// Retries waiting obligations until none makes progress. Returns whether any did.
    pub(super) fn run_pending(&mut self, force: bool) -> bool {
        let mut any = false;
        loop {
            let obs = std::mem::take(&mut self.pending);
            let before = obs.len();
            for ob in obs {
                if self.solve(&ob, force) == Progress::Wait {
                    self.pending.push(ob);
                }
            }
            if self.pending.len() == before {
                return any;
            }
            any = true;
        }
    }

    /// Reports every obligation still waiting.
    pub(super) fn fail_pending(&mut self) {
        for ob in std::mem::take(&mut self.pending) {
            let (what, span) = match &ob {
                Obligation::Call(c) => ("call", c.span),
                Obligation::Builtin { span, .. } => ("call", *span),
                Obligation::Field { span, .. } => ("field access's base", *span),
                Obligation::Elem { span, .. } => ("loop's collection", *span),
                Obligation::Index { span, .. }
                | Obligation::Slice { span, .. }
                | Obligation::Unary { span, .. }
                | Obligation::Binary { span, .. }
                | Obligation::Cast { span, .. }
                | Obligation::Int { span, .. } => ("expression", *span),
            };
            self.error(SemaError::CannotInfer { what, span });
        }
    }

    /// The class of a type.
    pub(super) fn class(&self, t: &Ty) -> Class {
        match self.shallow(t) {
            Ty::Var(_) => match self.var_kind(t) {
                Some(VarKind::Int) => Class::Int,
                Some(VarKind::Float) => Class::Float,
                _ => Class::Unknown,
            },
            Ty::Prim(p) if p.is_int() => Class::Int,
            Ty::Prim(p) if p.is_float() => Class::Float,
            Ty::Error => Class::Int,
            _ => Class::Other,
        }
    }

    /// Requires an integer; `None` while unknown.
    fn int_operand(&mut self, t: &Ty, force: bool) -> Option<bool> {
        match self.class(t) {
            Class::Int => Some(true),
            Class::Unknown if force => {
                let v = self.fresh(VarKind::Int);
                self.unify(t, &v).ok();
                Some(true)
            }
            Class::Unknown => None,
            _ => Some(false),
        }
    }

    fn bad_operand(&mut self, op: &str, t: &Ty, expected: &'static str, span: Span) {
        let ty = self.show(t);
        self.error(SemaError::BadOperand {
            op: op.to_string(),
            ty,
            expected,
            span,
        });
    }

    pub(super) fn solve(&mut self, ob: &Obligation, force: bool) -> Progress {
        use Progress::*;
        match ob {
            Obligation::Field {
                base,
                name,
                result,
                span,
            } => {
                let b = self.shallow(base);
                let field_ty = match &b {
                    Ty::Var(_) => {
                        return self.wait_or_fail(force, result, "field access's base", *span)
                    }
                    Ty::Error => Some(Ty::Error),
                    Ty::Adt(a) => self
                        .adts
                        .get(*a)
                        .and_then(|d| d.fields.iter().find(|f| &f.name == name))
                        .map(|f| f.ty.clone()),
                    Ty::Vector(p, n) => ["x", "y", "z", "w"]
                        .iter()
                        .position(|c| c == name)
                        .filter(|i| (*i as u32) < *n)
                        .map(|_| Ty::Prim(*p)),
                    _ => None,
                };
                match field_ty {
                    Some(t) => {
                        self.unify(result, &t).ok();
                    }
                    None => {
                        let ty = self.show(&b);
                        self.error(SemaError::NoSuchField {
                            ty,
                            name: name.clone(),
                            span: *span,
                        });
                        self.unify(result, &Ty::Error).ok();
                    }
                }
                Done
            }
            Obligation::Index {
                base,
                index,
                literal,
                result,
                span,
                index_span,
            } => {
                let b = self.shallow(base);
                if let Ty::Tuple(ts) = &b {
                    match literal {
                        None => self.error(SemaError::TupleIndexNotLiteral { span: *index_span }),
                        Some(i) if (*i as usize) < ts.len() && *i < u32::MAX as u128 => {
                            let t = ts[*i as usize].clone();
                            self.unify(result, &t).ok();
                            // The literal index itself is an ordinary integer.
                            self.int_operand(index, true);
                            return Done;
                        }
                        Some(i) => self.error(SemaError::TupleIndexRange {
                            index: *i,
                            len: ts.len(),
                            span: *index_span,
                        }),
                    }
                    self.unify(result, &Ty::Error).ok();
                    return Done;
                }
                let elem = match &b {
                    Ty::Var(_) => return self.wait_or_fail(force, result, "indexed value", *span),
                    Ty::Error => Some(Ty::Error),
                    Ty::Array(e, _) | Ty::Slice(e) => Some((**e).clone()),
                    Ty::Vector(p, _) => Some(Ty::Prim(*p)),
                    _ => None,
                };
                let Some(elem) = elem else {
                    let ty = self.show(&b);
                    self.error(SemaError::NotIndexable { ty, span: *span });
                    self.unify(result, &Ty::Error).ok();
                    return Done;
                };
                match self.int_operand(index, force) {
                    None => return Wait,
                    Some(false) => self.bad_operand("[]", index, "an integer index", *index_span),
                    Some(true) => {}
                }
                let len = match &b {
                    Ty::Array(_, n) => Some(*n),
                    Ty::Vector(_, n) => Some(*n as u64),
                    _ => None,
                };
                if let (Some(i), Some(len)) = (literal, len) {
                    if *i >= len as u128 {
                        self.error(SemaError::IndexRange {
                            index: *i,
                            len,
                            span: *index_span,
                        });
                    }
                }
                self.unify(result, &elem).ok();
                Done
            }
            Obligation::Slice {
                base,
                bounds,
                literal,
                result,
                span,
            } => {
                let b = self.shallow(base);
                let out = match &b {
                    Ty::Var(_) if self.class(&b) == Class::Unknown => {
                        return self.wait_or_fail(force, result, "sliced value", *span)
                    }
                    Ty::Error => Ty::Error,
                    Ty::Array(e, _) | Ty::Slice(e) => Ty::Slice(e.clone()),
                    _ if self.class(&b) == Class::Int => {
                        if let (Ty::Prim(p), Some((lo, hi))) = (&b, literal) {
                            let width = p.bits() as u128;
                            if !(lo < hi && *hi <= width) {
                                self.error(SemaError::BitRange {
                                    lo: *lo,
                                    hi: *hi,
                                    ty: p.name().to_string(),
                                    span: *span,
                                });
                            }
                        }
                        b.clone()
                    }
                    _ => {
                        let ty = self.show(&b);
                        self.error(SemaError::NotSliceable { ty, span: *span });
                        Ty::Error
                    }
                };
                for (t, _) in bounds.iter() {
                    if self.class(t) == Class::Unknown && !force {
                        return Wait;
                    }
                }
                for (t, s) in bounds.iter() {
                    if self.int_operand(t, true) == Some(false) {
                        self.bad_operand("[:]", t, "an integer bound", *s);
                    }
                }
                self.unify(result, &out).ok();
                Done
            }
            Obligation::Unary {
                op,
                operand,
                result,
                span,
            } => {
                let t = self.shallow(operand);
                let class = self.class(&t);
                if class == Class::Unknown {
                    return self.wait_or_fail(force, result, "operand", *span);
                }
                let ok = match op {
                    UnaryOp::Neg => {
                        let unsigned =
                            matches!(t, Ty::Prim(p) | Ty::Vector(p, _) if p.is_unsigned_int());
                        !unsigned
                            && (matches!(class, Class::Int | Class::Float)
                                || matches!(t, Ty::Vector(p, _) if p.is_numeric()))
                    }
                    UnaryOp::Not => {
                        t == Ty::bool()
                            || t == Ty::Error
                            || matches!(t, Ty::Vector(super::types::Prim::Bool, _))
                    }
                    UnaryOp::BitNot => {
                        class == Class::Int || matches!(t, Ty::Vector(p, _) if p.is_int())
                    }
                };
                if !ok {
                    let (sym, expected) = match op {
                        UnaryOp::Neg => ("-", "a signed number or vector"),
                        UnaryOp::Not => ("!", "`bool`"),
                        UnaryOp::BitNot => ("~", "an integer"),
                    };
                    self.bad_operand(sym, &t, expected, *span);
                }
                self.unify(result, &t).ok();
                Done
            }
            Obligation::Binary {
                op,
                lhs,
                rhs,
                result,
                span,
            } => self.solve_binary(*op, lhs, rhs, result, *span, force),
            Obligation::Cast {
                from,
                to,
                bits,
                span,
            } => {
                let f = self.shallow(from);
                let t = self.shallow(to);
                if f == Ty::Error || t == Ty::Error {
                    return Done;
                }
                if self.is_unknown(&f) && (*bits || self.class(&f) == Class::Unknown) {
                    if force && !*bits {
                        self.error(SemaError::CannotInfer {
                            what: "converted value",
                            span: *span,
                        });
                        return Done;
                    }
                    return Wait;
                }
                if *bits {
                    let (fb, tb) = (f.bit_size(), t.bit_size());
                    if fb.is_none() || fb != tb {
                        let show = |b: Option<u64>| {
                            b.map(|b| b.to_string())
                                .unwrap_or_else(|| "no fixed".into())
                        };
                        let (from_s, to_s) = (self.show(&f), self.show(&t));
                        self.error(SemaError::BadBitCast {
                            from: from_s,
                            to: to_s,
                            from_bits: show(fb),
                            to_bits: show(tb),
                            span: *span,
                        });
                    }
                    return Done;
                }
                let scalar =
                    |c: Class, t: &Ty| matches!(c, Class::Int | Class::Float) || *t == Ty::bool();
                let ok = match (&f, &t) {
                    (Ty::Vector(p, n), Ty::Vector(q, m)) => {
                        n == m && p.is_numeric() && q.is_numeric()
                    }
                    _ => scalar(self.class(&f), &f) && scalar(self.class(&t), &t),
                };
                if !ok {
                    let (from_s, to_s) = (self.show(&f), self.show(&t));
                    self.error(SemaError::BadCast {
                        from: from_s,
                        to: to_s,
                        span: *span,
                    });
                }
                Done
            }
            Obligation::Elem { iter, elem, span } => {
                match self.shallow(iter) {
                    Ty::Var(_) => {
                        return self.wait_or_fail(force, elem, "loop's collection", *span)
                    }
                    Ty::Error => {
                        self.unify(elem, &Ty::Error).ok();
                    }
                    Ty::Array(e, _) | Ty::Slice(e) | Ty::Set(e) => {
                        self.unify(elem, &e).ok();
                    }
                    other => {
                        let ty = self.show(&other);
                        self.error(SemaError::NotIterable { ty, span: *span });
                        self.unify(elem, &Ty::Error).ok();
                    }
                }
                Done
            }
            Obligation::Int { ty, check, span } => {
                let t = self.shallow(ty);
                let ok = match self.class(&t) {
                    Class::Unknown if !force => return Wait,
                    Class::Unknown => {
                        self.error(SemaError::CannotInfer {
                            what: "expression",
                            span: *span,
                        });
                        return Done;
                    }
                    Class::Int => true,
                    _ => *check == IntCheck::GroupBy && t == Ty::Ptr,
                };
                if !ok {
                    let (ty, span) = (self.show(&t), *span);
                    self.error(match check {
                        IntCheck::Discriminant => SemaError::DiscriminantNotInt { ty, span },
                        IntCheck::GroupSize => SemaError::GroupSizeNotInt { ty, span },
                        IntCheck::GroupBy => SemaError::GroupByNotIndex { ty, span },
                        IntCheck::FromKey => SemaError::FromKeyNotInt { ty, span },
                    });
                }
                Done
            }
            Obligation::Call(c) => self.solve_call(c, force),
            Obligation::Builtin {
                kind,
                args,
                result,
                span,
            } => self.solve_builtin(*kind, args, result, *span, force),
        }
    }

    /// An obligation whose subject is unknown: wait, or in forced mode report it.
    fn wait_or_fail(
        &mut self,
        force: bool,
        result: &Ty,
        what: &'static str,
        span: Span,
    ) -> Progress {
        if !force {
            return Progress::Wait;
        }
        self.error(SemaError::CannotInfer { what, span });
        self.unify(result, &Ty::Error).ok();
        Progress::Done
    }

    /// Makes the operands of a same-type operator agree, widening a narrower integer operand.
    /// Returns the common type, or `None` to wait.
    fn common_operand(
        &mut self,
        lhs: &(NodeId, Ty, Span),
        rhs: &(NodeId, Ty, Span),
        force: bool,
    ) -> Option<Ty> {
        let (l, r) = (self.shallow(&lhs.1), self.shallow(&rhs.1));
        if self.class(&l) == Class::Unknown && self.class(&r) == Class::Unknown && !force {
            return None;
        }
        if let (Ty::Prim(p), Ty::Prim(q)) = (&l, &r) {
            if p != q && p.is_int() && q.is_int() && p.is_signed_int() == q.is_signed_int() {
                let (wide, narrow_id) = if p.bits() > q.bits() {
                    (l.clone(), rhs.0)
                } else {
                    (r.clone(), lhs.0)
                };
                self.out.widenings.insert(narrow_id, wide.clone());
                return Some(wide);
            }
        }
        if self.unify(&l, &r).is_err() {
            let (expected, found) = (self.show(&l), self.show(&r));
            let context = match (&l, &r) {
                (Ty::Prim(p), Ty::Prim(q)) if p.is_int() && q.is_int() => {
                    "the operator's other operand (integers of different signedness need `as`)"
                }
                _ => "the operator's other operand",
            };
            self.error(SemaError::Mismatch {
                expected,
                found,
                span: rhs.2,
                context,
            });
            return Some(Ty::Error);
        }
        Some(l)
    }

    fn solve_binary(
        &mut self,
        op: BinaryOp,
        lhs: &(NodeId, Ty, Span),
        rhs: &(NodeId, Ty, Span),
        result: &Ty,
        span: Span,
        force: bool,
    ) -> Progress {
        use BinaryOp::*;
        let sym = op.as_str();
        match op {
            And | Or => {
                for (_, t, s) in [lhs, rhs] {
                    if self.unify(t, &Ty::bool()).is_err() {
                        self.bad_operand(sym, t, "`bool`", *s);
                    }
                }
                self.unify(result, &Ty::bool()).ok();
                Progress::Done
            }
            Shl | Shr => {
                let lc = self.class(&lhs.1);
                let rc = self.class(&rhs.1);
                if (lc == Class::Unknown || rc == Class::Unknown) && !force {
                    return Progress::Wait;
                }
                let l = self.shallow(&lhs.1);
                let int_vec = matches!(l, Ty::Vector(p, _) if p.is_int());
                if !int_vec && self.int_operand(&lhs.1, force) != Some(true) {
                    self.bad_operand(sym, &lhs.1, "an integer", lhs.2);
                }
                if self.int_operand(&rhs.1, force) != Some(true) && !int_vec {
                    self.bad_operand(sym, &rhs.1, "an integer shift amount", rhs.2);
                }
                self.unify(result, &lhs.1).ok();
                Progress::Done
            }
            _ => {
                let Some(t) = self.common_operand(lhs, rhs, force) else {
                    return Progress::Wait;
                };
                let t = self.shallow(&t);
                let class = self.class(&t);
                if class == Class::Unknown {
                    if !force {
                        return Progress::Wait;
                    }
                    self.error(SemaError::CannotInfer {
                        what: "operands",
                        span,
                    });
                    self.unify(result, &Ty::Error).ok();
                    return Progress::Done;
                }
                // Comparisons of vectors are lane by lane: a `bool` vector (`any`, `all` and
                // `select` take it).
                let lanes_of = |t: &Ty| match t {
                    Ty::Vector(_, n) => Ty::Vector(super::types::Prim::Bool, *n),
                    _ => Ty::bool(),
                };
                let (ok, expected, out) = match op {
                    Eq | Ne => (
                        matches!(class, Class::Int | Class::Float)
                            || matches!(t, Ty::Prim(_) | Ty::Ptr | Ty::Vector(..)),
                        "a scalar, vector or `ptr`",
                        lanes_of(&t),
                    ),
                    Lt | Le | Gt | Ge => (
                        matches!(class, Class::Int | Class::Float)
                            || matches!(t, Ty::Vector(p, _) if p.is_numeric()),
                        "a number or a numeric vector",
                        lanes_of(&t),
                    ),
                    Add | Sub | Mul | Div | Rem => (
                        matches!(class, Class::Int | Class::Float)
                            || matches!(t, Ty::Vector(p, _) if p.is_numeric()),
                        "numbers or numeric vectors of one type",
                        t.clone(),
                    ),
                    BitAnd | BitOr | BitXor => (
                        class == Class::Int
                            || t == Ty::bool()
                            || matches!(t, Ty::Vector(p, _) if p.is_int() || p == super::types::Prim::Bool),
                        "integers",
                        t.clone(),
                    ),
                    And | Or | Shl | Shr => (true, "", t.clone()),
                };
                if !ok {
                    self.bad_operand(sym, &t, expected, span);
                }
                self.unify(result, &out).ok();
                Progress::Done
            }
        }
    }
}
