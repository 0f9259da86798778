//! `mem-inline`: inlines calls of small non-recursive functions on the structured `tree`/`mem`
//! level (level: any → same; paper §7.3, "inlining of small functions"). Run before `mem-cse`,
//! it puts the bodies of `intersects(Ray, AABB)` and `distmin(Ray, AABB)` side by side in the
//! traversal, so that their two `slab_interval(ray, box)` calls on the same ray and box become
//! one (`mem-cse` merges calls of pure functions).
//!
//! A callee qualifies when it is defined, is not recursive (not on a cycle of the call graph,
//! itself included), has a single-block body of structured `tree`/`mem` ops with at most
//! `max-ops` ops counted through its regions (option `mem-inline:max-ops=N`, default
//! [`DEFAULT_MAX_OPS`]), holds none of the build-function ops (`tree.this`, `tree.build_*`,
//! `tree.append`, whose meaning is tied to the function placing a node) and no `tree.return`
//! inside a `tree.foreach`. Functions are visited callees first, so a callee's size is counted
//! after its own small callees were inlined into it. The callees stay in the module (they may
//! be entry points or have other callers); `dce` does not remove functions.
//!
//! Inlining a call copies the callee's body, makes the copy single-exit (below), replaces the
//! copy's parameters by the call's arguments, moves its ops before the call and replaces the
//! call's results by the operands of the copy's final `tree.return`.
//!
//! Single exit. A `tree.return` inside a region leaves the function from any depth; once
//! inlined it must leave only the inlined body. The first op of a block ending in
//! `tree.return` whose regions hold a `tree.return` (a `tree.if` or `tree.match`) takes the
//! rest of the block into each region that ends in `tree.yield` (a copy per such region, the
//! op's results replaced by the yielded values); then every region ends in `tree.return`, is
//! made single-exit in turn, and its final `tree.return` becomes a `tree.yield`; the op now
//! yields the function's results and the block ends in `tree.return` of them:
//!
//! ```text
//! tree.if(%c) ({ tree.return(%a) }, { tree.yield() })     %r = tree.if(%c) ({ tree.yield(%a) },
//! %b = tree.add(%x, %y)                              →              { %b = tree.add(%x, %y)
//! tree.return(%b)                                                     tree.yield(%b) })
//!                                                         tree.return(%r)
//! ```

use rustc_hash::{FxHashMap, FxHashSet};
use scion_ir::diag::Diagnostic;
use scion_ir::op::OpKind;
use scion_ir::rewrite::{
    clone_region, erase_op, inline_region_before, replace_all_uses, resolve_aliases,
};
use scion_ir::{tree, walk, BlockId, Builder, FuncId, Module, OpId, OpSpec, ValueId};
use scion_ir::{Pass, PassCx, PassError};

/// The default size limit of an inlined callee, in ops (nested regions included). It takes
/// the prelude's geometric predicates (`intersects` and `distmin` on boxes and triangles, 2 to
/// 10 ops) and `slab_lane` (31), and leaves the larger kernels (`slab_interval`, 50 ops and
/// more once its lanes are inlined; `hit_distance`, 66) as calls, which `mem-cse` merges when
/// repeated.
pub const DEFAULT_MAX_OPS: usize = 32;

/// The pass object.
#[derive(Default)]
pub struct MemInline;

impl Pass for MemInline {
    fn name(&self) -> &'static str {
        "mem-inline"
    }

    fn summary(&self) -> &'static str {
        "inline calls of small non-recursive tree/mem functions"
    }

    fn run(&mut self, m: &mut Module, cx: &mut PassCx) -> Result<bool, PassError> {
        let max = match cx.option("mem-inline", "max-ops") {
            None => DEFAULT_MAX_OPS,
            Some(s) => s.parse::<usize>().map_err(|_| {
                PassError::Diagnostics(
                    Diagnostic::error(
                        "E0962",
                        format!("mem-inline:max-ops={s}: expected a non-negative integer"),
                    )
                    .into(),
                )
            })?,
        };
        Ok(run(m, max))
    }
}

/// Inlines qualifying calls in the whole module; returns whether anything changed.
pub fn run(m: &mut Module, max_ops: usize) -> bool {
    let graph = CallGraph::of(m);
    let recursive = graph.recursive();
    let mut changed = false;
    for g in graph.bottom_up() {
        let sites: Vec<(OpId, FuncId)> = walk::func_ops(m, g, walk::Order::Pre)
            .into_iter()
            .filter_map(|op| Some((op, callee(m, op)?)))
            .collect();
        for (call, f) in sites {
            if f == g || recursive.contains(&f) || !inlinable(m, f, max_ops) {
                continue;
            }
            if inline_call(m, call, f) {
                // The next copy of this function's body must see its own values, not aliases.
                resolve_aliases(m);
                changed = true;
            }
        }
    }
    changed
}

/// The defined function a `tree.call` names.
fn callee(m: &Module, op: OpId) -> Option<FuncId> {
    let o = &m.ops[op];
    if !o.kind.is_tree(tree::Op::Call) {
        return None;
    }
    let f = m.func_by_name(o.callee()?)?;
    (!m.is_declaration(f)).then_some(f)
}

/// True when `f`'s body may be copied into a caller (size and shape; recursion is checked by
/// the caller).
fn inlinable(m: &Module, f: FuncId, max_ops: usize) -> bool {
    let body = m.funcs[f].body;
    let [entry] = m.regions[body].blocks[..] else {
        return false;
    };
    let ends_in_return = m.blocks[entry]
        .ops
        .last()
        .is_some_and(|&t| m.ops[t].kind.is_tree(tree::Op::Return));
    if !ends_in_return {
        return false;
    }
    let mut count = 0usize;
    let mut ok = true;
    walk::walk_region(m, body, walk::Order::Pre, &mut |op| {
        count += 1;
        let o = &m.ops[op];
        ok &= match o.kind {
            OpKind::Tree(
                tree::Op::This
                | tree::Op::BuildStore
                | tree::Op::BuildStoreBits
                | tree::Op::BuildChild
                | tree::Op::BuildLoad
                | tree::Op::ChildField
                | tree::Op::Append,
            ) => false,
            OpKind::Tree(tree::Op::Foreach) => !o.regions.iter().any(|&r| holds_return(m, r)),
            OpKind::Lo(_) => false,
            _ => true,
        };
    });
    ok && count <= max_ops
}

/// True when a `tree.return` occurs anywhere in `region`.
fn holds_return(m: &Module, region: scion_ir::RegionId) -> bool {
    let mut any = false;
    walk::walk_region(m, region, walk::Order::Pre, &mut |op| {
        any |= m.ops[op].kind.is_tree(tree::Op::Return)
    });
    any
}

/// Replaces the call `call` of `f` by a single-exit copy of `f`'s body; false (nothing
/// changed) when the copy cannot be made single-exit.
fn inline_call(m: &mut Module, call: OpId, f: FuncId) -> bool {
    let mut map = FxHashMap::default();
    let copy = clone_region(m, m.funcs[f].body, &mut map);
    let [entry] = m.regions[copy].blocks[..] else {
        return false;
    };
    if !single_exit(m, entry) {
        return false;
    }
    let args = m.ops[call].operands.to_vec();
    let Some(ret) = inline_region_before(m, copy, call, &args) else {
        return false;
    };
    let values = m.ops[ret].operands.to_vec();
    for (r, v) in m.ops[call].results.clone().into_iter().zip(values) {
        replace_all_uses(m, r, v);
    }
    erase_op(m, call);
    true
}

/// Rewrites `block`, which ends in `tree.return`, so that its final op is its only
/// `tree.return` (see the module comment). False when an op holding a `tree.return` is not a
/// `tree.if` or `tree.match` (a `tree.foreach`; [`inlinable`] excludes those beforehand).
fn single_exit(m: &mut Module, block: BlockId) -> bool {
    let ops = m.blocks[block].ops.clone();
    let Some((&ret, body)) = ops.split_last() else {
        return false;
    };
    if !m.ops[ret].kind.is_tree(tree::Op::Return) {
        return false;
    }
    let Some(i) = body
        .iter()
        .position(|&op| m.ops[op].regions.iter().any(|&r| holds_return(m, r)))
    else {
        return true;
    };
    let op = ops[i];
    if !matches!(m.ops[op].kind, OpKind::Tree(tree::Op::If | tree::Op::Match)) {
        return false;
    }
    let ret_types: Vec<_> = m.ops[ret]
        .operands
        .iter()
        .map(|&v| m.value_type(v))
        .collect();
    // The rest of the block moves to a detached region, copied from there into each region
    // that falls through.
    let rest_region = m.new_region();
    let rest_block = m.add_block(rest_region, &[]);
    let rest: Vec<OpId> = m.blocks[block].ops.split_off(i + 1);
    for &o in &rest {
        m.ops[o].parent = Some(rest_block);
    }
    m.blocks[rest_block].ops = rest;
    let results = m.ops[op].results.to_vec();
    let regions = m.ops[op].regions.to_vec();
    for &r in &regions {
        let [rb] = m.regions[r].blocks[..] else {
            return false;
        };
        let Some(&term) = m.blocks[rb].ops.last() else {
            return false;
        };
        if m.ops[term].kind.is_tree(tree::Op::Yield) {
            let mut map: FxHashMap<ValueId, ValueId> = results
                .iter()
                .copied()
                .zip(m.ops[term].operands.iter().copied())
                .collect();
            erase_op(m, term);
            let copy = clone_region(m, rest_region, &mut map);
            let cb = m.regions[copy].blocks[0];
            let moved = std::mem::take(&mut m.blocks[cb].ops);
            for &o in &moved {
                m.ops[o].parent = Some(rb);
            }
            m.blocks[rb].ops.extend(moved);
        }
        if !single_exit(m, rb) {
            return false;
        }
        let Some(&last) = m.blocks[rb].ops.last() else {
            return false;
        };
        let vals = m.ops[last].operands.to_vec();
        let span = m.span(last);
        erase_op(m, last);
        let mut b = Builder::at_end(m, rb);
        b.set_span(span);
        b.insert(OpSpec::new(tree::Op::Yield).operands(&vals));
    }
    // The op again, now yielding the function's results.
    let o = m.ops[op].clone();
    let mut spec = OpSpec::new(o.kind)
        .operands(&o.operands)
        .results(&ret_types);
    spec.attrs = o.attrs.clone();
    for &r in &regions {
        spec = spec.region(r);
    }
    m.ops[op].regions.clear();
    let span = m.span(op);
    let mut b = Builder::at_end(m, block);
    b.set_span(span);
    let new = b.insert(spec);
    let vals: Vec<ValueId> = (0..ret_types.len()).map(|i| b.result(new, i)).collect();
    b.insert(OpSpec::new(tree::Op::Return).operands(&vals));
    let pos = m.blocks[block].ops.iter().position(|&x| x == op);
    if let Some(pos) = pos {
        m.blocks[block].ops.remove(pos);
        m.ops[op].parent = None;
    }
    true
}

/// The call graph of the defined functions (by `tree.call`).
struct CallGraph {
    order: Vec<FuncId>,
    callees: FxHashMap<FuncId, Vec<FuncId>>,
}

impl CallGraph {
    fn of(m: &Module) -> CallGraph {
        let order: Vec<FuncId> = m
            .func_order
            .iter()
            .copied()
            .filter(|&f| !m.is_declaration(f))
            .collect();
        let callees = order
            .iter()
            .map(|&f| {
                let mut cs: Vec<FuncId> = walk::func_ops(m, f, walk::Order::Pre)
                    .into_iter()
                    .filter_map(|op| callee(m, op))
                    .collect();
                cs.dedup();
                (f, cs)
            })
            .collect();
        CallGraph { order, callees }
    }

    /// The functions on a cycle (a function calling itself included).
    fn recursive(&self) -> FxHashSet<FuncId> {
        self.order
            .iter()
            .copied()
            .filter(|&f| {
                let mut seen = FxHashSet::default();
                let mut stack = self.callees[&f].clone();
                while let Some(g) = stack.pop() {
                    if g == f {
                        return true;
                    }
                    if seen.insert(g) {
                        stack.extend(self.callees.get(&g).into_iter().flatten().copied());
                    }
                }
                false
            })
            .collect()
    }

    /// The functions callees first (depth-first post-order; a cycle is cut where it closes).
    fn bottom_up(&self) -> Vec<FuncId> {
        let mut out = Vec::new();
        let mut seen = FxHashSet::default();
        for &f in &self.order {
            self.post(f, &mut seen, &mut out);
        }
        out
    }

    fn post(&self, f: FuncId, seen: &mut FxHashSet<FuncId>, out: &mut Vec<FuncId>) {
        if !seen.insert(f) {
            return;
        }
        for &g in self.callees.get(&f).into_iter().flatten() {
            self.post(g, seen, out);
        }
        out.push(f);
    }
}
