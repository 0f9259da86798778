//! Type inference for the traversal language: the checker's state, scopes and statements
//! (paper §3, Figure 3).
//!
//! Input: the AST of function bodies, with the declared types and function signatures that
//! `resolve` collected. Output: entries in the [`TypedProgram`] side tables (types of
//! expressions, bindings, resolutions) with inference variables that `mod.rs` zonks once every
//! deferred obligation (`ops`, `overload`) is solved. A function's body is a statement; its
//! tail (the last statement of a block, each arm of a match, each branch of an `if`) is its
//! value.

use super::errors::SemaError;
use super::ops::Obligation;
use super::typed::{
    BindingId, BindingInfo, BindingKind, FuncId, MemberId, ParamInfo, TypedProgram,
};
use super::types::{AdtTable, Prim, Ty};
use super::unify::{VarKind, VarState};
use crate::syntax::ast::{
    Expr, ExprKind, Ident, MatchArm, NodeId, PatternKind, Program, Stmt, StmtKind,
};
use rustc_hash::FxHashMap;
use scion_ir::diag::Span;

/// What a name in scope stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Binding {
    Local(BindingId),
    Param(u32),
    LayoutParam(u32),
    Member(MemberId),
    BuildField(u32),
}

/// The function whose body is being checked.
#[derive(Clone, Debug)]
pub(super) struct FnCx {
    pub params: Vec<ParamInfo>,
    pub ret: Ty,
}

/// What kind of code is being checked: decides which names, statements and expressions exist.
#[derive(Clone, Debug)]
pub(super) enum Ctx {
    /// Field and parameter defaults: constants only.
    Const,
    /// A function body.
    Func(FnCx),
    /// Member expressions of layout `layout` (index into `out.layouts`).
    Layout { layout: usize },
    /// A build entry of the layout `layout` for variant `variant` (`None`: `build root`).
    Build {
        layout: usize,
        variant: Option<u32>,
        fields: Vec<(String, Ty)>,
        ret: Ty,
    },
}

/// How a statement ends, for the implicit-result rule.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Tail {
    /// Every path returns.
    Diverges,
    /// It ends with a value of this type.
    Value(Ty),
    /// Some path may end without a value.
    NoValue,
}

/// The state of semantic analysis over one program.
pub(crate) struct Checker<'a> {
    pub program: &'a Program,
    pub adts: AdtTable,
    pub out: TypedProgram,
    pub vars: Vec<VarState>,
    pub errors: Vec<SemaError>,
    pub pending: Vec<Obligation>,
    /// Function ids by name (overload sets).
    pub overloads: FxHashMap<String, Vec<FuncId>>,
    /// Names in scope, innermost last.
    pub scopes: Vec<FxHashMap<String, Binding>>,
    pub ctx: Ctx,
    /// Integer literals: id, value and type, checked for range after inference.
    pub int_literals: Vec<(NodeId, u128, Span)>,
    /// Results of `append(x, n)`: integers that default to `u32` rather than `i32`.
    pub append_results: Vec<Ty>,
    /// Literals already reported as not fitting (by `build x = n`).
    pub literal_reported: Vec<NodeId>,
}

impl<'a> Checker<'a> {
    /// A checker over `program` with nothing collected yet.
    pub(super) fn new(program: &'a Program) -> Checker<'a> {
        Checker {
            program,
            adts: AdtTable::default(),
            out: TypedProgram::default(),
            vars: Vec::new(),
            errors: Vec::new(),
            pending: Vec::new(),
            overloads: FxHashMap::default(),
            scopes: Vec::new(),
            ctx: Ctx::Const,
            int_literals: Vec::new(),
            append_results: Vec::new(),
            literal_reported: Vec::new(),
        }
    }

    pub(super) fn error(&mut self, e: SemaError) {
        self.errors.push(e);
    }

    /// Unifies `found` with `expected`, reporting a mismatch at `span`.
    pub(super) fn expect(
        &mut self,
        found: &Ty,
        expected: &Ty,
        span: Span,
        context: &'static str,
    ) -> bool {
        match self.unify(found, expected) {
            Ok(()) => true,
            Err(super::unify::UnifyError::Occurs) => {
                self.error(SemaError::InfiniteType { span });
                false
            }
            Err(super::unify::UnifyError::Mismatch) => {
                let (expected, found) = (self.show(expected), self.show(found));
                self.error(SemaError::Mismatch {
                    expected,
                    found,
                    span,
                    context,
                });
                false
            }
        }
    }

    // ---- scopes -----------------------------------------------------------------------------

    pub(super) fn push_scope(&mut self) {
        self.scopes.push(FxHashMap::default());
    }

    pub(super) fn pop_scope(&mut self) {
        self.scopes.pop();
    }

    pub(super) fn define(&mut self, name: &str, b: Binding) {
        if let Some(s) = self.scopes.last_mut() {
            s.insert(name.to_string(), b);
        }
    }

    pub(super) fn lookup(&self, name: &str) -> Option<Binding> {
        self.scopes.iter().rev().find_map(|s| s.get(name).copied())
    }

    /// A new local binding, in scope from now on.
    pub(super) fn new_binding(&mut self, name: &Ident, ty: Ty, kind: BindingKind) -> BindingId {
        let id = BindingId(self.out.bindings.len() as u32);
        self.out.bindings.push(BindingInfo {
            name: name.name.clone(),
            ty,
            kind,
            mutable: false,
            span: name.span,
        });
        if name.name != "_" {
            self.define(&name.name, Binding::Local(id));
        }
        id
    }

    /// The type of a binding in scope.
    pub(super) fn binding_ty(&self, b: Binding) -> Ty {
        match b {
            Binding::Local(id) => self.out.bindings[id.0 as usize].ty.clone(),
            Binding::Param(i) => match &self.ctx {
                Ctx::Func(f) => f
                    .params
                    .get(i as usize)
                    .map(|p| p.ty.clone())
                    .unwrap_or(Ty::Error),
                _ => Ty::Error,
            },
            Binding::LayoutParam(i) => self
                .current_layout()
                .and_then(|l| l.params.get(i as usize))
                .map(|p| p.1.clone())
                .unwrap_or(Ty::Error),
            Binding::Member(m) => self
                .current_layout()
                .and_then(|l| l.members.get(m.0 as usize))
                .map(|m| m.ty.clone())
                .unwrap_or(Ty::Error),
            Binding::BuildField(i) => match &self.ctx {
                Ctx::Build { fields, .. } => fields
                    .get(i as usize)
                    .map(|f| f.1.clone())
                    .unwrap_or(Ty::Error),
                _ => Ty::Error,
            },
        }
    }

    pub(super) fn current_layout(&self) -> Option<&super::typed::LayoutInfo> {
        match &self.ctx {
            Ctx::Layout { layout } | Ctx::Build { layout, .. } => self.out.layouts.get(*layout),
            _ => None,
        }
    }

    pub(super) fn record(&mut self, id: NodeId, ty: &Ty) {
        self.out.expr_types.insert(id, ty.clone());
    }

    // ---- functions --------------------------------------------------------------------------

    /// Checks the body of function `f`.
    pub(super) fn check_func(&mut self, f: FuncId) {
        let info = self.out.funcs[f.0 as usize].clone();
        let crate::syntax::ast::Item::Func(decl) = &self.program.items[info.item] else {
            return;
        };
        let declared_ret = decl.ret.is_some();
        self.ctx = Ctx::Func(FnCx {
            params: info.params.clone(),
            ret: info.ret.clone(),
        });
        self.scopes.clear();
        self.push_scope();
        for (i, p) in decl.params.iter().enumerate() {
            self.define(&p.name.name, Binding::Param(i as u32));
        }
        let tail = self.check_stmt(&decl.body, true);
        match tail {
            Tail::Diverges => {}
            Tail::Value(t) => {
                self.expect(
                    &t,
                    &info.ret,
                    tail_span(&decl.body),
                    "the function's result type",
                );
            }
            Tail::NoValue => {
                // Without a declared result, falling off the end makes the result `()`.
                let r = self.shallow(&info.ret);
                let missing = if declared_ret {
                    !r.is_unit() && r != Ty::Error
                } else {
                    self.unify(&info.ret, &Ty::unit()).is_err()
                };
                if missing {
                    let ret = self.show(&info.ret);
                    self.error(SemaError::MissingValue {
                        func: info.name.clone(),
                        ret,
                        span: decl.body.span,
                    });
                }
            }
        }
        if let (Some(_), Some(k)) = (info.order_by, &decl.order_by) {
            let r = self.shallow(&info.ret);
            if !r.is_unit() && r != Ty::Error {
                let ret = self.show(&info.ret);
                self.error(SemaError::OrderByResult {
                    func: info.name.clone(),
                    ret,
                    span: k.span,
                });
            }
        }
        self.scopes.clear();
        self.ctx = Ctx::Const;
    }

    // ---- statements -------------------------------------------------------------------------

    /// Checks a statement. `tail`: the statement's value is the enclosing body's value.
    pub(super) fn check_stmt(&mut self, s: &Stmt, tail: bool) -> Tail {
        match &s.kind {
            StmtKind::Expr(e) => {
                let t = self.infer_expr(e);
                if tail {
                    Tail::Value(t)
                } else {
                    Tail::NoValue
                }
            }
            StmtKind::Assign { target, value } => {
                let t = self.check_assign_target(target);
                let v = self.infer_expr(value);
                self.expect(&v, &t, value.span, "the assignment's target");
                Tail::NoValue
            }
            StmtKind::Block(stmts) => {
                self.push_scope();
                let mut result = Tail::NoValue;
                let mut diverged = false;
                for (i, st) in stmts.iter().enumerate() {
                    let last = i + 1 == stmts.len();
                    let t = self.check_stmt(st, tail && last);
                    if t == Tail::Diverges {
                        diverged = true;
                    }
                    if last {
                        result = t;
                    }
                }
                self.pop_scope();
                if diverged {
                    Tail::Diverges
                } else {
                    result
                }
            }
            StmtKind::Return(e) => {
                self.check_return(e.as_ref(), s.span);
                Tail::Diverges
            }
            StmtKind::Let {
                name,
                ty,
                value,
                mutable,
            } => {
                let declared = ty.as_ref().map(|t| self.lower_type_local(t));
                let v = self.infer_expr(value);
                let t = match declared {
                    Some(d) => {
                        self.expect(&v, &d, value.span, "the `let`'s declared type");
                        d
                    }
                    None => v,
                };
                let b = self.new_binding(name, t, BindingKind::Let);
                self.out.bindings[b.0 as usize].mutable = *mutable;
                self.out.binders.insert(s.id, b);
                Tail::NoValue
            }
            StmtKind::If {
                branches,
                otherwise,
            } => {
                let tails = self.check_if_branches(branches, otherwise.as_deref(), tail);
                match otherwise {
                    Some(_) => self.join_tails(tails, tail),
                    None => Tail::NoValue,
                }
            }
            StmtKind::Foreach {
                var,
                index,
                iter,
                body,
            } => {
                let it = self.infer_expr(iter);
                let elem = self.fresh(VarKind::General);
                self.solve_or_defer(Obligation::Elem {
                    iter: it,
                    elem: elem.clone(),
                    span: iter.span,
                });
                self.push_scope();
                let b = self.new_binding(var, elem, BindingKind::Foreach);
                self.out.binders.insert(s.id, b);
                if let Some(k) = index {
                    let kb = self.new_binding(k, Ty::Prim(Prim::U32), BindingKind::Foreach);
                    self.out.foreach_index.insert(s.id, kb);
                }
                self.check_stmt(body, false);
                self.pop_scope();
                Tail::NoValue
            }
            StmtKind::Match { scrutinee, arms } => self.check_match(scrutinee, arms, tail),
            StmtKind::Build { field, value } => {
                self.check_build_stmt(s, field, value.as_ref());
                Tail::NoValue
            }
        }
    }

    /// `if c { s } elif c { s } else { s }` as an expression: each branch's tail is a value of
    /// one type (or leaves the function); a branch without one is E0240.
    pub(super) fn infer_if(&mut self, branches: &[(Expr, Stmt)], otherwise: &Stmt) -> Ty {
        let tails = self.check_if_branches(branches, Some(otherwise), true);
        if let Some((_, span)) = tails.iter().find(|t| t.0 == Tail::NoValue) {
            self.error(SemaError::IfWithoutValue { span: *span });
            return Ty::Error;
        }
        match self.join_tails(tails, true) {
            Tail::Value(t) => t,
            // Every branch leaves the function: the value is never made; its type is whatever
            // the context asks for.
            _ => self.fresh(VarKind::General),
        }
    }

    /// Checks the conditions (booleans) and the branches of an `if`, each branch in its own
    /// scope; returns each branch's tail with its span, the `else` last.
    fn check_if_branches(
        &mut self,
        branches: &[(Expr, Stmt)],
        otherwise: Option<&Stmt>,
        tail: bool,
    ) -> Vec<(Tail, Span)> {
        let mut tails = Vec::new();
        for (cond, body) in branches {
            let c = self.infer_expr(cond);
            self.expect(&c, &Ty::bool(), cond.span, "an `if` condition");
            self.push_scope();
            tails.push((self.check_stmt(body, tail), tail_span(body)));
            self.pop_scope();
        }
        if let Some(o) = otherwise {
            self.push_scope();
            tails.push((self.check_stmt(o, tail), tail_span(o)));
            self.pop_scope();
        }
        tails
    }

    fn join_tails(&mut self, tails: Vec<(Tail, Span)>, tail: bool) -> Tail {
        if tails.iter().all(|t| t.0 == Tail::Diverges) {
            return Tail::Diverges;
        }
        if !tail || tails.iter().any(|t| t.0 == Tail::NoValue) {
            return Tail::NoValue;
        }
        let mut result: Option<Ty> = None;
        for (t, span) in tails {
            if let Tail::Value(ty) = t {
                match &result {
                    None => result = Some(ty),
                    Some(r) => {
                        let r = r.clone();
                        self.expect(&ty, &r, span, "the other branches' values");
                    }
                }
            }
        }
        result.map(Tail::Value).unwrap_or(Tail::Diverges)
    }

    fn check_return(&mut self, e: Option<&Expr>, span: Span) {
        let ret = match &self.ctx {
            Ctx::Func(f) => f.ret.clone(),
            Ctx::Build { ret, .. } => ret.clone(),
            _ => {
                self.error(SemaError::WrongContext {
                    what: "`return`",
                    span,
                    allowed: "in function bodies and builds",
                });
                if let Some(e) = e {
                    self.infer_expr(e);
                }
                return;
            }
        };
        let in_build = matches!(self.ctx, Ctx::Build { .. });
        match e {
            Some(e) => {
                let t = self.infer_expr(e);
                if in_build {
                    if self.unify(&t, &ret).is_err() {
                        let (expected, found) = (self.show(&ret), self.show(&t));
                        self.error(SemaError::BuildReturnType {
                            expected,
                            found,
                            span: e.span,
                        });
                    }
                } else {
                    self.expect(&t, &ret, e.span, "the function's result type");
                }
            }
            None => {
                if self.unify(&ret, &Ty::unit()).is_err() {
                    self.error(SemaError::ReturnValueInUnit { span });
                }
            }
        }
    }

    /// The type of an assignment target, checking that it is assignable.
    fn check_assign_target(&mut self, target: &Expr) -> Ty {
        if !self.is_assignable(target) {
            match root_name(target) {
                Some(name) if !matches!(target.kind, ExprKind::Slice { .. }) => {
                    self.error(SemaError::AssignImmutable {
                        name: name.name.clone(),
                        span: target.span,
                    })
                }
                _ => self.error(SemaError::BadAssignTarget { span: target.span }),
            }
        }
        let ty = self.infer_expr(target);
        if let ExprKind::Field { base, name } = &target.kind {
            let base_ty = self.out.expr_types.get(&base.id).cloned();
            if let Some(Ty::Adt(a)) = base_ty.map(|t| self.shallow(&t)) {
                if self.adts.get(a).is_some_and(|d| d.is_sum()) {
                    let shown = self.show(&Ty::Adt(a));
                    self.error(SemaError::SumFieldAssign {
                        field: name.name.clone(),
                        ty: shown,
                        span: target.span,
                    });
                }
            }
        }
        ty
    }

    fn is_assignable(&self, e: &Expr) -> bool {
        match &e.kind {
            ExprKind::Name(n) => match (self.lookup(&n.name), &self.ctx) {
                (Some(Binding::Param(i)), Ctx::Func(f)) => {
                    f.params.get(i as usize).is_some_and(|p| p.mutable)
                }
                (Some(Binding::Local(b)), _) => self.out.bindings[b.0 as usize].mutable,
                _ => false,
            },
            ExprKind::Field { base, .. } | ExprKind::Index { base, .. } => self.is_assignable(base),
            ExprKind::Slice { base, .. } => {
                matches!(base.kind, ExprKind::This) && matches!(self.ctx, Ctx::Build { .. })
            }
            _ => false,
        }
    }

    // ---- match ------------------------------------------------------------------------------

    fn check_match(&mut self, scrutinee: &Expr, arms: &[MatchArm], tail: bool) -> Tail {
        let st = self.infer_expr(scrutinee);
        let mut adt = match self.shallow(&st) {
            Ty::Adt(a) => Some(a),
            _ => None,
        };
        if adt.is_none() && self.is_unknown(&st) {
            // Infer the scrutinee's type from the first variant pattern whose name is unique.
            for arm in arms {
                if let PatternKind::Variant { name, .. } = &arm.pattern.kind {
                    let cands = self.adts.variants_named(&name.name);
                    if cands.len() == 1 {
                        adt = Some(cands[0].0);
                        self.unify(&st, &Ty::Adt(cands[0].0)).ok();
                        break;
                    }
                }
            }
        }
        let is_sum = adt
            .and_then(|a| self.adts.get(a))
            .is_some_and(|d| d.is_sum());
        let has_variant_pattern = arms
            .iter()
            .any(|a| matches!(a.pattern.kind, PatternKind::Variant { .. }));
        if !is_sum && has_variant_pattern && self.shallow(&st) != Ty::Error {
            let ty = self.show(&st);
            self.error(SemaError::NotASum {
                ty,
                span: scrutinee.span,
            });
        }
        let nvariants = adt
            .and_then(|a| self.adts.get(a))
            .map(|d| d.variants().len())
            .unwrap_or(0);
        let mut covered = vec![false; nvariants];
        let mut catch_all = false;
        let mut tails = Vec::new();
        for arm in arms {
            self.push_scope();
            let pat = &arm.pattern;
            let reachable = !catch_all;
            let mut new_cover = false;
            match &pat.kind {
                PatternKind::Wildcard => {
                    new_cover = covered.iter().any(|c| !*c) || nvariants == 0;
                    catch_all = true;
                }
                PatternKind::Bind { name, ty } => {
                    if let Some(t) = ty {
                        let d = self.lower_type_local(t);
                        self.expect(&st, &d, pat.span, "the pattern's type annotation");
                    }
                    let b =
                        self.new_binding(name, st.clone(), BindingKind::Pattern { field: None });
                    self.out.binders.insert(pat.id, b);
                    new_cover = covered.iter().any(|c| !*c) || nvariants == 0;
                    catch_all = true;
                }
                PatternKind::Variant { name, fields } => {
                    if let (Some(a), true) = (adt, is_sum) {
                        if let Some(v) =
                            self.check_variant_pattern(a, pat.id, name, fields, pat.span)
                        {
                            new_cover = !covered[v];
                            covered[v] = true;
                        }
                    }
                }
            }
            if (!reachable || !new_cover) && is_sum {
                self.error(SemaError::UnreachableArm {
                    span: arm.pattern.span,
                });
            }
            tails.push((self.check_stmt(&arm.body, tail), tail_span(&arm.body)));
            self.pop_scope();
        }
        if is_sum && !catch_all {
            let missing: Vec<String> = covered
                .iter()
                .enumerate()
                .filter(|(_, c)| !**c)
                .filter_map(|(i, _)| {
                    adt.and_then(|a| self.adts.get(a))
                        .map(|d| d.variants()[i].name.clone())
                })
                .collect();
            if !missing.is_empty() {
                self.error(SemaError::NonExhaustive {
                    missing,
                    span: scrutinee.span,
                });
            }
        }
        if tails.is_empty() {
            return Tail::NoValue;
        }
        self.join_tails(tails, tail)
    }

    /// Checks `Variant(p, ...)` against sum type `adt`; returns the variant index.
    fn check_variant_pattern(
        &mut self,
        adt: super::types::AdtId,
        id: NodeId,
        name: &Ident,
        fields: &[crate::syntax::ast::Pattern],
        span: Span,
    ) -> Option<usize> {
        let def = self.adts.get(adt)?.clone();
        let Some(v) = def.variant_index(&name.name) else {
            self.error(SemaError::UnknownVariant {
                name: name.name.clone(),
                ty: def.name.clone(),
                span: name.span,
            });
            return None;
        };
        self.out.pattern_variants.insert(id, (adt, v as u32));
        let all = def.variant_fields(v);
        // A bare `Variant` (no sub-patterns) matches without binding.
        if !fields.is_empty() && fields.len() != all.len() {
            let names: Vec<String> = all.iter().map(|f| f.name.clone()).collect();
            self.error(SemaError::PatternArity {
                variant: name.name.clone(),
                expected: all.len(),
                found: fields.len(),
                fields: names.join(", "),
                span,
            });
        }
        let mut bound: FxHashMap<&str, Span> = FxHashMap::default();
        for (i, (p, f)) in fields.iter().zip(all.iter()).enumerate() {
            match &p.kind {
                PatternKind::Wildcard => {}
                PatternKind::Bind { name, ty } => {
                    if let Some(prev) = bound.insert(&name.name, name.span) {
                        self.error(SemaError::Duplicate {
                            what: "pattern binding",
                            name: name.name.clone(),
                            span: name.span,
                            previous: prev,
                        });
                    }
                    if let Some(t) = ty {
                        let d = self.lower_type_local(t);
                        self.expect(&f.ty, &d, p.span, "the pattern's type annotation");
                    }
                    let b = self.new_binding(
                        name,
                        f.ty.clone(),
                        BindingKind::Pattern {
                            field: Some(i as u32),
                        },
                    );
                    self.out.binders.insert(p.id, b);
                }
                PatternKind::Variant { name, .. } => {
                    self.error(SemaError::WrongContext {
                        what: "a nested variant pattern",
                        span: name.span,
                        allowed: "at the top of a match arm",
                    });
                }
            }
        }
        Some(v)
    }
}

/// The span of a statement's value (its last statement, recursively).
pub(super) fn tail_span(s: &Stmt) -> Span {
    match &s.kind {
        StmtKind::Block(v) => v.last().map(tail_span).unwrap_or(s.span),
        _ => s.span,
    }
}

/// The variable at the root of a place expression.
fn root_name(e: &Expr) -> Option<&Ident> {
    match &e.kind {
        ExprKind::Name(n) => Some(n),
        ExprKind::Field { base, .. }
        | ExprKind::Index { base, .. }
        | ExprKind::Slice { base, .. } => root_name(base),
        _ => None,
    }
}
