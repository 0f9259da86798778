//! `lo-inline`: inlines calls of small leaf functions in the `lo` CFG (design note §5:
//! "non-recursive helpers may also be inlined"). Input and output: a `lo` module.
//!
//! A callee qualifies when it is defined, makes no calls itself, and either has at most
//! `max-ops` ops (option `lo-inline:max-ops=N`, default 48) or is called from exactly one place
//! in the module (inlining it then costs no code size in the caller's hot path: the traversal's
//! triangle test, and the traversal itself into its entry, whatever their size). The call's
//! block is split after the call
//! (the rest moves to a continuation block whose arguments are the call's results), a copy of
//! the callee's blocks joins the caller's region, the call becomes a branch to the copy's entry
//! with the arguments, and each copied `lo.return` becomes a branch to the continuation.
//! Rounds repeat (a caller whose calls were all inlined becomes a leaf, so inlining proceeds
//! from the leaves of the call graph up) up to eight times. The callees stay in the module (they
//! may be entry points).

use rustc_hash::FxHashMap;
use scion_ir::diag::Diagnostic;
use scion_ir::entity::{FuncId, OpId};
use scion_ir::lo::Op as L;
use scion_ir::op::OpKind;
use scion_ir::rewrite::{clone_region, erase_op, replace_all_uses, resolve_aliases};
use scion_ir::{Builder, Module, OpSpec, Pass, PassCx, PassError};

/// The default size limit of an inlined callee, in ops.
pub const DEFAULT_MAX_OPS: usize = 48;

/// The pass object.
pub struct LoInline;

impl Pass for LoInline {
    fn name(&self) -> &'static str {
        "lo-inline"
    }

    fn summary(&self) -> &'static str {
        "inline calls of small leaf functions in lo"
    }

    fn run(&mut self, m: &mut Module, cx: &mut PassCx) -> Result<bool, PassError> {
        let max = match cx.option("lo-inline", "max-ops") {
            None => DEFAULT_MAX_OPS,
            Some(s) => s.parse::<usize>().map_err(|_| {
                PassError::Diagnostics(
                    Diagnostic::error(
                        "E0962",
                        format!("lo-inline:max-ops={s}: expected a non-negative integer"),
                    )
                    .into(),
                )
            })?,
        };
        Ok(run(m, max))
    }
}

fn body_ops(m: &Module, f: FuncId) -> Vec<OpId> {
    m.regions[m.funcs[f].body]
        .blocks
        .iter()
        .flat_map(|&b| m.blocks[b].ops.iter().copied())
        .collect()
}

fn callee(m: &Module, op: OpId) -> Option<FuncId> {
    let o = &m.ops[op];
    if o.kind != OpKind::Lo(L::Call) {
        return None;
    }
    m.func_by_name(o.callee()?)
}

/// Inlines qualifying calls in the whole module; returns whether anything changed.
pub fn run(m: &mut Module, max_ops: usize) -> bool {
    let mut changed = false;
    for _ in 0..8 {
        let mut sites_of: FxHashMap<FuncId, usize> = FxHashMap::default();
        for &g in &m.func_order {
            if m.is_declaration(g) {
                continue;
            }
            for op in body_ops(m, g) {
                if let Some(f) = callee(m, op) {
                    *sites_of.entry(f).or_default() += 1;
                }
            }
        }
        let inlinable: FxHashMap<FuncId, ()> = m
            .func_order
            .iter()
            .copied()
            .filter(|&f| {
                if m.is_declaration(f) {
                    return false;
                }
                let ops = body_ops(m, f);
                let leaf = ops.iter().all(|&o| m.ops[o].kind != OpKind::Lo(L::Call));
                leaf && (ops.len() <= max_ops || sites_of.get(&f) == Some(&1))
            })
            .map(|f| (f, ()))
            .collect();
        let mut sites = Vec::new();
        for &g in &m.func_order {
            if m.is_declaration(g) {
                continue;
            }
            for op in body_ops(m, g) {
                if let Some(f) = callee(m, op) {
                    if f != g && inlinable.contains_key(&f) {
                        sites.push((g, op, f));
                    }
                }
            }
        }
        if sites.is_empty() {
            break;
        }
        for (g, op, f) in sites {
            inline_call(m, g, op, f);
        }
        resolve_aliases(m);
        changed = true;
    }
    changed
}

fn inline_call(m: &mut Module, g: FuncId, call: OpId, f: FuncId) {
    let Some(b) = m.ops[call].parent else {
        return;
    };
    let region = m.funcs[g].body;
    let Some(pos) = m.blocks[b].ops.iter().position(|&o| o == call) else {
        return;
    };
    let result_types: Vec<_> = m.ops[call]
        .results
        .iter()
        .map(|&r| m.values[r].ty)
        .collect();
    let cont = m.add_block(region, &result_types);
    let rest: Vec<OpId> = m.blocks[b].ops.split_off(pos + 1);
    for &o in &rest {
        m.ops[o].parent = Some(cont);
    }
    m.blocks[cont].ops = rest;
    let cont_args = m.blocks[cont].args.to_vec();
    for (r, a) in m.ops[call].results.clone().into_iter().zip(cont_args) {
        replace_all_uses(m, r, a);
    }
    let args = m.ops[call].operands.to_vec();
    erase_op(m, call);
    let mut map = FxHashMap::default();
    let copy = clone_region(m, m.funcs[f].body, &mut map);
    let blocks = std::mem::take(&mut m.regions[copy].blocks);
    for &nb in &blocks {
        m.blocks[nb].parent = Some(region);
    }
    let at = m.regions[region]
        .blocks
        .iter()
        .position(|&x| x == cont)
        .unwrap_or(m.regions[region].blocks.len());
    m.regions[region]
        .blocks
        .splice(at..at, blocks.iter().copied());
    let span = m.span(m.blocks[b].ops.last().copied().unwrap_or(call));
    let mut bl = Builder::at_end(m, b);
    bl.set_span(span);
    bl.insert(OpSpec::new(L::Br).successor(blocks[0], &args));
    for nb in blocks {
        let Some(&term) = m.blocks[nb].ops.last() else {
            continue;
        };
        if m.ops[term].kind == OpKind::Lo(L::Return) {
            let vals = m.ops[term].operands.to_vec();
            erase_op(m, term);
            Builder::at_end(m, nb).lo_br(cont, &vals);
        }
    }
}
