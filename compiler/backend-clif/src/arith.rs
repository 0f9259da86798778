//! The scalar operations of `lo` whose semantics take more than one Cranelift instruction:
//! integer division without traps, `min`/`max` that return the non-NaN operand, `next_up` /
//! `next_down`, and casts (saturating float-to-integer). Part of [`crate::translate`]'s
//! translation of an op ([`Fx`]).

use crate::translate::Fx;
use cranelift_codegen::ir::condcodes::{FloatCC, IntCC};
use cranelift_codegen::ir::{self, types, InstBuilder, MemFlags};
use cranelift_frontend::FunctionBuilder;
use scion_ir::entity::TypeId;
use scion_ir::lo::nan::MinMaxForm;
use scion_ir::types::{FloatTy, Type};

impl Fx<'_, '_> {
    /// Integer division without traps: `MIN / -1` wraps to `MIN` (and `MIN % -1` is 0) as in
    /// `tree`; division by zero, undefined in the IR, divides by 1 instead of trapping.
    pub(crate) fn int_div(
        &mut self,
        div: bool,
        signed: bool,
        x: ir::Value,
        y: ir::Value,
    ) -> ir::Value {
        let t = self.b.func.dfg.value_type(y);
        let one = self.b.ins().iconst(t, 1);
        let zero = self.b.ins().iconst(t, 0);
        let is_zero = self.b.ins().icmp(IntCC::Equal, y, zero);
        if !signed {
            let safe = self.b.ins().select(is_zero, one, y);
            return if div {
                self.b.ins().udiv(x, safe)
            } else {
                self.b.ins().urem(x, safe)
            };
        }
        let all_ones = if t.bits() >= 64 {
            -1i64
        } else {
            ((1u64 << t.bits()) - 1) as i64
        };
        let m1 = self.b.ins().iconst(t, all_ones);
        let is_m1 = self.b.ins().icmp(IntCC::Equal, y, m1);
        let bad = self.b.ins().bor(is_zero, is_m1);
        let safe = self.b.ins().select(bad, one, y);
        if div {
            let q = self.b.ins().sdiv(x, safe);
            let neg = self.b.ins().ineg(x);
            self.b.ins().select(is_m1, neg, q)
        } else {
            let r = self.b.ins().srem(x, safe);
            self.b.ins().select(is_m1, zero, r)
        }
    }

    /// minNum/maxNum: the other operand when one is NaN (`q` when both are), `p` on ties.
    pub(crate) fn min_max(
        &mut self,
        max: bool,
        p: ir::Value,
        q: ir::Value,
        t: ir::Type,
        signed: bool,
        form: MinMaxForm,
    ) -> ir::Value {
        if !(t == types::F32 || t == types::F64) {
            return match (max, signed) {
                (false, true) => self.b.ins().smin(p, q),
                (false, false) => self.b.ins().umin(p, q),
                (true, true) => self.b.ins().smax(p, q),
                (true, false) => self.b.ins().umax(p, q),
            };
        }
        // minNum/maxNum with the first operand on ties, in the cheapest form the operands
        // allow (scion_ir::lo::nan::MinMaxForm). Written as `select(fcmp lt x y, x, y)` (min)
        // and `select(fcmp lt y x, x, y)` (max), the shapes Cranelift's x64 backend turns into
        // one `minss`/`maxss`.
        let pick = |b: &mut FunctionBuilder<'_>, x: ir::Value, y: ir::Value| {
            // min: x < y ? x : y; max: x > y ? x : y (as y < x).
            let c = if max {
                b.ins().fcmp(FloatCC::LessThan, y, x)
            } else {
                b.ins().fcmp(FloatCC::LessThan, x, y)
            };
            b.ins().select(c, x, y)
        };
        if form == MinMaxForm::SelectSwapped {
            return pick(self.b, p, q);
        }
        let r = pick(self.b, q, p);
        if form == MinMaxForm::Select {
            return r;
        }
        // q < p is false when q is NaN, so `r` is then p; only a NaN p needs its own select.
        let p_nan = self.b.ins().fcmp(FloatCC::Unordered, p, p);
        self.b.ins().select(p_nan, q, r)
    }

    /// One ulp toward `+inf` (`up`) or `-inf`; NaN and the infinity in that direction stay.
    pub(crate) fn next(&mut self, up: bool, x: ir::Value, t: ir::Type) -> ir::Value {
        let (it, zero_step, inf) = if t == types::F32 {
            let inf = if up { f32::INFINITY } else { f32::NEG_INFINITY };
            let z: i64 = if up { 1 } else { 0x8000_0001 };
            (types::I32, z, self.b.ins().f32const(inf))
        } else {
            let inf = if up { f64::INFINITY } else { f64::NEG_INFINITY };
            let z: i64 = if up {
                1
            } else {
                0x8000_0000_0000_0001u64 as i64
            };
            (types::I64, z, self.b.ins().f64const(inf))
        };
        let zero = if t == types::F32 {
            self.b.ins().f32const(0.0)
        } else {
            self.b.ins().f64const(0.0)
        };
        let bits = self.b.ins().bitcast(it, MemFlags::new(), x);
        let inc = self.b.ins().iadd_imm(bits, 1);
        let dec = self.b.ins().iadd_imm(bits, -1);
        let pos = self.b.ins().fcmp(FloatCC::GreaterThan, x, zero);
        let stepped = if up {
            self.b.ins().select(pos, inc, dec)
        } else {
            self.b.ins().select(pos, dec, inc)
        };
        let zs = self.b.ins().iconst(it, zero_step);
        let is_zero = self.b.ins().fcmp(FloatCC::Equal, x, zero);
        let stepped = self.b.ins().select(is_zero, zs, stepped);
        let r = self.b.ins().bitcast(t, MemFlags::new(), stepped);
        let nan = self.b.ins().fcmp(FloatCC::Unordered, x, x);
        let at_inf = self.b.ins().fcmp(FloatCC::Equal, x, inf);
        let keep = self.b.ins().bor(nan, at_inf);
        self.b.ins().select(keep, x, r)
    }

    /// `lo.cast`: Rust `as` semantics between scalars.
    pub(crate) fn cast(
        &mut self,
        x: ir::Value,
        from: TypeId,
        to: TypeId,
    ) -> Result<ir::Value, String> {
        let m = self.m;
        let (ft, tt) = (m.types.get(from).clone(), m.types.get(to).clone());
        let ct = self.cty(to)?;
        let cf = self.b.func.dfg.value_type(x);
        let int_of = |t: &Type| match t {
            Type::Int(i) => Some((i.bits(), i.is_signed())),
            Type::Bool => Some((1, false)),
            _ => None,
        };
        Ok(match (&ft, &tt) {
            (_, Type::Bool) => match ft {
                Type::Float(_) => {
                    let z = if cf == types::F32 {
                        self.b.ins().f32const(0.0)
                    } else {
                        self.b.ins().f64const(0.0)
                    };
                    self.b.ins().fcmp(FloatCC::NotEqual, x, z)
                }
                _ => self.b.ins().icmp_imm(IntCC::NotEqual, x, 0),
            },
            (Type::Int(_) | Type::Bool, Type::Int(_)) => {
                let (fb, fs) = int_of(&ft).ok_or("bad cast")?;
                if cf.bits() == ct.bits() {
                    x
                } else if cf.bits() > ct.bits() {
                    self.b.ins().ireduce(ct, x)
                } else if fs && fb > 1 {
                    self.b.ins().sextend(ct, x)
                } else {
                    self.b.ins().uextend(ct, x)
                }
            }
            (Type::Int(_) | Type::Bool, Type::Float(_)) => {
                let (_, fs) = int_of(&ft).ok_or("bad cast")?;
                let wide = if cf.bits() < 32 {
                    if fs {
                        self.b.ins().sextend(types::I32, x)
                    } else {
                        self.b.ins().uextend(types::I32, x)
                    }
                } else {
                    x
                };
                if fs {
                    self.b.ins().fcvt_from_sint(ct, wide)
                } else {
                    self.b.ins().fcvt_from_uint(ct, wide)
                }
            }
            (Type::Float(_), Type::Int(it)) => {
                let (bits, signed) = (it.bits(), it.is_signed());
                if bits >= 32 {
                    if signed {
                        self.b.ins().fcvt_to_sint_sat(ct, x)
                    } else {
                        self.b.ins().fcvt_to_uint_sat(ct, x)
                    }
                } else {
                    let (lo, hi) = it.range();
                    let w = if signed {
                        self.b.ins().fcvt_to_sint_sat(types::I32, x)
                    } else {
                        self.b.ins().fcvt_to_uint_sat(types::I32, x)
                    };
                    let hi_c = self.b.ins().iconst(types::I32, hi as i64);
                    let c = if signed {
                        let lo_c = self.b.ins().iconst(types::I32, lo as i64);
                        let a = self.b.ins().smax(w, lo_c);
                        self.b.ins().smin(a, hi_c)
                    } else {
                        self.b.ins().umin(w, hi_c)
                    };
                    self.b.ins().ireduce(ct, c)
                }
            }
            (Type::Float(a), Type::Float(b)) if a == b => x,
            (Type::Float(_), Type::Float(FloatTy::F64)) => self.b.ins().fpromote(ct, x),
            (Type::Float(_), Type::Float(_)) => self.b.ins().fdemote(ct, x),
            _ => return Err("unsupported cast".into()),
        })
    }
}
