//! IR generation: the typed AST of the traversal language → the `tree` dialect.
//!
//! Input: a [`Program`] that parsed cleanly and the [`TypedProgram`] that `sema` produced for it
//! with no errors. Output: a [`Module`] holding every declared ADT (records and sums, in the
//! module's type table) and one `tree.func` per function (overloads under their unique names).
//! This module is the only one that sees both the typed AST and the IR (architecture invariant
//! 2). Layout declarations are read by the specialization passes; each `build` becomes one
//! function per variant (and one for `build root`), see `irgen/builds.rs`.
//!
//! Lowering rules (docs/ir.md has the op reference):
//! * `mut` parameters are `!tree.ref<T>` arguments; reading one is `tree.load`, assigning is
//!   `tree.store` (a component assignment loads, inserts and stores).
//! * `&&` and `||` short-circuit: they become `tree.if` with an `i1` result.
//! * Statements after a `return` in the same block are unreachable and not emitted.
//! * A function with a result lowers its body in *value mode*: the tail expression of a block,
//!   of each `if` branch and of each `match` arm is yielded as the op's result and returned once
//!   at the end; branches that end in `return` leave the function themselves.

mod builds;
mod exprs;
mod stmts;
mod types;

use crate::sema::{FuncId, TypedProgram};
use crate::syntax::ast::{Item, Program};
use rustc_hash::FxHashMap;
use scion_ir::diag::InternalError;
use scion_ir::entity::{TypeId, ValueId};
use scion_ir::{Builder, Module};

/// Lowers every function of `program` to the `tree` dialect.
///
/// `sema` must have accepted the program: a construct it should have rejected, or a type it left
/// unresolved, is reported as an [`InternalError`].
pub fn generate(program: &Program, typed: &TypedProgram) -> Result<Module, InternalError> {
    let mut m = Module::new();
    let mut tys = types::TypeMap::default();
    types::declare_adts(&mut m, &mut tys, typed)?;
    // Declare every function first so calls (also recursive and mutually recursive ones) see
    // their callee's signature.
    let mut entries = Vec::new();
    for (i, f) in typed.funcs.iter().enumerate() {
        let mut params = Vec::with_capacity(f.params.len());
        for p in &f.params {
            let t = tys.lower(&mut m, typed, &p.ty)?;
            params.push(if p.mutable {
                m.ty(scion_ir::types::Type::Ref(t))
            } else {
                t
            });
        }
        let results = tys.lower_results(&mut m, typed, &f.ret)?;
        let (fid, entry) = m.add_func(&f.unique_name, &params, &results);
        m.func_spans.insert(fid, f.span);
        if let Some(k) = f.order_by {
            m.funcs[fid].set_order_by(k as usize);
        }
        entries.push((FuncId(i as u32), entry, results));
    }
    for (fid, entry, results) in entries {
        let info = typed.func(fid);
        let Some(Item::Func(decl)) = program.items.get(info.item) else {
            return Err(InternalError::new(format!(
                "function `{}` has no declaration in the AST",
                info.name
            )));
        };
        let args: Vec<ValueId> = m.blocks[entry].args.to_vec();
        let mut b = Builder::at_end(&mut m, entry);
        let mut cx = FuncCx {
            program,
            typed,
            tys: &mut tys,
            func: fid,
            params: args,
            locals: FxHashMap::default(),
            build: None,
        };
        cx.lower_body(&mut b, &decl.body, &results)?;
    }
    builds::generate_builds(&mut m, &mut tys, program, typed)?;
    Ok(m)
}

/// State while lowering one function.
struct FuncCx<'a> {
    program: &'a Program,
    typed: &'a TypedProgram,
    tys: &'a mut types::TypeMap,
    func: FuncId,
    /// The function's block arguments, by parameter index.
    params: Vec<ValueId>,
    /// Values of `let`, `foreach` and pattern bindings.
    /// The value of each local binding in scope; for a `let mut` local, its cell
    /// (`!tree.ref<T>` from `tree.var`), read with `tree.load` and assigned with `tree.store`.
    locals: FxHashMap<crate::sema::BindingId, ValueId>,
    /// Set while lowering a build function (then `func` is not a function of `typed`).
    build: Option<builds::BuildCx>,
}

impl FuncCx<'_> {
    fn ty(&mut self, b: &mut Builder<'_>, t: &crate::sema::Ty) -> Result<TypeId, InternalError> {
        self.tys.lower(b.m, self.typed, t)
    }

    fn bug(&self, what: impl Into<String>) -> InternalError {
        if let Some(bc) = &self.build {
            return InternalError::new(format!("irgen, in `{}`: {}", bc.name, what.into()));
        }
        InternalError::new(format!(
            "irgen, in function `{}`: {}",
            self.typed.func(self.func).name,
            what.into()
        ))
    }
}
