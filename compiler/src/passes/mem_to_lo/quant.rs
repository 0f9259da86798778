//! The quantization builtins (`frame_origin`, `frame_step`, `quant_lo`, `quant_hi`, and the
//! snapped-grid `sg_bins`, `sg_code_up`, `sg_code_down`) as `lo` ops, lane by lane, computing
//! the same bits as the reference functions of [`scion_ir::tree::quant`] and
//! [`scion_ir::tree::snapped`] (layout catalog §2.4, §3.8): the same comparisons in the same order,
//! the same `f64` step arithmetic, and the same bit-by-bit code search, unrolled with selects
//! (no branches). When the bound `m` is a constant the search skips the bits above its top bit,
//! where no candidate can be `≤ m`; the result is the same.
//!
//! Input: operand leaves (one `f32` per lane, `m` any integer); output: one leaf per lane
//! (`f32` for the frame builtins, `u32` codes for `quant_lo`/`quant_hi`).

use super::{FnLower, R};
use scion_ir::attr::Attr;
use scion_ir::entity::{BlockId, TypeId, ValueId};
use scion_ir::lo::Op as L;
use scion_ir::module::ValueDef;
use scion_ir::op::OpKind;
use scion_ir::tree::quant::{FLT_MIN, MIN_STEP};
use scion_ir::tree::{CmpPred, Intrinsic};
use scion_ir::types::{FloatTy, IntTy};
use scion_ir::OpSpec;

/// Lowers the quantization builtin `intrinsic` on operand leaves `ins`.
pub(super) fn lower(
    cx: &mut FnLower<'_>,
    cur: BlockId,
    intrinsic: Intrinsic,
    ins: &[Vec<ValueId>],
) -> R<Vec<ValueId>> {
    use Intrinsic as I;
    let name = intrinsic.name();
    let arg = |i: usize| -> R<Vec<ValueId>> {
        ins.get(i)
            .cloned()
            .ok_or((format!("`{name}` is missing an operand"), None))
    };
    let scalar = |i: usize| -> R<ValueId> {
        match arg(i)?.as_slice() {
            [x] => Ok(*x),
            _ => Err((
                format!("`{name}`: the code bound must be one integer"),
                None,
            )),
        }
    };
    let mut q = Q { cx, cur };
    match intrinsic {
        I::FrameOrigin => arg(0).map(|x| x.into_iter().map(|x| q.frame_origin(x)).collect()),
        I::FrameStep => (|| {
            let (o, hi) = (arg(0)?, arg(1)?);
            let m = q.bound(scalar(2)?);
            Ok(o.iter()
                .zip(&hi)
                .map(|(&o, &hi)| q.frame_step(o, hi, m.0))
                .collect())
        })(),
        I::QuantLo | I::QuantHi => (|| {
            let (v, o, s) = (arg(0)?, arg(1)?, arg(2)?);
            let m = q.bound(scalar(3)?);
            Ok((0..v.len().min(o.len()).min(s.len()))
                .map(|i| {
                    let b = q.code_above(v[i], o[i], s[i], m);
                    if intrinsic == I::QuantLo {
                        let a = q.code_below(v[i], o[i], s[i], m);
                        let u32t = q.u32t();
                        q.cx.e1(q.cur, L::Min, &[a, b], u32t)
                    } else {
                        b
                    }
                })
                .collect())
        })(),
        I::SgBins => (|| {
            let (wlo, whi) = (arg(0)?, arg(1)?);
            let m = q.bound(scalar(2)?);
            Ok(wlo
                .iter()
                .zip(&whi)
                .map(|(&lo, &hi)| q.sg_frame(lo, hi, m.0).1)
                .collect())
        })(),
        I::SgCodeUp | I::SgCodeDown => (|| {
            let (v, wlo, whi) = (arg(0)?, arg(1)?, arg(2)?);
            let m = q.bound(scalar(3)?);
            let up = intrinsic == I::SgCodeUp;
            Ok((0..v.len().min(wlo.len()).min(whi.len()))
                .map(|i| q.sg_code(v[i], wlo[i], whi[i], m, up))
                .collect())
        })(),
        other => Err((format!("`{other}` is not a quantization builtin"), None)),
    }
}

/// The code bound as a `u32` value, and its value when it is a constant.
type Bound = (ValueId, Option<u32>);

struct Q<'a, 'b> {
    cx: &'a mut FnLower<'b>,
    cur: BlockId,
}

impl Q<'_, '_> {
    fn u32t(&mut self) -> TypeId {
        self.cx.dst.types.int(IntTy::U32)
    }

    fn f32t(&mut self) -> TypeId {
        self.cx.dst.types.float(FloatTy::F32)
    }

    fn f64t(&mut self) -> TypeId {
        self.cx.dst.types.float(FloatTy::F64)
    }

    fn konst(&mut self, ty: TypeId, value: Attr) -> ValueId {
        let o = self.cx.insert(
            self.cur,
            OpSpec::new(L::Const).results(&[ty]).attr("value", value),
        );
        self.cx.dst.ops[o].results[0]
    }

    fn op(&mut self, op: L, args: &[ValueId], ty: TypeId) -> ValueId {
        self.cx.e1(self.cur, op, args, ty)
    }

    fn cast(&mut self, x: ValueId, ty: TypeId) -> ValueId {
        if self.cx.ty_of(x) == ty {
            x
        } else {
            self.op(L::Cast, &[x], ty)
        }
    }

    fn cmp(&mut self, pred: CmpPred, a: ValueId, b: ValueId) -> ValueId {
        self.cx.cmp(self.cur, pred, a, b)
    }

    fn select(&mut self, c: ValueId, a: ValueId, b: ValueId) -> ValueId {
        let ty = self.cx.ty_of(a);
        self.op(L::Select, &[c, a, b], ty)
    }

    /// `m` converted to `u32` (as `as u32` does), with its constant value when it has one.
    fn bound(&mut self, m: ValueId) -> Bound {
        let known = match self.cx.dst.values[m].def {
            ValueDef::Result(op, 0) if self.cx.dst.ops[op].kind == OpKind::Lo(L::Const) => {
                self.cx.dst.ops[op].int_attr("value").map(|v| v as u32)
            }
            _ => None,
        };
        let u32t = self.u32t();
        (self.cast(m, u32t), known)
    }

    /// `frame_origin(x)`: `|x| < FLT_MIN ? (x < 0 ? -FLT_MIN : 0) : x`.
    fn frame_origin(&mut self, x: ValueId) -> ValueId {
        let f32t = self.f32t();
        let a = self.op(L::Abs, &[x], f32t);
        let min = self.konst(f32t, Attr::float(FLT_MIN as f64));
        let tiny = self.cmp(CmpPred::Lt, a, min);
        let zero = self.konst(f32t, Attr::float(0.0));
        let neg = self.cmp(CmpPred::Lt, x, zero);
        let nmin = self.konst(f32t, Attr::float(-FLT_MIN as f64));
        let down = self.select(neg, nmin, zero);
        self.select(tiny, down, x)
    }

    /// `frame_step(o, hi, m)`: the step computed in `f64`, rounded up, checked against `D(M)`.
    fn frame_step(&mut self, o: ValueId, hi: ValueId, m: ValueId) -> ValueId {
        let (u32t, f32t, f64t) = (self.u32t(), self.f32t(), self.f64t());
        let one = self.konst(u32t, Attr::Int(1));
        let mu = self.op(L::Max, &[m, one], u32t);
        let mf = self.cast(mu, f32t);
        let mf64 = self.cast(mf, f64t);
        let hi64 = self.cast(hi, f64t);
        let o64 = self.cast(o, f64t);
        let ext = self.op(L::Sub, &[hi64, o64], f64t);
        let d = self.op(L::Div, &[ext, mf64], f64t);
        let floor = self.konst(f64t, Attr::float(MIN_STEP));
        let small = self.cmp(CmpPred::Lt, d, floor);
        let d = self.select(small, floor, d);
        let s = self.cast(d, f32t);
        let s64 = self.cast(s, f64t);
        let low = self.cmp(CmpPred::Lt, s64, d);
        let up = self.op(L::NextUp, &[s], f32t);
        let s = self.select(low, up, s);
        let top = self.op(L::Fma, &[mf, s, o], f32t);
        let short = self.cmp(CmpPred::Lt, top, hi);
        let up = self.op(L::NextUp, &[s], f32t);
        self.select(short, up, s)
    }

    /// `D(q) = fma(f32(q), s, o)`.
    fn decode(&mut self, q: ValueId, o: ValueId, s: ValueId) -> ValueId {
        let f32t = self.f32t();
        let qf = self.cast(q, f32t);
        self.op(L::Fma, &[qf, s, o], f32t)
    }

    /// The largest `q ∈ [0, m]` with `pred(q)` (0 when none), bit by bit from the top.
    fn last_true(
        &mut self,
        m: Bound,
        pred: &mut dyn FnMut(&mut Self, ValueId) -> ValueId,
    ) -> ValueId {
        let u32t = self.u32t();
        let bits = m.1.map_or(32, |c| 32 - c.leading_zeros());
        let mut r = self.konst(u32t, Attr::Int(0));
        for k in (0..bits).rev() {
            let bit = self.konst(u32t, Attr::Int(1 << k));
            let t = self.op(L::Or, &[r, bit], u32t);
            let fits = self.cmp(CmpPred::Le, t, m.0);
            let p = pred(self, t);
            let bt = self.cx.dst.types.bool();
            let ok = self.op(L::And, &[fits, p], bt);
            r = self.select(ok, t, r);
        }
        r
    }

    /// `a(v)`: the largest code whose plane is at or below `v`.
    fn code_below(&mut self, v: ValueId, o: ValueId, s: ValueId, m: Bound) -> ValueId {
        self.last_true(m, &mut |q, t| {
            let d = q.decode(t, o, s);
            q.cmp(CmpPred::Le, d, v)
        })
    }

    /// `b(v)`: the smallest code whose plane is at or above `v` (`m` when none).
    fn code_above(&mut self, v: ValueId, o: ValueId, s: ValueId, m: Bound) -> ValueId {
        let mut below = |q: &mut Self, t: ValueId| {
            let d = q.decode(t, o, s);
            let ge = q.cmp(CmpPred::Ge, d, v);
            let bt = q.cx.dst.types.bool();
            q.op(L::Not, &[ge], bt)
        };
        let u32t = self.u32t();
        let zero = self.konst(u32t, Attr::Int(0));
        let below0 = below(self, zero);
        let r = self.last_true(m, &mut below);
        let more = self.cmp(CmpPred::Lt, r, m.0);
        let one = self.konst(u32t, Attr::Int(1));
        let next = self.op(L::Add, &[r, one], u32t);
        let b = self.select(more, next, m.0);
        self.select(below0, b, zero)
    }

    /// Directed `a - b` (`lo.add_rd`/`lo.add_ru` of `a` and `-b`).
    fn sub_dir(&mut self, a: ValueId, b: ValueId, up: bool) -> ValueId {
        let f32t = self.f32t();
        let nb = self.op(L::Neg, &[b], f32t);
        self.op(if up { L::AddRu } else { L::AddRd }, &[a, nb], f32t)
    }

    /// The largest `f32` at or below the `f64` value `x`, stepped one ulp down when
    /// `check(r)` fails (`snapped::down_to_f32`).
    fn down_to_f32(
        &mut self,
        x: ValueId,
        check: &mut dyn FnMut(&mut Self, ValueId) -> ValueId,
    ) -> ValueId {
        let (f32t, f64t) = (self.f32t(), self.f64t());
        let r = self.cast(x, f32t);
        let r64 = self.cast(r, f64t);
        let above = self.cmp(CmpPred::Gt, r64, x);
        let down = self.op(L::NextDown, &[r], f32t);
        let r = self.select(above, down, r);
        let ok = check(self, r);
        let down = self.op(L::NextDown, &[r], f32t);
        self.select(ok, r, down)
    }

    /// Howard's frame `(bininv, bins)` for `[wlo, whi]` with `m` bins (`snapped::frame`).
    fn sg_frame(&mut self, wlo: ValueId, whi: ValueId, m: ValueId) -> (ValueId, ValueId) {
        let (u32t, f32t, f64t) = (self.u32t(), self.f32t(), self.f64t());
        let one = self.konst(u32t, Attr::Int(1));
        let mu = self.op(L::Max, &[m, one], u32t);
        let mf = self.cast(mu, f32t);
        let l = self.sub_dir(whi, wlo, true);
        let zero = self.konst(f32t, Attr::float(0.0));
        let pos = self.cmp(CmpPred::Gt, l, zero);
        let onef = self.konst(f32t, Attr::float(1.0));
        let l = self.select(pos, l, onef);
        let inf = self.konst(f32t, Attr::float(f64::INFINITY));
        let is_inf = self.cmp(CmpPred::Eq, l, inf);
        let max = self.konst(f32t, Attr::float(f32::MAX as f64));
        let l = self.select(is_inf, max, l);
        let (l64, m64) = (self.cast(l, f64t), self.cast(mf, f64t));
        let quot = self.op(L::Div, &[m64, l64], f64t);
        let bininv = self.down_to_f32(quot, &mut |q, r| {
            let r64 = q.cast(r, f64t);
            let p = q.op(L::Mul, &[r64, l64], f64t);
            q.cmp(CmpPred::Le, p, m64)
        });
        let b64 = self.cast(bininv, f64t);
        let one64 = self.konst(f64t, Attr::float(1.0));
        let quot = self.op(L::Div, &[one64, b64], f64t);
        let bins = self.down_to_f32(quot, &mut |q, r| {
            let r64 = q.cast(r, f64t);
            let p = q.op(L::Mul, &[r64, b64], f64t);
            q.cmp(CmpPred::Le, p, one64)
        });
        (bininv, bins)
    }

    /// `sg_code_up(v, wlo, whi, m)` (`up`) or `sg_code_down` on one lane: Howard's closed form,
    /// clamped, and no larger than the largest code the decoder keeps conservative.
    fn sg_code(&mut self, v: ValueId, wlo: ValueId, whi: ValueId, m: Bound, up: bool) -> ValueId {
        let (u32t, f32t) = (self.u32t(), self.f32t());
        let (bininv, bins) = self.sg_frame(wlo, whi, m.0);
        let d = if up {
            self.sub_dir(v, wlo, false)
        } else {
            self.sub_dir(whi, v, false)
        };
        let p = self.op(L::MulRd, &[d, bininv], f32t);
        let fl = self.op(L::Floor, &[p], f32t);
        let c = self.cast(fl, u32t);
        let closed = self.op(L::Min, &[c, m.0], u32t);
        let search = self.last_true(m, &mut |q, t| {
            let tf = q.cast(t, f32t);
            let s = q.op(L::MulRd, &[tf, bins], f32t);
            if up {
                let plane = q.op(L::AddRd, &[wlo, s], f32t);
                q.cmp(CmpPred::Le, plane, v)
            } else {
                let plane = q.sub_dir(whi, s, true);
                q.cmp(CmpPred::Ge, plane, v)
            }
        });
        self.op(L::Min, &[closed, search], u32t)
    }
}
