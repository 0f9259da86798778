//! Type inference of expressions, shared by the three languages (paper Figures 3, 6, 10).
//!
//! Input: an expression and the current scopes and context. Output: its type (possibly an
//! inference variable), recorded in `expr_types`, its resolution for names, and deferred
//! obligations (`ops`) for operators, fields, indexing and calls whose operand types are not
//! known yet.

use super::errors::SemaError;
use super::infer::{Binding, Checker, Ctx};
use super::ops::Obligation;
use super::typed::Resolution;
use super::types::Ty;
use super::unify::VarKind;
use crate::syntax::ast::{Expr, ExprKind};

impl Checker<'_> {
    /// Infers the type of `e` and records it.
    pub(super) fn infer_expr(&mut self, e: &Expr) -> Ty {
        let t = self.infer_expr_inner(e);
        self.record(e.id, &t);
        t
    }

    fn infer_expr_inner(&mut self, e: &Expr) -> Ty {
        match &e.kind {
            ExprKind::Name(n) => self.infer_name(e, &n.name),
            ExprKind::Int(v) => {
                self.int_literals.push((e.id, *v, e.span));
                self.fresh(VarKind::Int)
            }
            ExprKind::Float(_) => self.fresh(VarKind::Float),
            ExprKind::Bool(_) => Ty::bool(),
            ExprKind::If {
                branches,
                otherwise,
            } => self.infer_if(branches, otherwise),
            ExprKind::Call { callee, args } => self.infer_call(e, callee, args),
            ExprKind::Field { base, name } => {
                let b = self.infer_expr(base);
                let result = self.fresh(VarKind::General);
                self.solve_or_defer(Obligation::Field {
                    base: b,
                    name: name.name.clone(),
                    result: result.clone(),
                    span: name.span,
                });
                result
            }
            ExprKind::Index { base, index } => {
                let b = self.infer_expr(base);
                let i = self.infer_expr(index);
                let literal = match index.kind {
                    ExprKind::Int(v) => Some(v),
                    _ => None,
                };
                let result = self.fresh(VarKind::General);
                self.solve_or_defer(Obligation::Index {
                    base: b,
                    index: i,
                    literal,
                    result: result.clone(),
                    span: e.span,
                    index_span: index.span,
                });
                result
            }
            ExprKind::Slice { base, lo, hi } => {
                let b = self.infer_expr(base);
                let l = self.infer_expr(lo);
                let h = self.infer_expr(hi);
                let result = self.fresh(VarKind::General);
                // Layouts and builds check their bit ranges structurally (E0325, E0413).
                let in_function = matches!(
                    self.ctx,
                    super::infer::Ctx::Func(_) | super::infer::Ctx::Const
                );
                let literal = match (&lo.kind, &hi.kind) {
                    (ExprKind::Int(a), ExprKind::Int(z)) if in_function => Some((*a, *z)),
                    _ => None,
                };
                self.solve_or_defer(Obligation::Slice {
                    base: b,
                    bounds: [(l, lo.span), (h, hi.span)],
                    literal,
                    result: result.clone(),
                    span: e.span,
                });
                result
            }
            ExprKind::Tuple(items) => Ty::Tuple(items.iter().map(|i| self.infer_expr(i)).collect()),
            ExprKind::Array(items) => {
                let tys: Vec<Ty> = items.iter().map(|i| self.infer_expr(i)).collect();
                let Some(first) = tys.first().cloned() else {
                    self.error(SemaError::EmptyArray { span: e.span });
                    return Ty::Error;
                };
                for (t, i) in tys.iter().zip(items).skip(1) {
                    self.expect(
                        t,
                        &first,
                        i.span,
                        "an array element (all have the first's type)",
                    );
                }
                Ty::Array(Box::new(first), items.len() as u64)
            }
            ExprKind::Unary { op, operand } => {
                let t = self.infer_expr(operand);
                let result = self.fresh(VarKind::General);
                self.solve_or_defer(Obligation::Unary {
                    op: *op,
                    operand: t,
                    result: result.clone(),
                    span: e.span,
                });
                result
            }
            ExprKind::Binary { op, lhs, rhs } => {
                let l = self.infer_expr(lhs);
                let r = self.infer_expr(rhs);
                let result = self.fresh(VarKind::General);
                self.solve_or_defer(Obligation::Binary {
                    op: *op,
                    lhs: (lhs.id, l, lhs.span),
                    rhs: (rhs.id, r, rhs.span),
                    result: result.clone(),
                    span: e.span,
                });
                result
            }
            ExprKind::Cast { expr, ty } => {
                let from = self.infer_expr(expr);
                let to = self.lower_type_local(ty);
                self.solve_or_defer(Obligation::Cast {
                    from,
                    to: to.clone(),
                    bits: false,
                    span: e.span,
                });
                to
            }
            ExprKind::BitCast { expr, ty } => {
                let from = self.infer_expr(expr);
                let to = self.lower_type_local(ty);
                self.solve_or_defer(Obligation::Cast {
                    from,
                    to: to.clone(),
                    bits: true,
                    span: e.span,
                });
                to
            }
            ExprKind::This => match &self.ctx {
                Ctx::Build { .. } => self
                    .current_layout()
                    .map(|l| l.build_ref_ty.clone())
                    .unwrap_or(Ty::Error),
                _ => {
                    self.error(SemaError::WrongContext {
                        what: "`this`",
                        span: e.span,
                        allowed: "in builds",
                    });
                    Ty::Error
                }
            },
            ExprKind::Parent(name) => {
                if !matches!(self.ctx, Ctx::Layout { .. }) {
                    self.error(SemaError::WrongContext {
                        what: "`parent.x`",
                        span: e.span,
                        allowed: "in layouts",
                    });
                    return Ty::Error;
                }
                // `parent.x` may name any member of the layout (the parent is a node of the
                // same layout), also from a reference component's default.
                let found = self.lookup(&name.name).or_else(|| {
                    let l = self.current_layout()?;
                    let i = l.members.iter().position(|m| m.name == name.name)?;
                    Some(Binding::Member(super::typed::MemberId(i as u32)))
                });
                match found {
                    Some(Binding::Member(m)) => {
                        self.out
                            .resolutions
                            .insert(e.id, Resolution::ParentMember(m));
                        self.binding_ty(Binding::Member(m))
                    }
                    Some(Binding::LayoutParam(i)) => {
                        self.out
                            .resolutions
                            .insert(e.id, Resolution::ParentParam(i));
                        self.binding_ty(Binding::LayoutParam(i))
                    }
                    // `parent.x` naming nothing is `check_layout`'s E0310.
                    _ => Ty::Error,
                }
            }
            ExprKind::Build(name) => self.infer_build_expr(e, name),
        }
    }

    fn infer_name(&mut self, e: &Expr, name: &str) -> Ty {
        if let Some(b) = self.lookup(name) {
            let res = match b {
                Binding::Local(id) => Resolution::Local(id),
                Binding::Param(i) => Resolution::Param(i),
                Binding::LayoutParam(i) => Resolution::LayoutParam(i),
                Binding::Member(m) => Resolution::LayoutMember(m),
                Binding::BuildField(i) => Resolution::BuildField(i),
            };
            self.out.resolutions.insert(e.id, res);
            return self.binding_ty(b);
        }
        // A field-less variant used as a value.
        let all = self.adts.variants_named(name);
        let fieldless: Vec<(super::types::AdtId, usize)> = all
            .iter()
            .copied()
            .filter(|(a, v)| {
                self.adts
                    .get(*a)
                    .is_some_and(|d| d.variant_fields(*v).is_empty())
            })
            .collect();
        match fieldless.as_slice() {
            [] if !all.is_empty() => {
                self.error(SemaError::VariantNeedsArgs {
                    name: name.to_string(),
                    span: e.span,
                });
                return Ty::Error;
            }
            [] => {}
            [(adt, v)] => {
                self.out
                    .resolutions
                    .insert(e.id, Resolution::Variant(*adt, *v as u32));
                return Ty::Adt(*adt);
            }
            _ => {
                // Variants of several types share the name: the expected type decides.
                let result = self.fresh(VarKind::General);
                let cands = fieldless
                    .iter()
                    .map(|(a, v)| super::overload::Callee::Variant(*a, *v as u32))
                    .collect();
                let ob = super::overload::CallOb {
                    id: e.id,
                    name: name.to_string(),
                    span: e.span,
                    cands,
                    args: Vec::new(),
                    result: result.clone(),
                };
                self.solve_or_defer(Obligation::Call(ob));
                return result;
            }
        }
        // In a layout, a name that resolves on no route is `check_layout`'s E0319; in a build,
        // a field of another variant is `check_build`'s E0418.
        let other_variant = matches!(self.ctx, Ctx::Build { .. })
            && self
                .current_layout()
                .is_some_and(|l| l.members.iter().any(|m| m.name == name));
        if !matches!(self.ctx, Ctx::Layout { .. }) && !other_variant {
            self.error(SemaError::UnknownName {
                name: name.to_string(),
                span: e.span,
            });
        }
        Ty::Error
    }
}
