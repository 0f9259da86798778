//! Directed rounding: the reference semantics of `fadd_rd` .. `fmul_ru` (and of `lo.add_rd` ..
//! `lo.mul_ru`), on `f32`.
//!
//! `add(a, b, Round::Up)` is IEEE 754 `addition` under `roundTowardPositive`, exactly: the
//! smallest `f32` at or above the exact sum (`+inf` past the largest float), the largest at or
//! below it for `Round::Down` (`-inf` past the lowest). An exact zero sum is `+0` rounding up
//! and `-0` rounding down, except that two zeros of one sign keep it (IEEE 754 §6.3).
//! Subnormals are kept (no flush to zero). A NaN result is the canonical quiet NaN, as for
//! every arithmetic op ([`crate::tree::scalar`]). Subtraction is `add(a, -b)`, which IEEE
//! defines to be the same operation in every rounding mode.
//!
//! These are the semantics of PTX's `add.rm.f32`/`add.rp.f32`/`mul.rm.f32`/`mul.rp.f32`
//! (non-`ftz`), so GPU code and CPU code agree bit for bit. CPUs have no per-instruction
//! rounding mode, so [`crate::lo::directed`] computes them from round-to-nearest operations
//! and an exact error term; this module computes them independently, from exact `f64`
//! arithmetic, so that each checks the other.
//!
//! Why `f32` only: an `f32` product is exact in `f64`, and an `f32` sum is exactly the
//! unevaluated pair `hi + lo` of an `f64` two-sum, which makes the reference simple and the CPU
//! emulation provably exact. The same for `f64` would need the error of an `f64` product deep in
//! the subnormal range, which `fma` does not deliver exactly. Quantized layouts decode in `f32`.

/// A rounding direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Round {
    /// Toward `-inf`.
    Down,
    /// Toward `+inf`.
    Up,
}

/// `a + b` rounded in direction `dir` (see the module doc).
pub fn add(a: f32, b: f32, dir: Round) -> f32 {
    if !a.is_finite() || !b.is_finite() {
        return canon(a + b);
    }
    let (x, y) = (f64::from(a), f64::from(b));
    let hi = x + y;
    // Knuth's two-sum: `hi + lo` is the exact sum (no overflow: f32 magnitudes fit f64).
    let bb = hi - x;
    let lo = (x - (hi - bb)) + (y - bb);
    if hi == 0.0 && lo == 0.0 {
        let both = |neg: bool| a.is_sign_negative() == neg && b.is_sign_negative() == neg;
        let negative = match dir {
            Round::Down => !both(false),
            Round::Up => both(true),
        };
        return if negative { -0.0 } else { 0.0 };
    }
    settle(
        hi as f32,
        |r| {
            let r = f64::from(r);
            if r == hi {
                0.0f64.partial_cmp(&lo)
            } else {
                r.partial_cmp(&hi)
            }
        },
        dir,
    )
}

/// `a - b` rounded in direction `dir`: `add(a, -b, dir)`.
pub fn sub(a: f32, b: f32, dir: Round) -> f32 {
    add(a, -b, dir)
}

/// `a * b` rounded in direction `dir` (see the module doc).
pub fn mul(a: f32, b: f32, dir: Round) -> f32 {
    let exact = f64::from(a) * f64::from(b);
    if exact.is_nan() {
        return canon(f32::NAN);
    }
    if exact == 0.0 || exact.is_infinite() {
        // Zero and infinite products are exact; round-to-nearest gives the right sign.
        return a * b;
    }
    settle(exact as f32, |r| f64::from(r).partial_cmp(&exact), dir)
}

/// From `r`, the round-to-nearest value of a nonzero exact `x` (or an infinity past the
/// range), steps to the directed result; `cmp(r)` orders `r` against `x`. Round-to-nearest
/// is within half an ulp of `x`, so at most one step is needed.
fn settle(r: f32, cmp: impl Fn(f32) -> Option<std::cmp::Ordering>, dir: Round) -> f32 {
    use std::cmp::Ordering::{Greater, Less};
    match (dir, cmp(r)) {
        (Round::Up, Some(Less)) => crate::interp::lo::next_f32(r, true),
        (Round::Down, Some(Greater)) => crate::interp::lo::next_f32(r, false),
        _ => r,
    }
}

fn canon(x: f32) -> f32 {
    if x.is_nan() {
        f32::from_bits(0x7fc0_0000)
    } else {
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MAX: f32 = f32::MAX;
    const TINY: f32 = 1.0e-45; // the smallest subnormal

    fn bits(x: f32) -> u32 {
        x.to_bits()
    }

    /// The directed results of an exact value known as an `f64` (exact for these cases).
    fn oracle(x: f64, dir: Round) -> f32 {
        let r = x as f32;
        let rr = f64::from(r);
        match dir {
            Round::Up if rr < x => crate::interp::lo::next_f32(r, true),
            Round::Down if rr > x => crate::interp::lo::next_f32(r, false),
            _ => r,
        }
    }

    #[test]
    fn exact_sums_and_products_are_unchanged() {
        for dir in [Round::Down, Round::Up] {
            assert_eq!(add(1.0, 2.0, dir), 3.0);
            assert_eq!(mul(1.5, 4.0, dir), 6.0);
            assert_eq!(sub(1.0, 0.25, dir), 0.75);
            assert_eq!(add(TINY, TINY, dir), 2.0 * TINY);
        }
    }

    #[test]
    fn inexact_results_go_outward_by_one_ulp_at_most() {
        let third = 1.0f32 / 3.0; // 0x3eaaaaab, just above 1/3: 3 * third = 1 + 2^-25
        assert_eq!(mul(third, 3.0, Round::Up), 1.0f32.next_up());
        assert_eq!(mul(third, 3.0, Round::Down), 1.0);
        assert_eq!(mul(-third, 3.0, Round::Down), -1.0f32.next_up());
        // A far smaller addend still moves the result by exactly one ulp.
        assert_eq!(add(1.0, 1e-30, Round::Up), 1.0f32.next_up());
        assert_eq!(add(1.0, 1e-30, Round::Down), 1.0);
        assert_eq!(add(1.0, -1e-30, Round::Down), 1.0f32.next_down());
        assert_eq!(add(1.0, -1e-30, Round::Up), 1.0);
        assert_eq!(add(1.0, TINY, Round::Up), 1.0f32.next_up());
    }

    #[test]
    fn overflow_and_underflow_follow_the_direction() {
        assert_eq!(add(MAX, MAX, Round::Up), f32::INFINITY);
        assert_eq!(add(MAX, MAX, Round::Down), MAX);
        assert_eq!(add(-MAX, -MAX, Round::Up), -MAX);
        assert_eq!(add(-MAX, -MAX, Round::Down), f32::NEG_INFINITY);
        assert_eq!(add(MAX, 1.0, Round::Up), f32::INFINITY);
        assert_eq!(add(MAX, 1.0, Round::Down), MAX);
        assert_eq!(mul(MAX, 2.0, Round::Down), MAX);
        assert_eq!(mul(-MAX, 2.0, Round::Up), -MAX);
        assert_eq!(mul(TINY, 0.5, Round::Up), TINY);
        assert_eq!(bits(mul(TINY, 0.5, Round::Down)), 0);
        assert_eq!(bits(mul(-TINY, 0.5, Round::Up)), bits(-0.0));
        assert_eq!(mul(-TINY, 0.5, Round::Down), -TINY);
    }

    #[test]
    fn signed_zeros_follow_ieee() {
        assert_eq!(bits(add(1.5, -1.5, Round::Up)), bits(0.0));
        assert_eq!(bits(add(1.5, -1.5, Round::Down)), bits(-0.0));
        assert_eq!(bits(sub(2.0, 2.0, Round::Down)), bits(-0.0));
        assert_eq!(bits(add(0.0, 0.0, Round::Down)), bits(0.0));
        assert_eq!(bits(add(-0.0, -0.0, Round::Up)), bits(-0.0));
        assert_eq!(bits(add(0.0, -0.0, Round::Up)), bits(0.0));
        assert_eq!(bits(add(0.0, -0.0, Round::Down)), bits(-0.0));
        assert_eq!(bits(mul(-0.0, 3.0, Round::Up)), bits(-0.0));
        assert_eq!(bits(mul(0.0, -3.0, Round::Down)), bits(-0.0));
    }

    #[test]
    fn nans_are_canonical_and_infinities_exact() {
        let nan = f32::from_bits(0xffc0_1234);
        for dir in [Round::Down, Round::Up] {
            assert_eq!(bits(add(nan, 1.0, dir)), 0x7fc0_0000);
            assert_eq!(
                bits(add(f32::INFINITY, f32::NEG_INFINITY, dir)),
                0x7fc0_0000
            );
            assert_eq!(bits(mul(0.0, f32::INFINITY, dir)), 0x7fc0_0000);
            assert_eq!(bits(mul(nan, 2.0, dir)), 0x7fc0_0000);
            assert_eq!(add(f32::INFINITY, -MAX, dir), f32::INFINITY);
            assert_eq!(mul(f32::NEG_INFINITY, 2.0, dir), f32::NEG_INFINITY);
        }
    }

    #[test]
    fn agrees_with_exact_f64_arithmetic_on_a_grid_of_values() {
        // Sums whose exponents are close enough to be exact in f64, and all products.
        let mut xs = vec![
            0.0f32,
            -0.0,
            TINY,
            -TINY,
            1.0,
            -1.0,
            MAX,
            -MAX,
            f32::MIN_POSITIVE,
        ];
        let mut s = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..400 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let x = f32::from_bits(s as u32);
            if x.is_finite() {
                xs.push(x);
                xs.push(x.next_up());
            }
        }
        for &a in &xs {
            for &b in &xs {
                for dir in [Round::Down, Round::Up] {
                    let p = f64::from(a) * f64::from(b);
                    if p != 0.0 {
                        assert_eq!(bits(mul(a, b, dir)), bits(oracle(p, dir)), "{a:e}*{b:e}");
                    }
                    // Exponents at most 28 apart: 24 + 28 bits fit an f64's 53.
                    let e = |x: f32| f64::from(x).abs().log2().floor();
                    let near = a == 0.0 || b == 0.0 || (e(a) - e(b)).abs() <= 28.0;
                    let s = f64::from(a) + f64::from(b);
                    if near && s != 0.0 {
                        assert_eq!(bits(add(a, b, dir)), bits(oracle(s, dir)), "{a:e}+{b:e}");
                    }
                }
            }
        }
    }
}
