//! Which algebraic data type a layout realizes.
//!
//! Input: a [`LayoutDecl`] and its [`Program`]; output: the [`Adt`] (its variants and their
//! logical fields, shared fields first, each marked recursive or array) or an E0311 diagnostic.
//! The ADT is the sum type that has every variant the split arms name; a layout without splits
//! realizes the type whose variants its build names, or else the program's only one-variant sum
//! type. When several sum types have the named variants (`BVH` and `BVH8` both have `Interior`
//! and `Leaf`), the one whose logical field names the layout declares best is chosen, then the
//! one whose field types the layout's stored fields and constructor calls agree with; a tie is
//! an error.

use crate::layout::model::{Adt, AdtVariant, LogicalField};
use crate::syntax::ast::{
    Ident, Item, LayoutDecl, Member, MemberKind, Program, SplitArmBody, TypeExpr, TypeExprKind,
};
use scion_ir::diag::{Diagnostic, Diagnostics, Span};

fn err(code: &str, msg: impl Into<String>, span: Span, label: &str) -> Diagnostic {
    Diagnostic::error(code, msg).with_primary(span, label)
}

/// Finds the sum type whose variants the layout's split arms name (E0311 when there is none or
/// more than one).
pub(crate) fn find_adt(
    decl: &LayoutDecl,
    program: &Program,
    diags: &mut Diagnostics,
) -> Option<Adt> {
    let mut named: Vec<Ident> = Vec::new();
    collect_arm_variants(&decl.members, &mut named, 0);
    if named.is_empty() {
        for item in &program.items {
            if let Item::Build(b) = item {
                if b.name.name == decl.name.name {
                    named.extend(b.variants.iter().map(|v| v.name.clone()));
                }
            }
        }
    }
    let mut sums: Vec<_> = program
        .items
        .iter()
        .filter_map(|i| match i {
            Item::Type(t) if t.variants.is_some() => Some(t),
            _ => None,
        })
        .collect();
    sums.dedup_by(|a, b| a.name.name == b.name.name);
    let has = |t: &crate::syntax::ast::TypeDecl, v: &str| {
        t.variants
            .as_ref()
            .is_some_and(|vs| vs.iter().any(|x| x.name.name == v))
    };
    let chosen = if named.is_empty() {
        let single: Vec<_> = sums
            .iter()
            .filter(|t| t.variants.as_ref().is_some_and(|v| v.len() == 1))
            .collect();
        if single.len() == 1 {
            Some(*single[0])
        } else {
            diags.push(
                err(
                    "E0311",
                    format!(
                        "cannot tell which type layout `{}` realizes",
                        decl.name.name
                    ),
                    decl.name.span,
                    "no split names a variant",
                )
                .with_note("name the variants in `split` arms, or write a build for this layout"),
            );
            None
        }
    } else {
        let mut unknown = false;
        for v in &named {
            if !sums.iter().any(|t| has(t, &v.name)) {
                unknown = true;
                diags.push(err(
                    "E0311",
                    format!("`{}` is not a variant of any type", v.name),
                    v.span,
                    "unknown variant",
                ));
            }
        }
        let mut all: Vec<_> = sums
            .iter()
            .filter(|t| named.iter().all(|v| has(t, &v.name)))
            .collect();
        if all.len() > 1 {
            // Several types have these variant names (BVH and BVH8 both have Interior and
            // Leaf): keep those whose logical fields the layout declares best.
            // Ties (BVH over AABB and DopBVH over DOP14 have the same field names) go to the
            // type whose field types the layout agrees with: a stored field of the logical
            // type, or a derived field built by the type's constructor.
            let mut declared: Vec<(&str, Evidence<'_>)> = Vec::new();
            collect_member_names(&decl.members, &mut declared, 0);
            let score = |t: &crate::syntax::ast::TypeDecl| {
                let mut fields: Vec<&crate::syntax::ast::FieldDecl> = t.fields.iter().collect();
                for v in t.variants.iter().flatten() {
                    fields.extend(v.fields.iter());
                }
                let found = fields
                    .iter()
                    .filter(|f| declared.iter().any(|(n, _)| *n == f.name.name))
                    .count();
                let agree = fields
                    .iter()
                    .filter(|f| {
                        declared
                            .iter()
                            .any(|(n, e)| *n == f.name.name && e.agrees(&f.ty, &declared))
                    })
                    .count();
                ((found * 1000) / fields.len().max(1), agree)
            };
            let best = all.iter().map(|t| score(t)).max().unwrap_or((0, 0));
            all.retain(|t| score(t) == best);
        }
        match all.len() {
            1 => Some(*all[0]),
            0 if unknown => None,
            0 => {
                let owners: Vec<String> = named
                    .iter()
                    .map(|v| {
                        let t = sums
                            .iter()
                            .find(|t| has(t, &v.name))
                            .map(|t| t.name.name.as_str())
                            .unwrap_or("?");
                        format!("`{}` of `{t}`", v.name)
                    })
                    .collect();
                diags.push(
                    err(
                        "E0311",
                        "split arms name variants of different types",
                        decl.name.span,
                        "a layout realizes exactly one type",
                    )
                    .with_note(format!("the arms name {}", owners.join(", "))),
                );
                None
            }
            _ => {
                let names: Vec<String> = all.iter().map(|t| format!("`{}`", t.name.name)).collect();
                diags.push(
                    err(
                        "E0311",
                        format!("layout `{}` could realize several types", decl.name.name),
                        decl.name.span,
                        "ambiguous",
                    )
                    .with_note(format!("candidates: {}", names.join(", "))),
                );
                None
            }
        }
    };
    adt_of_decl(chosen?)
}

/// E0311 for every variant a split arm of `decl` names that `chosen` (the type the checker
/// chose for it) does not have.
pub(crate) fn unknown_variants(
    decl: &LayoutDecl,
    program: &Program,
    chosen: &crate::syntax::ast::TypeDecl,
    diags: &mut Diagnostics,
) {
    let mut named: Vec<Ident> = Vec::new();
    collect_arm_variants(&decl.members, &mut named, 0);
    let has = |t: &crate::syntax::ast::TypeDecl, v: &str| {
        t.variants
            .as_ref()
            .is_some_and(|vs| vs.iter().any(|x| x.name.name == v))
    };
    for v in named.iter().filter(|v| !has(chosen, &v.name)) {
        let elsewhere = program
            .items
            .iter()
            .any(|i| matches!(i, Item::Type(t) if has(t, &v.name)));
        let msg = if elsewhere {
            format!(
                "`{}` is not a variant of `{}`, the type layout `{}` realizes",
                v.name, chosen.name.name, decl.name.name
            )
        } else {
            format!("`{}` is not a variant of any type", v.name)
        };
        diags.push(err("E0311", msg, v.span, "unknown variant"));
    }
}

/// The logical tree of sum type `t`: its variants with their fields, shared ones first.
pub(crate) fn adt_of_decl(t: &crate::syntax::ast::TypeDecl) -> Option<Adt> {
    let shared = &t.fields;
    let variants = t
        .variants
        .as_ref()?
        .iter()
        .map(|v| AdtVariant {
            name: v.name.clone(),
            fields: shared
                .iter()
                .chain(v.fields.iter())
                .map(|f| LogicalField {
                    name: f.name.clone(),
                    ty: f.ty.clone(),
                    recursive: mentions_type(&f.ty, &t.name.name),
                    array: matches!(f.ty.kind, TypeExprKind::Array { .. }),
                })
                .collect(),
        })
        .collect();
    Some(Adt {
        name: t.name.name.clone(),
        variants,
    })
}

fn mentions_type(ty: &TypeExpr, name: &str) -> bool {
    match &ty.kind {
        TypeExprKind::Named(id) => id.name == name,
        TypeExprKind::Array { elem, .. } | TypeExprKind::Set(elem) | TypeExprKind::Option(elem) => {
            mentions_type(elem, name)
        }
        TypeExprKind::Tuple(ts) => ts.iter().any(|t| mentions_type(t, name)),
        TypeExprKind::Vector { .. } => false,
    }
}

/// What a layout member says about the type of the logical field of the same name.
enum Evidence<'a> {
    Stored(&'a TypeExpr),
    Derived(Option<&'a str>),
    /// A slice of the member named here (`data = primitives[a : b]`).
    SliceOf(&'a str),
}

impl Evidence<'_> {
    /// Whether the logical type `ty` agrees with this member; `declared` resolves the array a
    /// slice is of (its element type is the logical array's: `Triangle` or `Segment`).
    fn agrees(&self, ty: &TypeExpr, declared: &[(&str, Evidence<'_>)]) -> bool {
        match self {
            Evidence::Stored(t) => crate::layout::types::same_type(t, ty),
            Evidence::Derived(Some(ctor)) => {
                matches!(&ty.kind, TypeExprKind::Named(n) if n.name == *ctor)
            }
            Evidence::Derived(None) => false,
            Evidence::SliceOf(base) => declared.iter().any(|(n, e)| match (e, &ty.kind) {
                (Evidence::Stored(t), TypeExprKind::Array { elem, .. }) if n == base => {
                    matches!(&t.kind, TypeExprKind::Array { elem: stored, .. }
                        if crate::layout::types::same_type(stored, elem))
                }
                _ => false,
            }),
        }
    }
}

fn collect_member_names<'a>(
    members: &'a [Member],
    out: &mut Vec<(&'a str, Evidence<'a>)>,
    depth: u32,
) {
    if depth > 64 {
        return;
    }
    for m in members {
        match &m.kind {
            MemberKind::Field { name, ty } => out.push((&name.name, Evidence::Stored(ty))),
            MemberKind::Derived { name, value } => {
                use crate::syntax::ast::ExprKind;
                let evidence = match &value.kind {
                    ExprKind::Call { callee, .. } => Evidence::Derived(Some(callee.name.as_str())),
                    ExprKind::Slice { base, .. } => match &base.kind {
                        ExprKind::Name(b) => Evidence::SliceOf(b.name.as_str()),
                        _ => Evidence::Derived(None),
                    },
                    _ => Evidence::Derived(None),
                };
                out.push((&name.name, evidence))
            }
            MemberKind::Group(g) => collect_member_names(&g.members, out, depth + 1),
            MemberKind::Split { arms, .. } => {
                for a in arms {
                    if let SplitArmBody::Members { members, .. } = &a.body {
                        collect_member_names(members, out, depth + 1);
                    }
                }
            }
            _ => {}
        }
    }
}

fn collect_arm_variants(members: &[Member], out: &mut Vec<Ident>, depth: u32) {
    if depth > 64 {
        return;
    }
    for m in members {
        match &m.kind {
            MemberKind::Group(g) => collect_arm_variants(&g.members, out, depth + 1),
            MemberKind::Split { arms, .. } => {
                for a in arms {
                    match &a.body {
                        SplitArmBody::Members { variant, members } => {
                            if !out.iter().any(|v| v.name == variant.name) {
                                out.push(variant.clone());
                            }
                            collect_arm_variants(members, out, depth + 1);
                        }
                        SplitArmBody::From { variant, .. } => {
                            if !out.iter().any(|v| v.name == variant.name) {
                                out.push(variant.clone());
                            }
                        }
                    }
                }
            }
            _ => {}
        }
    }
}
