//! `build root` and the globals (paper §5.3.2; codes E04xx): the root block runs once before
//! the tree and writes each plain global (not an array size, which the constructor sets, and
//! not a global array, which `append` fills) exactly once, reading none before writing it.
//!
//! Input: the layout's model and the root block's statements; output: diagnostics. Also the
//! [`GlobalFacts`] the variant checks use.

use crate::layout::model::{LayoutModel, MemberId, MemberModel, Storage};
use crate::layout::resolve::names_in;
use crate::syntax::ast::{Expr, Ident, Stmt, StmtKind};
use rustc_hash::{FxHashMap, FxHashSet};
use scion_ir::diag::{Diagnostic, Diagnostics, Span};

/// Facts about the layout's globals.
pub(crate) struct GlobalFacts {
    /// Scalar globals (in the globals block) by name.
    pub(crate) scalars: FxHashMap<String, MemberId>,
    /// Globals that size a group or a global array: the constructor writes them.
    pub(crate) sizes: FxHashSet<String>,
    /// Global arrays (filled by `append`).
    pub(crate) arrays: FxHashSet<String>,
}

impl GlobalFacts {
    pub(crate) fn of(m: &LayoutModel) -> GlobalFacts {
        let mut scalars = FxHashMap::default();
        let mut arrays = FxHashSet::default();
        for &mid in &m.scopes[0].members {
            if let MemberModel::Stored(s) = &m.members[mid].kind {
                match s.storage {
                    Storage::Globals { .. } => {
                        scalars.insert(s.name.name.clone(), mid);
                    }
                    Storage::GlobalArray(_) => {
                        arrays.insert(s.name.name.clone());
                    }
                    _ => {}
                }
            }
        }
        let mut sizes: FxHashSet<String> =
            m.global_arrays.iter().map(|g| g.len.name.clone()).collect();
        for g in &m.groups {
            if let Some(e) = &g.size {
                sizes.extend(names_in(e).into_iter().map(|i| i.name));
            }
        }
        GlobalFacts {
            scalars,
            sizes,
            arrays,
        }
    }
}

/// `build root`: writes each non-size scalar global exactly once; nothing else.
pub(crate) fn check_root(
    m: &LayoutModel,
    facts: &GlobalFacts,
    body: &[Stmt],
    span: Span,
    d: &mut Diagnostics,
) {
    let mut written: FxHashMap<String, Span> = FxHashMap::default();
    root_stmts(m, facts, body, &mut written, d, 0);
    let mut missing: Vec<(&String, &MemberId)> = facts
        .scalars
        .iter()
        .filter(|(n, _)| !facts.sizes.contains(*n) && !written.contains_key(*n))
        .collect();
    missing.sort_by_key(|(_, m)| **m);
    for (name, mid) in missing {
        d.push(
            Diagnostic::error("E0407", format!("global `{name}` is never written"))
                .with_primary(span, format!("`build root` must write `{name}`"))
                .with_secondary(m.members[*mid].span, "declared here"),
        );
    }
}

/// Walks `build root`'s statements in order; writes inside branches and loops count as writes
/// (the root block is straight-line code in practice, so it is not path-sensitive).
fn root_stmts(
    m: &LayoutModel,
    facts: &GlobalFacts,
    body: &[Stmt],
    written: &mut FxHashMap<String, Span>,
    d: &mut Diagnostics,
    depth: u32,
) {
    if depth > 256 {
        return;
    }
    for s in body {
        match &s.kind {
            StmtKind::Block(b) => root_stmts(m, facts, b, written, d, depth + 1),
            StmtKind::If {
                branches,
                otherwise,
            } => {
                for (c, b) in branches {
                    root_reads(facts, c, written, d);
                    root_stmts(m, facts, std::slice::from_ref(b), written, d, depth + 1);
                }
                if let Some(o) = otherwise {
                    root_stmts(m, facts, std::slice::from_ref(o), written, d, depth + 1);
                }
            }
            StmtKind::Match { scrutinee, arms } => {
                root_reads(facts, scrutinee, written, d);
                for a in arms {
                    root_stmts(
                        m,
                        facts,
                        std::slice::from_ref(&a.body),
                        written,
                        d,
                        depth + 1,
                    );
                }
            }
            StmtKind::Foreach { iter, body, .. } => {
                root_reads(facts, iter, written, d);
                root_stmts(m, facts, std::slice::from_ref(body), written, d, depth + 1);
            }
            StmtKind::Build { field, value } => {
                if let Some(v) = value {
                    root_reads(facts, v, written, d);
                }
                root_write(m, facts, field, written, d);
            }
            _ => {
                let mut reads: Vec<&Expr> = Vec::new();
                crate::layout::resolve::stmt_exprs(s, &mut |e| reads.push(e));
                for e in reads {
                    root_reads(facts, e, written, d);
                }
            }
        }
    }
}

fn root_write(
    m: &LayoutModel,
    facts: &GlobalFacts,
    field: &Ident,
    written: &mut FxHashMap<String, Span>,
    d: &mut Diagnostics,
) {
    let name = &field.name;
    if facts.sizes.contains(name) {
        d.push(
            Diagnostic::error(
                "E0416",
                format!("global `{name}` is set by the constructor"),
            )
            .with_primary(field.span, "do not write it")
            .with_note("globals that size arrays or groups get their element count automatically"),
        );
    } else if facts.arrays.contains(name) {
        d.push(
            Diagnostic::error(
                "E0416",
                format!("global array `{name}` is filled by `append`"),
            )
            .with_primary(field.span, "cannot be written here"),
        );
    } else if !facts.scalars.contains_key(name) {
        d.push(
            Diagnostic::error(
                "E0416",
                format!("`{name}` is not a global of layout `{}`", m.name.name),
            )
            .with_primary(field.span, "`build root` writes globals only"),
        );
    } else if let Some(first) = written.get(name) {
        d.push(
            Diagnostic::error("E0408", format!("global `{name}` is written twice"))
                .with_primary(field.span, "second write")
                .with_secondary(*first, "first write"),
        );
    } else {
        written.insert(name.clone(), field.span);
    }
}

fn root_reads(
    facts: &GlobalFacts,
    e: &Expr,
    written: &FxHashMap<String, Span>,
    d: &mut Diagnostics,
) {
    for id in names_in(e) {
        if facts.scalars.contains_key(&id.name)
            && !facts.sizes.contains(&id.name)
            && !written.contains_key(&id.name)
        {
            d.push(
                Diagnostic::error(
                    "E0409",
                    format!("global `{}` is read before it is written", id.name),
                )
                .with_primary(id.span, "not written yet"),
            );
        }
    }
}
