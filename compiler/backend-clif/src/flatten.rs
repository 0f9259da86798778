//! Short-circuit conditions as one value: the Cranelift backend's preparation of a `lo` module
//! (after [`scion_ir::lo::directed::expanded`], before [`crate::translate`]).
//!
//! The front end lowers `a || b` to `if a { true } else { b }` and `a && b` to
//! `if a { b } else { false }`, which reach `lo` as a diamond: the block testing `a` branches to
//! an arm yielding the constant and to an arm computing `b`, and both jump to a join block whose
//! one `i1` argument is the condition's value. When `b`'s arm is a few ops that cannot trap,
//! running it unconditionally gives the same value, and the diamond becomes
//! `%r = or %a, %b` (or `and`, with `not %a` where the constant arm is the other one) and a jump
//! to the join:
//!
//! ```text
//!   "lo.cond_br"(%a)[^t, ^f]                 %b = "lo.cmp"(%u, %zero) {pred = "lt"}
//! ^t: %k = "lo.const"() {value = true}       %r = "lo.or"(%a, %b)
//!     "lo.br"()[^j(%k)]               ==>    "lo.br"()[^j(%r)]
//! ^f: %b = "lo.cmp"(%u, %zero) {pred = "lt"}
//!     "lo.br"()[^j(%b)]
//! ```
//!
//! Why here: Cranelift does not if-convert, so each condition of a chain was a conditional
//! branch of its own (each mispredicted on its own on incoherent rays), and its code placement
//! recomputes the values the conditions share in each arm (the triangle test's `u`, `v` and
//! `1 / det` were computed up to four times per test). LLVM's SimplifyCFG does this speculation
//! by itself, by its own cost model, so the LLVM backend gets the diamonds as they are (done at
//! the tree level for both backends, it made LLVM's code 1-3 % slower).
//!
//! What may run unconditionally: `lo` ops that are pure and cannot trap (everything but loads,
//! stores, calls, stack slots, thread ids, and integer division and remainder, which trap on
//! zero); at most [`MAX_OPS`] of them that are not constants. Chains flatten from the inside
//! out, so `a || b || c` becomes `(a | b) | c`; the arms left behind are unreachable, and the
//! translation (reverse post-order from the entry) never sees them.

use rustc_hash::FxHashMap;
use scion_ir::attr::Attr;
use scion_ir::entity::{BlockId, FuncId, OpId, ValueId};
use scion_ir::lo::Op as L;
use scion_ir::op::OpKind;
use scion_ir::rewrite;
use scion_ir::types::Type;
use scion_ir::{Builder, Module, OpSpec};

/// The largest arm run unconditionally, in ops that are not constants.
pub const MAX_OPS: usize = 3;

/// Flattens every qualifying diamond of `m`'s functions; returns whether anything changed.
pub fn flatten(m: &mut Module) -> bool {
    let mut changed = false;
    for f in m.func_order.clone() {
        if m.is_declaration(f) {
            continue;
        }
        while flatten_one(m, f) {
            changed = true;
        }
    }
    rewrite::resolve_aliases(m);
    changed
}

/// The edges into each block of `f`: (terminator, successor index).
pub(crate) fn predecessors(m: &Module, f: FuncId) -> FxHashMap<BlockId, Vec<(OpId, usize)>> {
    let mut preds: FxHashMap<BlockId, Vec<(OpId, usize)>> = FxHashMap::default();
    for &b in &m.regions[m.funcs[f].body].blocks {
        if let Some(&t) = m.blocks[b].ops.last() {
            for (i, s) in m.ops[t].successors.iter().enumerate() {
                preds.entry(s.block).or_default().push((t, i));
            }
        }
    }
    preds
}

/// Whether running `op` where its block would not have run changes nothing and cannot trap.
pub(crate) fn speculatable(m: &Module, op: OpId) -> bool {
    let o = &m.ops[op];
    let OpKind::Lo(k) = o.kind else {
        return false;
    };
    match k {
        L::Load | L::Store | L::Call | L::StackSlot | L::GlobalId => false,
        L::Br | L::CondBr | L::Return => false,
        L::Div | L::Rem => o
            .results
            .first()
            .is_some_and(|&r| m.types.as_float(m.values[r].ty).is_some()),
        _ => k.is_pure(),
    }
}

/// The boolean constant `v` is, if it is one.
fn const_bool(m: &Module, v: ValueId) -> Option<bool> {
    let o = &m.ops[m.def_op(v)?];
    if o.kind != OpKind::Lo(L::Const) {
        return None;
    }
    match o.attr("value") {
        Some(Attr::Bool(b)) => Some(*b),
        _ => None,
    }
}

/// An arm of a diamond: a block entered only from the test, no arguments, ending in a `br` to
/// the join with one value. Returns (its ops but the `br`, the join, the value).
fn arm(
    m: &Module,
    preds: &FxHashMap<BlockId, Vec<(OpId, usize)>>,
    b: BlockId,
) -> Option<(Vec<OpId>, BlockId, ValueId)> {
    if preds.get(&b).map_or(0, Vec::len) != 1 || !m.blocks[b].args.is_empty() {
        return None;
    }
    let (&term, body) = m.blocks[b].ops.split_last()?;
    let t = &m.ops[term];
    if t.kind != OpKind::Lo(L::Br) {
        return None;
    }
    let [s] = &t.successors[..] else {
        return None;
    };
    let [v] = s.args[..] else {
        return None;
    };
    Some((body.to_vec(), s.block, v))
}

/// Flattens the first qualifying diamond of `f`; returns whether there was one.
fn flatten_one(m: &mut Module, f: FuncId) -> bool {
    let preds = predecessors(m, f);
    let blocks = m.regions[m.funcs[f].body].blocks.clone();
    for head in blocks {
        let Some(&term) = m.blocks[head].ops.last() else {
            continue;
        };
        let t = &m.ops[term];
        if t.kind != OpKind::Lo(L::CondBr) || t.successors.len() != 2 {
            continue;
        }
        let (tb, fb) = (t.successors[0].block, t.successors[1].block);
        if tb == fb || !t.successors.iter().all(|s| s.args.is_empty()) {
            continue;
        }
        let cond = t.operands[0];
        let (Some((t_ops, tj, tv)), Some((f_ops, fj, fv))) =
            (arm(m, &preds, tb), arm(m, &preds, fb))
        else {
            continue;
        };
        let join = tj;
        if fj != join
            || preds.get(&join).map_or(0, Vec::len) != 2
            || m.blocks[join].args.len() != 1
            || *m.types.get(m.values[m.blocks[join].args[0]].ty) != Type::Bool
        {
            continue;
        }
        // The constant arm (its value, whether it is the `true` successor) and the other one.
        let (k, k_on_true, src, ops, x) = match (const_bool(m, tv), const_bool(m, fv)) {
            (Some(k), _) if t_ops.iter().all(|&o| m.ops[o].kind == OpKind::Lo(L::Const)) => {
                (k, true, fb, f_ops, fv)
            }
            (_, Some(k)) if f_ops.iter().all(|&o| m.ops[o].kind == OpKind::Lo(L::Const)) => {
                (k, false, tb, t_ops, tv)
            }
            _ => continue,
        };
        if !ops.iter().all(|&o| speculatable(m, o)) {
            continue;
        }
        let cost = ops
            .iter()
            .filter(|&&o| m.ops[o].kind != OpKind::Lo(L::Const))
            .count();
        if cost > MAX_OPS {
            continue;
        }
        // Move the arm's ops before the test's branch, then compute the condition's value and
        // jump to the join with it.
        let pos = m.blocks[head].ops.len() - 1;
        for (i, &o) in ops.iter().enumerate() {
            m.blocks[src].ops.retain(|&x| x != o);
            m.ops[o].parent = Some(head);
            m.blocks[head].ops.insert(pos + i, o);
        }
        let i1 = m.values[m.blocks[join].args[0]].ty;
        let span = m.span(term);
        rewrite::erase_op(m, term);
        let mut b = Builder::at_end(m, head);
        b.set_span(span);
        // `if c {k} else {x}`: k true is `c | x`, k false `!c & x`; `if c {x} else {k}`: k
        // false is `c & x`, k true `!c | x`.
        let c = if k_on_true == k {
            cond
        } else {
            b.build1(L::Not, &[cond], i1)
        };
        let r = b.build1(if k { L::Or } else { L::And }, &[c, x], i1);
        b.insert(OpSpec::new(L::Br).successor(join, &[r]));
        // The arms are unreachable now: empty them so that no one reads them as edges into
        // the join.
        for arm_block in [tb, fb] {
            let rest = std::mem::take(&mut m.blocks[arm_block].ops);
            for o in rest {
                m.ops[o].parent = None;
            }
        }
        m.regions[m.funcs[f].body]
            .blocks
            .retain(|&x| x != tb && x != fb);
        return true;
    }
    false
}
