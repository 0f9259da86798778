//! Directed rounding on targets without it: rewrites `lo.add_rd`, `lo.add_ru`, `lo.mul_rd` and
//! `lo.mul_ru` into round-to-nearest `lo` ops that give the same bits
//! ([`crate::tree::directed`]: exact IEEE rounding toward `-inf`/`+inf` on `f32`).
//!
//! CPUs round per instruction only through a global mode (MXCSR, FPCR), which serializes and
//! is not modelled by the JITs, so `scion-clif` and `scion-llvm` on x86-64/AArch64 run this
//! expansion first; NVPTX has the rounding per instruction (`add.rp.f32` ...) and keeps the
//! ops. Each op becomes:
//!
//! * `add`: `r = a + b` (round-to-nearest: one of the two floats around the exact sum, or
//!   the canonical NaN), and the exact sum as the pair `s + e` of Knuth's two-sum on the
//!   operands widened to `f64` (`bb = s - a`, `e = (a - (s - bb)) + (b - bb)`): no `f32` sum
//!   overflows `f64`, whereas the same two-sum in `f32` overflows in `s - a` when `a + b`
//!   rounds up to near the largest float. `r` is on the wrong side of the sum when the widened
//!   `r` is past `s` (rounding is monotone, so `s` orders it like the exact sum) or equal to
//!   `s` with `e` pointing past it; then it steps one ulp (`next_up` up, `next_down` down).
//!   That also turns an overflow against the direction into the largest finite float
//!   (`next_down(+inf)`). Rounding down, an exact zero sum is `-((-a) + (-b))` (so `x + (-x)`
//!   is `-0`, and only `+0 + +0` stays `+0`).
//! * `mul`: `r = a * b`, and the product of the operands widened to `f64`, which is exact; `r`
//!   steps outward when the widened `r` lies on the wrong side of it. Zero signs and
//!   infinities need nothing more.
//!
//! About twenty and eight ops respectively, all branch-free, against one for PTX; the paper
//! notes the cost on architectures without per-instruction rounding (§9.2.3).

use crate::builder::{Builder, InsertPoint};
use crate::entity::{OpId, ValueId};
use crate::lo::Op as L;
use crate::module::Module;
use crate::op::OpKind;
use crate::rewrite;
use crate::tree::directed::Round;
use crate::tree::CmpPred;
use crate::walk::{walk_region, Order};
use std::borrow::Cow;

/// True when some function of `m` has a directed-rounding op.
pub fn has_directed(m: &Module) -> bool {
    !directed_ops(m).is_empty()
}

/// `m` with every directed-rounding op expanded (borrowed unchanged when there is none).
pub fn expanded(m: &Module) -> Cow<'_, Module> {
    if has_directed(m) {
        let mut owned = m.clone();
        expand(&mut owned);
        Cow::Owned(owned)
    } else {
        Cow::Borrowed(m)
    }
}

/// Expands every directed-rounding op of `m` in place; returns whether there was one.
pub fn expand(m: &mut Module) -> bool {
    let ops = directed_ops(m);
    for &op in &ops {
        let OpKind::Lo(kind) = m.ops[op].kind else {
            continue;
        };
        let Some((mul, dir)) = kind.directed() else {
            continue;
        };
        let (a, b) = (m.ops[op].operands[0], m.ops[op].operands[1]);
        let span = m.span(op);
        let mut bld = Builder::new(m);
        bld.set_insertion_point(InsertPoint::Before(op));
        bld.set_span(span);
        let r = if mul {
            expand_mul(&mut bld, a, b, dir)
        } else {
            expand_add(&mut bld, a, b, dir)
        };
        rewrite::replace_op(m, op, &[r]);
    }
    rewrite::resolve_aliases(m);
    !ops.is_empty()
}

fn directed_ops(m: &Module) -> Vec<OpId> {
    let mut found = Vec::new();
    for &f in &m.func_order {
        walk_region(m, m.funcs[f].body, Order::Pre, &mut |op| {
            if matches!(m.ops[op].kind, OpKind::Lo(k) if k.directed().is_some()) {
                found.push(op);
            }
        });
    }
    found
}

fn expand_add(bld: &mut Builder, a: ValueId, b: ValueId, dir: Round) -> ValueId {
    let f = bld.m.types.f32();
    let d = bld.m.types.float(crate::types::FloatTy::F64);
    // Round-to-nearest: one of the two floats around the exact sum (and the canonical NaN).
    let r = bld.lo1(L::Add, &[a, b], f);
    // The exact sum as the pair `s + e` (two-sum in f64, where no f32 sum overflows).
    let wa = bld.lo1(L::Cast, &[a], d);
    let wb = bld.lo1(L::Cast, &[b], d);
    let s = bld.lo1(L::Add, &[wa, wb], d);
    let bb = bld.lo1(L::Sub, &[s, wa], d);
    let t = bld.lo1(L::Sub, &[s, bb], d);
    let ea = bld.lo1(L::Sub, &[wa, t], d);
    let eb = bld.lo1(L::Sub, &[wb, bb], d);
    let e = bld.lo1(L::Add, &[ea, eb], d);
    let wr = bld.lo1(L::Cast, &[r], d);
    let zero = bld.lo_float(d, 0.0);
    // `r` is on the wrong side of the exact sum: strictly, as `s` orders it (rounding is
    // monotone), or equal to `s` with the error `e` pointing past it.
    let (beyond, err_past, step) = match dir {
        Round::Up => (CmpPred::Lt, CmpPred::Gt, L::NextUp),
        Round::Down => (CmpPred::Gt, CmpPred::Lt, L::NextDown),
    };
    let i1 = bld.m.types.bool();
    let past = bld.lo_cmp(beyond, wr, s);
    let on_s = bld.lo_cmp(CmpPred::Eq, wr, s);
    let e_past = bld.lo_cmp(err_past, e, zero);
    let tie_past = bld.lo1(L::And, &[on_s, e_past], i1);
    let wrong = bld.lo1(L::Or, &[past, tie_past], i1);
    let stepped = bld.lo1(step, &[r], f);
    let r1 = bld.lo1(L::Select, &[wrong, stepped, r], f);
    if dir == Round::Up {
        return r1;
    }
    // Rounding down, an exact zero sum is -0 unless both operands are +0.
    let fzero = bld.lo_float(f, 0.0);
    let is_zero = bld.lo_cmp(CmpPred::Eq, r, fzero);
    let na = bld.lo1(L::Neg, &[a], f);
    let nb = bld.lo1(L::Neg, &[b], f);
    let flipped = bld.lo1(L::Add, &[na, nb], f);
    let signed_zero = bld.lo1(L::Neg, &[flipped], f);
    bld.lo1(L::Select, &[is_zero, signed_zero, r1], f)
}

fn expand_mul(bld: &mut Builder, a: ValueId, b: ValueId, dir: Round) -> ValueId {
    let f = bld.m.types.f32();
    let d = bld.m.types.float(crate::types::FloatTy::F64);
    let r = bld.lo1(L::Mul, &[a, b], f);
    let wa = bld.lo1(L::Cast, &[a], d);
    let wb = bld.lo1(L::Cast, &[b], d);
    let exact = bld.lo1(L::Mul, &[wa, wb], d);
    let wr = bld.lo1(L::Cast, &[r], d);
    let (pred, step) = match dir {
        Round::Up => (CmpPred::Lt, L::NextUp),
        Round::Down => (CmpPred::Gt, L::NextDown),
    };
    let wrong_side = bld.lo_cmp(pred, wr, exact);
    let stepped = bld.lo1(step, &[r], f);
    bld.lo1(L::Select, &[wrong_side, stepped, r], f)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diag::FileId;
    use crate::interp::lo::LoInterp;
    use crate::interp::Val;
    use crate::tree::directed;

    const SRC: &str = r#"
func @add_rd(%a: f32, %b: f32) -> (f32) {
  %r = "lo.add_rd"(%a, %b) : (f32, f32) -> f32
  "lo.return"(%r) : (f32) -> ()
}
func @add_ru(%a: f32, %b: f32) -> (f32) {
  %r = "lo.add_ru"(%a, %b) : (f32, f32) -> f32
  "lo.return"(%r) : (f32) -> ()
}
func @mul_rd(%a: f32, %b: f32) -> (f32) {
  %r = "lo.mul_rd"(%a, %b) : (f32, f32) -> f32
  "lo.return"(%r) : (f32) -> ()
}
func @mul_ru(%a: f32, %b: f32) -> (f32) {
  %r = "lo.mul_ru"(%a, %b) : (f32, f32) -> f32
  "lo.return"(%r) : (f32) -> ()
}
"#;

    fn edge_values() -> Vec<f32> {
        let mut xs = vec![
            0.0,
            -0.0,
            1.0e-45,
            -1.0e-45,
            f32::MIN_POSITIVE,
            1.0,
            -1.0,
            1.0 / 3.0,
            3.0,
            1.0e-30,
            -1.0e-30,
            f32::MAX,
            -f32::MAX,
            f32::MAX.next_down(),
            -1.016_827_7e38,
            2.0f32.powi(103),
            -2.0f32.powi(103),
            2.0f32.powi(104),
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            f32::from_bits(0xffc0_1234),
        ];
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..120 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            xs.push(f32::from_bits(s as u32));
            // Near the top of the range, where two-sum's intermediates could overflow.
            xs.push(f32::from_bits(0x7f00_0000 | (s >> 40) as u32 & 0x007f_ffff));
            // One binade lower and negative: added to `MAX`, round-to-nearest can tie upward
            // and `r - a` then passes `MAX` (CI found `-1.0168277e38 + MAX`).
            xs.push(f32::from_bits(0xfe80_0000 | (s >> 20) as u32 & 0x007f_ffff));
        }
        xs
    }

    #[test]
    fn the_expansion_gives_the_reference_bits() {
        let m = crate::parse_module(SRC, FileId(0)).unwrap();
        crate::verify(&m).unwrap();
        let ex = expanded(&m);
        assert!(matches!(ex, Cow::Owned(_)));
        crate::verify(&ex).unwrap();
        assert!(!has_directed(&ex));
        let xs = edge_values();
        let mut interp = LoInterp::new(&ex);
        for (name, mul, dir) in [
            ("add_rd", false, Round::Down),
            ("add_ru", false, Round::Up),
            ("mul_rd", true, Round::Down),
            ("mul_ru", true, Round::Up),
        ] {
            for &a in &xs {
                for &b in &xs {
                    let want = if mul {
                        directed::mul(a, b, dir)
                    } else {
                        directed::add(a, b, dir)
                    };
                    let got = interp.call(name, vec![Val::F32(a), Val::F32(b)]).unwrap();
                    let Val::F32(g) = got[0] else {
                        panic!("{got:?}")
                    };
                    assert_eq!(
                        g.to_bits(),
                        want.to_bits(),
                        "{name}({a:e} [{:#x}], {b:e} [{:#x}]): {g:e} but the reference {want:e}",
                        a.to_bits(),
                        b.to_bits()
                    );
                }
            }
        }
    }

    #[test]
    fn modules_without_directed_ops_are_borrowed() {
        let m = crate::parse_module(
            "func @f(%a: f32) -> (f32) {\n  \"lo.return\"(%a) : (f32) -> ()\n}\n",
            FileId(0),
        )
        .unwrap();
        assert!(matches!(expanded(&m), Cow::Borrowed(_)));
    }
}
