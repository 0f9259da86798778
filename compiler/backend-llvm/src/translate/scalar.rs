//! Scalar semantics of the `lo` ops that need more than one LLVM instruction: float constants by
//! their bits, the canonical NaN in place of an observable one, comparisons (ordered except
//! `ne`), integer division and remainder by the operand types' signedness,
//! `minNum`/`maxNum` with first-operand ties, `next_up`/`next_down` as integer steps on the bits,
//! value casts (saturating float-to-int, NaN to 0) and the GPU thread index. Input: operands
//! already translated; output: the result value. The same semantics as `scion-clif` and the
//! `lo` interpreter, bit for bit.

use super::*;

impl<'c> Fn<'_, 'c> {
    pub(super) fn fconst(&self, ty: BasicTypeEnum<'c>, bits: u64) -> R<FloatValue<'c>> {
        // Through the integer bits, so NaN payloads and signed zeros are exact.
        let ity = int_type(self.cx, ty.into_float_type().get_bit_width());
        let v = self
            .b
            .build_bit_cast(ity.const_int(bits, false), ty, "")
            .map_err(be)?;
        Ok(v.into_float_value())
    }

    /// The canonical quiet NaN in place of any NaN `v`.
    pub(super) fn canon(&self, v: FloatValue<'c>) -> R<BasicValueEnum<'c>> {
        let ty = v.get_type().as_basic_type_enum();
        let nan = if v.get_type().get_bit_width() == 32 {
            self.fconst(ty, 0x7fc0_0000)?
        } else {
            self.fconst(ty, scion_ir::attr::CANONICAL_NAN_BITS)?
        };
        let uno = self
            .b
            .build_float_compare(FloatPredicate::UNO, v, v, "")
            .map_err(be)?;
        self.b.build_select(uno, nan, v, "").map_err(be)
    }

    /// `v` (the value of `lo` value `x`), canonicalized when [`NanFacts::canonicalize`] says so.
    pub(super) fn canon_if_needed(
        &self,
        x: ValueId,
        v: BasicValueEnum<'c>,
    ) -> R<BasicValueEnum<'c>> {
        if self.nan.canonicalize(x) {
            self.canon(v.into_float_value())
        } else {
            Ok(v)
        }
    }

    pub(super) fn compare(
        &self,
        pred: CmpPred,
        x: BasicValueEnum<'c>,
        y: BasicValueEnum<'c>,
        signed: bool,
    ) -> R<IntValue<'c>> {
        let b = self.b;
        if x.is_float_value() {
            let p = match pred {
                CmpPred::Eq => FloatPredicate::OEQ,
                CmpPred::Ne => FloatPredicate::UNE,
                CmpPred::Lt => FloatPredicate::OLT,
                CmpPred::Le => FloatPredicate::OLE,
                CmpPred::Gt => FloatPredicate::OGT,
                CmpPred::Ge => FloatPredicate::OGE,
            };
            return b
                .build_float_compare(p, x.into_float_value(), y.into_float_value(), "")
                .map_err(be);
        }
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
        if x.is_pointer_value() {
            return b
                .build_int_compare(
                    p,
                    b.build_ptr_to_int(x.into_pointer_value(), self.cx.i64_type(), "")
                        .map_err(be)?,
                    b.build_ptr_to_int(y.into_pointer_value(), self.cx.i64_type(), "")
                        .map_err(be)?,
                    "",
                )
                .map_err(be);
        }
        b.build_int_compare(p, x.into_int_value(), y.into_int_value(), "")
            .map_err(be)
    }

    /// Integer division without traps: `MIN / -1` wraps to `MIN` (and `MIN % -1` is 0);
    /// division by zero, undefined in the IR, divides by 1 (as `scion-clif` does).
    pub(super) fn int_div(
        &self,
        div: bool,
        signed: bool,
        x: IntValue<'c>,
        y: IntValue<'c>,
    ) -> R<IntValue<'c>> {
        let b = self.b;
        let t = y.get_type();
        let one = t.const_int(1, false);
        let zero = t.const_zero();
        let is_zero = b
            .build_int_compare(IntPredicate::EQ, y, zero, "")
            .map_err(be)?;
        if !signed {
            let safe = b
                .build_select(is_zero, one, y, "")
                .map_err(be)?
                .into_int_value();
            return if div {
                b.build_int_unsigned_div(x, safe, "")
            } else {
                b.build_int_unsigned_rem(x, safe, "")
            }
            .map_err(be);
        }
        let m1 = t.const_all_ones();
        let is_m1 = b
            .build_int_compare(IntPredicate::EQ, y, m1, "")
            .map_err(be)?;
        let bad = b.build_or(is_zero, is_m1, "").map_err(be)?;
        let safe = b
            .build_select(bad, one, y, "")
            .map_err(be)?
            .into_int_value();
        let r = if div {
            let q = b.build_int_signed_div(x, safe, "").map_err(be)?;
            let neg = b.build_int_neg(x, "").map_err(be)?;
            b.build_select(is_m1, neg, q, "")
        } else {
            let r = b.build_int_signed_rem(x, safe, "").map_err(be)?;
            b.build_select(is_m1, zero, r, "")
        };
        Ok(r.map_err(be)?.into_int_value())
    }

    /// minNum/maxNum: the other operand when one is NaN (`q` when both are), `p` on ties.
    pub(super) fn min_max(
        &self,
        max: bool,
        p: BasicValueEnum<'c>,
        q: BasicValueEnum<'c>,
        signed: bool,
        form: MinMaxForm,
    ) -> R<BasicValueEnum<'c>> {
        let b = self.b;
        if !p.is_float_value() {
            let name = match (max, signed) {
                (false, true) => "llvm.smin",
                (false, false) => "llvm.umin",
                (true, true) => "llvm.smax",
                (true, false) => "llvm.umax",
            };
            return self.call_intr(name, &[p.get_type()], &[p, q]);
        }
        // minNum/maxNum with the first operand on ties, in the cheapest form the operands
        // allow (scion_ir::lo::nan::MinMaxForm); `select(q < p, q, p)` is one x86 `minss`.
        let (pf, qf) = (p.into_float_value(), q.into_float_value());
        let pred = if max {
            FloatPredicate::OGT
        } else {
            FloatPredicate::OLT
        };
        if form == MinMaxForm::SelectSwapped {
            let better = b.build_float_compare(pred, pf, qf, "").map_err(be)?;
            return b.build_select(better, p, q, "").map_err(be);
        }
        let better = b.build_float_compare(pred, qf, pf, "").map_err(be)?;
        let r = b.build_select(better, q, p, "").map_err(be)?;
        if form == MinMaxForm::Select {
            return Ok(r);
        }
        // q < p is false when q is NaN, so `r` is then p; only a NaN p needs its own select.
        let p_nan = b
            .build_float_compare(FloatPredicate::UNO, pf, pf, "")
            .map_err(be)?;
        b.build_select(p_nan, q, r, "").map_err(be)
    }

    /// One ulp toward `+inf` (`up`) or `-inf`; NaN and the infinity in that direction stay.
    pub(super) fn next(&self, up: bool, x: FloatValue<'c>) -> R<BasicValueEnum<'c>> {
        let b = self.b;
        let ft = x.get_type();
        let wide = ft.get_bit_width() == 64;
        let it = int_type(self.cx, ft.get_bit_width());
        let (zero_step, inf_bits) = match (wide, up) {
            (false, true) => (1u64, u64::from(f32::INFINITY.to_bits())),
            (false, false) => (0x8000_0001, u64::from(f32::NEG_INFINITY.to_bits())),
            (true, true) => (1, f64::INFINITY.to_bits()),
            (true, false) => (0x8000_0000_0000_0001, f64::NEG_INFINITY.to_bits()),
        };
        let fty = ft.as_basic_type_enum();
        let inf = self.fconst(fty, inf_bits)?;
        let zero = ft.const_zero();
        let bits = b.build_bit_cast(x, it, "").map_err(be)?.into_int_value();
        let one = it.const_int(1, false);
        let inc = b.build_int_add(bits, one, "").map_err(be)?;
        let dec = b.build_int_sub(bits, one, "").map_err(be)?;
        let pos = b
            .build_float_compare(FloatPredicate::OGT, x, zero, "")
            .map_err(be)?;
        let stepped = if up {
            b.build_select(pos, inc, dec, "")
        } else {
            b.build_select(pos, dec, inc, "")
        }
        .map_err(be)?;
        let is_zero = b
            .build_float_compare(FloatPredicate::OEQ, x, zero, "")
            .map_err(be)?;
        let zs = it.const_int(zero_step, false);
        let stepped = b
            .build_select(is_zero, zs.into(), stepped, "")
            .map_err(be)?;
        let r = b.build_bit_cast(stepped, ft, "").map_err(be)?;
        let nan = b
            .build_float_compare(FloatPredicate::UNO, x, x, "")
            .map_err(be)?;
        let at_inf = b
            .build_float_compare(FloatPredicate::OEQ, x, inf, "")
            .map_err(be)?;
        let keep = b.build_or(nan, at_inf, "").map_err(be)?;
        b.build_select(keep, x.into(), r, "").map_err(be)
    }

    /// `lo.cast`: Rust `as` semantics between scalars.
    pub(super) fn cast(
        &self,
        x: BasicValueEnum<'c>,
        from: TypeId,
        to: TypeId,
    ) -> R<BasicValueEnum<'c>> {
        let b = self.b;
        let m = self.m;
        let (ft, tt) = (m.types.get(from).clone(), m.types.get(to).clone());
        let lt = llvm_type(self.cx, m, to)?;
        Ok(match (&ft, &tt) {
            (Type::Bool, Type::Bool) => x,
            (Type::Float(_), Type::Bool) => {
                let xf = x.into_float_value();
                b.build_float_compare(FloatPredicate::UNE, xf, xf.get_type().const_zero(), "")
                    .map_err(be)?
                    .into()
            }
            (Type::Int(_), Type::Bool) => {
                let xi = x.into_int_value();
                b.build_int_compare(IntPredicate::NE, xi, xi.get_type().const_zero(), "")
                    .map_err(be)?
                    .into()
            }
            (Type::Int(_) | Type::Bool, Type::Int(_)) => {
                let s = matches!(ft, Type::Int(i) if i.is_signed());
                b.build_int_cast_sign_flag(x.into_int_value(), lt.into_int_type(), s, "")
                    .map_err(be)?
                    .into()
            }
            (Type::Int(_) | Type::Bool, Type::Float(_)) => {
                let s = matches!(ft, Type::Int(i) if i.is_signed());
                let (xi, fty) = (x.into_int_value(), lt.into_float_type());
                if s {
                    b.build_signed_int_to_float(xi, fty, "")
                } else {
                    b.build_unsigned_int_to_float(xi, fty, "")
                }
                .map_err(be)?
                .into()
            }
            (Type::Float(_), Type::Int(it)) => {
                let name = if it.is_signed() {
                    "llvm.fptosi.sat"
                } else {
                    "llvm.fptoui.sat"
                };
                self.call_intr(name, &[lt, x.get_type()], &[x])?
            }
            (Type::Float(a), Type::Float(c)) if a == c => x,
            (Type::Float(_), Type::Float(FloatTy::F64)) => b
                .build_float_ext(x.into_float_value(), lt.into_float_type(), "")
                .map_err(be)?
                .into(),
            (Type::Float(_), Type::Float(_)) => b
                .build_float_trunc(x.into_float_value(), lt.into_float_type(), "")
                .map_err(be)?
                .into(),
            _ => return Err("unsupported cast".into()),
        })
    }

    /// `blockIdx.x * blockDim.x + threadIdx.x` as a `u64` (NVPTX only).
    pub(super) fn global_id(&self) -> R<IntValue<'c>> {
        if self.target != Target::Nvptx64 {
            return Err(format!(
                "`lo.global_id` is a GPU op: target {} is a CPU",
                self.target.name()
            ));
        }
        let b = self.b;
        let i64t = self.cx.i64_type();
        let sreg = |name: &str| -> R<IntValue<'c>> {
            let v = self.call_intr(name, &[], &[])?.into_int_value();
            b.build_int_z_extend(v, i64t, "").map_err(be)
        };
        let ctaid = sreg("llvm.nvvm.read.ptx.sreg.ctaid.x")?;
        let ntid = sreg("llvm.nvvm.read.ptx.sreg.ntid.x")?;
        let tid = sreg("llvm.nvvm.read.ptx.sreg.tid.x")?;
        let block = b.build_int_nuw_mul(ctaid, ntid, "").map_err(be)?;
        b.build_int_nuw_add(block, tid, "").map_err(be)
    }
}
