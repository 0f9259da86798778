//! `recursion-to-stack` for a best-first function (source `order by k`, attribute `order_by`):
//! its recursive calls go into a bounded priority queue, and the loop runs the pending call with
//! the smallest key next.
//!
//! The semantics (docs/ir.md, "Best-first functions"; the interpreters implement it directly):
//! a call of the function from its own body does not run at once but is queued with its
//! arguments; when the visit ends, the queued call with the smallest key (its argument `k`)
//! runs, then the next, until the queue is empty. Equal keys run in the order they were queued,
//! and a NaN key counts as `+inf`. So the body may read and write anything after a call; only a
//! cell of its own frame cannot be passed (the frame does not outlive the visit), E0971.
//!
//! The queue is a binary min-heap of `stack-size` entries in the frame, ordered by (key, sequence
//! number). An entry is 8-byte cells: the sequence number (`u64`), the key with NaN replaced by
//! `+inf`, then each argument that some call changes. A push sifts up (a new entry never goes
//! before an older one with an equal key, its sequence number being larger, so only the key is
//! compared); a pop takes the root, then sifts the last entry down from the root. A push to a
//! full queue returns status 1, as a full stack does ([`super::recursion_to_stack`]).

use super::recursion_to_stack::{
    body_of, changed_args, check_stack_bytes, entry_addr, exits, split_at_call, split_entry,
};
use scion_ir::attr::Attr;
use scion_ir::diag::Diagnostic;
use scion_ir::entity::{BlockId, FuncId, OpId, TypeId, ValueId};
use scion_ir::lo::Op as L;
use scion_ir::module::ORDER_BY;
use scion_ir::op::OpKind;
use scion_ir::tree::CmpPred;
use scion_ir::types::{IntTy, Type};
use scion_ir::{Builder, Module};

/// Bytes of an entry's header: the sequence number, then the key.
const SEQ: i64 = 0;
const KEY: i64 = 8;
const ARGS: i64 = 16;

/// Rewrites the best-first function `f` (ordered by parameter `key`), whose recursive calls
/// are `calls`, into a loop over a priority queue of `size` entries (see the module docs).
pub(super) fn rewrite(
    m: &mut Module,
    f: FuncId,
    key: usize,
    calls: &[OpId],
    size: u32,
) -> Result<(), Diagnostic> {
    let (region, entry, params) = body_of(m, f, calls)?;
    if key >= params.len() {
        return Err(Diagnostic::error(
            "E0971",
            format!(
                "`@{}`: `order_by = {key}` names no parameter",
                m.funcs[f].name
            ),
        ));
    }
    let changed = changed_args(
        m,
        calls,
        &params,
        "it passes a cell of the caller's frame (a `let mut` local), which does not outlive the \
         visit that queues the call",
    )?;
    let entry_bytes = (ARGS as u64) + 8 * changed.len() as u64;
    check_stack_bytes(m, f, entry_bytes, size)?;
    let i32t = m.types.i32();
    let u32t = m.types.u32();
    let u64t = m.types.int(IntTy::U64);
    let param_tys = m.funcs[f].params.clone();
    let key_ty = param_tys[key];
    let body_blocks: Vec<BlockId> = m.regions[region].blocks.clone();

    // Cells copied when an entry moves: the header and the changed arguments.
    let mut cells: Vec<(i64, TypeId)> = vec![(SEQ, u64t), (KEY, key_ty)];
    cells.extend(
        changed
            .iter()
            .enumerate()
            .map(|(k, &i)| (ARGS + 8 * k as i64, param_tys[i])),
    );

    let (new_entry, new_params) = split_entry(m, f, &params, &changed);
    let (heap, nc, seqc);
    {
        let mut b = Builder::at_end(m, new_entry);
        heap = b.lo_stack_slot(entry_bytes * u64::from(size), 8);
        nc = b.lo_stack_slot(4, 4);
        seqc = b.lo_stack_slot(8, 8);
        let zero = b.lo_int(u32t, 0);
        b.lo_store(nc, 0, zero);
        let zero64 = b.lo_int(u64t, 0);
        b.lo_store(seqc, 0, zero64);
        let args: Vec<ValueId> = changed.iter().map(|&i| new_params[i]).collect();
        b.lo_br(entry, &args);
    }
    let addr = |b: &mut Builder<'_>, i: ValueId| entry_addr(b, heap, i, entry_bytes);
    let copy = |b: &mut Builder<'_>, from: ValueId, to: ValueId| {
        for &(off, ty) in &cells {
            let v = b.lo_load(from, off, ty);
            b.lo_store(to, off, v);
        }
    };
    // (ak, as) before (bk, bs): a smaller key, or an equal key and an older entry.
    let before = |b: &mut Builder<'_>, a: (ValueId, ValueId), c: (ValueId, ValueId)| {
        let lt = b.lo_cmp(CmpPred::Lt, a.0, c.0);
        let eq = b.lo_cmp(CmpPred::Eq, a.0, c.0);
        let older = b.lo_cmp(CmpPred::Lt, a.1, c.1);
        let bool_t = b.m.types.bool();
        b.lo1(L::Select, &[eq, older, lt], bool_t)
    };

    // The loop head: pop the smallest entry into the body, or return when the queue is empty.
    let head = m.add_block(region, &[]);
    let done = m.add_block(region, &[]);
    let pop = m.add_block(region, &[]);
    let overflow = m.add_block(region, &[]);
    let down = m.add_block(region, &[u32t]);
    let kids = m.add_block(region, &[]);
    let pick = m.add_block(region, &[]);
    let chosen = m.add_block(region, &[u32t, key_ty, u64t]);
    let sink = m.add_block(region, &[]);
    let settle = m.add_block(region, &[]);
    exits(m, done, overflow);
    {
        let mut b = Builder::at_end(m, head);
        let n = b.lo_load(nc, 0, u32t);
        let zero = b.lo_int(u32t, 0);
        let empty = b.lo_cmp(CmpPred::Eq, n, zero);
        b.lo_cond_br(empty, (done, &[]), (pop, &[]));
    }
    // pop: the root's arguments go to the body; the last entry sinks from the root.
    let (top_args, n1, last, last_key, last_seq) = {
        let mut b = Builder::at_end(m, pop);
        let n = b.lo_load(nc, 0, u32t);
        let zero = b.lo_int(u32t, 0);
        let root = addr(&mut b, zero);
        let top: Vec<ValueId> = changed
            .iter()
            .enumerate()
            .map(|(k, &i)| b.lo_load(root, ARGS + 8 * k as i64, param_tys[i]))
            .collect();
        let one = b.lo_int(u32t, 1);
        let n1 = b.lo1(L::Sub, &[n, one], u32t);
        b.lo_store(nc, 0, n1);
        let last = addr(&mut b, n1);
        let lk = b.lo_load(last, KEY, key_ty);
        let ls = b.lo_load(last, SEQ, u64t);
        b.lo_br(down, &[zero]);
        (top, n1, last, lk, ls)
    };
    {
        // down(i): the hole is at i; its smaller child moves up while it goes before the last.
        let i = m.blocks[down].args[0];
        let mut b = Builder::at_end(m, down);
        let two = b.lo_int(u32t, 2);
        let one = b.lo_int(u32t, 1);
        let i2 = b.lo1(L::Mul, &[i, two], u32t);
        let c = b.lo1(L::Add, &[i2, one], u32t);
        let has = b.lo_cmp(CmpPred::Lt, c, n1);
        b.lo_cond_br(has, (kids, &[]), (settle, &[]));
        b.set_insertion_point_to_end(kids);
        let c2 = b.lo1(L::Add, &[c, one], u32t);
        let at_c = addr(&mut b, c);
        let ck = b.lo_load(at_c, KEY, key_ty);
        let cs = b.lo_load(at_c, SEQ, u64t);
        let has2 = b.lo_cmp(CmpPred::Lt, c2, n1);
        b.lo_cond_br(has2, (pick, &[]), (chosen, &[c, ck, cs]));
        b.set_insertion_point_to_end(pick);
        let at_c2 = addr(&mut b, c2);
        let c2k = b.lo_load(at_c2, KEY, key_ty);
        let c2s = b.lo_load(at_c2, SEQ, u64t);
        let right = before(&mut b, (c2k, c2s), (ck, cs));
        let cc = b.lo1(L::Select, &[right, c2, c], u32t);
        let kk = b.lo1(L::Select, &[right, c2k, ck], key_ty);
        let ss = b.lo1(L::Select, &[right, c2s, cs], u64t);
        b.lo_br(chosen, &[cc, kk, ss]);
        let (cc, kk, ss) = (
            b.m.blocks[chosen].args[0],
            b.m.blocks[chosen].args[1],
            b.m.blocks[chosen].args[2],
        );
        b.set_insertion_point_to_end(chosen);
        let up = before(&mut b, (kk, ss), (last_key, last_seq));
        b.lo_cond_br(up, (sink, &[]), (settle, &[]));
        b.set_insertion_point_to_end(sink);
        let from = addr(&mut b, cc);
        let to = addr(&mut b, i);
        copy(&mut b, from, to);
        b.lo_br(down, &[cc]);
        // settle: the last entry fills the hole (when the queue is not empty now), then the
        // popped entry's visit starts.
        b.set_insertion_point_to_end(settle);
        let to = addr(&mut b, i);
        copy(&mut b, last, to);
        b.lo_br(entry, &top_args);
    }
    // Returns of the body end the visit.
    for &bb in &body_blocks {
        let Some(&term) = m.blocks[bb].ops.last() else {
            continue;
        };
        if m.ops[term].kind == OpKind::Lo(L::Return) {
            scion_ir::rewrite::erase_op(m, term);
            Builder::at_end(m, bb).lo_br(head, &[]);
        }
    }
    // Each recursive call is a push: sift up from the end, then place the entry.
    for &c in calls {
        let (bb, cont, args) = split_at_call(m, c);
        let start = m.add_block(region, &[]);
        let up = m.add_block(region, &[u32t]);
        let parent = m.add_block(region, &[]);
        let lift = m.add_block(region, &[]);
        let place = m.add_block(region, &[u32t]);
        let mut b = Builder::at_end(m, bb);
        let n = b.lo_load(nc, 0, u32t);
        let cap = b.lo_int(u32t, i128::from(size));
        let full = b.lo_cmp(CmpPred::Ge, n, cap);
        b.lo_cond_br(full, (overflow, &[]), (start, &[]));
        b.set_insertion_point_to_end(start);
        let seq = b.lo_load(seqc, 0, u64t);
        let one64 = b.lo_int(u64t, 1);
        let seq1 = b.lo1(L::Add, &[seq, one64], u64t);
        b.lo_store(seqc, 0, seq1);
        let k = canonical_key(&mut b, args[key], key_ty);
        let one = b.lo_int(u32t, 1);
        let n1 = b.lo1(L::Add, &[n, one], u32t);
        b.lo_store(nc, 0, n1);
        b.lo_br(up, &[n]);
        let i = b.m.blocks[up].args[0];
        b.set_insertion_point_to_end(up);
        let zero = b.lo_int(u32t, 0);
        let at_root = b.lo_cmp(CmpPred::Eq, i, zero);
        b.lo_cond_br(at_root, (place, &[i]), (parent, &[]));
        b.set_insertion_point_to_end(parent);
        let two = b.lo_int(u32t, 2);
        let im1 = b.lo1(L::Sub, &[i, one], u32t);
        let p = b.lo1(L::Div, &[im1, two], u32t);
        let at_p = addr(&mut b, p);
        let pk = b.lo_load(at_p, KEY, key_ty);
        let smaller = b.lo_cmp(CmpPred::Lt, k, pk);
        b.lo_cond_br(smaller, (lift, &[]), (place, &[i]));
        b.set_insertion_point_to_end(lift);
        let to = addr(&mut b, i);
        copy(&mut b, at_p, to);
        b.lo_br(up, &[p]);
        let j = b.m.blocks[place].args[0];
        b.set_insertion_point_to_end(place);
        let at = addr(&mut b, j);
        b.lo_store(at, SEQ, seq);
        b.lo_store(at, KEY, k);
        for (slot, &i) in changed.iter().enumerate() {
            b.lo_store(at, ARGS + 8 * slot as i64, args[i]);
        }
        b.lo_br(cont, &[]);
    }
    m.funcs[f].results = vec![i32t];
    m.funcs[f].attrs.set("status", Attr::Unit);
    // The queue holds every pending call, not a path: what a tree needs is not its depth.
    m.funcs[f].attrs.set("deferred_calls", Attr::Unit);
    m.funcs[f].attrs.remove(ORDER_BY);
    m.funcs[f].attrs.set("best_first", Attr::Unit);
    Ok(())
}

/// The key as the queue orders it: a float NaN is `+inf`.
fn canonical_key(b: &mut Builder<'_>, k: ValueId, ty: TypeId) -> ValueId {
    if !matches!(b.m.types.get(ty), Type::Float(_)) {
        return k;
    }
    let nan = b.lo_cmp(CmpPred::Ne, k, k);
    let inf = b.lo_float(ty, f64::INFINITY);
    b.lo1(L::Select, &[nan, inf, k], ty)
}
