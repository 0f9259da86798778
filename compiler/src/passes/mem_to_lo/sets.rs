//! `set[T]` in `mem-to-lo`: a set the traversal only adds to is a *sink* (docs/c-abi.md), three
//! leaves like a view: the address of a caller-owned array of `T`, its capacity and the count
//! of insertions so far (both `u64`).
//!
//! `insert(s, x)` on a `mut set[T]` parameter (irgen: load, `set_insert`, store) stores `x` at
//! `data + count * stride(T)` when `count < capacity` and counts it either way, so a caller
//! whose array was too small learns how large it must be and runs again. The sink keeps every
//! insertion in order; making it a set (sorting, dropping repeats) is the caller's, once the
//! traversal is done. Nothing else reads a set in compiled code: `len`, `foreach` and set
//! values that are not a `mut` parameter's stay reported (the interpreters run them).

use super::{flat, FnLower, R};
use scion_ir::entity::{BlockId, TypeId, ValueId};
use scion_ir::lo::Op as L;
use scion_ir::tree::CmpPred;
use scion_ir::types::{IntTy, Type};
use scion_ir::Builder;

impl FnLower<'_> {
    /// `set_insert(old, x)` where `old` is a sink's leaves (data, capacity, count) and `x` the
    /// leaves of an element of type `elem`: the conditional store, then the sink with the
    /// count plus one. Returns the block to go on in and the new sink's leaves.
    pub(super) fn sink_insert(
        &mut self,
        cur: BlockId,
        sink: &[ValueId],
        x: &[ValueId],
        elem: TypeId,
    ) -> R<(BlockId, Vec<ValueId>)> {
        let &[data, capacity, count] = sink else {
            return self.err("a set is not a sink of three leaves");
        };
        let (size, align, offs) = flat::layout(self.src, elem).map_err(|e| (e, self.span))?;
        if offs.len() != x.len() {
            return self.err("an inserted value does not match the set's element type");
        }
        let stride = size.div_ceil(align) * align;
        let u64t = self.dst.types.int(IntTy::U64);
        let ptrt = self.dst.ty(Type::Ptr);
        let region = self.dst.blocks[cur]
            .parent
            .ok_or(("detached block".to_string(), None))?;
        let store = self.dst.add_block(region, &[]);
        let join = self.dst.add_block(region, &[]);
        let room = self.cmp(cur, CmpPred::Lt, count, capacity);
        let one = self.int_const(cur, u64t, 1);
        let next = self.e1(cur, L::Add, &[count, one], u64t);
        let mut b = Builder::at_end(self.dst, cur);
        b.set_span(self.span);
        b.lo_cond_br(room, (store, &[]), (join, &[]));
        let s = self.int_const(store, u64t, stride as i128);
        let off = self.e1(store, L::Mul, &[count, s], u64t);
        let at = self.e1(store, L::PtrAdd, &[data, off], ptrt);
        self.store_leaves(store, at, &offs, x);
        let mut b = Builder::at_end(self.dst, store);
        b.set_span(self.span);
        b.lo_br(join, &[]);
        Ok((join, vec![data, capacity, next]))
    }
}
