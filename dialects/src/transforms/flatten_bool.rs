//! `flatten-bool`: turns a short-circuit `&&` or `||` whose right side is a few ops that cannot
//! trap into a plain `and` or `or` of both sides (level: any → same).
//!
//! The front end lowers `a || b` to `if a { true } else { b }` and `a && b` to
//! `if a { b } else { false }` (docs/language.md: the right side runs only when needed). When
//! `b` is cheap and has no effect, running it anyway gives the same value, and the chain of
//! conditions becomes one value and one branch:
//!
//! ```text
//! %2 = "tree.if"(%0) ({
//!   %k = "tree.const"() {value = true} : () -> i1
//!   "tree.yield"(%k) : (i1) -> ()
//! }, {
//!   %1 = "tree.cmp"(%u, %zero) {pred = "lt"} : (f32, f32) -> i1
//!   "tree.yield"(%1) : (i1) -> ()
//! }) : (i1) -> i1
//! // becomes
//! %1 = "tree.cmp"(%u, %zero) {pred = "lt"} : (f32, f32) -> i1
//! %2 = "tree.or"(%0, %1) : (i1, i1) -> i1
//! ```
//!
//! Why: a backend without if-conversion (Cranelift) otherwise emits one conditional branch per
//! condition, each mispredicted on its own on incoherent rays, and its code placement recomputes
//! values used on both sides of such a chain in each arm (the triangle test's `u`, `v` and
//! `1 / det` were computed up to four times per test). LLVM's SimplifyCFG does the same
//! speculation by itself.
//!
//! What may be run unconditionally: ops without regions of the `tree` arithmetic, comparison,
//! logic, select, cast, aggregate (tuple, extract, field, vector, lane) kinds, reads of a
//! variable (`tree.load`: nothing runs between the `if` and its arm), and the `min`, `max` and
//! `abs` intrinsics; integer division and remainder (which trap on zero), calls, stores, layout
//! reads (`mem` ops) and nested regions are never speculated. Only arms of at most `max-ops`
//! such ops (option `flatten-bool:max-ops=N`, default 3; constants are free) are flattened, so
//! a long condition keeps its branch. Nested conditions flatten from the inside out (a walk in
//! post-order), so `a || b || c` becomes `(a | b) | c`.

use crate::attr::Attr;
use crate::builder::{Builder, InsertPoint};
use crate::diag::Diagnostic;
use crate::entity::{OpId, RegionId, ValueId};
use crate::module::Module;
use crate::op::OpKind;
use crate::pass::{Pass, PassCx, PassError};
use crate::rewrite;
use crate::tree::Op;
use crate::types::Type;
use crate::walk;

/// The default largest arm flattened, in ops that are not constants.
pub const DEFAULT_MAX_OPS: usize = 3;

/// The `flatten-bool` pass.
#[derive(Default)]
pub struct FlattenBool;

impl Pass for FlattenBool {
    fn name(&self) -> &'static str {
        "flatten-bool"
    }

    fn summary(&self) -> &'static str {
        "Turn `&&`/`||` whose right side is a few ops that cannot trap into `and`/`or` (one branch)"
    }

    fn run(&mut self, m: &mut Module, cx: &mut PassCx) -> Result<bool, PassError> {
        let max = match cx.option("flatten-bool", "max-ops") {
            None => DEFAULT_MAX_OPS,
            Some(s) => s.parse::<usize>().map_err(|_| {
                PassError::Diagnostics(
                    Diagnostic::error(
                        "E0962",
                        format!("flatten-bool:max-ops={s}: expected a non-negative integer"),
                    )
                    .into(),
                )
            })?,
        };
        Ok(run(m, max))
    }
}

/// Flattens every qualifying `tree.if` of the module; returns whether anything changed.
pub fn run(m: &mut Module, max_ops: usize) -> bool {
    let mut changed = false;
    for f in m.func_order.clone() {
        for op in walk::func_ops(m, f, walk::Order::Post) {
            changed |= flatten(m, op, max_ops);
        }
    }
    changed
}

/// The boolean constant `v` stands for, if it is one.
fn const_bool(m: &Module, v: ValueId) -> Option<bool> {
    let v = rewrite::resolve_value(m, v);
    let def = m.def_op(v)?;
    let o = &m.ops[def];
    if !o.kind.is_tree(Op::Const) {
        return None;
    }
    match o.attr("value") {
        Some(Attr::Bool(b)) => Some(*b),
        _ => None,
    }
}

/// The value a one-block region yields, when it yields exactly one and has no arguments.
fn yielded(m: &Module, r: RegionId) -> Option<ValueId> {
    let [b] = m.regions[r].blocks[..] else {
        return None;
    };
    if !m.blocks[b].args.is_empty() {
        return None;
    }
    let &term = m.blocks[b].ops.last()?;
    let t = &m.ops[term];
    if !t.kind.is_tree(Op::Yield) || t.operands.len() != 1 {
        return None;
    }
    Some(rewrite::resolve_value(m, t.operands[0]))
}

/// Whether running `op` when its arm would not have run changes nothing and cannot trap.
fn speculatable(m: &Module, op: OpId) -> bool {
    let o = &m.ops[op];
    if !o.regions.is_empty() || !o.successors.is_empty() {
        return false;
    }
    let OpKind::Tree(k) = o.kind else {
        return false;
    };
    match k {
        Op::Const
        | Op::Add
        | Op::Sub
        | Op::Mul
        | Op::Neg
        | Op::And
        | Op::Or
        | Op::Xor
        | Op::Shl
        | Op::Shr
        | Op::BitNot
        | Op::Not
        | Op::Cmp
        | Op::Select
        | Op::Cast
        | Op::Bitcast
        | Op::Tuple
        | Op::Extract
        | Op::Field
        | Op::Vector
        | Op::Lane
        | Op::Load => true,
        Op::Div | Op::Rem => o.results.first().is_some_and(|&r| {
            let t = m.types.scalar_of(m.values[r].ty);
            m.types.as_float(t).is_some()
        }),
        Op::Intrinsic => matches!(o.str_attr("name"), Some("min" | "max" | "abs")),
        _ => false,
    }
}

/// The arm's ops (all but its `yield`) when they may all run unconditionally and at most
/// `max_ops` of them are not constants.
fn cheap_arm(m: &Module, r: RegionId, max_ops: usize) -> Option<()> {
    let [b] = m.regions[r].blocks[..] else {
        return None;
    };
    let ops = &m.blocks[b].ops;
    let body = &ops[..ops.len().checked_sub(1)?];
    if !body.iter().all(|&o| speculatable(m, o)) {
        return None;
    }
    let cost = body
        .iter()
        .filter(|&&o| !m.ops[o].kind.is_tree(Op::Const))
        .count();
    (cost <= max_ops).then_some(())
}

/// Flattens `op` when it is a qualifying `tree.if`; returns whether it did.
fn flatten(m: &mut Module, op: OpId, max_ops: usize) -> bool {
    let o = &m.ops[op];
    if !o.kind.is_tree(Op::If) || o.parent.is_none() || o.regions.len() != 2 {
        return false;
    }
    let [res] = o.results[..] else {
        return false;
    };
    let i1 = m.values[res].ty;
    if *m.types.get(i1) != Type::Bool {
        return false;
    }
    let cond = rewrite::resolve_value(m, o.operands[0]);
    let (then_r, else_r) = (o.regions[0], o.regions[1]);
    // Which arm is the constant, its value, and the other arm.
    let (k_in_then, k, arm) = match (
        yielded(m, then_r).and_then(|v| const_bool(m, v)),
        yielded(m, else_r).and_then(|v| const_bool(m, v)),
    ) {
        (Some(k), _) => (true, k, else_r),
        (None, Some(k)) => (false, k, then_r),
        (None, None) => return false,
    };
    if cheap_arm(m, arm, max_ops).is_none() {
        return false;
    }
    let span = m.span(op);
    let Some(term) = rewrite::inline_region_before(m, arm, op, &[]) else {
        return false;
    };
    let x = rewrite::resolve_value(m, m.ops[term].operands[0]);
    let mut b = Builder::new(m);
    b.set_insertion_point(InsertPoint::Before(op));
    b.set_span(span);
    // `if c {k} else {x}`: k true is `c | x`, k false `!c & x`; `if c {x} else {k}`: k false is
    // `c & x`, k true `!c | x`.
    let c = if k_in_then == k {
        cond
    } else {
        b.build1(Op::Not, &[cond], i1)
    };
    let v = b.build1(if k { Op::Or } else { Op::And }, &[c, x], i1);
    rewrite::replace_op(m, op, &[v]);
    true
}
