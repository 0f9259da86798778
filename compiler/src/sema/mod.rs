//! Semantic analysis: name resolution and Hindley-Milner type inference for the traversal
//! language, with overloads, and the typing of layouts and builds (paper §3-§5).
//!
//! Input: the [`Program`] the parser produced. Output: a [`TypedProgram`] (declared types,
//! functions with unique names, side tables of types and resolutions keyed by `NodeId`, typed
//! layouts and builds) and the [`Diagnostics`] found (codes `E02xx`, `E0350`-`E0369`,
//! `E0450`-`E0499`). The order: declared types, then every function signature (so bodies may
//! call functions declared later, recursively or mutually), field and parameter defaults,
//! function bodies, layouts, builds; then deferred obligations (operators, fields, overloaded
//! calls) are solved to a fixpoint, literals default to `i32`/`f32`, the fixpoint runs again,
//! and every type is made final. Structural well-formedness of layouts and builds (`§6`) is
//! `check_layout` and `check_build`'s job.

mod build_types;
mod builtins;
mod dump;
pub mod errors;
mod expr;
mod infer;
mod layout_types;
mod ops;
mod overload;
mod resolve;
pub mod typed;
pub mod types;
mod unify;

#[cfg(test)]
mod tests;

pub use dump::dump_types;
pub use layout_types::named_members;
pub use typed::{
    ArmInfo, BindingId, BindingInfo, BindingKind, BuildInfo, BuildTarget, BuildVariantInfo,
    Builtin, FuncId, FuncInfo, LayoutId, LayoutInfo, MemberId, MemberInfo, MemberKindInfo,
    ParamInfo, Resolution, TypedProgram,
};
pub use types::{AdtDef, AdtId, AdtKind, AdtTable, FieldDef, Prim, Ty, VariantDef};

use crate::syntax::ast::{Item, Program};
use errors::SemaError;
use infer::Checker;
use rustc_hash::FxHashMap;
use scion_ir::diag::{Diagnostics, Span};

/// Resolves names and infers the types of every function, layout and build of `program`.
pub fn check_program(program: &Program) -> (TypedProgram, Diagnostics) {
    let mut cx = Checker::new(program);
    let mut globals: FxHashMap<String, Span> = FxHashMap::default();
    cx.collect_adts(program, &mut globals);
    cx.check_record_cycles(program);
    cx.collect_funcs(program, &globals);
    cx.check_field_defaults(program);
    cx.check_param_defaults(program);
    for f in 0..cx.out.funcs.len() {
        cx.check_func(FuncId(f as u32));
    }
    // A second layout or build of one name is `check_layout`'s E0302 / `check_build`'s E0414;
    // only the first is typed.
    let mut layouts: FxHashMap<String, Span> = FxHashMap::default();
    for (i, l) in layout_types::layout_items(program) {
        if layouts.insert(l.name.name.clone(), l.name.span).is_some() {
            continue;
        }
        cx.check_layout(i, l);
    }
    let mut builds: FxHashMap<String, Span> = FxHashMap::default();
    for (i, item) in program.items.iter().enumerate() {
        if let Item::Build(b) = item {
            if builds.insert(b.name.name.clone(), b.name.span).is_some() {
                continue;
            }
            cx.check_build(i, b);
        }
    }
    cx.solve_all();
    cx.check_literals();
    cx.check_physical_types();
    cx.finish()
}

impl Checker<'_> {
    /// Solves deferred obligations: to a fixpoint, then with literals defaulted, then forcing.
    fn solve_all(&mut self) {
        self.run_pending(false);
        for t in std::mem::take(&mut self.append_results) {
            if self.is_unknown(&t) {
                self.unify(&t, &Ty::Prim(Prim::U32)).ok();
            }
        }
        self.default_literals();
        self.run_pending(false);
        self.run_pending(true);
        self.default_literals();
        self.run_pending(true);
        self.fail_pending();
    }

    /// Integer literals must fit their inferred type.
    fn check_literals(&mut self) {
        for (id, v, span) in std::mem::take(&mut self.int_literals) {
            if self.literal_reported.contains(&id) {
                continue;
            }
            let t = self.zonk(self.out.expr_ty(id));
            if let Some(max) = t.as_int().and_then(|p| p.int_literal_max()) {
                if v > max {
                    let ty = self.show(&t);
                    self.error(SemaError::LiteralRange { value: v, ty, span });
                }
            }
        }
    }

    /// The final type: bound variables replaced, unbound ones become [`Ty::Error`].
    fn finalize(&self, t: &Ty) -> Ty {
        match self.zonk(t) {
            t if !t.has_vars() => t,
            t => erase_vars(&t),
        }
    }

    /// Zonks every table and turns errors into diagnostics.
    fn finish(mut self) -> (TypedProgram, Diagnostics) {
        let mut unsolved = false;
        let ids: Vec<_> = self.out.expr_types.keys().copied().collect();
        for id in ids {
            let t = self.zonk(&self.out.expr_types[&id]);
            unsolved |= t.has_vars();
            let t = self.finalize(&t);
            self.out.expr_types.insert(id, t);
        }
        let quiet = self.errors.iter().any(|e| e.to_diagnostic().is_error());
        for i in 0..self.out.funcs.len() {
            if self.zonk(&self.out.funcs[i].ret).has_vars() && !quiet {
                let span = self.out.funcs[i].span;
                self.error(SemaError::CannotInfer {
                    what: "function's result",
                    span,
                });
                unsolved = false;
            }
            let ret = self.finalize(&self.out.funcs[i].ret);
            self.out.funcs[i].ret = ret;
        }
        for i in 0..self.out.bindings.len() {
            if self.zonk(&self.out.bindings[i].ty).has_vars() && !quiet {
                let span = self.out.bindings[i].span;
                self.error(SemaError::CannotInfer {
                    what: "binding",
                    span,
                });
                unsolved = false;
            }
            let t = self.finalize(&self.out.bindings[i].ty);
            self.out.bindings[i].ty = t;
        }
        for l in 0..self.out.layouts.len() {
            for m in 0..self.out.layouts[l].members.len() {
                let t = self.finalize(&self.out.layouts[l].members[m].ty);
                self.out.layouts[l].members[m].ty = t;
            }
        }
        let ids: Vec<_> = self.out.widenings.keys().copied().collect();
        for id in ids {
            let t = self.finalize(&self.out.widenings[&id]);
            self.out.widenings.insert(id, t);
        }
        if unsolved && !self.errors.iter().any(|e| e.to_diagnostic().is_error()) {
            let span = self
                .program
                .items
                .first()
                .map(|i| i.span())
                .unwrap_or_default();
            self.error(SemaError::CannotInfer {
                what: "program",
                span,
            });
        }
        self.out.adts = self.adts.clone();
        let mut diags = Diagnostics::new();
        for e in &self.errors {
            diags.push(e.to_diagnostic());
        }
        (self.out, diags)
    }
}

fn erase_vars(t: &Ty) -> Ty {
    match t {
        Ty::Var(_) => Ty::Error,
        Ty::Tuple(ts) => Ty::Tuple(ts.iter().map(erase_vars).collect()),
        Ty::Array(e, n) => Ty::Array(Box::new(erase_vars(e)), *n),
        Ty::Slice(e) => Ty::Slice(Box::new(erase_vars(e))),
        Ty::Set(e) => Ty::Set(Box::new(erase_vars(e))),
        Ty::Option(e) => Ty::Option(Box::new(erase_vars(e))),
        t => t.clone(),
    }
}
