//! Specialization of the layout-agnostic `tree` level to one physical layout (paper §7.1-§7.2):
//! `tree` → `tree` + `mem`.
//!
//! Input: a module of `tree` traversals and, in the [`PassCx`] extension [`LayoutSpec`], the
//! layout model and buffer plan of the chosen layout (the driver builds it from `--layout NAME`).
//! Output: the same module with every function that takes the layout's tree type rewritten to
//! read the layout's buffers ([`destructor`]). These passes are the only code of the back half
//! that reads `layout/`: field paths come from `layout::resolve`, buffer indices and strides
//! from `layout::plan`. The interface (op names, the `%B` convention) is fixed by
//! `docs/design/specialization.md` §2.
//!
//! Layout expressions (group indices `by I`, split discriminants, derived fields such as
//! `right = I + c_o`, `from g[key]` keys) are held by the layout model as syntax; `reader.rs`
//! lowers the subset they use (names, integer literals, arithmetic, comparisons, casts, bit
//! slices, slices and elements of global arrays) inline, each name at most once per
//! destruction. This stands in for the per-layout accessor functions of the design note §1.

pub mod constructor;
pub mod counters;
pub mod destructor;
mod entries;
mod logical_nodes;
mod predicates;
mod reader;

use crate::layout::model::LayoutModel;
use crate::layout::plan::{BufferKind, BufferPlan};
use crate::syntax::ast::{TypeExpr, TypeExprKind};
use scion_ir::diag::{Diagnostic, Span};
use scion_ir::types::{FloatTy, IntTy, Type};
use scion_ir::{Module, PassCx, PassError, TypeId};

/// The layout the specialization passes target: its model and buffer plan. The driver puts one
/// into the [`PassCx`] (`cx.insert_ext(LayoutSpec::new(model))`).
#[derive(Clone, Debug)]
pub struct LayoutSpec {
    /// The physical model (`layout::model`).
    pub model: LayoutModel,
    /// Its buffers, in the order of the table `%B` points to.
    pub plan: BufferPlan,
}

impl LayoutSpec {
    /// The spec of `model`, with its buffer plan.
    pub fn new(model: LayoutModel) -> LayoutSpec {
        let plan = BufferPlan::of(&model);
        LayoutSpec { model, plan }
    }

    /// The name of the tree type's first variant: what the reader resolves global names in
    /// (empty when the type is unknown or has none).
    pub fn first_variant(&self) -> String {
        self.model
            .adt
            .as_ref()
            .and_then(|a| a.variants.first())
            .map(|v| v.name.name.clone())
            .unwrap_or_default()
    }

    /// The index in the buffer table of the buffer holding `kind`.
    pub fn buffer_index(&self, kind: &BufferKind) -> Option<usize> {
        self.plan.buffers.iter().position(|b| &b.kind == kind)
    }
}

/// The layout a module's `tree.layout` records are specialized to when the pass context has
/// no [`LayoutSpec`] (`scion-opt --layout NAME`; without it, the module's only layout).
#[derive(Clone, Debug)]
pub struct LayoutChoice(pub String);

/// The layout spec of the pass context; without one, the spec of the layout the module carries
/// (`LayoutChoice`'s, or the only one), which it then keeps. Errors say which layout is missing.
fn spec_of<'a>(m: &Module, cx: &'a mut PassCx, pass: &str) -> Result<&'a LayoutSpec, PassError> {
    if cx.ext::<LayoutSpec>().is_none() {
        let name = cx.ext::<LayoutChoice>().map(|c| c.0.clone());
        let model = crate::layout::carried::model_of(&m.layouts, name.as_deref()).map_err(|d| {
            let mut d = d;
            for x in &mut d.list {
                *x = x.clone().with_note(format!("needed by `{pass}`"));
            }
            PassError::Diagnostics(d)
        })?;
        cx.insert_ext(LayoutSpec::new(model));
    }
    Ok(cx.ext::<LayoutSpec>().expect("inserted above"))
}

/// A construct the specialization passes do not handle (E0380), with the span of the layout or
/// traversal code responsible.
fn unsupported(span: Option<Span>, what: impl Into<String>) -> Diagnostic {
    let d = Diagnostic::error("E0380", what.into()).with_note(
        "this layout or traversal uses a feature destructor specialization does not handle yet",
    );
    match span {
        Some(s) => d.with_primary(s, "here"),
        None => d,
    }
}

/// The IR type of a layout's physical type: primitives, vectors, fixed arrays and the records
/// declared in the module.
fn ir_type(m: &mut Module, t: &TypeExpr) -> Option<TypeId> {
    let ty = match &t.kind {
        TypeExprKind::Named(id) => match prim(&id.name) {
            Some(ty) => ty,
            None => {
                m.adt(&id.name)?;
                Type::Adt(id.name.clone())
            }
        },
        TypeExprKind::Vector { elem, lanes } => {
            let e = prim(&elem.name)?;
            let e = m.ty(e);
            Type::Vector {
                elem: e,
                lanes: *lanes,
            }
        }
        TypeExprKind::Array { elem, len } => {
            let e = ir_type(m, elem)?;
            match len {
                crate::syntax::ast::ArrayLen::Const(n, _) => Type::Array {
                    elem: e,
                    len: Some(*n),
                },
                _ => return None,
            }
        }
        _ => return None,
    };
    Some(m.ty(ty))
}

pub(super) fn prim(name: &str) -> Option<Type> {
    Some(match name {
        "bool" => Type::Bool,
        "i8" => Type::Int(IntTy::I8),
        "i16" => Type::Int(IntTy::I16),
        "i32" => Type::Int(IntTy::I32),
        "i64" => Type::Int(IntTy::I64),
        "u8" => Type::Int(IntTy::U8),
        "u16" => Type::Int(IntTy::U16),
        "u32" => Type::Int(IntTy::U32),
        "u64" => Type::Int(IntTy::U64),
        "f16" => Type::Float(FloatTy::F16),
        "f32" => Type::Float(FloatTy::F32),
        "f64" => Type::Float(FloatTy::F64),
        "ptr" => Type::Ptr,
        _ => return None,
    })
}
#[cfg(test)]
mod exec_tests;
#[cfg(test)]
mod tests;
