//! Typing of builds (paper §5, Figures 9 and 10).
//!
//! Input: a `build` declaration and the typed layout of the same name. Output: a
//! [`BuildInfo`], the targets of `build x` statements, and side-table entries for the bodies.
//! Scope of a variant's body: the variant's logical fields (the build's parameters, which must
//! match the variant's fields by name and type, shared fields first), then the layout members
//! the variant reaches, then locals. `this` has the layout's reference type; `build x` in an
//! expression builds the child in recursive field `x` and yields its reference (the physical
//! type of `x`); `append(x, n)` yields `u32`; `build x = e` needs `e` to have the stored field's
//! type (an integer literal must fit it); `build x` copies logical field `x` into the stored
//! field `x` when their types agree. `build root { ... }` sees the layout's globals and the
//! shared fields of the root node.

use super::errors::SemaError;
use super::infer::{Binding, Checker, Ctx};
use super::resolve::LenScope;
use super::typed::{
    BuildInfo, BuildTarget, BuildVariantInfo, LayoutId, MemberId, MemberKindInfo, Resolution,
};
use super::types::{Prim, Ty};
use super::unify::VarKind;
use crate::syntax::ast::{BuildDecl, Expr, ExprKind, Ident, Stmt};
use rustc_hash::FxHashMap;
use scion_ir::diag::Span;

impl Checker<'_> {
    /// Types build item `item`.
    pub(super) fn check_build(&mut self, item: usize, decl: &BuildDecl) {
        // A build without a layout is `check_build`'s E0401.
        let Some(LayoutId(li)) = self.out.layout_named(&decl.name.name) else {
            self.out.builds.push(BuildInfo {
                item,
                layout: None,
                variants: Vec::new(),
            });
            return;
        };
        let layout = li as usize;
        let mut info = BuildInfo {
            item,
            layout: Some(LayoutId(li)),
            variants: Vec::new(),
        };
        let ref_ty = self.out.layouts[layout].build_ref_ty.clone();
        if let Some(root) = &decl.root {
            // The root block sees the globals and the shared fields of the root node.
            let shared: Vec<(String, Ty)> = self.out.layouts[layout]
                .adt
                .and_then(|a| self.adts.get(a))
                .map(|d| {
                    d.fields
                        .iter()
                        .map(|f| (f.name.clone(), f.ty.clone()))
                        .collect()
                })
                .unwrap_or_default();
            self.ctx = Ctx::Build {
                layout,
                variant: None,
                fields: shared.clone(),
                ret: ref_ty.clone(),
            };
            self.scopes.clear();
            self.push_scope();
            self.define_visible_members(layout, None);
            self.push_scope();
            for (i, f) in shared.iter().enumerate() {
                self.define(&f.0, Binding::BuildField(i as u32));
            }
            self.push_scope();
            for s in &root.body {
                self.check_stmt(s, false);
            }
            self.scopes.clear();
        }
        let Some(adt) = self.out.layouts[layout].adt else {
            self.out.builds.push(info);
            self.ctx = Ctx::Const;
            return;
        };
        let Some(def) = self.adts.get(adt).cloned() else {
            return;
        };
        let mut seen: FxHashMap<usize, Span> = FxHashMap::default();
        for (entry, bv) in decl.variants.iter().enumerate() {
            let Some(v) = def.variant_index(&bv.name.name) else {
                continue;
            };
            // An unknown or twice-built variant is `check_build`'s error (E0403, E0404).
            if seen.insert(v, bv.name.span).is_some() {
                continue;
            }
            let logical = def.variant_fields(v);
            let param_names: Vec<String> = bv.params.iter().map(|p| p.name.name.clone()).collect();
            if bv.params.len() != logical.len() {
                let fields = logical
                    .iter()
                    .map(|f| f.name.clone())
                    .collect::<Vec<_>>()
                    .join(", ");
                self.error(SemaError::BuildParamCount {
                    variant: bv.name.name.clone(),
                    expected: logical.len(),
                    found: bv.params.len(),
                    fields,
                    span: bv.name.span,
                });
            }
            // Array lengths may name any logical field, whatever the parameters are called.
            let mut len_names = param_names.clone();
            len_names.extend(logical.iter().map(|f| f.name.clone()));
            for (p, f) in bv.params.iter().zip(logical.iter()) {
                if p.name.name != f.name {
                    // A name that is no field of the variant is `check_build`'s E0415; a field
                    // out of its place is reported here.
                    if logical.iter().any(|g| g.name == p.name.name) {
                        self.error(SemaError::BuildParamName {
                            expected: f.name.clone(),
                            found: p.name.name.clone(),
                            span: p.name.span,
                        });
                    }
                    continue;
                }
                let t = self.lower_type(&p.ty, &LenScope::Names(&len_names));
                if t != f.ty && !t.has_error() {
                    let (expected, found) = (
                        f.ty.display(&self.adts).to_string(),
                        t.display(&self.adts).to_string(),
                    );
                    self.error(SemaError::BuildParamType {
                        name: f.name.clone(),
                        expected,
                        found,
                        span: p.ty.span,
                    });
                }
            }
            let fields: Vec<(String, Ty)> = logical
                .iter()
                .map(|f| (f.name.clone(), f.ty.clone()))
                .collect();
            self.ctx = Ctx::Build {
                layout,
                variant: Some(v as u32),
                fields: fields.clone(),
                ret: ref_ty.clone(),
            };
            self.scopes.clear();
            self.push_scope();
            self.define_visible_members(layout, Some(v as u32));
            self.push_scope();
            for (i, f) in fields.iter().enumerate() {
                self.define(&f.0, Binding::BuildField(i as u32));
            }
            self.push_scope();
            for s in &bv.body {
                self.check_stmt(s, false);
            }
            self.scopes.clear();
            info.variants.push(BuildVariantInfo {
                entry,
                variant: v as u32,
                fields,
            });
        }
        self.out.builds.push(info);
        self.ctx = Ctx::Const;
    }

    /// Defines the stored and derived members that variant `variant` reaches (`None`: globals
    /// only, for `build root`).
    fn define_visible_members(&mut self, layout: usize, variant: Option<u32>) {
        let members: Vec<(String, MemberId)> = self.out.layouts[layout]
            .members
            .iter()
            .enumerate()
            .filter(|(_, m)| matches!(m.kind, MemberKindInfo::Stored | MemberKindInfo::Derived))
            .filter(|(_, m)| match variant {
                None => m.group.is_none() && m.variant.is_none(),
                Some(v) => m.variant.is_none() || m.variant == Some(v),
            })
            .map(|(i, m)| (m.name.clone(), MemberId(i as u32)))
            .collect();
        for (n, id) in members.into_iter().rev() {
            self.define(&n, Binding::Member(id));
        }
    }

    /// The stored member named `name` reachable in the current build context.
    fn build_member(&self, name: &str) -> Option<MemberId> {
        let Ctx::Build {
            layout, variant, ..
        } = &self.ctx
        else {
            return None;
        };
        let l = self.out.layouts.get(*layout)?;
        l.members
            .iter()
            .position(|m| {
                m.name == name
                    && m.kind == MemberKindInfo::Stored
                    && match variant {
                        None => m.group.is_none() && m.variant.is_none(),
                        Some(v) => m.variant.is_none() || m.variant == Some(*v),
                    }
            })
            .map(|i| MemberId(i as u32))
    }

    /// Logical field `name` of the variant being built: index, type, and whether it is recursive.
    fn build_field(&self, name: &str) -> Option<(u32, Ty, bool)> {
        let Ctx::Build { fields, layout, .. } = &self.ctx else {
            return None;
        };
        let adt = self.out.layouts.get(*layout)?.adt?;
        let i = fields.iter().position(|f| f.0 == name)?;
        let t = fields[i].1.clone();
        let rec = self.adts.mentions(&t, adt);
        Some((i as u32, t, rec))
    }

    fn physical_in_build(&self, logical: &Ty) -> Ty {
        let Ctx::Build { layout, .. } = &self.ctx else {
            return logical.clone();
        };
        let Some(l) = self.out.layouts.get(*layout) else {
            return logical.clone();
        };
        match l.adt {
            Some(adt) => self.physical_of(logical, adt, &l.build_ref_ty),
            None => logical.clone(),
        }
    }

    /// `build x` / `build x = e` as a statement.
    pub(super) fn check_build_stmt(&mut self, s: &Stmt, field: &Ident, value: Option<&Expr>) {
        if !matches!(self.ctx, Ctx::Build { .. }) {
            self.error(SemaError::WrongContext {
                what: "a `build` statement",
                span: s.span,
                allowed: "in builds",
            });
            if let Some(v) = value {
                self.infer_expr(v);
            }
            return;
        }
        let member = self.build_member(&field.name);
        let logical = self.build_field(&field.name);
        let member_ty = member.and_then(|m| {
            self.current_layout()
                .map(|l| l.members[m.0 as usize].ty.clone())
        });
        // `build x` without a value copies logical field `x`: a target that is neither a logical
        // nor a stored field is `check_build`'s E0406 / E0417, and a stored field of another type
        // than the logical field `check_layout`'s E0327 (on every variant's route).
        if let Some(e) = value {
            let t = self.infer_expr(e);
            // An unknown target is `check_build`'s E0406.
            if let Some(mt) = member_ty {
                if let (ExprKind::Int(v), Some(p)) = (&e.kind, mt.as_int()) {
                    if p.int_literal_max().is_some_and(|max| *v > max) {
                        let ty = self.show(&mt);
                        self.literal_reported.push(e.id);
                        self.error(SemaError::BuildLiteralFit {
                            field: field.name.clone(),
                            value: *v,
                            ty,
                            span: e.span,
                        });
                    }
                }
                if self.unify(&t, &mt).is_err() {
                    let (expected, found) = (self.show(&mt), self.show(&t));
                    self.error(SemaError::BuildValueType {
                        field: field.name.clone(),
                        expected,
                        found,
                        span: e.span,
                    });
                }
            }
        }
        let (field_ix, child) = match logical {
            Some((i, _, rec)) => (Some(i), rec),
            None => (None, false),
        };
        self.out.build_targets.insert(
            s.id,
            BuildTarget {
                member,
                field: field_ix,
                child,
            },
        );
    }

    /// `build x` as an expression: builds the child in recursive field `x`.
    pub(super) fn infer_build_expr(&mut self, e: &Expr, name: &Ident) -> Ty {
        if !matches!(
            self.ctx,
            Ctx::Build {
                variant: Some(_),
                ..
            }
        ) {
            self.error(SemaError::WrongContext {
                what: "`build x` as an expression",
                span: e.span,
                allowed: "in the build of a variant",
            });
            return Ty::Error;
        }
        match self.build_field(&name.name) {
            Some((i, t, true)) => {
                self.out.resolutions.insert(e.id, Resolution::BuildChild(i));
                self.physical_in_build(&t)
            }
            // Not a child: `check_build`'s E0410.
            _ => Ty::Error,
        }
    }

    /// `append(x, n)` in a build.
    pub(super) fn infer_append(&mut self, e: &Expr, args: &[Expr]) -> Ty {
        self.out
            .resolutions
            .insert(e.id, Resolution::Builtin(super::typed::Builtin::Append));
        let tys: Vec<Ty> = args.iter().map(|a| self.infer_expr(a)).collect();
        if args.len() != 2 {
            self.error(SemaError::ArgCount {
                callee: "append".into(),
                min: 2,
                max: 2,
                found: args.len(),
                span: e.span,
            });
            return Ty::Prim(Prim::U32);
        }
        // Whether `x` is a dependent-length logical field is `check_build`'s E0412.
        let n = self.shallow(&tys[1]);
        if !(n.as_int().is_some() || n == Ty::Error || self.var_kind(&n).is_some()) {
            let ty = self.show(&n);
            self.error(SemaError::BadOperand {
                op: "append".into(),
                ty,
                expected: "an integer count",
                span: args[1].span,
            });
        } else if self.var_kind(&n) == Some(VarKind::General) {
            let v = self.fresh(VarKind::Int);
            self.unify(&n, &v).ok();
        }
        // The start index is an integer of the type the context asks for, `u32` otherwise.
        let start = self.fresh(VarKind::Int);
        self.append_results.push(start.clone());
        start
    }
}
