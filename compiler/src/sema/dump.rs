//! A readable dump of what semantic analysis found (for `scionc --emit=types` and tests).
//!
//! Input: a [`Program`] and its [`TypedProgram`]. Output: text listing the declared types, every
//! function's signature and unique name with the type of each local binding, every layout's
//! reference type, realized ADT and member types, and every build's variants. The format is
//! stable enough to check with FileCheck.

use super::typed::{MemberKindInfo, TypedProgram};
use super::types::{AdtKind, FieldDef, Ty};
use crate::syntax::ast::{Item, Program, Stmt, StmtKind};
use std::fmt::Write;

fn fields(typed: &TypedProgram, fs: &[FieldDef]) -> String {
    let parts: Vec<String> = fs
        .iter()
        .map(|f| match &f.len_field {
            Some(n) => match &f.ty {
                Ty::Slice(e) => format!("{}: {}[{}]", f.name, e.display(&typed.adts), n),
                t => format!("{}: {}", f.name, t.display(&typed.adts)),
            },
            None => format!("{}: {}", f.name, f.ty.display(&typed.adts)),
        })
        .collect();
    parts.join(", ")
}

fn bindings_of(typed: &TypedProgram, s: &Stmt, depth: usize, out: &mut String) {
    let pad = "  ".repeat(depth);
    let show = |id| {
        typed
            .binders
            .get(&id)
            .map(|b| &typed.bindings[b.0 as usize])
    };
    match &s.kind {
        StmtKind::Let { .. } => {
            if let Some(b) = show(s.id) {
                let _ = writeln!(out, "{pad}let {}: {}", b.name, b.ty.display(&typed.adts));
            }
        }
        StmtKind::Foreach { body, .. } => {
            if let Some(b) = show(s.id) {
                let _ = writeln!(
                    out,
                    "{pad}foreach {}: {}",
                    b.name,
                    b.ty.display(&typed.adts)
                );
            }
            bindings_of(typed, body, depth + 1, out);
        }
        StmtKind::Block(v) => v.iter().for_each(|s| bindings_of(typed, s, depth, out)),
        StmtKind::If {
            branches,
            otherwise,
        } => {
            for (_, b) in branches {
                bindings_of(typed, b, depth, out);
            }
            if let Some(o) = otherwise {
                bindings_of(typed, o, depth, out);
            }
        }
        StmtKind::Match { arms, .. } => {
            for arm in arms {
                let variant = typed
                    .pattern_variants
                    .get(&arm.pattern.id)
                    .and_then(|(a, v)| {
                        typed
                            .adts
                            .get(*a)
                            .and_then(|d| d.variants().get(*v as usize))
                    })
                    .map(|v| v.name.clone())
                    .unwrap_or_else(|| "_".to_string());
                let mut binds = Vec::new();
                let pats = match &arm.pattern.kind {
                    crate::syntax::ast::PatternKind::Variant { fields, .. } => {
                        fields.iter().collect()
                    }
                    _ => vec![&arm.pattern],
                };
                for p in pats {
                    if let Some(b) = show(p.id) {
                        binds.push(format!("{}: {}", b.name, b.ty.display(&typed.adts)));
                    }
                }
                let _ = writeln!(out, "{pad}| {variant}({})", binds.join(", "));
                bindings_of(typed, &arm.body, depth + 1, out);
            }
        }
        StmtKind::Expr(_)
        | StmtKind::Assign { .. }
        | StmtKind::Return(_)
        | StmtKind::Build { .. } => {}
    }
}

/// The dump of `typed` (checked from `program`).
pub fn dump_types(program: &Program, typed: &TypedProgram) -> String {
    let mut out = String::new();
    for a in &typed.adts.adts {
        match &a.kind {
            AdtKind::Record => {
                let _ = writeln!(out, "type {}({})", a.name, fields(typed, &a.fields));
            }
            AdtKind::Sum(vs) => {
                let vs: Vec<String> = vs
                    .iter()
                    .map(|v| format!("{}({})", v.name, fields(typed, &v.fields)))
                    .collect();
                let _ = writeln!(
                    out,
                    "type {}({}) = {}",
                    a.name,
                    fields(typed, &a.fields),
                    vs.join(" | ")
                );
            }
        }
    }
    for f in &typed.funcs {
        let ps: Vec<String> = f
            .params
            .iter()
            .map(|p| {
                format!(
                    "{}: {}{}",
                    p.name,
                    if p.mutable { "mut " } else { "" },
                    p.ty.display(&typed.adts)
                )
            })
            .collect();
        let _ = writeln!(
            out,
            "func {}({}) -> {}  [{}]",
            f.name,
            ps.join(", "),
            f.ret.display(&typed.adts),
            f.unique_name
        );
        if let Some(Item::Func(d)) = program.items.get(f.item) {
            bindings_of(typed, &d.body, 1, &mut out);
        }
    }
    for l in &typed.layouts {
        let adt = l
            .adt
            .and_then(|a| typed.adts.get(a))
            .map(|d| d.name.as_str())
            .unwrap_or("?");
        let _ = writeln!(
            out,
            "layout {} realizes {adt}, reference {}",
            l.name,
            l.ref_ty.display(&typed.adts)
        );
        for m in &l.members {
            let depth = {
                let mut d = 1;
                let mut g = m.group;
                while let Some(id) = g {
                    d += 1;
                    g = l.members.get(id.0 as usize).and_then(|p| p.group);
                }
                d
            };
            let pad = "  ".repeat(depth);
            let kind = match m.kind {
                MemberKindInfo::Stored => "stored",
                MemberKindInfo::Derived => "derived",
                MemberKindInfo::Let => "let",
                MemberKindInfo::Group => "group",
                MemberKindInfo::IndirectGroup => "indirect group",
            };
            let variant = m
                .variant
                .and_then(|v| {
                    l.adt
                        .and_then(|a| typed.adts.get(a))
                        .and_then(|d| d.variants().get(v as usize))
                })
                .map(|v| format!(" in {}", v.name))
                .unwrap_or_default();
            if matches!(
                m.kind,
                MemberKindInfo::Group | MemberKindInfo::IndirectGroup
            ) {
                let _ = writeln!(out, "{pad}{kind} {}{variant}", m.name);
            } else {
                let _ = writeln!(
                    out,
                    "{pad}{}: {} ({kind}{variant})",
                    m.name,
                    m.ty.display(&typed.adts)
                );
            }
        }
    }
    for b in &typed.builds {
        let name = b
            .layout
            .and_then(|l| typed.layouts.get(l.0 as usize))
            .map(|l| l.name.as_str())
            .unwrap_or("?");
        let adt = b
            .layout
            .and_then(|l| typed.layouts.get(l.0 as usize))
            .and_then(|l| l.adt)
            .and_then(|a| typed.adts.get(a));
        let _ = writeln!(out, "build {name}");
        for v in &b.variants {
            let vname = adt
                .and_then(|d| d.variants().get(v.variant as usize))
                .map(|v| v.name.as_str())
                .unwrap_or("?");
            let fs: Vec<String> = v
                .fields
                .iter()
                .map(|(n, t)| format!("{n}: {}", t.display(&typed.adts)))
                .collect();
            let _ = writeln!(out, "  {vname}({})", fs.join(", "));
        }
    }
    out
}
