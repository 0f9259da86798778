//! Walks over the nested structure: the ops of a region, a function or a module, in pre-order
//! (an op before the ops of its regions) or post-order (after them), plus the small analyses
//! passes build on demand instead of maintaining use-lists (use counts, removability).
//!
//! Walks follow block lists, so detached (erased) ops are never visited.

use crate::entity::{FuncId, OpId, RegionId, ValueId};
use crate::module::Module;
use crate::op::OpKind;
use crate::tree;
use rustc_hash::FxHashMap;

/// Whether an op is visited before or after the ops nested in its regions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    /// Parents first.
    Pre,
    /// Children first.
    Post,
}

/// Calls `f` on every op of `region` and of the regions nested in it.
pub fn walk_region(m: &Module, region: RegionId, order: Order, f: &mut impl FnMut(OpId)) {
    for &b in &m.regions[region].blocks {
        for &op in &m.blocks[b].ops {
            if order == Order::Pre {
                f(op);
            }
            for &r in &m.ops[op].regions {
                walk_region(m, r, order, f);
            }
            if order == Order::Post {
                f(op);
            }
        }
    }
}

/// Every op of a function's body, nested ones included, in the given order.
pub fn func_ops(m: &Module, func: FuncId, order: Order) -> Vec<OpId> {
    let mut out = Vec::new();
    walk_region(m, m.funcs[func].body, order, &mut |op| out.push(op));
    out
}

/// Every op of a region, nested ones included, in pre-order.
pub fn region_ops(m: &Module, region: RegionId) -> Vec<OpId> {
    let mut out = Vec::new();
    walk_region(m, region, Order::Pre, &mut |op| out.push(op));
    out
}

/// How many times each value is read (as an operand or a successor argument) inside `func`.
pub fn use_counts(m: &Module, func: FuncId) -> FxHashMap<ValueId, u32> {
    let mut counts = FxHashMap::default();
    walk_region(m, m.funcs[func].body, Order::Pre, &mut |op| {
        let o = &m.ops[op];
        for &v in o
            .operands
            .iter()
            .chain(o.successors.iter().flat_map(|s| s.args.iter()))
        {
            *counts.entry(v).or_insert(0) += 1;
        }
    });
    counts
}

/// True when removing `op` (if its results are unused) changes nothing observable: its kind is
/// pure, or it is a `tree.if`/`tree.match` whose regions hold only removable ops and yields.
/// A `tree.return` inside a region makes the op not removable (it may leave the function).
pub fn is_removable(m: &Module, op: OpId) -> bool {
    let o = &m.ops[op];
    match o.kind {
        OpKind::Tree(tree::Op::If | tree::Op::Match) => o.regions.iter().all(|&r| {
            region_ops(m, r)
                .into_iter()
                .all(|inner| m.ops[inner].kind.is_tree(tree::Op::Yield) || is_removable(m, inner))
        }),
        kind => kind.is_pure(),
    }
}
