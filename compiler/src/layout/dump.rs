//! A textual byte map of a [`LayoutModel`], for `--emit`-style dumps, documentation and golden
//! tests: the reference, the globals block, the global arrays and every group array with the
//! offset and size of each member, splits with their arms indented below them.

use crate::layout::model::{ArmBody, GroupKind, LayoutModel, MemberModel, ScopeId, ScopeKind};
use crate::syntax::ast::{SplitPatternKind, TypeExpr, TypeExprKind};
use std::fmt::Write;

/// The byte map of `model`.
pub fn byte_map(model: &LayoutModel) -> String {
    let mut out = String::new();
    let comps: Vec<String> = model
        .components
        .iter()
        .map(|c| format!("{}: {}", c.name.name, type_text(&c.ty)))
        .collect();
    let _ = writeln!(
        out,
        "layout {}({}): reference {} B",
        model.name.name,
        comps.join(", "),
        model.reference.size
    );
    if let Some(adt) = &model.adt {
        let _ = writeln!(out, "realizes {}", adt.name);
    }
    let _ = writeln!(
        out,
        "globals: {} B, align {}",
        model.globals.size, model.globals.align
    );
    members(model, 0, 1, None, &mut out);
    for g in &model.groups {
        if g.kind == GroupKind::Nested {
            continue;
        }
        let how = match g.kind {
            GroupKind::Direct => "direct",
            GroupKind::Pointer => "pointer-indexed",
            _ => "indirect",
        };
        let _ = writeln!(out, "group {} ({how})", g.name.name);
        for (k, a) in g.arrays.iter().enumerate() {
            let _ = writeln!(
                out,
                "  array {k}: {} B, align {}, stride {}",
                a.size, a.align, a.stride
            );
            members(model, g.scope, 2, Some(k), &mut out);
        }
    }
    out
}

fn members(
    model: &LayoutModel,
    scope: ScopeId,
    depth: usize,
    part: Option<usize>,
    out: &mut String,
) {
    let pad = "  ".repeat(depth);
    for &m in &model.scopes[scope].members {
        let info = &model.members[m];
        if part.is_some_and(|p| p != info.part) {
            continue;
        }
        match &info.kind {
            MemberModel::Stored(s) => {
                let at = match s.storage {
                    crate::layout::model::Storage::Globals { offset } => format!("@{offset}"),
                    crate::layout::model::Storage::Element { offset, .. } => format!("@{offset}"),
                    crate::layout::model::Storage::GlobalArray(_) => "array".to_string(),
                    crate::layout::model::Storage::None => "?".to_string(),
                };
                let size = match s.storage {
                    crate::layout::model::Storage::GlobalArray(i) => {
                        format!("{} B each", model.global_arrays[i].shape.size)
                    }
                    _ => format!("{} B", s.size),
                };
                let _ = writeln!(
                    out,
                    "{pad}{at:<6} {}: {} ({size})",
                    s.name.name,
                    type_text(&s.ty)
                );
            }
            MemberModel::Padding { bytes, offset } => {
                let _ = writeln!(out, "{pad}@{offset:<5} padding ({bytes} B)");
            }
            MemberModel::Derived { name, .. } => {
                let _ = writeln!(out, "{pad}       {} = ...", name.name);
            }
            MemberModel::Let { name, .. } => {
                let _ = writeln!(out, "{pad}       let {} = ...", name.name);
            }
            MemberModel::Group(g) => {
                let grp = &model.groups[*g];
                if grp.kind != GroupKind::Nested {
                    continue;
                }
                let (_, _, off) = grp.parent.unwrap_or((0, 0, 0));
                let _ = writeln!(
                    out,
                    "{pad}@{off:<5} group {}[{}]",
                    grp.name.name,
                    grp.count.unwrap_or(1)
                );
                for (k, a) in grp.arrays.iter().enumerate() {
                    let _ = writeln!(
                        out,
                        "{pad}  array {k} @{}: {} B, align {}, stride {}",
                        a.offset, a.size, a.align, a.stride
                    );
                    members(model, grp.scope, depth + 2, Some(k), out);
                }
            }
            MemberModel::Split(sp) => {
                let split = &model.splits[*sp];
                let _ = writeln!(out, "{pad}@{:<5} split ({} B)", split.offset, split.size);
                for (i, arm) in split.arms.iter().enumerate() {
                    let how = match &arm.body {
                        ArmBody::Members(_) => String::new(),
                        ArmBody::From { group_name, .. } => {
                            format!(" from {}[...]", group_name.name)
                        }
                    };
                    let _ = writeln!(
                        out,
                        "{pad}  {} -> {}{how}",
                        pattern_text(&arm.pattern.kind),
                        arm.variant.name
                    );
                    let arm_scope = model
                        .scopes
                        .iter()
                        .position(|s| s.kind == ScopeKind::Arm { split: *sp, arm: i });
                    if let Some(s) = arm_scope {
                        members(model, s, depth + 2, None, out);
                    }
                }
            }
            MemberModel::Separator => {}
        }
    }
}

fn pattern_text(p: &SplitPatternKind) -> String {
    match p {
        SplitPatternKind::Eq(n) => format!("{n}"),
        SplitPatternKind::Ne(n) => format!("~ {n}"),
        SplitPatternKind::Lt(n) => format!("< {n}"),
        SplitPatternKind::Le(n) => format!("<= {n}"),
        SplitPatternKind::Gt(n) => format!("> {n}"),
        SplitPatternKind::Ge(n) => format!(">= {n}"),
        SplitPatternKind::Wildcard => "_".to_string(),
    }
}

/// A written type as text.
pub fn type_text(t: &TypeExpr) -> String {
    match &t.kind {
        TypeExprKind::Named(n) => n.name.clone(),
        TypeExprKind::Vector { elem, lanes } => format!("{}x{lanes}", elem.name),
        TypeExprKind::Array { elem, len } => match len {
            crate::syntax::ast::ArrayLen::Const(n, _) => format!("{}[{n}]", type_text(elem)),
            crate::syntax::ast::ArrayLen::Name(n) => format!("{}[{}]", type_text(elem), n.name),
        },
        TypeExprKind::Tuple(ts) => format!(
            "({})",
            ts.iter().map(type_text).collect::<Vec<_>>().join(", ")
        ),
        TypeExprKind::Set(t) => format!("set[{}]", type_text(t)),
        TypeExprKind::Option(t) => format!("option[{}]", type_text(t)),
    }
}
