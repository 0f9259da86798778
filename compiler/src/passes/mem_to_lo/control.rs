//! Structured control flow in `mem-to-lo`: `tree.if` (a `lo.cond_br` to two blocks and a join
//! block whose arguments are the yielded leaves), `tree.match` on a record (its one arm), and
//! `tree.foreach` over a fixed array (unrolled; a view's loop is `mem_ops.rs`'s).

use super::{FnLower, Step, R};
use scion_ir::entity::{BlockId, OpId, ValueId};
use scion_ir::types::Type;
use scion_ir::Builder;

impl FnLower<'_> {
    pub(super) fn lower_if(&mut self, op: OpId, cond: ValueId, cur: BlockId) -> R<Step> {
        let src = self.src;
        let o = &src.ops[op];
        let region = self.dst.blocks[cur]
            .parent
            .ok_or(("detached block".to_string(), None))?;
        let then_b = self.dst.add_block(region, &[]);
        let else_b = self.dst.add_block(region, &[]);
        let mut b = Builder::at_end(self.dst, cur);
        b.set_span(self.span);
        b.lo_cond_br(cond, (then_b, &[]), (else_b, &[]));
        let mut arms = Vec::new();
        for (i, start) in [then_b, else_b].into_iter().enumerate() {
            let tb = src.regions[o.regions[i]].blocks[0];
            if let Some(done) = self.lower_block(tb, Vec::new(), start)? {
                arms.push(done);
            }
        }
        self.join(op, arms, region)
    }

    /// Continues after a region op whose arms ended in `arms` (block, yielded leaves): a join
    /// block taking the results, or nothing when no arm falls through.
    fn join(
        &mut self,
        op: OpId,
        arms: Vec<(BlockId, Vec<ValueId>)>,
        region: scion_ir::RegionId,
    ) -> R<Step> {
        if arms.is_empty() {
            return Ok(Step::Dead);
        }
        let mut tys = Vec::new();
        for &r in &self.src.ops[op].results.clone() {
            tys.extend(self.lo_ty(self.src.values[r].ty)?);
        }
        let join = self.dst.add_block(region, &tys);
        for (b, vals) in arms {
            let mut bl = Builder::at_end(self.dst, b);
            bl.set_span(self.span);
            bl.lo_br(join, &vals);
        }
        let args = self.dst.blocks[join].args.to_vec();
        self.bind_results(op, args, join)?;
        Ok(Step::Next(join))
    }

    pub(super) fn lower_match(&mut self, op: OpId, scrut: &[ValueId], cur: BlockId) -> R<Step> {
        let src = self.src;
        let o = &src.ops[op];
        let ty = src.values[o.operands[0]].ty;
        let is_record = src.adt_of_type(ty).is_some_and(|d| d.is_record());
        if !is_record || o.regions.len() != 1 {
            return self.err("`tree.match` on a sum type needs a layout");
        }
        let tb = src.regions[o.regions[0]].blocks[0];
        let nargs = src.blocks[tb].args.len();
        let mut args = Vec::new();
        if nargs > 0 {
            let mut start = 0;
            for i in 0..nargs {
                let (_, n) = self.member_range(ty, i)?;
                args.push(scrut[start..start + n].to_vec());
                start += n;
            }
        }
        let region = self.dst.blocks[cur]
            .parent
            .ok_or(("detached block".to_string(), None))?;
        let arms: Vec<_> = self.lower_block(tb, args, cur)?.into_iter().collect();
        self.join(op, arms, region)
    }

    pub(super) fn lower_foreach(
        &mut self,
        op: OpId,
        elems: &[ValueId],
        mut cur: BlockId,
    ) -> R<Step> {
        let src = self.src;
        let o = &src.ops[op];
        let n = match src.types.get(src.values[o.operands[0]].ty) {
            Type::Array { len: Some(n), .. } => *n as usize,
            Type::View(elem) => return self.foreach_view(op, elems, *elem, cur),
            _ => return self.err("`tree.foreach` over a slice or set needs a layout or a view"),
        };
        let tb = src.regions[o.regions[0]].blocks[0];
        let with_index = src.blocks[tb].args.len() == 2;
        let k = elems.len().checked_div(n).unwrap_or(0);
        for i in 0..n {
            let mut args = vec![elems[i * k..(i + 1) * k].to_vec()];
            if with_index {
                let it = self.lo_ty(src.values[src.blocks[tb].args[1]].ty)?[0];
                args.push(vec![self.int_const(cur, it, i as i128)]);
            }
            match self.lower_block(tb, args, cur)? {
                Some((b, _)) => cur = b,
                None => return Ok(Step::Dead),
            }
        }
        Ok(Step::Next(cur))
    }
}
