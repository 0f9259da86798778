//! Tree-carried components (`parent.x`, language notes): which components of a layout's
//! reference a traversal fills from the parent when it descends, and the ones the compiler
//! adds for `parent.x` reads that no declared component carries.

use crate::layout::model::{Component, LayoutModel, MemberModel};
use crate::layout::types::{record_shape, round_up, Shape, TypeEnv};
use crate::syntax::ast::{Expr, Ident};
use scion_ir::diag::Diagnostic;

fn err(code: &str, msg: impl Into<String>, span: scion_ir::diag::Span, label: &str) -> Diagnostic {
    Diagnostic::error(code, msg).with_primary(span, label)
}

/// Tree-carried state (language notes: "`parent.x` makes `x` part of the child's
/// reference"). A component `c: T = parent.x` carries `x` explicitly (`Models::of` declares
/// one for a derived `x` from its checked type); a `parent.x` read by an expression with
/// no such component gets one, named `parent.x`, appended to the reference, when `x` is a
/// stored field or a component (a derived `x` whose type no component takes is E0328).
/// The placed (first) component cannot be carried (E0328).
pub(crate) fn carry_parents(m: &mut LayoutModel, env: &TypeEnv<'_>) {
    if let Some(c) = m.components.first().filter(|c| c.carried.is_some()) {
        m.diagnostics.push(
            err(
                "E0328",
                format!("the first reference component `{}` is tree-carried", c.name.name),
                c.name.span,
                "a build places this component",
            )
            .with_note("put the carried components after the one a build places: `layout L(I: u32, b: AABB = parent.bounds)`"),
        );
    }
    let mut exprs: Vec<Expr> = Vec::new();
    for info in &m.members {
        if let MemberModel::Derived { value, .. } | MemberModel::Let { value, .. } = &info.kind {
            exprs.push(value.clone());
        }
    }
    for s in &m.splits {
        exprs.push(s.discriminant.clone());
    }
    let mut added: Vec<String> = Vec::new();
    for e in &exprs {
        for id in crate::layout::resolve::names_in(e) {
            let Some(x) = id.name.strip_prefix("parent.") else {
                continue;
            };
            if added.iter().any(|a| a == x)
                || m.components
                    .iter()
                    .any(|c| c.carried.as_ref().is_some_and(|c| c.name == x))
            {
                continue;
            }
            let ty = if let Some(i) = m.component(x) {
                Some(m.components[i].ty.clone())
            } else {
                m.members.iter().find_map(|mi| match &mi.kind {
                    MemberModel::Stored(s) if s.name.name == x => Some(s.ty.clone()),
                    _ => None,
                })
            };
            let derived = m.members.iter().any(|mi| {
                matches!(&mi.kind, MemberModel::Derived { name, .. } | MemberModel::Let { name, .. } if name.name == x)
            });
            let Some(ty) = ty.filter(|_| !derived) else {
                if derived {
                    m.diagnostics.push(
                        err(
                            "E0328",
                            format!("no reference component can carry `parent.{x}`, a derived field of a type a component cannot take"),
                            id.span,
                            "carried by no component",
                        )
                        .with_note(format!("a component is a scalar, a vector, a declared type or a fixed array of them; carry the parts of `{x}` (`parent.y` of fields of those types), or declare one: `layout {}(..., p: T = parent.{x})`", m.name.name)),
                    );
                }
                // An unknown `x` is E0310.
                continue;
            };
            let shape = env.shape(&ty).ok();
            added.push(x.to_string());
            m.components.push(Component {
                name: Ident {
                    name: id.name.clone(),
                    span: id.span,
                },
                ty,
                shape,
                default: None,
                carried: Some(Ident {
                    name: x.to_string(),
                    span: id.span,
                }),
                offset: 0,
            });
        }
    }
    if added.is_empty() {
        return;
    }
    let mut end = 0u64;
    let mut shapes = Vec::new();
    for c in &mut m.components {
        let sh = c.shape.unwrap_or(Shape { size: 0, align: 1 });
        c.offset = round_up(end, sh.align);
        end = c.offset.saturating_add(sh.size);
        shapes.push(sh);
    }
    m.reference = record_shape(&shapes);
}
