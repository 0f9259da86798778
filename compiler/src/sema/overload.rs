//! Calls: functions (with overloads), record and variant constructors, vector constructors,
//! conversions written as calls, and builtins (paper §3; `docs/language.md`, "Overloading").
//!
//! Input: a call expression. Output: its resolution ([`Resolution::Func`], `Ctor`, `Variant`,
//! `VectorCtor`, `PrimConv`, `Builtin`) and its type. A call with several candidates (functions
//! sharing a name, or variants of several types sharing a name) waits until its argument types
//! tell the candidates apart: candidates whose arity and parameter types are compatible with
//! the arguments remain; exactly one is chosen; none is an error listing the candidates; more
//! than one once the arguments are known is an ambiguity naming them.

use super::errors::SemaError;
use super::infer::{Binding, Checker, Ctx};
use super::ops::{Obligation, Progress};
use super::typed::{Builtin, FuncId, Resolution};
use super::types::{vector_from_name, AdtId, Prim, Ty};
use super::unify::VarKind;
use crate::syntax::ast::{Expr, ExprKind, Ident, NodeId};
use scion_ir::diag::Span;

/// A possible target of a call.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Callee {
    Func(FuncId),
    Ctor(AdtId),
    Variant(AdtId, u32),
}

/// An argument of a call.
#[derive(Clone, Debug)]
pub(super) struct Arg {
    pub ty: Ty,
    pub span: Span,
    /// The argument is a `mut` parameter of the enclosing function or a `let mut` local (can be
    /// passed by reference).
    pub mut_place: bool,
}

/// A call waiting for overload resolution.
#[derive(Clone, Debug)]
pub(super) struct CallOb {
    pub id: NodeId,
    pub name: String,
    pub span: Span,
    pub cands: Vec<Callee>,
    pub args: Vec<Arg>,
    pub result: Ty,
}

/// One parameter of a candidate's signature.
struct SigParam {
    name: String,
    ty: Ty,
    has_default: bool,
    mutable: bool,
}

impl Checker<'_> {
    pub(super) fn infer_call(&mut self, e: &Expr, callee: &Ident, args: &[Expr]) -> Ty {
        let name = callee.name.as_str();
        if name == "append" && matches!(self.ctx, Ctx::Build { .. }) {
            return self.infer_append(e, args);
        }
        let arg_info: Vec<Arg> = args
            .iter()
            .map(|a| {
                let ty = self.infer_expr(a);
                Arg {
                    ty,
                    span: a.span,
                    mut_place: self.is_mut_param(a),
                }
            })
            .collect();
        let mut cands: Vec<Callee> = self
            .overloads
            .get(name)
            .map(|v| v.iter().map(|f| Callee::Func(*f)).collect())
            .unwrap_or_default();
        if let Some(adt) = self.adts.by_name(name) {
            if self.adts.get(adt).is_some_and(|d| d.is_sum()) {
                self.error(SemaError::NotCallable {
                    name: name.to_string(),
                    span: callee.span,
                    why: "a sum type is built with one of its variants",
                });
                return Ty::Error;
            }
            cands.push(Callee::Ctor(adt));
        }
        for (adt, v) in self.adts.variants_named(name) {
            cands.push(Callee::Variant(adt, v as u32));
        }
        if cands.is_empty() {
            if let Some((p, n)) = vector_from_name(name) {
                self.out
                    .resolutions
                    .insert(e.id, Resolution::VectorCtor(p, n));
                if arg_info.len() != n as usize {
                    self.error(SemaError::ArgCount {
                        callee: name.to_string(),
                        min: n as usize,
                        max: n as usize,
                        found: arg_info.len(),
                        span: e.span,
                    });
                }
                for a in &arg_info {
                    self.expect(&a.ty, &Ty::Prim(p), a.span, "the vector's element type");
                }
                return Ty::Vector(p, n);
            }
            if let Some(p) = Prim::from_name(name) {
                self.out.resolutions.insert(e.id, Resolution::PrimConv(p));
                if arg_info.len() != 1 {
                    self.error(SemaError::ArgCount {
                        callee: name.to_string(),
                        min: 1,
                        max: 1,
                        found: arg_info.len(),
                        span: e.span,
                    });
                    return Ty::Prim(p);
                }
                let from = arg_info[0].ty.clone();
                self.solve_or_defer(Obligation::Cast {
                    from,
                    to: Ty::Prim(p),
                    bits: false,
                    span: e.span,
                });
                return Ty::Prim(p);
            }
            if let Some(b) = Builtin::from_name(name) {
                self.out.resolutions.insert(e.id, Resolution::Builtin(b));
                if arg_info.len() != b.arity() {
                    self.error(SemaError::ArgCount {
                        callee: name.to_string(),
                        min: b.arity(),
                        max: b.arity(),
                        found: arg_info.len(),
                        span: e.span,
                    });
                    return Ty::Error;
                }
                if b == Builtin::Insert && !arg_info[0].mut_place {
                    self.error(SemaError::MutArgNotPlace {
                        param: "s".into(),
                        span: arg_info[0].span,
                    });
                }
                let result = self.fresh(VarKind::General);
                let args = arg_info.into_iter().map(|a| (a.ty, a.span)).collect();
                self.solve_or_defer(Obligation::Builtin {
                    kind: b,
                    args,
                    result: result.clone(),
                    span: e.span,
                });
                return result;
            }
            self.error(SemaError::UnknownCallee {
                name: name.to_string(),
                span: callee.span,
            });
            return Ty::Error;
        }
        let result = self.fresh(VarKind::General);
        let ob = CallOb {
            id: e.id,
            name: name.to_string(),
            span: e.span,
            cands,
            args: arg_info,
            result: result.clone(),
        };
        self.solve_or_defer(Obligation::Call(ob));
        result
    }

    fn is_mut_param(&self, e: &Expr) -> bool {
        let ExprKind::Name(n) = &e.kind else {
            return false;
        };
        match (self.lookup(&n.name), &self.ctx) {
            (Some(Binding::Param(i)), Ctx::Func(f)) => {
                f.params.get(i as usize).is_some_and(|p| p.mutable)
            }
            (Some(Binding::Local(b)), _) => self.out.bindings[b.0 as usize].mutable,
            _ => false,
        }
    }

    fn signature(&self, c: Callee) -> (Vec<SigParam>, Ty) {
        match c {
            Callee::Func(f) => {
                let info = &self.out.funcs[f.0 as usize];
                let ps = info
                    .params
                    .iter()
                    .map(|p| SigParam {
                        name: p.name.clone(),
                        ty: p.ty.clone(),
                        has_default: p.has_default,
                        mutable: p.mutable,
                    })
                    .collect();
                (ps, info.ret.clone())
            }
            Callee::Ctor(a) | Callee::Variant(a, _) => {
                let Some(def) = self.adts.get(a) else {
                    return (Vec::new(), Ty::Error);
                };
                let fields = match c {
                    Callee::Variant(_, v) => def.variant_fields(v as usize),
                    _ => def.fields.iter().collect(),
                };
                let ps = fields
                    .iter()
                    .map(|f| SigParam {
                        name: f.name.clone(),
                        ty: f.ty.clone(),
                        has_default: f.has_default,
                        mutable: false,
                    })
                    .collect();
                (ps, Ty::Adt(a))
            }
        }
    }

    /// Minimum and maximum argument counts (trailing defaulted parameters may be omitted).
    fn arity(ps: &[SigParam]) -> (usize, usize) {
        let min = ps
            .iter()
            .rposition(|p| !p.has_default)
            .map(|i| i + 1)
            .unwrap_or(0);
        (min, ps.len())
    }

    fn describe(&self, c: Callee) -> String {
        let (ps, _) = self.signature(c);
        let tys: Vec<String> = ps.iter().map(|p| self.show(&p.ty)).collect();
        let head = match c {
            Callee::Func(f) => self.out.funcs[f.0 as usize].name.clone(),
            Callee::Ctor(a) => self.adts.get(a).map(|d| d.name.clone()).unwrap_or_default(),
            Callee::Variant(a, v) => self
                .adts
                .get(a)
                .map(|d| format!("{}.{}", d.name, d.variants()[v as usize].name))
                .unwrap_or_default(),
        };
        format!("{head}({})", tys.join(", "))
    }

    fn viable(&self, c: Callee, args: &[Arg]) -> bool {
        let (ps, _) = self.signature(c);
        let (min, max) = Self::arity(&ps);
        (min..=max).contains(&args.len())
            && args
                .iter()
                .zip(ps.iter())
                .all(|(a, p)| self.compatible(&a.ty, &p.ty))
    }

    pub(super) fn solve_call(&mut self, c: &CallOb, force: bool) -> Progress {
        if c.cands.len() == 1 {
            self.apply_call(c, c.cands[0]);
            return Progress::Done;
        }
        let by_args: Vec<Callee> = c
            .cands
            .iter()
            .copied()
            .filter(|k| self.viable(*k, &c.args))
            .collect();
        if by_args.is_empty() {
            let args: Vec<String> = c.args.iter().map(|a| self.show(&a.ty)).collect();
            let candidates = c.cands.iter().map(|k| self.describe(*k)).collect();
            self.error(SemaError::NoOverload {
                name: c.name.clone(),
                args: format!("({})", args.join(", ")),
                candidates,
                span: c.span,
            });
            self.unify(&c.result, &Ty::Error).ok();
            return Progress::Done;
        }
        if by_args.len() == 1 {
            self.apply_call(c, by_args[0]);
            return Progress::Done;
        }
        // Several candidates take these arguments: the expected result type may decide.
        let by_result: Vec<Callee> = by_args
            .iter()
            .copied()
            .filter(|k| self.compatible(&c.result, &self.signature(*k).1))
            .collect();
        if by_result.len() == 1 {
            self.apply_call(c, by_result[0]);
            return Progress::Done;
        }
        let known =
            c.args.iter().all(|a| !self.zonk(&a.ty).has_vars()) && !self.zonk(&c.result).has_vars();
        if !known && !force {
            return Progress::Wait;
        }
        let remaining = if by_result.is_empty() {
            &by_args
        } else {
            &by_result
        };
        let candidates = remaining.iter().map(|k| self.describe(*k)).collect();
        self.error(SemaError::AmbiguousOverload {
            name: c.name.clone(),
            candidates,
            span: c.span,
        });
        self.unify(&c.result, &Ty::Error).ok();
        Progress::Done
    }

    fn apply_call(&mut self, c: &CallOb, k: Callee) {
        let res = match k {
            Callee::Func(f) => Resolution::Func(f),
            Callee::Ctor(a) => Resolution::Ctor(a),
            Callee::Variant(a, v) => Resolution::Variant(a, v),
        };
        self.out.resolutions.insert(c.id, res);
        let (ps, ret) = self.signature(k);
        let (min, max) = Self::arity(&ps);
        if !(min..=max).contains(&c.args.len()) {
            self.error(SemaError::ArgCount {
                callee: c.name.clone(),
                min,
                max,
                found: c.args.len(),
                span: c.span,
            });
        }
        for (a, p) in c.args.iter().zip(ps.iter()) {
            self.expect(&a.ty, &p.ty, a.span, "the parameter's type");
            if p.mutable && !a.mut_place {
                self.error(SemaError::MutArgNotPlace {
                    param: p.name.clone(),
                    span: a.span,
                });
            }
        }
        self.unify(&c.result, &ret).ok();
    }
}
