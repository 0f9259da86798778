//! `mem-cse`: common-subexpression elimination and redundant load elimination over the
//! structured `tree`/`mem` level (level: any → same; paper §7.3, "redundant loads are
//! eliminated and common subexpressions reused across control-flow boundaries").
//!
//! An op is replaced by an equivalent op that dominates it: same kind, same operands (after
//! aliasing), same attributes and same result types, defined earlier in the same block or in an
//! enclosing block. Regions are structured, so dominance is scoping: an op inside a region of a
//! `tree.if`/`tree.match`/`tree.foreach` may reuse one from outside, never one from a sibling
//! region. The copy's results are aliased to the original's (`rewrite::replace_all_uses`) and
//! the copy is erased (it is pure, and `dce` would keep a call); `dce` afterwards removes what
//! became dead through the merge.
//!
//! ```text
//! %a = "mem.load"(%n) {offset = 28} : (ptr) -> u16
//! %r = "tree.if"(%c) ({ %b = "mem.load"(%n) {offset = 28} : (ptr) -> u16 ... })   // %b → %a
//! ```
//!
//! Candidates: pure `tree` ops except `tree.var` (each makes a fresh cell), and `mem.buffer`,
//! `mem.addr`, `mem.view`, `mem.load`, plus two kinds keyed by a memory epoch:
//!
//! * Layout loads (`mem.load`) count as pure because the layout's buffers are immutable during
//!   a traversal. Where a function does write (the constructor's `mem.store`s, the build ops, a
//!   call of a function that writes, or a region holding one of these), loads are keyed by a
//!   layout epoch that each write advances, so a load never reuses one from before a write (a
//!   region that writes advances the epoch both before and after it, which covers loops).
//! * Cell loads (`tree.load` of a `mut` parameter or a local `tree.var`) are keyed by a cell
//!   epoch that every `tree.store` and every call of a function that is not pure advances (any
//!   cell: two references may name the same cell), again before and after a region holding
//!   one. Two loads of the same reference with no store or such call between them merge.
//! * Calls of pure functions (`tree.call` of a defined function whose parameters and results
//!   hold no reference, which writes no layout, holds no build op and calls only pure
//!   functions) are keyed by the layout epoch: the same arguments give the same results.
//!   Other calls are never merged. `lo` functions (CFG regions) are left alone.
//!
//! Merging a pure call is what makes the prelude's slab test shared between `intersects` and
//! `distmin` once `mem-inline` put both in the traversal. What remains of `distmin` then tests
//! the condition `intersects` already decided: a `tree.if` whose condition is that of an
//! enclosing `tree.if` (after merging) is folded to the region the enclosing one implies (true
//! in a then region, false in an else region), when that region ends in `tree.yield`; its ops
//! are then visited like the others.

use rustc_hash::{FxHashMap, FxHashSet};
use scion_ir::module::Module;
use scion_ir::op::OpKind;
use scion_ir::pass::{Pass, PassCx, PassError};
use scion_ir::{mem, rewrite, tree, walk, BlockId, FuncId, OpId, TypeId, ValueId};

/// The `mem-cse` pass.
#[derive(Default)]
pub struct MemCse;

impl Pass for MemCse {
    fn name(&self) -> &'static str {
        "mem-cse"
    }

    fn summary(&self) -> &'static str {
        "reuse dominating equivalent pure tree/mem ops (loads of the immutable layout included)"
    }

    fn run(&mut self, m: &mut Module, _cx: &mut PassCx) -> Result<bool, PassError> {
        let writers = layout_writers(m);
        let pure = pure_funcs(m, &writers);
        let mut changed = false;
        for f in m.func_order.clone() {
            let body = m.funcs[f].body;
            let blocks = m.regions[body].blocks.clone();
            if blocks.len() != 1 {
                continue;
            }
            let mut cx = Scope {
                writers: &writers,
                pure: &pure,
                epoch: 0,
                cell_epoch: 0,
                table: FxHashMap::default(),
                known: FxHashMap::default(),
                changed: false,
            };
            cx.block(m, blocks[0]);
            changed |= cx.changed;
        }
        Ok(changed)
    }
}

/// What makes two ops equivalent: kind, resolved operands, attributes (printed, since they are
/// compared whole), result types, and for `mem.load` the memory epoch (0 for other ops).
type Key = (OpKind, Vec<ValueId>, String, Vec<TypeId>, u32);

/// The walk's state: the table of available ops, valid in the current block and its enclosing
/// ones, and the memory epochs (layout: advanced by every layout write; cells: by every cell
/// store or impure call).
struct Scope<'a> {
    writers: &'a FxHashSet<FuncId>,
    pure: &'a FxHashSet<FuncId>,
    epoch: u32,
    cell_epoch: u32,
    table: FxHashMap<Key, OpId>,
    /// Conditions of the enclosing `tree.if`s: true in a then region, false in an else region.
    known: FxHashMap<ValueId, bool>,
    changed: bool,
}

impl Scope<'_> {
    /// Visits the ops of `block` in order, then removes what it added to the table.
    fn block(&mut self, m: &mut Module, block: BlockId) {
        let mut added = Vec::new();
        let mut i = 0;
        while let Some(&op) = m.blocks[block].ops.get(i) {
            let kind = m.ops[op].kind;
            if !kind.has_structured_regions() {
                i += 1;
                continue;
            }
            if self.candidate(m, op)
                && m.ops[op].regions.is_empty()
                && !m.ops[op].results.is_empty()
            {
                let epoch = match kind {
                    OpKind::Mem(mem::Op::Load) | OpKind::Tree(tree::Op::Call) => self.epoch,
                    OpKind::Tree(tree::Op::Load) => self.cell_epoch,
                    _ => 0,
                };
                let key = key_of(m, op, epoch);
                if let Some(&prev) = self.table.get(&key) {
                    let (old, new) = (m.ops[op].results.clone(), m.ops[prev].results.clone());
                    for (o, n) in old.into_iter().zip(new) {
                        rewrite::replace_all_uses(m, o, n);
                    }
                    // Erased here rather than left to `dce`, which keeps every call.
                    rewrite::erase_op(m, op);
                    self.changed = true;
                } else {
                    self.table.insert(key.clone(), op);
                    added.push(key);
                    i += 1;
                }
                continue;
            }
            if self.fold_known_if(m, op) {
                // The taken region's ops now stand at `i`; visit them next.
                self.changed = true;
                continue;
            }
            let writes = writes_layout(m, self.writers, op);
            let stores = writes_cells(m, self.pure, op);
            if writes {
                self.epoch += 1;
            }
            if stores {
                self.cell_epoch += 1;
            }
            let cond = kind
                .is_tree(tree::Op::If)
                .then(|| rewrite::resolve_value(m, m.ops[op].operands[0]));
            for (ri, r) in m.ops[op].regions.clone().into_iter().enumerate() {
                let blocks = m.regions[r].blocks.clone();
                if let [b] = blocks[..] {
                    let saved = cond.map(|c| (c, self.known.insert(c, ri == 0)));
                    self.block(m, b);
                    match saved {
                        Some((c, Some(prev))) => {
                            self.known.insert(c, prev);
                        }
                        Some((c, None)) => {
                            self.known.remove(&c);
                        }
                        None => {}
                    }
                }
            }
            if writes {
                self.epoch += 1;
            }
            if stores {
                self.cell_epoch += 1;
            }
            i += 1;
        }
        for k in added {
            self.table.remove(&k);
        }
    }

    /// Folds `op` when it is a `tree.if` on a condition an enclosing `tree.if` decides: the
    /// taken region's ops move before it and its results become the region's yielded values.
    /// Not when the taken region ends in `tree.return` (the rest of the block would be dead,
    /// which is `dce`'s business only once it is structured away).
    fn fold_known_if(&mut self, m: &mut Module, op: OpId) -> bool {
        if !m.ops[op].kind.is_tree(tree::Op::If) {
            return false;
        }
        let cond = rewrite::resolve_value(m, m.ops[op].operands[0]);
        let Some(&taken) = self.known.get(&cond) else {
            return false;
        };
        let Some(&region) = m.ops[op].regions.get(usize::from(!taken)) else {
            return false;
        };
        let ends_in_yield = m.regions[region].blocks.first().is_some_and(|&b| {
            m.blocks[b]
                .ops
                .last()
                .is_some_and(|&t| m.ops[t].kind.is_tree(tree::Op::Yield))
        });
        if !ends_in_yield {
            return false;
        }
        let Some(term) = rewrite::inline_region_before(m, region, op, &[]) else {
            return false;
        };
        let values = m.ops[term].operands.to_vec();
        rewrite::replace_op(m, op, &values);
        true
    }

    /// True for the ops this pass may merge.
    fn candidate(&self, m: &Module, op: OpId) -> bool {
        match m.ops[op].kind {
            OpKind::Tree(tree::Op::Var) => false,
            OpKind::Tree(tree::Op::Load) => true,
            OpKind::Tree(tree::Op::Call) => {
                callee_of(m, op).is_some_and(|f| self.pure.contains(&f))
            }
            OpKind::Tree(op) => op.is_pure(),
            OpKind::Mem(op) => op.is_pure(),
            OpKind::Lo(_) => false,
        }
    }
}

/// The equivalence key of `op`.
fn key_of(m: &Module, op: OpId, epoch: u32) -> Key {
    let o = &m.ops[op];
    (
        o.kind,
        o.operands
            .iter()
            .map(|&v| rewrite::resolve_value(m, v))
            .collect(),
        format!("{:?}", o.attrs),
        o.results.iter().map(|&r| m.value_type(r)).collect(),
        epoch,
    )
}

/// True when `op` (or an op in its regions) may write a layout: `mem.store`, a build op, a
/// call of a writer, or a call without a known callee.
fn writes_layout(m: &Module, writers: &FxHashSet<FuncId>, op: OpId) -> bool {
    let here = |op: OpId| {
        let o = &m.ops[op];
        match o.kind {
            OpKind::Tree(tree::Op::Call) => match o.callee() {
                Some(s) => m
                    .func_by_name(s)
                    .is_none_or(|g| writers.contains(&g) || m.is_declaration(g)),
                None => true,
            },
            kind => writes_directly(kind),
        }
    };
    if here(op) {
        return true;
    }
    let mut any = false;
    for &r in &m.ops[op].regions {
        walk::walk_region(m, r, walk::Order::Pre, &mut |inner| any |= here(inner));
    }
    any
}

/// The function a `tree.call` names, when the module has it.
fn callee_of(m: &Module, op: OpId) -> Option<FuncId> {
    m.ops[op].callee().and_then(|s| m.func_by_name(s))
}

/// True when `op` (or an op in its regions) may write a cell: `tree.store`, or a call of a
/// function that is not pure (it may store through a reference argument).
fn writes_cells(m: &Module, pure: &FxHashSet<FuncId>, op: OpId) -> bool {
    let here = |op: OpId| match m.ops[op].kind {
        OpKind::Tree(tree::Op::Store) => true,
        OpKind::Tree(tree::Op::Call) => callee_of(m, op).is_none_or(|f| !pure.contains(&f)),
        OpKind::Lo(_) => true,
        _ => false,
    };
    if here(op) {
        return true;
    }
    let mut any = false;
    for &r in &m.ops[op].regions {
        walk::walk_region(m, r, walk::Order::Pre, &mut |inner| any |= here(inner));
    }
    any
}

/// The pure functions (see the module comment), to a fixed point over the call graph.
fn pure_funcs(m: &Module, writers: &FxHashSet<FuncId>) -> FxHashSet<FuncId> {
    let mut calls: FxHashMap<FuncId, Vec<Option<FuncId>>> = FxHashMap::default();
    let mut pure = FxHashSet::default();
    for &f in &m.func_order {
        if m.is_declaration(f) || writers.contains(&f) {
            continue;
        }
        let func = &m.funcs[f];
        if func
            .params
            .iter()
            .chain(&func.results)
            .any(|&t| mentions_ref(m, t))
        {
            continue;
        }
        let mut callees = Vec::new();
        let mut ok = true;
        walk::walk_region(
            m,
            func.body,
            walk::Order::Pre,
            &mut |op| match m.ops[op].kind {
                OpKind::Tree(tree::Op::Call) => callees.push(callee_of(m, op)),
                OpKind::Tree(tree::Op::This | tree::Op::BuildLoad | tree::Op::ChildField)
                | OpKind::Lo(_) => ok = false,
                kind => ok &= !writes_directly(kind),
            },
        );
        if ok {
            pure.insert(f);
            calls.insert(f, callees);
        }
    }
    loop {
        let impure: Vec<FuncId> = pure
            .iter()
            .copied()
            .filter(|f| {
                calls[f]
                    .iter()
                    .any(|c| c.is_none_or(|g| !pure.contains(&g)))
            })
            .collect();
        if impure.is_empty() {
            return pure;
        }
        for f in impure {
            pure.remove(&f);
        }
    }
}

/// True when type `t` is or contains a `!tree.ref`.
fn mentions_ref(m: &Module, t: TypeId) -> bool {
    use scion_ir::types::Type;
    match m.types.get(t) {
        Type::Ref(_) => true,
        Type::Vector { elem, .. } | Type::Array { elem, .. } => mentions_ref(m, *elem),
        Type::Set(e) | Type::Option(e) => mentions_ref(m, *e),
        Type::Tuple(ts) => ts.iter().any(|&e| mentions_ref(m, e)),
        _ => false,
    }
}

/// True for the kinds that write a layout themselves (`lo` ops count: not analysed).
fn writes_directly(kind: OpKind) -> bool {
    matches!(
        kind,
        OpKind::Mem(mem::Op::Store)
            | OpKind::Tree(
                tree::Op::BuildStore
                    | tree::Op::BuildStoreBits
                    | tree::Op::BuildChild
                    | tree::Op::Append
            )
            | OpKind::Lo(_)
    )
}

/// The functions that may write a layout: those holding `mem.store` or a build op, and those
/// calling one of them (or a function without a body), to a fixed point.
pub(super) fn layout_writers(m: &Module) -> FxHashSet<FuncId> {
    let mut calls: FxHashMap<FuncId, Vec<String>> = FxHashMap::default();
    let mut writers = FxHashSet::default();
    for &f in &m.func_order {
        let mut callees = Vec::new();
        let mut writes = false;
        walk::walk_region(m, m.funcs[f].body, walk::Order::Pre, &mut |op| {
            let o = &m.ops[op];
            match o.kind {
                OpKind::Tree(tree::Op::Call) => match o.callee() {
                    Some(s) => callees.push(s.to_string()),
                    None => writes = true,
                },
                kind => writes |= writes_directly(kind),
            }
        });
        if writes {
            writers.insert(f);
        }
        calls.insert(f, callees);
    }
    loop {
        let mut grew = false;
        for &f in &m.func_order {
            if writers.contains(&f) {
                continue;
            }
            let bad = calls[&f].iter().any(|c| match m.func_by_name(c) {
                Some(g) => writers.contains(&g) || m.is_declaration(g),
                None => true,
            });
            if bad {
                writers.insert(f);
                grew = true;
            }
        }
        if !grew {
            return writers;
        }
    }
}
