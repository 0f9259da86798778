//! Exported entry points and the C header (docs/design/backends.md §1–§2).
//!
//! `scionc --layout L --entry A` asks for the C ABI of algorithm `A` specialized to layout `L`.
//! [`signature`] reads `A`'s signature from the `tree` module (before specialization) and
//! classifies its parameters: the one parameter of the layout's tree type (the root reference),
//! the `mut` parameters (the result record) and the others (the query record). After the
//! module is lowered to `lo`, [`entries::add`] adds the exported functions `@scion_L_sizes`,
//! `@scion_L_build`, `@scion_L_root`, `@scion_A_L` (and for GPU targets the kernels) and
//! [`header::render`] writes the matching C header.
//!
//! Errors are driver diagnostics E0910–E0916 (see docs/c-abi.md).

pub mod entries;
pub mod header;
pub mod logical_c;
pub mod record;

use crate::layout::logical::LogicalAbi;
use crate::passes::tree_to_mem::LayoutSpec;
use crate::syntax::ast::{Item, Program};
use record::Record;
use scion_ir::diag::Diagnostic;
use scion_ir::types::Type;
use scion_ir::Module;
use std::ops::Range;

/// What a parameter of the algorithm becomes at the C boundary.
#[derive(Clone, Debug, PartialEq)]
pub enum Role {
    /// The tree: the entry's `%root` argument.
    Tree,
    /// Read from the query record: these fields of [`EntrySig::query`].
    Query(Range<usize>),
    /// A `mut` cell inside the result record, at this byte offset.
    Result(u64),
}

/// One buffer of the layout's plan, as the header describes it.
#[derive(Clone, Debug, PartialEq)]
pub struct BufferInfo {
    /// Its name in the plan.
    pub name: String,
    /// Bytes of data per element.
    pub elem_size: u64,
    /// Distance between elements.
    pub stride: u64,
    /// Alignment of the base.
    pub align: u64,
}

/// The C-level signature of `--entry A` for `--layout L`.
#[derive(Clone, Debug, PartialEq)]
pub struct EntrySig {
    /// `A`, the algorithm's source name.
    pub algorithm: String,
    /// `L`, the layout's source name.
    pub layout: String,
    /// One role per source parameter, in order.
    pub roles: Vec<Role>,
    /// The query record.
    pub query: Record,
    /// The result record (in/out).
    pub result: Record,
    /// The layout's buffers, in the order of the `%B` table.
    pub buffers: Vec<BufferInfo>,
    /// The logical tree `scion_L_build` reads: the runtime's schema of the tree type.
    pub logical: scion_runtime::bvh::schema::Schema,
    /// Its C declarations (the node struct and the schema constant).
    pub logical_c: String,
}

impl EntrySig {
    /// `scion_L_sizes` and friends: `scion_{L}_{what}`.
    pub fn layout_fn(&self, what: &str) -> String {
        format!("scion_{}_{what}", self.layout)
    }

    /// `scion_A_L`, the batch entry.
    pub fn batch_fn(&self) -> String {
        format!("scion_{}_{}", self.algorithm, self.layout)
    }

    /// How many trees the entry traverses (its parameters of the tree type): the batch entry
    /// takes a buffer table and a root for each.
    pub fn trees(&self) -> usize {
        self.roles.iter().filter(|r| **r == Role::Tree).count()
    }

    /// The largest buffer alignment of the plan (at least 1).
    pub fn buffer_align(&self) -> u64 {
        self.buffers
            .iter()
            .map(|b| b.align)
            .max()
            .unwrap_or(1)
            .max(1)
    }
}

/// Whether the entries are for the host (an object or JIT) or a GPU (PTX kernels too).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum EntryTarget {
    /// x86-64, AArch64, the Cranelift JIT.
    #[default]
    Host,
    /// `nvptx64`: also the kernels of backends.md §1.
    Gpu,
}

fn is_c_ident(s: &str) -> bool {
    let mut cs = s.chars();
    cs.next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && cs.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Reads and checks the signature of `algorithm` in the `tree` module `m` (fresh from irgen)
/// against the layout `spec`, whose logical tree (`layout::logical`, derived by the caller
/// from its tree type) the header declares.
pub fn signature(
    program: &Program,
    m: &Module,
    algorithm: &str,
    spec: &LayoutSpec,
    logical: Option<&Result<LogicalAbi, String>>,
) -> Result<EntrySig, Diagnostic> {
    let layout = spec.model.name.name.clone();
    let decls: Vec<_> = program
        .items
        .iter()
        .filter_map(|it| match it {
            Item::Func(d) if d.name.name == algorithm => Some(d),
            _ => None,
        })
        .collect();
    let adt = spec.model.adt.as_ref().map(|a| a.name.clone());
    let tree_ty = adt
        .as_ref()
        .and_then(|a| m.types.lookup(&Type::Adt(a.clone())));
    let traversals = || -> String {
        let names: Vec<String> = m
            .func_order
            .iter()
            .filter(|&&f| {
                tree_ty.is_some_and(|t| m.funcs[f].params.contains(&t))
                    && program
                        .items
                        .iter()
                        .any(|it| matches!(it, Item::Func(d) if d.name.name == m.funcs[f].name))
            })
            .map(|&f| format!("`{}`", m.funcs[f].name))
            .collect();
        if names.is_empty() {
            "no function of the inputs takes the layout's tree".to_string()
        } else {
            format!("functions taking the layout's tree: {}", names.join(", "))
        }
    };
    let decl = match decls.as_slice() {
        [] => {
            return Err(Diagnostic::error(
                "E0911",
                format!("`--entry {algorithm}`: no function of that name"),
            )
            .with_note(traversals()))
        }
        [d] => *d,
        [first, ..] => {
            return Err(Diagnostic::error(
                "E0912",
                format!("`--entry {algorithm}`: the function is overloaded"),
            )
            .with_primary(first.name.span, "first of several declarations")
            .with_note("an entry point needs exactly one signature; rename the others"))
        }
    };
    let span = decl.name.span;
    if !is_c_ident(algorithm) || !is_c_ident(&layout) {
        return Err(Diagnostic::error(
            "E0913",
            format!("`scion_{algorithm}_{layout}` is not a C identifier"),
        )
        .with_primary(span, "entry named here"));
    }
    let f = m.func_by_name(algorithm).ok_or_else(|| {
        Diagnostic::error(
            "E0911",
            format!("`--entry {algorithm}`: the function has no generated code"),
        )
        .with_primary(span, "declared here")
        .with_note("generic functions cannot be entry points")
    })?;
    let Some(adt) = adt else {
        return Err(Diagnostic::error(
            "E0912",
            format!("`--layout {layout}` realizes no tree type, so it has no entry points"),
        ));
    };
    let func = &m.funcs[f];
    if func.params.len() != decl.params.len() {
        return Err(Diagnostic::error(
            "E0912",
            format!("`--entry {algorithm}`: the function has default or implicit parameters"),
        )
        .with_primary(span, "declared here"));
    }
    let trees: Vec<usize> = (0..func.params.len())
        .filter(|&i| Some(func.params[i]) == tree_ty)
        .collect();
    if trees.is_empty() {
        return Err(Diagnostic::error(
            "E0912",
            format!(
                "`--entry {algorithm}`: the function takes no parameter of the layout's tree \
                 type `{adt}`"
            ),
        )
        .with_primary(span, "declared here")
        .with_note(
            "an entry point traverses trees of the layout: at least one parameter of the tree \
             type (collision takes two)",
        )
        .with_note(traversals()));
    }
    let returns_value = func
        .results
        .iter()
        .any(|&r| !matches!(m.types.get(r), Type::Tuple(es) if es.is_empty()));
    if returns_value {
        return Err(Diagnostic::error(
            "E0913",
            format!("`--entry {algorithm}`: the function returns a value"),
        )
        .with_primary(span, "declared here")
        .with_note("entry points return results through `mut` parameters (the result record)"));
    }
    let mut query = Record::new();
    let mut result = Record::new();
    let mut roles = Vec::new();
    for (i, (&ty, p)) in func.params.iter().zip(&decl.params).enumerate() {
        if trees.contains(&i) {
            roles.push(Role::Tree);
            continue;
        }
        let bad = |why: String| {
            Diagnostic::error(
                "E0913",
                format!(
                    "`--entry {algorithm}`: parameter `{}` cannot cross the C boundary",
                    p.name.name
                ),
            )
            .with_primary(p.span, why)
        };
        match m.types.get(ty) {
            Type::Ref(inner) => {
                let (off, _) = result.push(m, &p.name.name, *inner).map_err(bad)?;
                roles.push(Role::Result(off));
            }
            _ if p.mutable => return Err(bad("a `mut` parameter of this type".into())),
            _ => {
                let (_, fields) = query.push(m, &p.name.name, ty).map_err(bad)?;
                roles.push(Role::Query(fields));
            }
        }
    }
    let buffers = spec
        .plan
        .buffers
        .iter()
        .map(|b| BufferInfo {
            name: b.name.clone(),
            elem_size: b.elem_size,
            stride: b.stride,
            align: b.align,
        })
        .collect();
    let logical = match logical {
        Some(Ok(l)) => l,
        Some(Err(e)) => {
            return Err(Diagnostic::error(
                "E0380",
                format!("layout `{layout}` cannot be packed: {e}"),
            )
            .with_primary(spec.model.span, "layout declared here")
            .with_note("constructor specialization reads the logical tree the runtime builds"))
        }
        None => {
            return Err(Diagnostic::error(
                "E0912",
                format!("`--layout {layout}` has no logical tree"),
            ))
        }
    };
    Ok(EntrySig {
        algorithm: algorithm.to_string(),
        layout,
        roles,
        query,
        result,
        buffers,
        logical_c: logical_c::render(logical, m),
        logical: logical.schema.clone(),
    })
}

/// E0910: `--entry` without `--layout`.
pub fn needs_layout(algorithm: &str) -> Diagnostic {
    Diagnostic::error("E0910", format!("`--entry {algorithm}` needs a layout"))
        .with_note("entry points are specialized to one layout: add `--layout NAME`")
}
