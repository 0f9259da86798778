//! The `mem` ops in `mem-to-lo` (design note §2): address arithmetic and one scalar load or
//! store per leaf.
//!
//! * `mem.buffer {index}` `(%B)` is the `ptr` at byte `8 * index` of the buffer table, loaded
//!   with `global = true` (buffers live in the device's global memory on a GPU).
//! * `mem.load/store/addr {offset, stride}` `(%base, %i?)` address `base + i * stride + offset`
//!   (the index converted to `u64`; a signed index wraps as two's complement); a record, vector
//!   or tuple is one access per leaf at `offset +` its layout offset.
//! * A `!mem.view<T>` is three leaves: the address of its first element, its length and its
//!   stride (both `u64`), so views pass through calls and block arguments. `tree.foreach` over
//!   a view is a loop (header with the index as block argument, body, latch), `tree.index` on
//!   a view is a load at `ptr + i * stride`, `len` is the length leaf.

use super::{flat, FnLower, Step, R};
use scion_ir::attr::Attr;
use scion_ir::entity::{BlockId, OpId, TypeId, ValueId};
use scion_ir::lo::Op as L;
use scion_ir::mem::Op as M;
use scion_ir::tree::CmpPred;
use scion_ir::types::{IntTy, Type};
use scion_ir::{Builder, OpSpec};

impl FnLower<'_> {
    fn u64t(&mut self) -> TypeId {
        self.dst.types.int(IntTy::U64)
    }

    fn ptrt(&mut self) -> TypeId {
        self.dst.ty(Type::Ptr)
    }

    /// `base + i * stride` (`base` when there is no index).
    fn indexed(
        &mut self,
        cur: BlockId,
        base: ValueId,
        idx: Option<ValueId>,
        stride: i128,
    ) -> ValueId {
        let Some(i) = idx else {
            return base;
        };
        let u64t = self.u64t();
        let ptrt = self.ptrt();
        let wide = if self.ty_of(i) == u64t {
            i
        } else {
            self.e1(cur, L::Cast, &[i], u64t)
        };
        let s = self.int_const(cur, u64t, stride);
        let off = self.e1(cur, L::Mul, &[wide, s], u64t);
        self.e1(cur, L::PtrAdd, &[base, off], ptrt)
    }

    /// Loads the leaves of `ty` (a source type) at `ptr + offset`.
    pub(super) fn load_value(
        &mut self,
        cur: BlockId,
        ptr: ValueId,
        offset: i128,
        ty: TypeId,
    ) -> R<Vec<ValueId>> {
        let (_, _, offs) = flat::layout(self.src, ty).map_err(|e| (e, self.span))?;
        let tys = self.lo_ty(ty)?;
        Ok(offs
            .iter()
            .zip(tys)
            .map(|(&o, t)| {
                let l = self.insert(
                    cur,
                    OpSpec::new(L::Load)
                        .operands(&[ptr])
                        .results(&[t])
                        .attr("offset", Attr::Int(offset + o as i128)),
                );
                self.dst.ops[l].results[0]
            })
            .collect())
    }

    /// Lowers one `mem` op.
    pub(super) fn lower_mem(
        &mut self,
        op: OpId,
        kind: M,
        ins: &[Vec<ValueId>],
        cur: BlockId,
    ) -> R<Step> {
        let src = self.src;
        let o = &src.ops[op];
        let offset = o.int_attr("offset").unwrap_or(0);
        let stride = o.int_attr("stride").unwrap_or(0);
        let scalar = |i: usize| ins.get(i).and_then(|l| l.first().copied());
        let out = match kind {
            M::Buffer => {
                let index = o.int_attr("index").unwrap_or(0);
                let ptrt = self.ptrt();
                let b = scalar(0).ok_or(("mem.buffer needs %B".to_string(), self.span))?;
                let l = self.insert(
                    cur,
                    OpSpec::new(L::Load)
                        .operands(&[b])
                        .results(&[ptrt])
                        .attr("offset", Attr::Int(8 * index))
                        .attr("global", Attr::Bool(true)),
                );
                vec![self.dst.ops[l].results[0]]
            }
            M::Load => {
                let base = scalar(0).ok_or(("mem.load needs a base".to_string(), self.span))?;
                let p = self.indexed(cur, base, scalar(1).filter(|_| ins.len() == 2), stride);
                let ty = src.values[o.results[0]].ty;
                self.load_value(cur, p, offset, ty)?
            }
            M::Store => {
                let base = scalar(0).ok_or(("mem.store needs a base".to_string(), self.span))?;
                let idx = if ins.len() == 3 { scalar(1) } else { None };
                let value_src = *o
                    .operands
                    .last()
                    .ok_or(("mem.store needs a value".to_string(), self.span))?;
                let p = self.indexed(cur, base, idx, stride);
                let (_, _, offs) =
                    flat::layout(src, src.values[value_src].ty).map_err(|e| (e, self.span))?;
                let vals = ins.last().cloned().unwrap_or_default();
                for (&off, &v) in offs.iter().zip(&vals) {
                    self.insert(
                        cur,
                        OpSpec::new(L::Store)
                            .operands(&[p, v])
                            .attr("offset", Attr::Int(offset + off as i128)),
                    );
                }
                Vec::new()
            }
            M::Addr => {
                let base = scalar(0).ok_or(("mem.addr needs a base".to_string(), self.span))?;
                let p = self.indexed(cur, base, scalar(1).filter(|_| ins.len() == 2), stride);
                if offset == 0 {
                    vec![p]
                } else {
                    let u64t = self.u64t();
                    let ptrt = self.ptrt();
                    let c = self.int_const(cur, u64t, offset);
                    vec![self.e1(cur, L::PtrAdd, &[p, c], ptrt)]
                }
            }
            M::View => {
                let (Some(base), Some(start), Some(len)) = (scalar(0), scalar(1), scalar(2)) else {
                    return self.err("mem.view needs base, start and len");
                };
                let first = self.indexed(cur, base, Some(start), stride);
                let u64t = self.u64t();
                let n = if self.ty_of(len) == u64t {
                    len
                } else {
                    self.e1(cur, L::Cast, &[len], u64t)
                };
                let s = self.int_const(cur, u64t, stride);
                vec![first, n, s]
            }
        };
        self.bind_results(op, out, cur)
    }

    /// `tree.foreach` over a view: a loop over `0..len`.
    pub(super) fn foreach_view(
        &mut self,
        op: OpId,
        view: &[ValueId],
        elem: TypeId,
        cur: BlockId,
    ) -> R<Step> {
        let src = self.src;
        let o = &src.ops[op];
        let [ptr, len, stride] = view else {
            return self.err("a view has three leaves");
        };
        let (ptr, len, stride) = (*ptr, *len, *stride);
        let u64t = self.u64t();
        let ptrt = self.ptrt();
        let region = self.dst.blocks[cur]
            .parent
            .ok_or(("detached block".to_string(), None))?;
        let head = self.dst.add_block(region, &[u64t]);
        let body = self.dst.add_block(region, &[]);
        let exit = self.dst.add_block(region, &[]);
        let zero = self.int_const(cur, u64t, 0);
        Builder::at_end(self.dst, cur).lo_br(head, &[zero]);
        let i = self.dst.blocks[head].args[0];
        let more = self.cmp(head, CmpPred::Lt, i, len);
        Builder::at_end(self.dst, head).lo_cond_br(more, (body, &[]), (exit, &[]));
        let off = self.e1(body, L::Mul, &[i, stride], u64t);
        let at = self.e1(body, L::PtrAdd, &[ptr, off], ptrt);
        let tb = src.regions[o.regions[0]].blocks[0];
        // An element nothing reads is not loaded (`mem-sink` moves a conditional use of it
        // into a `tree.index` where it is needed).
        let used = src.blocks[tb]
            .args
            .first()
            .is_some_and(|&e| region_reads(src, o.regions[0], e));
        let e = if used {
            self.load_value(body, at, 0, elem)?
        } else {
            Vec::new()
        };
        let mut args = vec![e];
        if src.blocks[tb].args.len() == 2 {
            let it = self.lo_ty(src.values[src.blocks[tb].args[1]].ty)?[0];
            args.push(vec![if it == u64t {
                i
            } else {
                self.e1(body, L::Cast, &[i], it)
            }]);
        }
        if let Some((end, _)) = self.lower_block(tb, args, body)? {
            let one = self.int_const(end, u64t, 1);
            let next = self.e1(end, L::Add, &[i, one], u64t);
            Builder::at_end(self.dst, end).lo_br(head, &[next]);
        }
        Ok(Step::Next(exit))
    }

    /// `tree.index` on a view.
    pub(super) fn index_view(
        &mut self,
        cur: BlockId,
        view: &[ValueId],
        idx: ValueId,
        elem: TypeId,
    ) -> R<Vec<ValueId>> {
        let [ptr, _, stride] = view else {
            return self.err("a view has three leaves");
        };
        let (ptr, stride) = (*ptr, *stride);
        let u64t = self.u64t();
        let ptrt = self.ptrt();
        let i = if self.ty_of(idx) == u64t {
            idx
        } else {
            self.e1(cur, L::Cast, &[idx], u64t)
        };
        let off = self.e1(cur, L::Mul, &[i, stride], u64t);
        let at = self.e1(cur, L::PtrAdd, &[ptr, off], ptrt);
        self.load_value(cur, at, 0, elem)
    }
}

/// Whether an op of `region` (at any depth) reads `v`.
fn region_reads(m: &scion_ir::Module, region: scion_ir::RegionId, v: ValueId) -> bool {
    let mut found = false;
    scion_ir::walk::walk_region(m, region, scion_ir::walk::Order::Pre, &mut |op| {
        found |= m.ops[op].operands.contains(&v)
            || m.ops[op].successors.iter().any(|s| s.args.contains(&v));
    });
    found
}
