//! Snapped-grid quantization (`sg-eq`, Howard et al. 2019; layout catalog §3.8): the reference
//! semantics of the builtins `sg_bins`, `sg_code_up` and `sg_code_down` on one `f32` lane.
//!
//! A frame is the world box `[wlo, whi]` and a bin width `bins`; `M = f32(max(m, 1))` bins per
//! axis. Low planes count bins up from `wlo`, high planes down from `whi`, and decode with
//! directed rounding ([`super::directed`]), exactly as the layout's derived fields do:
//!
//! * `D_lo(q) = RD(wlo + RD(f32(q) · bins))`, `D_hi(q) = RU(whi − RD(f32(q) · bins))`.
//! * `sg_bins(wlo, whi, m)`: Howard's frame, computed without his `f32` overflow: `L =
//!   RU(whi − wlo)` (`1` when not positive, the largest float when the extent overflows
//!   `f32`), `bininv = RD(M / L)` and `bins = RD(1 / bininv)`, each quotient taken in `f64`,
//!   rounded down to `f32`, then checked with an exact `f64` product (`bininv · L ≤ M`,
//!   `bins · bininv ≤ 1`) and stepped one ulp down if the check fails. `bininv` is not stored:
//!   the encoders recompute it from the same globals.
//! * `sg_code_up(v, wlo, whi, m)`: Howard's closed form `floor(RD(RD(v − wlo) · bininv))`,
//!   clamped to `[0, m]` (NaN gives `0`), and, as every encoder ends (catalog §2.4), checked
//!   against the decoder: the result is the smaller of it and the largest code `q` with
//!   `D_lo(q) ≤ v`, so `D_lo(code) ≤ v` whatever the rounding did (`0` when none is).
//! * `sg_code_down(v, wlo, whi, m)`: the mirror, `floor(RD(RD(whi − v) · bininv))`, and the
//!   largest `q` with `D_hi(q) ≥ v`.
//!
//! The decoders are monotone in `q` (directed rounding is monotone), so the largest such code
//! is found by the same bit-by-bit search as `quant_lo` ([`super::quant`]), which `mem-to-lo`
//! unrolls. For any box `lo ≤ hi` inside the frame, `D_lo(sg_code_up(lo)) ≤ lo` and
//! `D_hi(sg_code_down(hi)) ≥ hi`. Howard's proof makes the closed form conservative by
//! itself; the check keeps that true for frames his `f32` arithmetic did not anticipate.

use super::directed::{self, Round};
use super::quant::last_true;

/// `M`, the number of bins per axis, as the decoder sees it.
fn bin_count(m: u32) -> f32 {
    m.max(1) as f32
}

/// The largest `f32` at or below the `f64` value `x`, with `check(r)` true; one ulp down when
/// the check fails.
fn down_to_f32(x: f64, check: impl Fn(f32) -> bool) -> f32 {
    let mut r = x as f32;
    if f64::from(r) > x {
        r = crate::interp::lo::next_f32(r, false);
    }
    if !check(r) {
        r = crate::interp::lo::next_f32(r, false);
    }
    r
}

/// Howard's frame on one lane: `(bininv, bins)` (see the module doc).
pub fn frame(wlo: f32, whi: f32, m: u32) -> (f32, f32) {
    let mf = bin_count(m);
    let mut l = directed::sub(whi, wlo, Round::Up);
    // Not positive, or NaN: Howard's extent 1.
    if l.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        l = 1.0;
    }
    if l == f32::INFINITY {
        l = f32::MAX;
    }
    let (l64, m64) = (f64::from(l), f64::from(mf));
    let bininv = down_to_f32(m64 / l64, |r| f64::from(r) * l64 <= m64);
    let b64 = f64::from(bininv);
    let bins = down_to_f32(1.0 / b64, |r| f64::from(r) * b64 <= 1.0);
    (bininv, bins)
}

/// `sg_bins(wlo, whi, m)` on one lane.
pub fn sg_bins(wlo: f32, whi: f32, m: u32) -> f32 {
    frame(wlo, whi, m).1
}

/// The low plane of code `q`: `RD(wlo + RD(f32(q) · bins))`.
pub fn decode_lo(q: u32, wlo: f32, bins: f32) -> f32 {
    directed::add(wlo, directed::mul(q as f32, bins, Round::Down), Round::Down)
}

/// The high plane of code `q` (counted down from `whi`): `RU(whi − RD(f32(q) · bins))`.
pub fn decode_hi(q: u32, whi: f32, bins: f32) -> f32 {
    directed::sub(whi, directed::mul(q as f32, bins, Round::Down), Round::Up)
}

/// `floor(x)` as a code in `[0, m]` (NaN and negatives give 0), as the saturating float-to-
/// integer conversion then `min` compute it.
fn floor_code(x: f32, m: u32) -> u32 {
    (x.floor() as u32).min(m)
}

/// `sg_code_up(v, wlo, whi, m)` on one lane (see the module doc).
pub fn sg_code_up(v: f32, wlo: f32, whi: f32, m: u32) -> u32 {
    let (bininv, bins) = frame(wlo, whi, m);
    let d = directed::sub(v, wlo, Round::Down);
    let closed = floor_code(directed::mul(d, bininv, Round::Down), m);
    closed.min(last_true(m, |q| decode_lo(q, wlo, bins) <= v))
}

/// `sg_code_down(v, wlo, whi, m)` on one lane (see the module doc).
pub fn sg_code_down(v: f32, wlo: f32, whi: f32, m: u32) -> u32 {
    let (bininv, bins) = frame(wlo, whi, m);
    let d = directed::sub(whi, v, Round::Down);
    let closed = floor_code(directed::mul(d, bininv, Round::Down), m);
    closed.min(last_true(m, |q| decode_hi(q, whi, bins) >= v))
}

#[cfg(test)]
mod tests {
    use super::*;

    const M: u32 = 1023;

    fn encloses(lo: f32, hi: f32, wlo: f32, whi: f32) {
        let bins = sg_bins(wlo, whi, M);
        let (ql, qh) = (sg_code_up(lo, wlo, whi, M), sg_code_down(hi, wlo, whi, M));
        assert!(ql <= M && qh <= M);
        let (dl, dh) = (decode_lo(ql, wlo, bins), decode_hi(qh, whi, bins));
        assert!(
            dl <= lo,
            "{lo} in [{wlo}, {whi}]: code {ql} decodes to {dl}"
        );
        assert!(
            dh >= hi,
            "{hi} in [{wlo}, {whi}]: code {qh} decodes to {dh}"
        );
    }

    #[test]
    fn the_frame_satisfies_howards_inequalities() {
        for (wlo, whi) in [
            (0.0f32, 1.0f32),
            (-3.5, 7.25),
            (1e6, 1e6 + 1.0),
            (-1e-30, 1e-30),
        ] {
            let (bininv, bins) = frame(wlo, whi, M);
            let l = f64::from(whi) - f64::from(wlo);
            assert!(f64::from(bininv) * l <= 1023.0, "{wlo} {whi}");
            assert!(f64::from(bins) * f64::from(bininv) <= 1.0);
            // Tight: one more ulp of bininv would break the first inequality (up to L's rounding).
            assert!(f64::from(bininv.next_up()) * l > 1023.0 * (1.0 - 1e-6));
        }
        // A flat axis gets L = 1 (Howard); an extent past f32 is clamped, never infinite.
        assert_eq!(frame(5.0, 5.0, M).0, 1023.0);
        let (bininv, bins) = frame(-f32::MAX, f32::MAX, M);
        assert!(bininv > 0.0 && bins.is_finite());
    }

    #[test]
    fn the_root_box_gets_the_whole_range_and_boxes_enclose() {
        let (wlo, whi) = (-2.0f32, 3.0f32);
        assert_eq!(sg_code_up(wlo, wlo, whi, M), 0);
        assert_eq!(sg_code_down(whi, wlo, whi, M), 0);
        assert_eq!(decode_lo(0, wlo, 1.0), wlo);
        encloses(wlo, whi, wlo, whi);
        let mut s = 0x1234_5678_9abc_def0u64;
        for _ in 0..20_000 {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let t = |k: u32| ((s >> k) & 0xffff) as f32 / 65535.0;
            for (wlo, whi) in [
                (-2.0f32, 3.0f32),
                (1e6, 1e6 + 1.0),
                (-1e30, 1e-3),
                (0.0, 1e-38),
            ] {
                let at = |x: f32| {
                    (f64::from(wlo) + f64::from(x) * (f64::from(whi) - f64::from(wlo))) as f32
                };
                let (a, b) = (at(t(0)).clamp(wlo, whi), at(t(16)).clamp(wlo, whi));
                encloses(a.min(b), a.max(b), wlo, whi);
            }
        }
    }

    #[test]
    fn nan_planes_and_huge_frames_stay_in_range() {
        assert_eq!(sg_code_up(f32::NAN, 0.0, 1.0, M), 0);
        assert_eq!(sg_code_down(f32::NAN, 0.0, 1.0, M), 0);
        encloses(-3e38, 3e38, -f32::MAX, f32::MAX);
        encloses(1.0, 2.0, -f32::MAX, f32::MAX);
    }
}
