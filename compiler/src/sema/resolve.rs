//! Name resolution of declarations: written types, `type` declarations and function
//! signatures (paper §3, Figure 3).
//!
//! Input: the items of a [`Program`]. Output: the [`AdtTable`] (records with defaults; sums with
//! shared then per-variant fields), the function table with its overload sets and unique names,
//! and diagnostics for unknown types and duplicate definitions. Signatures are collected before
//! any body is checked, so recursion and mutual recursion need no forward declarations. Names
//! inside bodies are resolved while they are typed (`expr`, `overload`), in the scopes kept by
//! the checker.

use super::errors::SemaError;
use super::infer::{Checker, Ctx};
use super::typed::{FuncId, FuncInfo, ParamInfo};
use super::types::{AdtDef, AdtId, AdtKind, FieldDef, Prim, Ty, VariantDef};
use super::unify::VarKind;
use crate::syntax::ast::TypeExpr;
use crate::syntax::ast::{ArrayLen, FieldDecl, Item, Program, TypeExprKind};
use rustc_hash::FxHashMap;
use scion_ir::diag::Span;

/// The declared types a value of `ty` holds inline (not through a slice or a set).
fn record_parts(ty: &Ty) -> Vec<AdtId> {
    match ty {
        Ty::Adt(a) => vec![*a],
        Ty::Tuple(ts) => ts.iter().flat_map(record_parts).collect(),
        Ty::Array(e, _) | Ty::Option(e) => record_parts(e),
        _ => Vec::new(),
    }
}

/// How the length name of a dependent array `T[x]` is checked.
pub(super) enum LenScope<'s> {
    /// `x` must be one of these names (earlier fields or parameters).
    Names(&'s [String]),
    /// Inside a layout: `x` must be a member of the layout.
    Layout(&'s [String]),
    /// In a body: `x` must be in scope.
    Scope,
}

impl Checker<'_> {
    /// The semantic type of a written type.
    pub(super) fn lower_type(&mut self, te: &TypeExpr, lens: &LenScope) -> Ty {
        match &te.kind {
            TypeExprKind::Named(id) => {
                let n = id.name.as_str();
                if let Some(p) = Prim::from_name(n) {
                    Ty::Prim(p)
                } else if n == "ptr" {
                    Ty::Ptr
                } else if let Some(a) = self.adts.by_name(n) {
                    Ty::Adt(a)
                } else if let Some((p, lanes)) = super::types::vector_from_name(n) {
                    Ty::Vector(p, lanes)
                } else {
                    self.error(SemaError::UnknownType {
                        name: n.to_string(),
                        span: id.span,
                    });
                    Ty::Error
                }
            }
            TypeExprKind::Vector { elem, lanes } => match Prim::from_name(&elem.name) {
                Some(p) if p != Prim::Bool && *lanes >= 1 => Ty::Vector(p, *lanes),
                _ => {
                    self.error(SemaError::UnknownType {
                        name: format!("{}x{}", elem.name, lanes),
                        span: te.span,
                    });
                    Ty::Error
                }
            },
            TypeExprKind::Array { elem, len } => {
                let e = self.lower_type(elem, lens);
                match len {
                    ArrayLen::Const(n, _) => Ty::Array(Box::new(e), *n),
                    ArrayLen::Name(x) => {
                        let known = match lens {
                            LenScope::Names(ns) | LenScope::Layout(ns) => {
                                ns.iter().any(|n| n == &x.name)
                            }
                            LenScope::Scope => self.lookup(&x.name).is_some(),
                        };
                        if !known {
                            let (name, span) = (x.name.clone(), x.span);
                            self.error(match lens {
                                LenScope::Layout(_) => SemaError::LayoutArrayLen { name, span },
                                _ => SemaError::UnknownArrayLen { name, span },
                            });
                        }
                        Ty::Slice(Box::new(e))
                    }
                }
            }
            TypeExprKind::Tuple(ts) => {
                Ty::Tuple(ts.iter().map(|t| self.lower_type(t, lens)).collect())
            }
            TypeExprKind::Set(t) => Ty::Set(Box::new(self.lower_type(t, lens))),
            TypeExprKind::Option(t) => Ty::Option(Box::new(self.lower_type(t, lens))),
        }
    }

    /// A written type inside a body (`let`, `as`, patterns): lengths are names in scope.
    pub(super) fn lower_type_local(&mut self, te: &TypeExpr) -> Ty {
        self.lower_type(te, &LenScope::Scope)
    }

    /// Collects every `type` declaration into the ADT table.
    pub(super) fn collect_adts(
        &mut self,
        program: &Program,
        globals: &mut FxHashMap<String, Span>,
    ) {
        let mut decls = Vec::new();
        for (i, item) in program.items.iter().enumerate() {
            let Item::Type(d) = item else { continue };
            if let Some(prev) = globals.get(&d.name.name) {
                self.error(SemaError::Duplicate {
                    what: "type",
                    name: d.name.name.clone(),
                    span: d.name.span,
                    previous: *prev,
                });
                continue;
            }
            if Prim::from_name(&d.name.name).is_some()
                || d.name.name == "ptr"
                || super::types::vector_from_name(&d.name.name).is_some()
            {
                self.error(SemaError::Duplicate {
                    what: "type",
                    name: d.name.name.clone(),
                    span: d.name.span,
                    previous: d.name.span,
                });
                continue;
            }
            globals.insert(d.name.name.clone(), d.name.span);
            self.adts.adts.push(AdtDef {
                name: d.name.name.clone(),
                item: i,
                fields: Vec::new(),
                kind: AdtKind::Record,
            });
            decls.push(d);
        }
        for (k, d) in decls.into_iter().enumerate() {
            let shared = self.lower_fields(&d.fields, &[]);
            let kind = match &d.variants {
                None => AdtKind::Record,
                Some(vs) => {
                    let mut seen: FxHashMap<&str, Span> = FxHashMap::default();
                    let mut out = Vec::new();
                    for v in vs {
                        if let Some(prev) = seen.insert(&v.name.name, v.name.span) {
                            self.error(SemaError::Duplicate {
                                what: "variant",
                                name: v.name.name.clone(),
                                span: v.name.span,
                                previous: prev,
                            });
                        }
                        let fields = self.lower_fields(&v.fields, &d.fields);
                        out.push(VariantDef {
                            name: v.name.name.clone(),
                            fields,
                        });
                    }
                    AdtKind::Sum(out)
                }
            };
            self.adts.adts[k].fields = shared;
            self.adts.adts[k].kind = kind;
        }
    }

    /// Lowers the fields of a record, a sum's shared prefix, or a variant (`before`: the shared
    /// fields, visible as array lengths and not to be redeclared).
    fn lower_fields(&mut self, fields: &[FieldDecl], before: &[FieldDecl]) -> Vec<FieldDef> {
        let mut names: Vec<String> = before.iter().map(|f| f.name.name.clone()).collect();
        let mut spans: FxHashMap<String, Span> = before
            .iter()
            .map(|f| (f.name.name.clone(), f.name.span))
            .collect();
        let mut out = Vec::new();
        for f in fields {
            if let Some(prev) = spans.get(&f.name.name) {
                self.error(SemaError::Duplicate {
                    what: "field",
                    name: f.name.name.clone(),
                    span: f.name.span,
                    previous: *prev,
                });
            }
            let ty = self.lower_type(&f.ty, &LenScope::Names(&names));
            let len_field = match &f.ty.kind {
                TypeExprKind::Array {
                    len: ArrayLen::Name(x),
                    ..
                } => Some(x.name.clone()),
                _ => None,
            };
            out.push(FieldDef {
                name: f.name.name.clone(),
                ty,
                len_field,
                has_default: f.default.is_some(),
            });
            names.push(f.name.name.clone());
            spans.insert(f.name.name.clone(), f.name.span);
        }
        out
    }

    /// Types the default expressions of record and variant fields.
    pub(super) fn check_field_defaults(&mut self, program: &Program) {
        for a in 0..self.adts.adts.len() {
            let item = self.adts.adts[a].item;
            let Some(Item::Type(d)) = program.items.get(item) else {
                continue;
            };
            let mut groups: Vec<(&[FieldDecl], Vec<Ty>)> = vec![(
                &d.fields,
                self.adts.adts[a]
                    .fields
                    .iter()
                    .map(|f| f.ty.clone())
                    .collect(),
            )];
            if let Some(vs) = &d.variants {
                for (vi, v) in vs.iter().enumerate() {
                    let tys = self.adts.adts[a]
                        .variants()
                        .get(vi)
                        .map(|v| v.fields.iter().map(|f| f.ty.clone()).collect())
                        .unwrap_or_default();
                    groups.push((&v.fields, tys));
                }
            }
            for (fields, tys) in groups {
                for (f, t) in fields.iter().zip(tys) {
                    if let Some(def) = &f.default {
                        self.ctx = Ctx::Const;
                        self.scopes.clear();
                        let dt = self.infer_expr(def);
                        self.expect(&dt, &t, def.span, "the field's type");
                    }
                }
            }
        }
    }

    /// A record may not contain itself, directly or through other records: its values would be
    /// infinitely large. Sums may (that is what a tree is).
    pub(super) fn check_record_cycles(&mut self, program: &Program) {
        for a in 0..self.adts.adts.len() {
            if self.adts.adts[a].is_sum() {
                continue;
            }
            let me = AdtId(a as u32);
            let mut stack: Vec<AdtId> = vec![me];
            let mut seen: Vec<AdtId> = Vec::new();
            let mut cyclic = false;
            while let Some(r) = stack.pop() {
                let Some(def) = self.adts.get(r) else {
                    continue;
                };
                for f in &def.fields {
                    for inner in record_parts(&f.ty) {
                        if inner == me {
                            cyclic = true;
                        } else if !seen.contains(&inner)
                            && self.adts.get(inner).is_some_and(|d| !d.is_sum())
                        {
                            seen.push(inner);
                            stack.push(inner);
                        }
                    }
                }
            }
            if cyclic {
                let item = self.adts.adts[a].item;
                if let Some(Item::Type(d)) = program.items.get(item) {
                    self.error(SemaError::RecursiveRecord {
                        name: d.name.name.clone(),
                        span: d.name.span,
                    });
                }
            }
        }
    }

    /// Collects every function signature, building the overload sets.
    pub(super) fn collect_funcs(&mut self, program: &Program, globals: &FxHashMap<String, Span>) {
        for (i, item) in program.items.iter().enumerate() {
            let Item::Func(d) = item else { continue };
            if let Some(prev) = globals.get(&d.name.name) {
                self.error(SemaError::Duplicate {
                    what: "name",
                    name: d.name.name.clone(),
                    span: d.name.span,
                    previous: *prev,
                });
                continue;
            }
            let mut names: Vec<String> = Vec::new();
            let mut params = Vec::new();
            let mut seen: FxHashMap<&str, Span> = FxHashMap::default();
            for p in &d.params {
                if let Some(prev) = seen.insert(&p.name.name, p.name.span) {
                    self.error(SemaError::Duplicate {
                        what: "parameter",
                        name: p.name.name.clone(),
                        span: p.name.span,
                        previous: prev,
                    });
                }
                let ty = self.lower_type(&p.ty, &LenScope::Names(&names));
                names.push(p.name.name.clone());
                params.push(ParamInfo {
                    name: p.name.name.clone(),
                    ty,
                    mutable: p.mutable,
                    has_default: p.default.is_some(),
                });
            }
            let ret = match &d.ret {
                Some(t) => self.lower_type(t, &LenScope::Names(&names)),
                None => self.fresh(VarKind::General),
            };
            let set = self
                .overloads
                .entry(d.name.name.clone())
                .or_default()
                .clone();
            let mut dup = None;
            for f in &set {
                let other = &self.out.funcs[f.0 as usize];
                if other.params.len() == params.len()
                    && other
                        .params
                        .iter()
                        .zip(params.iter())
                        .all(|(a, b)| a.ty == b.ty)
                {
                    dup = Some(other.span);
                }
            }
            if let Some(prev) = dup {
                let tys: Vec<String> = params.iter().map(|p| self.show(&p.ty)).collect();
                self.error(SemaError::DuplicateOverload {
                    name: d.name.name.clone(),
                    params: format!("({})", tys.join(", ")),
                    span: d.name.span,
                    previous: prev,
                });
                continue;
            }
            let unique_name = if set.is_empty() {
                d.name.name.clone()
            } else {
                format!("{}.{}", d.name.name, set.len())
            };
            let order_by = d
                .order_by
                .as_ref()
                .and_then(|k| self.order_key(d, &params, k));
            let id = FuncId(self.out.funcs.len() as u32);
            self.out.funcs.push(FuncInfo {
                item: i,
                name: d.name.name.clone(),
                unique_name,
                params,
                ret,
                order_by,
                span: d.name.span,
            });
            self.overloads
                .entry(d.name.name.clone())
                .or_default()
                .push(id);
        }
    }

    /// The parameter `order by k` names: a parameter passed by value whose type is a number.
    fn order_key(
        &mut self,
        d: &crate::syntax::ast::FuncDecl,
        params: &[ParamInfo],
        k: &crate::syntax::ast::Ident,
    ) -> Option<u32> {
        let Some(i) = params.iter().position(|p| p.name == k.name) else {
            self.error(SemaError::OrderByNotParam {
                func: d.name.name.clone(),
                name: k.name.clone(),
                span: k.span,
            });
            return None;
        };
        let p = &params[i];
        let numeric = matches!(p.ty, Ty::Prim(q) if q.is_numeric() && q != Prim::F16);
        if p.mutable || !numeric {
            let ty = self.show(&p.ty);
            self.error(SemaError::OrderByType {
                name: k.name.clone(),
                ty: if p.mutable { format!("mut {ty}") } else { ty },
                span: k.span,
                param: d.params[i].span,
            });
            return None;
        }
        Some(i as u32)
    }

    /// Types the default expressions of function parameters.
    pub(super) fn check_param_defaults(&mut self, program: &Program) {
        for f in 0..self.out.funcs.len() {
            let item = self.out.funcs[f].item;
            let Some(Item::Func(d)) = program.items.get(item) else {
                continue;
            };
            for (p, info) in d.params.iter().zip(self.out.funcs[f].params.clone()) {
                if let Some(def) = &p.default {
                    self.ctx = Ctx::Const;
                    self.scopes.clear();
                    let t = self.infer_expr(def);
                    self.expect(&t, &info.ty, def.span, "the parameter's type");
                }
            }
        }
    }
}
