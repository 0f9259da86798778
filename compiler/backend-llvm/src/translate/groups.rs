//! The source's four- and eight-lane vector operations as LLVM vector instructions.
//!
//! `lo` is scalar: `mem-to-lo` lowers `a - b` on two `f32x4` as four `lo.sub`, one per lane,
//! and marks them `lane = [group, k, n]` (`FnLower::tag_lanes`). Left scalar, LLVM's SLP
//! vectorizer has to find the vectors again, and where one lane's computation holds several
//! operations of one shape (the components of a cross product, the dot products of a
//! Möller-Trumbore test) it packs those together and mixes the lanes with shuffles
//! (docs/performance-eight-wide.md, "Fifteenth session"). So a run of `n` consecutive ops marked as lanes
//! `0 .. n` of one group, all of one kind (and predicate), is translated here as one `<n x T>`
//! operation, whose lanes are then the `lo` values (`extractelement`, which LLVM folds away where
//! the next group reads the whole vector). An operand is the vector of an earlier group when its
//! lanes are exactly that group's lanes in order, else it is assembled from the scalars
//! (`insertelement`; LLVM turns consecutive loads so assembled into one vector load).
//!
//! Every lane computes exactly what its scalar op computes (the same LLVM operation lane by
//! lane; a NaN result is made canonical where any lane's must be, which changes nothing for the
//! lanes whose NaN cannot be seen; `min`/`max` in the cheapest form every lane allows). Integer
//! division and float casts stay scalar, as does every op on NVPTX, whose registers are scalar.

use super::*;
use inkwell::types::VectorType;
use inkwell::values::VectorValue;
use scion_ir::lo::lanes::lane_groups;
use scion_ir::lo::layout_reads;
use scion_ir::OpId;

/// Whether a group of `kind` can be one vector instruction (its result type `rt`).
fn vector_kind(m: &Module, kind: L, o: &scion_ir::Operation) -> bool {
    let rt = m.values[o.results[0]].ty;
    let float = matches!(m.types.get(rt), Type::Float(_));
    let int = matches!(m.types.get(rt), Type::Int(_));
    match kind {
        L::Add | L::Sub | L::Mul => float || int,
        L::Div => float,
        L::And | L::Or | L::Xor | L::Not | L::BitNot => !float,
        L::Shl | L::Shr => int,
        L::Neg | L::Cmp | L::Select | L::Bitcast | L::Min | L::Max => true,
        L::Cast => {
            let from = m.values[o.operands[0]].ty;
            int && matches!(m.types.get(from), Type::Int(_) | Type::Bool)
        }
        _ => false,
    }
}

/// The groups of the blocks `blocks` LLVM emits as vector instructions (all of the kinds
/// [`vector_kind`] takes; `scion_ir::lo::lanes`), each keyed by its first op.
pub(super) fn groups(m: &Module, blocks: &[BlockId]) -> HashMap<OpId, Vec<OpId>> {
    lane_groups(m, blocks, |m, op| match m.ops[op].kind {
        OpKind::Lo(kind) => vector_kind(m, kind, &m.ops[op]),
        _ => false,
    })
}

impl<'c> Fn<'_, 'c> {
    /// The four lanes `xs` as one vector load when they are loads of consecutive 32-bit words
    /// of a layout buffer the function does not write, so that reading them again here reads
    /// the same words (`scion_ir::lo::layout_reads`; a lane may be an inlined call's parameter
    /// that stands for such a load). The node's two boxes of the binary closest hit's
    /// `distmin_pair` are then two 16-byte loads of each node; left to LLVM, the eight scalar
    /// loads of each vector became a 8-byte and a 16-byte load and four shuffles.
    fn quad_load(&self, xs: &[ValueId]) -> R<Option<VectorValue<'c>>> {
        let m = self.m;
        if xs.len() != 4 || !self.layout_readonly {
            return Ok(None);
        }
        let mut ops = Vec::with_capacity(4);
        for &x in xs {
            match m.def_op(layout_reads::passed_value(m, x)) {
                Some(op) if m.ops[op].kind == OpKind::Lo(L::Load) => ops.push(op),
                _ => return Ok(None),
            }
        }
        let first = &m.ops[ops[0]];
        let addr = first.operands[0];
        let ty = m.values[first.results[0]].ty;
        let off0 = first.int_attr("offset").unwrap_or(0);
        let bits32 = match m.types.get(ty) {
            Type::Float(FloatTy::F32) => true,
            Type::Int(t) => t.bits() == 32,
            _ => false,
        };
        if !bits32 || first.attr("global").is_some() || !layout_reads::in_layout(m, addr) {
            return Ok(None);
        }
        for (k, &op) in ops.iter().enumerate() {
            let o = &m.ops[op];
            if o.operands[0] != addr
                || m.values[o.results[0]].ty != ty
                || o.int_attr("offset").unwrap_or(0) != off0 + 4 * k as i128
            {
                return Ok(None);
            }
        }
        let p = self.offset_ptr(self.v(addr)?, off0)?;
        let vt = Self::vec_type(self.v(xs[0])?.get_type(), 4)?;
        let v = self.b.build_load(vt, p, "").map_err(be)?;
        if let Some(i) = v.as_instruction_value() {
            i.set_alignment(4).map_err(be)?;
        }
        Ok(Some(v.into_vector_value()))
    }

    /// The vector type of `n` lanes of `t`.
    fn vec_type(t: BasicTypeEnum<'c>, n: u32) -> R<VectorType<'c>> {
        Ok(match t {
            BasicTypeEnum::FloatType(f) => f.vec_type(n),
            BasicTypeEnum::IntType(i) => i.vec_type(n),
            _ => return Err("a vector lane of neither an integer nor a float".into()),
        })
    }

    /// `<n x T>` splat of the constant `c`.
    fn splat_const(c: BasicValueEnum<'c>, n: usize) -> VectorValue<'c> {
        VectorType::const_vector(&vec![c; n])
    }

    /// The vector whose lanes are the values `xs`.
    fn lane_vector(&self, xs: &[ValueId]) -> R<VectorValue<'c>> {
        if let Some(&(v, 0)) = self.lane_vecs.get(&xs[0]) {
            if xs
                .iter()
                .enumerate()
                .all(|(k, x)| self.lane_vecs.get(x) == Some(&(v, k as u32)))
            {
                return Ok(v);
            }
        }
        if let Some(v) = self.quad_load(xs)? {
            return Ok(v);
        }
        if xs.len() == 8 {
            if let (Some(lo), Some(hi)) = (self.quad_load(&xs[..4])?, self.quad_load(&xs[4..])?) {
                let mask: Vec<_> = (0..8u64)
                    .map(|k| self.cx.i32_type().const_int(k, false))
                    .collect();
                let mask = VectorType::const_vector(&mask);
                return self.b.build_shuffle_vector(lo, hi, mask, "").map_err(be);
            }
        }
        let scalars: Vec<BasicValueEnum<'c>> = xs.iter().map(|&x| self.v(x)).collect::<R<_>>()?;
        let vt = Self::vec_type(scalars[0].get_type(), xs.len() as u32)?;
        let mut acc = vt.get_poison();
        for (k, s) in scalars.into_iter().enumerate() {
            let at = self.cx.i32_type().const_int(k as u64, false);
            acc = self.b.build_insert_element(acc, s, at, "").map_err(be)?;
        }
        Ok(acc)
    }

    /// `min`/`max` lane by lane: the scalar translation's compare-and-select in the form every
    /// lane allows (the general one, which is right for every lane, when their forms differ).
    fn min_max_lanes(
        &self,
        max: bool,
        ops: &[OpId],
        args: &[VectorValue<'c>],
        signed: bool,
    ) -> R<VectorValue<'c>> {
        let b = self.b;
        let (p, q) = (args[0], args[1]);
        if !p.get_type().get_element_type().is_float_type() {
            let name = match (max, signed) {
                (false, true) => "llvm.smin",
                (false, false) => "llvm.umin",
                (true, true) => "llvm.smax",
                (true, false) => "llvm.umax",
            };
            let t = p.get_type().as_basic_type_enum();
            return Ok(self
                .call_intr(name, &[t], &[p.into(), q.into()])?
                .into_vector_value());
        }
        let form = self
            .nan
            .lanes_min_max_form(self.m, ops)
            .unwrap_or(MinMaxForm::General);
        let pred = if max {
            FloatPredicate::OGT
        } else {
            FloatPredicate::OLT
        };
        if form == MinMaxForm::SelectSwapped {
            let better = b.build_float_compare(pred, p, q, "").map_err(be)?;
            return Ok(b
                .build_select(better, p, q, "")
                .map_err(be)?
                .into_vector_value());
        }
        let better = b.build_float_compare(pred, q, p, "").map_err(be)?;
        let r = b.build_select(better, q, p, "").map_err(be)?;
        if form == MinMaxForm::Select {
            return Ok(r.into_vector_value());
        }
        let p_nan = b
            .build_float_compare(FloatPredicate::UNO, p, p, "")
            .map_err(be)?;
        Ok(b.build_select(p_nan, q, r.into_vector_value(), "")
            .map_err(be)?
            .into_vector_value())
    }

    /// Translates the group `ops` (see the module documentation) and binds its lanes.
    pub(super) fn group(&mut self, ops: &[OpId]) -> R<()> {
        let m = self.m;
        let first = &m.ops[ops[0]];
        let OpKind::Lo(kind) = first.kind else {
            return Err("a lane group of non-lo ops".into());
        };
        let n = ops.len();
        let args: Vec<VectorValue<'c>> = (0..first.operands.len())
            .map(|j| {
                let xs: Vec<ValueId> = ops.iter().map(|&o| m.ops[o].operands[j]).collect();
                self.lane_vector(&xs)
            })
            .collect::<R<_>>()?;
        let rt = llvm_type(self.cx, m, m.values[first.results[0]].ty)?;
        let vt = Self::vec_type(rt, n as u32)?;
        let signed = self.signed(first.operands[0]);
        let is_float = rt.is_float_type();
        let b = self.b;
        let v: VectorValue<'c> = match kind {
            L::Add if is_float => b.build_float_add(args[0], args[1], "").map_err(be)?,
            L::Sub if is_float => b.build_float_sub(args[0], args[1], "").map_err(be)?,
            L::Mul if is_float => b.build_float_mul(args[0], args[1], "").map_err(be)?,
            L::Div => b.build_float_div(args[0], args[1], "").map_err(be)?,
            L::Add => b.build_int_add(args[0], args[1], "").map_err(be)?,
            L::Sub => b.build_int_sub(args[0], args[1], "").map_err(be)?,
            L::Mul => b.build_int_mul(args[0], args[1], "").map_err(be)?,
            L::And => b.build_and(args[0], args[1], "").map_err(be)?,
            L::Or => b.build_or(args[0], args[1], "").map_err(be)?,
            L::Xor => b.build_xor(args[0], args[1], "").map_err(be)?,
            L::Not | L::BitNot => b.build_not(args[0], "").map_err(be)?,
            L::Neg if is_float => b.build_float_neg(args[0], "").map_err(be)?,
            L::Neg => b.build_int_neg(args[0], "").map_err(be)?,
            L::Shl | L::Shr => {
                // The amount modulo the width, as the scalar translation takes it.
                let amt = b
                    .build_int_cast_sign_flag(args[1], vt, false, "")
                    .map_err(be)?;
                let width = rt.into_int_type().get_bit_width();
                let mask = rt.into_int_type().const_int(u64::from(width - 1), false);
                let amt = b
                    .build_and(amt, Self::splat_const(mask.into(), n), "")
                    .map_err(be)?;
                match kind {
                    L::Shl => b.build_left_shift(args[0], amt, ""),
                    _ => b.build_right_shift(args[0], amt, signed, ""),
                }
                .map_err(be)?
            }
            L::Cmp => {
                let pred = first.pred().ok_or("bad predicate")?;
                let float = m.types.get(m.values[first.operands[0]].ty).clone();
                if matches!(float, Type::Float(_)) {
                    let p = match pred {
                        CmpPred::Eq => FloatPredicate::OEQ,
                        CmpPred::Ne => FloatPredicate::UNE,
                        CmpPred::Lt => FloatPredicate::OLT,
                        CmpPred::Le => FloatPredicate::OLE,
                        CmpPred::Gt => FloatPredicate::OGT,
                        CmpPred::Ge => FloatPredicate::OGE,
                    };
                    b.build_float_compare(p, args[0], args[1], "").map_err(be)?
                } else {
                    let p = match (pred, signed) {
                        (CmpPred::Eq, _) => IntPredicate::EQ,
                        (CmpPred::Ne, _) => IntPredicate::NE,
                        (CmpPred::Lt, true) => IntPredicate::SLT,
                        (CmpPred::Le, true) => IntPredicate::SLE,
                        (CmpPred::Gt, true) => IntPredicate::SGT,
                        (CmpPred::Ge, true) => IntPredicate::SGE,
                        (CmpPred::Lt, false) => IntPredicate::ULT,
                        (CmpPred::Le, false) => IntPredicate::ULE,
                        (CmpPred::Gt, false) => IntPredicate::UGT,
                        (CmpPred::Ge, false) => IntPredicate::UGE,
                    };
                    b.build_int_compare(p, args[0], args[1], "").map_err(be)?
                }
            }
            L::Select => b
                .build_select(args[0], args[1], args[2], "")
                .map_err(be)?
                .into_vector_value(),
            L::Cast => {
                let s = matches!(
                    m.types.get(m.values[first.operands[0]].ty),
                    Type::Int(i) if i.is_signed()
                );
                b.build_int_cast_sign_flag(args[0], vt, s, "").map_err(be)?
            }
            L::Bitcast => b
                .build_bit_cast(args[0], vt, "")
                .map_err(be)?
                .into_vector_value(),
            L::Min | L::Max => self.min_max_lanes(kind == L::Max, ops, &args, signed)?,
            _ => return Err(format!("lane group of `lo.{}`", kind.mnemonic())),
        };
        // A NaN made canonical where some lane's can be seen (`canon` works lane by lane).
        let v = if is_float
            && ops
                .iter()
                .any(|&o| self.nan.canonicalize(m.ops[o].results[0]))
        {
            let uno = b
                .build_float_compare(FloatPredicate::UNO, v, v, "")
                .map_err(be)?;
            let nan_bits = if rt.into_float_type().get_bit_width() == 32 {
                0x7fc0_0000
            } else {
                scion_ir::attr::CANONICAL_NAN_BITS
            };
            let nan = self.fconst(rt, nan_bits)?;
            b.build_select(uno, Self::splat_const(nan.into(), n), v, "")
                .map_err(be)?
                .into_vector_value()
        } else {
            v
        };
        for (k, &o) in ops.iter().enumerate() {
            let at = self.cx.i32_type().const_int(k as u64, false);
            let lane = b.build_extract_element(v, at, "").map_err(be)?;
            let r = m.ops[o].results[0];
            self.vals.insert(r, lane);
            self.lane_vecs.insert(r, (v, k as u32));
        }
        Ok(())
    }
}
