//! `recursion-to-stack`: a recursive traversal whose recursive calls are tail calls in sequence
//! becomes a loop over a fixed-size explicit stack (design note §4, paper §7.3).
//!
//! It runs on the `lo` CFG, right after `mem-to-lo`: structured `mem` has no general loop, and
//! in the CFG the rewrite is local. A function `@f` qualifies when it returns nothing and every
//! block that calls `@f` ends with the calls (nothing between them but more calls to `@f`) and
//! then only reaches `lo.return` through blocks without side effects; each call passes the
//! function's own parameter wherever it does not change it (`mut` parameters are pointers
//! passed through). The *changed* positions form a stack entry.
//!
//! The rewrite: a new entry block allocates the stack (`lo.stack_slot`, `stack-size` entries,
//! each changed argument in an 8-byte cell) and runs the old body on the original arguments
//! with an empty stack. The old entry block becomes the loop body's head: its arguments are the
//! changed parameters and the stack pointer `sp` (an SSA value, the number of pending entries;
//! parameters that no call changes are read from the new entry directly, not passed around the
//! loop). Where the body made `n` recursive calls it now pushes the arguments of the last
//! `n - 1`, last first, and jumps straight back into the body with the first call's arguments
//! (the entry a push would have popped next); where it returned it jumps to the loop head, which
//! pops the next entry into the body, or returns when the stack is empty. So the visit order,
//! and every result, is the recursion's, and a binary traversal pushes one entry per interior
//! node: a node at depth `k` (the root at 1) runs with at most `k - 1` pending entries.
//!
//! **Status results.** A rewritten function returns an `i32` status: 0 done, 1 the stack
//! overflowed (a push to a full stack returns at once; `mut` results hold what was computed so
//! far). A caller of a function with a status gets a status too, appended as its last result:
//! after the call it returns the status (other results zero) when it is not 0. Such functions
//! carry the attribute `status`.
//!
//! **Best-first functions** (attribute `order_by`, source `order by k`) queue their recursive
//! calls in a bounded priority queue instead ([`super::best_first`]).
//!
//! **Calls elsewhere.** Recursive calls that are not in that tail shape (under conditions, one
//! per child of an unrolled loop) are deferred ([`super::deferred_calls`]): each becomes a push
//! and the visit's entries are reversed when it ends, which is the recursion exactly when
//! nothing after a call observes it; otherwise E0971 names the call and what follows it.

use rustc_hash::{FxHashMap, FxHashSet};
use scion_ir::attr::Attr;
use scion_ir::diag::{Diagnostic, Diagnostics};
use scion_ir::entity::{BlockId, FuncId, OpId, RegionId, TypeId, ValueId};
use scion_ir::lo::Op as L;
use scion_ir::module::{ValueData, ValueDef};
use scion_ir::op::OpKind;
use scion_ir::tree::CmpPred;
use scion_ir::types::{IntTy, Type};
use scion_ir::{Builder, Module, Pass, PassCx, PassError};

/// The default number of stack entries of a traversal whose calls end its visit in sequence
/// (at most one pending entry per level of the tree for a binary one).
pub const DEFAULT_STACK_SIZE: u32 = 64;

/// The default number of entries of a traversal whose visits push all their calls (deferred
/// calls, best-first queues): a visit of a node with `w` children can leave `w - 1` entries per
/// level, so an eight-wide tree of depth 10 needs 70 (`closest_point8` with no radius).
pub const DEFAULT_DEFERRED_STACK_SIZE: u32 = 512;

/// The largest explicit stack, in bytes: it lives in the frame of the thread that runs the
/// traversal (a worker thread has 2 MiB in all), so a larger one is an error, not a crash.
pub const MAX_STACK_BYTES: u64 = 256 * 1024;

/// The pass object.
pub struct RecursionToStack;

impl Pass for RecursionToStack {
    fn name(&self) -> &'static str {
        "recursion-to-stack"
    }

    fn summary(&self) -> &'static str {
        "recursive traversals (tail calls in sequence) to a loop over a fixed stack"
    }

    fn run(&mut self, m: &mut Module, cx: &mut PassCx) -> Result<bool, PassError> {
        let size = match cx.option("recursion-to-stack", "stack-size") {
            None => None,
            Some(s) => match s.parse::<u32>() {
                Ok(n) if n > 0 => Some(n),
                _ => {
                    let d = Diagnostic::error(
                        "E0962",
                        format!("recursion-to-stack:stack-size={s}: expected a positive integer"),
                    );
                    return Err(PassError::Diagnostics(d.into()));
                }
            },
        };
        run(m, size).map_err(|d| {
            let mut ds = Diagnostics::new();
            ds.push(d);
            PassError::Diagnostics(ds)
        })
    }
}

fn callee_of(m: &Module, op: OpId) -> Option<&str> {
    let o = &m.ops[op];
    if o.kind != OpKind::Lo(L::Call) {
        return None;
    }
    o.callee()
}

/// Rewrites every qualifying function of the `lo` module `m` with stacks of `stack_size`
/// entries (`None`: [`DEFAULT_STACK_SIZE`], or [`DEFAULT_DEFERRED_STACK_SIZE`] for a function
/// whose visits push all their calls); returns whether anything changed.
pub fn run(m: &mut Module, stack_size: Option<u32>) -> Result<bool, Diagnostic> {
    let deferred = stack_size.unwrap_or(DEFAULT_DEFERRED_STACK_SIZE);
    let stack_size = stack_size.unwrap_or(DEFAULT_STACK_SIZE);
    let mut with_status: Vec<FuncId> = Vec::new();
    for f in m.func_order.clone() {
        if m.is_declaration(f) {
            continue;
        }
        let name = m.funcs[f].name.clone();
        let calls: Vec<OpId> = body_ops(m, f)
            .into_iter()
            .filter(|&o| callee_of(m, o) == Some(name.as_str()))
            .collect();
        if calls.is_empty() {
            // Without recursive calls nothing is queued: the function is an ordinary one.
            m.funcs[f].attrs.remove(scion_ir::module::ORDER_BY);
            continue;
        }
        if let Some(key) = m.funcs[f].order_by() {
            super::best_first::rewrite(m, f, key, &calls, deferred)?;
        } else if tail_shape(m, &calls).is_ok() {
            rewrite(m, f, &calls, stack_size)?;
        } else {
            super::deferred_calls::rewrite(m, f, &calls, deferred)?;
        }
        with_status.push(f);
    }
    let changed = !with_status.is_empty();
    propagate_status(m, with_status);
    Ok(changed)
}

fn body_ops(m: &Module, f: FuncId) -> Vec<OpId> {
    m.regions[m.funcs[f].body]
        .blocks
        .iter()
        .flat_map(|&b| m.blocks[b].ops.iter().copied())
        .collect()
}

pub(super) fn not_tail(m: &Module, op: OpId, why: &str) -> Diagnostic {
    let name = callee_of(m, op).unwrap_or("?").to_string();
    let mut d = Diagnostic::error(
        "E0971",
        format!("the recursive call of `@{name}` cannot become an explicit stack: {why}"),
    );
    if let Some(s) = m.span(op) {
        d = d.with_primary(s, "this call");
    }
    d.with_note(
        "a recursive traversal may end an arm with recursive calls in sequence, or make them \
         anywhere when nothing after them reads or writes what they write; other parameters \
         pass through unchanged",
    )
}

/// True when `b` reaches a result-less `lo.return` through blocks of pure ops only.
pub(super) fn exits_quietly(m: &Module, mut b: BlockId) -> bool {
    for _ in 0..64 {
        let ops = &m.blocks[b].ops;
        let Some((&term, body)) = ops.split_last() else {
            return false;
        };
        if !body.iter().all(|&o| m.ops[o].kind.is_pure()) {
            return false;
        }
        let t = &m.ops[term];
        match t.kind {
            OpKind::Lo(L::Return) => return t.operands.is_empty(),
            OpKind::Lo(L::Br) => b = t.successors[0].block,
            _ => return false,
        }
    }
    false
}

/// Whether `v` points into the function's own frame: a `lo.stack_slot` (a `tree.var` cell) or
/// an offset from one. After the rewrite one frame serves every call, so such a pointer would
/// alias between the calls it is passed to.
pub(super) fn in_frame(m: &Module, mut v: ValueId) -> bool {
    for _ in 0..64 {
        let ValueDef::Result(op, _) = m.values[v].def else {
            return false;
        };
        match m.ops[op].kind {
            OpKind::Lo(L::StackSlot) => return true,
            OpKind::Lo(L::PtrAdd) => v = m.ops[op].operands[0],
            _ => return false,
        }
    }
    false
}

/// The recursive calls grouped by block when every block that makes them ends with them (and
/// then exits quietly): the tail-call shape [`rewrite`] turns into jumps and pushes.
fn tail_shape(m: &Module, calls: &[OpId]) -> Result<FxHashMap<BlockId, Vec<OpId>>, Diagnostic> {
    let mut by_block: FxHashMap<BlockId, Vec<OpId>> = FxHashMap::default();
    for &c in calls {
        let b = m.ops[c]
            .parent
            .ok_or_else(|| not_tail(m, c, "detached call"))?;
        by_block.entry(b).or_default().push(c);
    }
    for (&b, cs) in &by_block {
        let ops = &m.blocks[b].ops;
        let n = cs.len();
        if ops.len() < n + 1 {
            return Err(not_tail(m, cs[0], "unexpected block shape"));
        }
        let tail = &ops[ops.len() - 1 - n..ops.len() - 1];
        if tail.iter().any(|o| !cs.contains(o)) {
            return Err(not_tail(m, cs[0], "other work follows the recursive call"));
        }
        let term = &m.ops[ops[ops.len() - 1]];
        let quiet = match term.kind {
            OpKind::Lo(L::Return) => term.operands.is_empty(),
            OpKind::Lo(L::Br) => exits_quietly(m, term.successors[0].block),
            _ => false,
        };
        if !quiet {
            return Err(not_tail(m, cs[0], "the function does more after the call"));
        }
    }
    Ok(by_block)
}

/// E0962 when `size` entries of `entry_bytes` do not fit [`MAX_STACK_BYTES`].
pub(super) fn check_stack_bytes(
    m: &Module,
    f: FuncId,
    entry_bytes: u64,
    size: u32,
) -> Result<(), Diagnostic> {
    if entry_bytes * u64::from(size) <= MAX_STACK_BYTES {
        return Ok(());
    }
    let name = m.funcs[f].name.clone();
    Err(Diagnostic::error(
        "E0962",
        format!(
            "recursion-to-stack:stack-size={size}: the stack of `@{name}` would take {} bytes \
             of the thread's stack ({entry_bytes} per entry), more than {MAX_STACK_BYTES}",
            entry_bytes * u64::from(size)
        ),
    )
    .with_note(format!(
        "at most {} entries here; a traversal needs about as many as the tree is deep",
        MAX_STACK_BYTES / entry_bytes
    )))
}

fn rewrite(m: &mut Module, f: FuncId, calls: &[OpId], size: u32) -> Result<(), Diagnostic> {
    let (region, entry, params) = body_of(m, f, calls)?;
    let by_block = tail_shape(m, calls)?;
    let mut changed: FxHashSet<usize> = FxHashSet::default();
    for cs in by_block.values() {
        for &c in cs {
            for (i, &a) in m.ops[c].operands.iter().enumerate() {
                if a != params[i] {
                    if in_frame(m, a) {
                        return Err(not_tail(
                            m,
                            c,
                            "it passes a cell of the caller's frame (a `let mut` local), which \
                             one explicit stack for all calls cannot keep per call",
                        ));
                    }
                    changed.insert(i);
                }
            }
        }
    }
    let mut changed: Vec<usize> = changed.into_iter().collect();
    changed.sort_unstable();
    let entry_bytes = 8 * changed.len().max(1) as u64;
    check_stack_bytes(m, f, entry_bytes, size)?;
    let i32t = m.types.i32();
    let u32t = m.types.u32();
    let param_tys = m.funcs[f].params.clone();

    // New entry: the stack, then the old body on the original arguments with an empty stack.
    // The old entry becomes the loop body's head: its arguments are the changed parameters
    // and the stack pointer `sp` (the number of pending entries).
    let (new_entry, new_params) = split_entry(m, f, &params, &changed);
    let sp_entry = m.add_block_arg(entry, u32t);
    let head = m.add_block(region, &[u32t]);
    let sp_head = m.blocks[head].args[0];
    let done = m.add_block(region, &[]);
    let pop = m.add_block(region, &[]);
    let overflow = m.add_block(region, &[]);
    let stack;
    {
        let mut b = Builder::at_end(m, new_entry);
        stack = b.lo_stack_slot(entry_bytes * u64::from(size), 8);
        let zero = b.lo_int(u32t, 0);
        let mut args: Vec<ValueId> = changed.iter().map(|&i| new_params[i]).collect();
        args.push(zero);
        b.lo_br(entry, &args);
    }
    // The loop head: pop the next entry into the body, or return when the stack is empty.
    {
        exits(m, done, overflow);
        let mut b = Builder::at_end(m, head);
        let zero = b.lo_int(u32t, 0);
        let empty = b.lo_cmp(CmpPred::Eq, sp_head, zero);
        b.lo_cond_br(empty, (done, &[]), (pop, &[]));
        b.set_insertion_point_to_end(pop);
        let one = b.lo_int(u32t, 1);
        let sp1 = b.lo1(L::Sub, &[sp_head, one], u32t);
        let at = entry_addr(&mut b, stack, sp1, entry_bytes);
        let mut args = Vec::with_capacity(changed.len() + 1);
        for (k, &i) in changed.iter().enumerate() {
            args.push(b.lo_load(at, 8 * k as i64, param_tys[i]));
        }
        args.push(sp1);
        b.lo_br(entry, &args);
    }
    // Returns of the body go to the loop head.
    let body_blocks: Vec<BlockId> = m.regions[region]
        .blocks
        .iter()
        .copied()
        .filter(|&x| ![new_entry, head, done, pop, overflow].contains(&x))
        .collect();
    for &bb in &body_blocks {
        let Some(&term) = m.blocks[bb].ops.last() else {
            continue;
        };
        if m.ops[term].kind == OpKind::Lo(L::Return) && !by_block.contains_key(&bb) {
            scion_ir::rewrite::erase_op(m, term);
            Builder::at_end(m, bb).lo_br(head, &[sp_entry]);
        }
    }
    // Recursive calls: all but the first are pushed, last first; the first is a jump straight
    // back into the body (it would be the next entry popped anyway).
    for (bb, cs) in by_block {
        let term = *m.blocks[bb].ops.last().expect("checked above");
        let arg_lists: Vec<Vec<ValueId>> = cs.iter().map(|&c| m.ops[c].operands.to_vec()).collect();
        for &c in &cs {
            scion_ir::rewrite::erase_op(m, c);
        }
        scion_ir::rewrite::erase_op(m, term);
        let mut cur = bb;
        let mut sp = sp_entry;
        let shape = Stack {
            slot: stack,
            entry_bytes,
            size,
            overflow,
        };
        for args in arg_lists.iter().skip(1).rev() {
            (cur, sp) = shape.push(m, cur, sp, &changed, args);
        }
        let mut args: Vec<ValueId> = changed.iter().map(|&i| arg_lists[0][i]).collect();
        args.push(sp);
        Builder::at_end(m, cur).lo_br(entry, &args);
    }
    m.funcs[f].results = vec![i32t];
    m.funcs[f].attrs.set("status", Attr::Unit);
    drop_unreachable(m, f);
    Ok(())
}

/// A new entry block of `f` with its parameters, before the old entry `params`' block, which
/// keeps only the `changed` parameters as its arguments: the parameters no recursive call
/// changes are the same on every visit, so their uses read the new entry's arguments. Returns
/// the new entry and its arguments.
pub(super) fn split_entry(
    m: &mut Module,
    f: FuncId,
    params: &[ValueId],
    changed: &[usize],
) -> (BlockId, Vec<ValueId>) {
    let region = m.funcs[f].body;
    let entry = m.regions[region].blocks[0];
    let param_tys = m.funcs[f].params.clone();
    let new_entry = m.add_block(region, &param_tys);
    let blocks = &mut m.regions[region].blocks;
    blocks.retain(|&x| x != new_entry);
    blocks.insert(0, new_entry);
    let new_params: Vec<ValueId> = m.blocks[new_entry].args.to_vec();
    for (i, &p) in params.iter().enumerate() {
        if !changed.contains(&i) {
            scion_ir::rewrite::replace_all_uses(m, p, new_params[i]);
        }
    }
    let kept: Vec<ValueId> = changed.iter().map(|&i| params[i]).collect();
    for (k, &v) in kept.iter().enumerate() {
        m.values[v].def = ValueDef::BlockArg(entry, k as u32);
    }
    m.blocks[entry].args = kept.into_iter().collect();
    (new_entry, new_params)
}

/// Splits the block of call `c` after it (the rest goes to a new block, returned) and erases
/// the call: the block ends open for what replaces the call. Returns the block, the
/// continuation and the call's arguments.
pub(super) fn split_at_call(m: &mut Module, c: OpId) -> (BlockId, BlockId, Vec<ValueId>) {
    let bb = m.ops[c].parent.expect("placed");
    let region = m.blocks[bb].parent.expect("placed");
    let pos = m.blocks[bb]
        .ops
        .iter()
        .position(|&o| o == c)
        .expect("listed");
    let rest: Vec<OpId> = m.blocks[bb].ops.split_off(pos + 1);
    let cont = m.add_block(region, &[]);
    for &o in &rest {
        m.ops[o].parent = Some(cont);
    }
    m.blocks[cont].ops = rest;
    let args = m.ops[c].operands.to_vec();
    scion_ir::rewrite::erase_op(m, c);
    (bb, cont, args)
}

/// The parameter positions some recursive call of `calls` changes (an argument other than
/// the function's own parameter), in order: what a stack entry keeps. A changed argument that
/// is a cell of the caller's frame is E0971 (`frame_why` says why it cannot be kept).
pub(super) fn changed_args(
    m: &Module,
    calls: &[OpId],
    params: &[ValueId],
    frame_why: &str,
) -> Result<Vec<usize>, Diagnostic> {
    let mut changed: Vec<usize> = Vec::new();
    for &c in calls {
        for (i, &a) in m.ops[c].operands.iter().enumerate() {
            if a != params[i] {
                if in_frame(m, a) {
                    return Err(not_tail(m, c, frame_why));
                }
                if !changed.contains(&i) {
                    changed.push(i);
                }
            }
        }
    }
    changed.sort_unstable();
    Ok(changed)
}

/// The body's region, its entry block and the parameters of `f`, whose recursive calls are
/// `calls`; a function with results cannot become a loop of calls (E0971).
pub(super) fn body_of(
    m: &Module,
    f: FuncId,
    calls: &[OpId],
) -> Result<(RegionId, BlockId, Vec<ValueId>), Diagnostic> {
    if !m.funcs[f].results.is_empty() {
        return Err(not_tail(m, calls[0], "the function returns values"));
    }
    let region = m.funcs[f].body;
    let entry = m.regions[region].blocks[0];
    Ok((region, entry, m.blocks[entry].args.to_vec()))
}

/// Fills the loop's two exits: `done` returns status 0, `overflow` status 1.
pub(super) fn exits(m: &mut Module, done: BlockId, overflow: BlockId) {
    let i32t = m.types.i32();
    let mut b = Builder::at_end(m, done);
    let ok = b.lo_int(i32t, 0);
    b.lo_ret(&[ok]);
    b.set_insertion_point_to_end(overflow);
    let one = b.lo_int(i32t, 1);
    b.lo_ret(&[one]);
}

/// An explicit stack: its frame slot, the bytes of an entry (8 per kept argument), its
/// capacity in entries and the block that reports an overflow.
pub(super) struct Stack {
    pub slot: ValueId,
    pub entry_bytes: u64,
    pub size: u32,
    pub overflow: BlockId,
}

impl Stack {
    /// Pushes the `changed` positions of `args` at entry `sp` (a `u32`) at the end of `bb`: to
    /// the overflow block when `sp` is at the capacity, else on. Returns the block that goes on
    /// (open at its end) and `sp + 1`.
    pub(super) fn push(
        &self,
        m: &mut Module,
        bb: BlockId,
        sp: ValueId,
        changed: &[usize],
        args: &[ValueId],
    ) -> (BlockId, ValueId) {
        let region = m.blocks[bb].parent.expect("placed");
        let next = m.add_block(region, &[]);
        let u32t = m.types.u32();
        let mut b = Builder::at_end(m, bb);
        let cap = b.lo_int(u32t, i128::from(self.size));
        let full = b.lo_cmp(CmpPred::Ge, sp, cap);
        b.lo_cond_br(full, (self.overflow, &[]), (next, &[]));
        b.set_insertion_point_to_end(next);
        let at = entry_addr(&mut b, self.slot, sp, self.entry_bytes);
        for (k, &i) in changed.iter().enumerate() {
            b.lo_store(at, 8 * k as i64, args[i]);
        }
        let one = b.lo_int(u32t, 1);
        let sp1 = b.lo1(L::Add, &[sp, one], u32t);
        (next, sp1)
    }
}

/// The address of stack entry `sp` (a `u32`) of `entry_bytes` bytes.
pub(super) fn entry_addr(
    b: &mut Builder<'_>,
    stack: ValueId,
    sp: ValueId,
    entry_bytes: u64,
) -> ValueId {
    let u64t = b.m.types.int(IntTy::U64);
    let ptrt = b.m.ty(Type::Ptr);
    let sp64 = b.lo1(L::Cast, &[sp], u64t);
    let width = b.lo_int(u64t, entry_bytes as i128);
    let off = b.lo1(L::Mul, &[sp64, width], u64t);
    b.lo1(L::PtrAdd, &[stack, off], ptrt)
}

/// Removes blocks no path from the entry reaches (the quiet exits after rewritten calls).
pub(super) fn drop_unreachable(m: &mut Module, f: FuncId) {
    let region = m.funcs[f].body;
    let blocks = m.regions[region].blocks.clone();
    let mut seen: FxHashSet<BlockId> = FxHashSet::default();
    let mut work = vec![blocks[0]];
    while let Some(b) = work.pop() {
        if !seen.insert(b) {
            continue;
        }
        if let Some(&t) = m.blocks[b].ops.last() {
            work.extend(m.ops[t].successors.iter().map(|s| s.block));
        }
    }
    m.regions[region].blocks.retain(|b| seen.contains(b));
    for b in blocks {
        if !seen.contains(&b) {
            m.blocks[b].parent = None;
        }
    }
}

/// Gives every caller of a function with a status a status of its own (appended as the last
/// result), returning early when a callee reports one.
fn propagate_status(m: &mut Module, mut work: Vec<FuncId>) {
    let mut done: FxHashSet<FuncId> = work.iter().copied().collect();
    let i32t = m.types.i32();
    while let Some(callee) = work.pop() {
        let name = m.funcs[callee].name.clone();
        for g in m.func_order.clone() {
            if m.is_declaration(g) {
                continue;
            }
            let sites: Vec<OpId> = body_ops(m, g)
                .into_iter()
                .filter(|&o| callee_of(m, o) == Some(name.as_str()))
                .collect();
            if sites.is_empty() || g == callee {
                continue;
            }
            let newly = done.insert(g);
            if newly {
                add_status_result(m, g, i32t);
                work.push(g);
            }
            for site in sites {
                let status = m.values.alloc(ValueData {
                    ty: i32t,
                    def: ValueDef::Result(site, m.ops[site].results.len() as u32),
                });
                m.ops[site].results.push(status);
                split_after_status(m, g, site, status);
            }
        }
    }
}

/// Appends an `i32` result to `g`, returning 0 at every existing return.
fn add_status_result(m: &mut Module, g: FuncId, i32t: TypeId) {
    m.funcs[g].results.push(i32t);
    m.funcs[g].attrs.set("status", Attr::Unit);
    for op in body_ops(m, g) {
        if m.ops[op].kind == OpKind::Lo(L::Return) {
            let mut b = Builder::new(m);
            b.set_insertion_point(scion_ir::InsertPoint::Before(op));
            let z = b.lo_int(i32t, 0);
            m.ops[op].operands.push(z);
        }
    }
}

/// After the call `site` in `g`, returns `status` (other results zero) when it is not 0.
fn split_after_status(m: &mut Module, g: FuncId, site: OpId, status: ValueId) {
    let Some(b) = m.ops[site].parent else {
        return;
    };
    let region = m.funcs[g].body;
    let pos = m.blocks[b].ops.iter().position(|&o| o == site).unwrap_or(0);
    let rest: Vec<OpId> = m.blocks[b].ops.split_off(pos + 1);
    let cont = m.add_block(region, &[]);
    for &o in &rest {
        m.ops[o].parent = Some(cont);
    }
    m.blocks[cont].ops = rest;
    let fail = m.add_block(region, &[]);
    let results = m.funcs[g].results.clone();
    let mut bl = Builder::at_end(m, b);
    let zero = bl.lo_int(results[results.len() - 1], 0);
    let bad = bl.lo_cmp(CmpPred::Ne, status, zero);
    bl.lo_cond_br(bad, (fail, &[]), (cont, &[]));
    bl.set_insertion_point_to_end(fail);
    let mut vals = Vec::new();
    for &t in &results[..results.len() - 1] {
        vals.push(zero_of(&mut bl, t));
    }
    vals.push(status);
    bl.lo_ret(&vals);
}

fn zero_of(b: &mut Builder<'_>, t: TypeId) -> ValueId {
    match b.m.types.get(t).clone() {
        Type::Bool => b.lo_bool(false),
        Type::Float(_) => b.lo_float(t, 0.0),
        _ => b.lo_int(t, 0),
    }
}
