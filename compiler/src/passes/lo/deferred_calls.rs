//! `recursion-to-stack` for recursive calls anywhere in the body (under conditions, in an
//! unrolled loop over eight children), when running them later changes nothing the body sees.
//!
//! The body of a visit runs to its end with each recursive call replaced by a push of its
//! arguments; when the visit ends, the entries it pushed are reversed in place, so the loop pops
//! them in call order: the calls run in the recursion's order, each subtree before the next
//! call's, only after the visit instead of in the middle of it. That is the recursion exactly
//! when nothing after a call in the body observes the call: after a recursive call the body may
//! only compute, branch, read memory the recursive calls never write (the layout's buffers,
//! read through a parameter nothing stores through), use its own frame, call functions that
//! take no pointers, and make more recursive calls. Whatever else follows a call is E0971,
//! naming what.
//!
//! **Visits with known calls.** Where every path of a visit to one of its ends makes the same
//! calls (an arm that ends with `hit(a); hit(b);`, or one that makes none), that end needs no
//! reversal: it pushes the calls' arguments last first and jumps straight back into the body
//! with the first call's (the tail-call scheme of [`super::recursion_to_stack`]), and those
//! calls push nothing where they stand. An end reached by paths with different calls (calls
//! under conditions) keeps the pushes and the reversal. [`known_ends`] finds the ends.
//!
//! The stack pointer lives in a frame cell (promoted to a register by LLVM); a full stack
//! returns status 1 as in the tail-call scheme of [`super::recursion_to_stack`].

use super::recursion_to_stack::exits_quietly;
use super::recursion_to_stack::{
    body_of, changed_args, check_stack_bytes, drop_unreachable, entry_addr, exits, not_tail,
    split_at_call, split_entry, Stack,
};
use rustc_hash::{FxHashMap, FxHashSet};
use scion_ir::attr::Attr;
use scion_ir::diag::Diagnostic;
use scion_ir::entity::{BlockId, FuncId, OpId, ValueId};
use scion_ir::lo::Op as L;
use scion_ir::module::ValueDef;
use scion_ir::op::OpKind;
use scion_ir::tree::CmpPred;
use scion_ir::types::Type;
use scion_ir::{Builder, InsertPoint, Module};

/// Where a pointer comes from.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Root {
    /// Parameter `i` (or memory reached through it).
    Param(usize),
    /// The function's own frame.
    Frame,
    /// Anything else (a block argument of a loop, a call's result).
    Unknown,
}

fn root(m: &Module, params: &[ValueId], mut v: ValueId) -> Root {
    for _ in 0..64 {
        if let Some(i) = params.iter().position(|&p| p == v) {
            return Root::Param(i);
        }
        let ValueDef::Result(op, _) = m.values[v].def else {
            return Root::Unknown;
        };
        match m.ops[op].kind {
            OpKind::Lo(L::StackSlot) => return Root::Frame,
            OpKind::Lo(L::PtrAdd | L::Load) => v = m.ops[op].operands[0],
            _ => return Root::Unknown,
        }
    }
    Root::Unknown
}

fn is_ptr(m: &Module, v: ValueId) -> bool {
    matches!(m.types.get(m.values[v].ty), Type::Ptr)
}

/// Why running the calls of `f` after the rest of the visit could change what the body
/// computes: the first op after a call that might observe it, and what it does.
fn check(m: &Module, f: FuncId, calls: &[OpId], params: &[ValueId]) -> Result<(), (OpId, String)> {
    let name = m.funcs[f].name.as_str();
    let region = m.funcs[f].body;
    let blocks = m.regions[region].blocks.clone();
    let is_self =
        |op: OpId| m.ops[op].kind == OpKind::Lo(L::Call) && m.ops[op].callee() == Some(name);
    // Parameters written through: stores, pointers passed to other functions, or to the
    // recursion at another position.
    let mut written: FxHashSet<usize> = FxHashSet::default();
    for &b in &blocks {
        for &op in &m.blocks[b].ops {
            let o = &m.ops[op];
            match o.kind {
                OpKind::Lo(L::Store) => {
                    if let Root::Param(i) = root(m, params, o.operands[0]) {
                        written.insert(i);
                    }
                }
                OpKind::Lo(L::Call) => {
                    for (k, &a) in o.operands.iter().enumerate() {
                        if !is_ptr(m, a) {
                            continue;
                        }
                        if let Root::Param(i) = root(m, params, a) {
                            if !is_self(op) || k != i {
                                written.insert(i);
                            }
                        }
                    }
                }
                _ => {}
            }
        }
    }
    // Everything that runs after a recursive call: the rest of its block, and every block
    // reachable from there.
    let mut after: Vec<OpId> = Vec::new();
    let mut seen: FxHashSet<BlockId> = FxHashSet::default();
    let mut work: Vec<BlockId> = Vec::new();
    for &c in calls {
        let b = m.ops[c].parent.expect("placed");
        let ops = &m.blocks[b].ops;
        let at = ops.iter().position(|&o| o == c).expect("listed");
        after.extend(&ops[at + 1..]);
        if let Some(&t) = ops.last() {
            work.extend(m.ops[t].successors.iter().map(|s| s.block));
        }
    }
    while let Some(b) = work.pop() {
        if !seen.insert(b) {
            continue;
        }
        after.extend(&m.blocks[b].ops);
        if let Some(&t) = m.blocks[b].ops.last() {
            work.extend(m.ops[t].successors.iter().map(|s| s.block));
        }
    }
    for op in after {
        let o = &m.ops[op];
        let fail = |why: &str| Err((op, why.to_string()));
        match o.kind {
            _ if is_self(op) => {}
            OpKind::Lo(L::Br | L::CondBr) => {}
            OpKind::Lo(L::Return) if o.operands.is_empty() => {}
            OpKind::Lo(L::Load) => match root(m, params, o.operands[0]) {
                Root::Frame => {}
                Root::Param(i) if !written.contains(&i) => {}
                _ => {
                    return fail(
                        "it reads memory the recursive call may write (read the mutable \
                         state before the children, or test it when a child is visited)",
                    )
                }
            },
            OpKind::Lo(L::Store) => {
                if root(m, params, o.operands[0]) != Root::Frame {
                    return fail("it writes memory after the recursive call");
                }
            }
            OpKind::Lo(L::Call) => {
                if o.operands.iter().any(|&a| is_ptr(m, a)) {
                    return fail("it calls a function with a pointer after the recursive call");
                }
            }
            k if k.is_pure() => {}
            _ => return fail("it does something after the recursive call that may observe it"),
        }
    }
    Ok(())
}

/// The calls made since the visit started, when every path to a point made the same ones.
#[derive(Clone, PartialEq, Eq)]
enum Made {
    Same(Vec<OpId>),
    Differs,
}

/// The ends of a visit of `f` (blocks that return, or branch to a block that exits quietly)
/// at which every path through the body made the same recursive calls, with those calls in
/// order; and the calls that only such ends follow (they become the ends' pushes and jump
/// instead of pushing where they stand). An end is kept only when each of its calls is one
/// of those, so a call never has to push on one path and not on another.
fn known_ends(
    m: &Module,
    f: FuncId,
    calls: &[OpId],
) -> (Vec<(BlockId, Vec<OpId>)>, FxHashSet<OpId>) {
    let region = m.funcs[f].body;
    let blocks: Vec<BlockId> = m.regions[region].blocks.clone();
    let is_call: FxHashSet<OpId> = calls.iter().copied().collect();
    let term = |b: BlockId| m.blocks[b].ops.last().copied();
    let is_end = |b: BlockId| {
        term(b).is_some_and(|t| {
            let o = &m.ops[t];
            match o.kind {
                OpKind::Lo(L::Return) => o.operands.is_empty(),
                OpKind::Lo(L::Br) => exits_quietly(m, o.successors[0].block),
                _ => false,
            }
        })
    };
    // Forward: the calls made before each block (joins of different lists differ).
    let mut before: FxHashMap<BlockId, Made> = FxHashMap::default();
    before.insert(blocks[0], Made::Same(Vec::new()));
    let mut work = vec![blocks[0]];
    let mut out: FxHashMap<BlockId, Made> = FxHashMap::default();
    while let Some(b) = work.pop() {
        let mut made = before[&b].clone();
        if let Made::Same(list) = &mut made {
            list.extend(m.blocks[b].ops.iter().filter(|o| is_call.contains(o)));
        }
        out.insert(b, made.clone());
        if is_end(b) {
            continue;
        }
        let Some(t) = term(b) else { continue };
        for s in m.ops[t].successors.iter().map(|s| s.block) {
            let next = match before.get(&s) {
                None => made.clone(),
                Some(old) if *old == made => continue,
                Some(_) => Made::Differs,
            };
            if before.get(&s) != Some(&next) {
                before.insert(s, next);
                work.push(s);
            }
        }
    }
    let mut ends: FxHashMap<BlockId, Vec<OpId>> = blocks
        .iter()
        .filter(|&&b| is_end(b))
        .filter_map(|&b| match out.get(&b) {
            Some(Made::Same(list)) => Some((b, list.clone())),
            _ => None,
        })
        .collect();
    // The ends each call reaches (a call in an end's own block reaches that end).
    let reach = |c: OpId| -> Vec<BlockId> {
        let start = m.ops[c].parent.expect("placed");
        let mut seen: FxHashSet<BlockId> = FxHashSet::default();
        let mut found = Vec::new();
        let mut work = vec![start];
        while let Some(b) = work.pop() {
            if !seen.insert(b) {
                continue;
            }
            if is_end(b) {
                found.push(b);
                continue;
            }
            if let Some(t) = term(b) {
                work.extend(m.ops[t].successors.iter().map(|s| s.block));
            }
        }
        found
    };
    let reached: Vec<(OpId, Vec<BlockId>)> = calls.iter().map(|&c| (c, reach(c))).collect();
    loop {
        let grouped: FxHashSet<OpId> = reached
            .iter()
            .filter(|(_, es)| !es.is_empty() && es.iter().all(|e| ends.contains_key(e)))
            .map(|&(c, _)| c)
            .collect();
        let before = ends.len();
        ends.retain(|_, list| list.iter().all(|c| grouped.contains(c)));
        if ends.len() == before {
            let mut list: Vec<(BlockId, Vec<OpId>)> = ends.into_iter().collect();
            list.sort_by_key(|(b, _)| blocks.iter().position(|x| x == b));
            return (list, grouped);
        }
    }
}

/// Rewrites `f`, whose recursive calls are `calls`, into a loop over a stack of `size`
/// entries with deferred calls (see the module docs).
pub(super) fn rewrite(
    m: &mut Module,
    f: FuncId,
    calls: &[OpId],
    size: u32,
) -> Result<(), Diagnostic> {
    let (region, entry, params) = body_of(m, f, calls)?;
    check(m, f, calls, &params).map_err(|(op, why)| {
        let mut d = not_tail(m, calls[0], &why);
        if let Some(s) = m.span(op) {
            d = d.with_secondary(s, "this follows the call");
        }
        d
    })?;
    let changed = changed_args(
        m,
        calls,
        &params,
        "it passes a cell of the caller's frame (a `let mut` local), which one explicit stack \
         for all calls cannot keep per call",
    )?;
    let entry_bytes = 8 * changed.len().max(1) as u64;
    check_stack_bytes(m, f, entry_bytes, size)?;
    let i32t = m.types.i32();
    let u32t = m.types.u32();
    let param_tys = m.funcs[f].params.clone();
    let body_blocks: Vec<BlockId> = m.regions[region].blocks.clone();
    let (known, grouped) = known_ends(m, f, calls);

    // New entry: the stack and its pointer cell, then the old body on the arguments.
    let (new_entry, new_params) = split_entry(m, f, &params, &changed);
    let head = m.add_block(region, &[]);
    let done = m.add_block(region, &[]);
    let pop = m.add_block(region, &[]);
    let overflow = m.add_block(region, &[]);
    let rev = m.add_block(region, &[u32t, u32t]);
    let swap = m.add_block(region, &[]);
    let (stack, spc);
    {
        let mut b = Builder::at_end(m, new_entry);
        stack = b.lo_stack_slot(entry_bytes * u64::from(size), 8);
        spc = b.lo_stack_slot(4, 4);
        let zero = b.lo_int(u32t, 0);
        b.lo_store(spc, 0, zero);
        let args: Vec<ValueId> = changed.iter().map(|&i| new_params[i]).collect();
        b.lo_br(entry, &args);
    }
    let slot = |b: &mut Builder<'_>, sp: ValueId| entry_addr(b, stack, sp, entry_bytes);
    // The stack pointer when the visit starts: the visit's entries are the ones above it.
    let first = m.blocks[entry].ops[0];
    let sp0 = {
        let mut b = Builder::new(m);
        b.set_insertion_point(InsertPoint::Before(first));
        b.lo_load(spc, 0, u32t)
    };
    // The loop head: pop the next entry into the body, or return when the stack is empty.
    {
        exits(m, done, overflow);
        let mut b = Builder::at_end(m, head);
        let sp = b.lo_load(spc, 0, u32t);
        let zero = b.lo_int(u32t, 0);
        let empty = b.lo_cmp(CmpPred::Eq, sp, zero);
        b.lo_cond_br(empty, (done, &[]), (pop, &[]));
        b.set_insertion_point_to_end(pop);
        let one = b.lo_int(u32t, 1);
        let sp1 = b.lo1(L::Sub, &[sp, one], u32t);
        b.lo_store(spc, 0, sp1);
        let at = slot(&mut b, sp1);
        let args: Vec<ValueId> = changed
            .iter()
            .enumerate()
            .map(|(k, &i)| b.lo_load(at, 8 * k as i64, param_tys[i]))
            .collect();
        b.lo_br(entry, &args);
    }
    // The end of a visit: reverse its entries [i, j) in place, then back to the head.
    {
        let (i, j) = (m.blocks[rev].args[0], m.blocks[rev].args[1]);
        let mut b = Builder::at_end(m, rev);
        let one = b.lo_int(u32t, 1);
        let i1 = b.lo1(L::Add, &[i, one], u32t);
        let more = b.lo_cmp(CmpPred::Lt, i1, j);
        b.lo_cond_br(more, (swap, &[]), (head, &[]));
        b.set_insertion_point_to_end(swap);
        let j1 = b.lo1(L::Sub, &[j, one], u32t);
        let (lo, hi) = (slot(&mut b, i), slot(&mut b, j1));
        for (k, &p) in changed.iter().enumerate() {
            let off = 8 * k as i64;
            let a = b.lo_load(lo, off, param_tys[p]);
            let c = b.lo_load(hi, off, param_tys[p]);
            b.lo_store(lo, off, c);
            b.lo_store(hi, off, a);
        }
        b.lo_br(rev, &[i1, j1]);
    }
    // A push of `args` at the end of `bb`: to the overflow exit when the stack is full, else
    // on; returns the block that goes on.
    let shape = Stack {
        slot: stack,
        entry_bytes,
        size,
        overflow,
    };
    let push = |m: &mut Module, bb: BlockId, args: &[ValueId]| -> BlockId {
        let sp = Builder::at_end(m, bb).lo_load(spc, 0, u32t);
        let (next, sp1) = shape.push(m, bb, sp, &changed, args);
        Builder::at_end(m, next).lo_store(spc, 0, sp1);
        next
    };
    // Ends whose calls are known: push all but the first, last first, and go on with the
    // first (or pop the next entry when the visit made none).
    let args_of: FxHashMap<OpId, Vec<ValueId>> = grouped
        .iter()
        .map(|&c| (c, m.ops[c].operands.to_vec()))
        .collect();
    for &c in &grouped {
        scion_ir::rewrite::erase_op(m, c);
    }
    for (bb, list) in &known {
        let term = *m.blocks[*bb].ops.last().expect("an end has a terminator");
        scion_ir::rewrite::erase_op(m, term);
        let mut cur = *bb;
        for c in list.iter().skip(1).rev() {
            cur = push(m, cur, &args_of[c]);
        }
        let mut b = Builder::at_end(m, cur);
        match list.first() {
            None => b.lo_br(head, &[]),
            Some(c) => {
                let args: Vec<ValueId> = changed.iter().map(|&i| args_of[c][i]).collect();
                b.lo_br(entry, &args)
            }
        };
    }
    // Returns of the body end the visit.
    for &bb in &body_blocks {
        let Some(&term) = m.blocks[bb].ops.last() else {
            continue;
        };
        if m.ops[term].kind == OpKind::Lo(L::Return) {
            scion_ir::rewrite::erase_op(m, term);
            let mut b = Builder::at_end(m, bb);
            let sp = b.lo_load(spc, 0, u32t);
            b.lo_br(rev, &[sp0, sp]);
        }
    }
    // Every other recursive call pushes its arguments and the body goes on.
    for &c in calls.iter().filter(|c| !grouped.contains(c)) {
        let (bb, cont, args) = split_at_call(m, c);
        let next = push(m, bb, &args);
        Builder::at_end(m, next).lo_br(cont, &[]);
    }
    m.funcs[f].results = vec![i32t];
    m.funcs[f].attrs.set("status", Attr::Unit);
    // A visit pushes all of its calls: the stack a tree needs is not its depth.
    m.funcs[f].attrs.set("deferred_calls", Attr::Unit);
    drop_unreachable(m, f);
    Ok(())
}
