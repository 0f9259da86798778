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
        let tb = src.regions[o.regions[0]].blocks[0];
        // A body that acts only every `step`-th iteration steps over the others.
        let guard = guarded_stride(src, tb);
        let step = guard.map_or(1, |(step, _)| step);
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
        let done = match guard {
            None => self.lower_block(tb, args, body)?,
            Some((_, guard)) => {
                // The block's pure ops (the guard's condition among them, which holds at every
                // iteration left), then the guarded arm in place of the `if`.
                for (&a, l) in src.blocks[tb].args.iter().zip(args) {
                    self.vals.insert(a, l);
                }
                let mut cur = body;
                for &op in src.blocks[tb].ops.iter().take_while(|&&op| op != guard) {
                    match self.lower_op(op, cur)? {
                        Step::Next(b) => cur = b,
                        _ => return self.err("a guarded loop body's pure op ended its block"),
                    }
                }
                let arm = src.regions[src.ops[guard].regions[0]].blocks[0];
                self.lower_block(arm, Vec::new(), cur)?
            }
        };
        if let Some((end, _)) = done {
            let one = self.int_const(end, u64t, step as i128);
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

/// The step of a `foreach` body that does something only at every `step`-th index, and the
/// `tree.if` that says so: the body block is pure arithmetic (constants, `and`, compares, casts)
/// and one `if (k & (step - 1)) == 0` on the loop's index `k`, with an empty else arm, no results
/// and nothing after it. The iterations between are no-ops, so the loop can step over them:
/// closest hit's leaves take their triangles in runs of four (`if (k & 3) == 0`, the run's
/// triangles read in the arm), and went round the loop for every triangle.
fn guarded_stride(m: &scion_ir::Module, body: BlockId) -> Option<(u64, OpId)> {
    use scion_ir::op::OpKind;
    use scion_ir::tree::Op as T;
    let tree = |op: OpId| match m.ops[op].kind {
        OpKind::Tree(k) => Some(k),
        _ => None,
    };
    let def = |v: ValueId| m.def_op(v).filter(|&d| m.blocks[body].ops.contains(&d));
    let constant = |v: ValueId| {
        m.def_op(v)
            .filter(|&d| tree(d) == Some(T::Const))
            .and_then(|d| m.ops[d].int_attr("value"))
    };
    let block = &m.blocks[body];
    let [_, k] = block.args[..] else {
        return None;
    };
    let (&last, rest) = block.ops.split_last()?;
    if tree(last) != Some(T::Yield) || !m.ops[last].operands.is_empty() {
        return None;
    }
    let mut guard = None;
    for &op in rest {
        match tree(op)? {
            T::Const | T::And | T::Cmp | T::Cast if m.ops[op].regions.is_empty() => {}
            T::If if guard.is_none() => guard = Some(op),
            _ => return None,
        }
    }
    let guard = guard?;
    let g = &m.ops[guard];
    if !g.results.is_empty() || g.regions.len() != 2 || *rest.last()? != guard {
        return None;
    }
    let else_block = m.regions[g.regions[1]].blocks.first()?;
    if m.blocks[*else_block].ops.len() != 1 {
        return None;
    }
    let cmp = def(g.operands[0]).filter(|&c| tree(c) == Some(T::Cmp))?;
    if m.ops[cmp].pred() != Some(CmpPred::Eq) {
        return None;
    }
    let [a, b] = m.ops[cmp].operands[..] else {
        return None;
    };
    let masked = match (constant(a), constant(b)) {
        (_, Some(0)) => a,
        (Some(0), _) => b,
        _ => return None,
    };
    let and = def(masked).filter(|&d| tree(d) == Some(T::And))?;
    let [x, y] = m.ops[and].operands[..] else {
        return None;
    };
    let (index, mask) = match (constant(x), constant(y)) {
        (None, Some(c)) => (x, c),
        (Some(c), None) => (y, c),
        _ => return None,
    };
    // The index, or an integer cast of it (a cast keeps the low bits).
    let index_ok = index == k
        || def(index).is_some_and(|c| {
            tree(c) == Some(T::Cast)
                && m.ops[c].operands[0] == k
                && matches!(m.types.get(m.values[index].ty), Type::Int(_))
        });
    let step = u64::try_from(mask).ok()?.checked_add(1)?;
    let bits = m.types.bit_width(m.values[index].ty)?;
    (index_ok && mask > 0 && step.is_power_of_two() && step.trailing_zeros() < bits.min(16))
        .then_some((step, guard))
}
