//! `prune-functions`: drops the functions that no function written in the user's files reaches
//! (prelude helpers nobody calls), so that `--emit=tree` shows the user's code and exactly what
//! it depends on, and the lowering to `lo` sees only what is used. Input and output: any level.
//!
//! The roots are the functions whose span lies in one of the files of the [`UserFiles`]
//! extension the driver puts in the pass context; without it (text IR given to `scion-opt`,
//! whose functions have no source files) the pass keeps everything. Functions generated from a
//! user's layout (the specializations' `@L.build`, `@L.sizes`, ...) carry its span, so they stay.

use rustc_hash::FxHashSet;
use scion_ir::diag::FileId;
use scion_ir::entity::FuncId;
use scion_ir::lo::Op as L;
use scion_ir::op::OpKind;
use scion_ir::tree::Op;
use scion_ir::{Module, Pass, PassCx, PassError};

/// The files the user wrote (not the prelude): the roots of `prune-functions`.
#[derive(Clone, Debug, Default)]
pub struct UserFiles(pub Vec<FileId>);

/// The pass object.
pub struct PruneFunctions;

impl Pass for PruneFunctions {
    fn name(&self) -> &'static str {
        "prune-functions"
    }

    fn summary(&self) -> &'static str {
        "drop functions that no function of the user's files reaches"
    }

    fn run(&mut self, m: &mut Module, cx: &mut PassCx) -> Result<bool, PassError> {
        let Some(UserFiles(files)) = cx.ext::<UserFiles>() else {
            return Ok(false);
        };
        Ok(keep_reachable(m, files))
    }
}

/// Drops the functions that no function whose span lies in `inputs` reaches; returns whether
/// any was dropped.
pub fn keep_reachable(m: &mut Module, inputs: &[FileId]) -> bool {
    let mut live: FxHashSet<FuncId> = FxHashSet::default();
    let mut work: Vec<FuncId> = m
        .func_order
        .iter()
        .copied()
        .filter(|&f| {
            m.func_spans
                .get(f)
                .is_some_and(|s| inputs.contains(&s.file))
        })
        .collect();
    while let Some(f) = work.pop() {
        if !live.insert(f) {
            continue;
        }
        for callee in callees(m, f) {
            if let Some(g) = m.func_by_name(&callee) {
                work.push(g);
            }
        }
    }
    let dead: Vec<FuncId> = m
        .func_order
        .iter()
        .copied()
        .filter(|f| !live.contains(f))
        .collect();
    let changed = !dead.is_empty();
    for f in dead {
        m.remove_func(f);
    }
    changed
}

/// The functions `f` calls (`tree.call` at any depth, or `lo.call`).
fn callees(m: &Module, f: FuncId) -> Vec<String> {
    let mut names = Vec::new();
    let mut regions = vec![m.funcs[f].body];
    while let Some(r) = regions.pop() {
        for &b in &m.regions[r].blocks {
            for &op in &m.blocks[b].ops {
                let o = &m.ops[op];
                if matches!(o.kind, OpKind::Tree(Op::Call) | OpKind::Lo(L::Call)) {
                    if let Some(s) = o.callee() {
                        names.push(s.to_string());
                    }
                }
                regions.extend(o.regions.iter().copied());
            }
        }
    }
    names
}
