//! The quantization builtins `frame_origin`, `frame_step`, `quant_lo` and `quant_hi` on one
//! `f32` lane: the reference semantics (layout catalog §2.4, "conservative quantization"). The
//! interpreter calls these functions; `mem-to-lo` lowers the builtins to `lo` ops that compute
//! the same bits (compiler/tests/quant_diff.rs checks interpreter, Cranelift and LLVM against
//! each other and these functions against the enclosure property).
//!
//! A frame is an origin `o` and a step `s`; code `q` decodes to `D(q) = fma(f32(q), s, o)`,
//! exactly the derived-field expression of a quantized layout (`pbrt-q16`). For `s ≥ 0`, `D`
//! is monotone non-decreasing in `q`, and:
//!
//! * `frame_origin(x)`: `x` rounded down to `0` or a normal float: `+0` for `0 ≤ x < FLT_MIN`
//!   (including `-0` and positive subnormals), `-FLT_MIN` for `-FLT_MIN < x < 0`, else `x`
//!   (NaN and infinities pass through).
//! * `frame_step(o, hi, m)`: with `M = f32(m)` (`m` as `u32`, `0` taken as `1`),
//!   `d = (f64(hi) − f64(o)) / f64(M)` raised to at least `2·FLT_MIN`, rounded *up* to `f32`,
//!   then bumped by one ulp if `D(M) = fma(M, s, o) < hi`. One bump always suffices: `d` is
//!   within `2^-52` relative of the exact quotient and one ulp adds at least `2^-24` relative,
//!   so `D(M) ≥ hi` holds for every finite `o ≤ hi` (checked by the property tests). NaN in,
//!   the canonical quiet NaN out.
//! * `a(v)` = the largest `q ∈ [0, m]` with `D(q) ≤ v` (`0` when there is none), `b(v)` = the
//!   smallest `q ∈ [0, m]` with `D(q) ≥ v` (`m` when there is none); both by a bit-by-bit
//!   binary search over the 32 bits of `q` (no early exit, so a backend can unroll it).
//!   `quant_lo(v, o, s, m) = min(a(v), b(v))` and `quant_hi(v, o, s, m) = b(v)`. The `min`
//!   keeps the low code at or below the high code where `D` has plateaus (a grid finer than
//!   the float spacing at `o`). A NaN `v` gives `quant_lo = 0`, `quant_hi = m`.
//!
//! Conservativeness: for `o = frame_origin(lo_min)`, `s = frame_step(o, hi_max, m)` and any box
//! `lo ≤ hi` inside `[lo_min, hi_max]`, `D(quant_lo(lo)) ≤ lo` and `D(quant_hi(hi)) ≥ hi`.

use std::cmp::Ordering;

/// `FLT_MIN`, the smallest positive normal `f32`.
pub const FLT_MIN: f32 = f32::MIN_POSITIVE;

/// `2·FLT_MIN` as an `f64`, the smallest step a frame gets.
pub const MIN_STEP: f64 = 2.0 * f32::MIN_POSITIVE as f64;

/// The decoder `D(q) = fma(f32(q), s, o)`.
pub fn decode(q: u32, origin: f32, step: f32) -> f32 {
    (q as f32).mul_add(step, origin)
}

/// `frame_origin(x)` on one lane (see the module doc).
pub fn frame_origin(x: f32) -> f32 {
    if x.abs() < FLT_MIN {
        if x < 0.0 {
            -FLT_MIN
        } else {
            0.0
        }
    } else {
        x
    }
}

/// The quantization bound `m` as the `u32` the search runs over (`0` is taken as `1` only by
/// [`frame_step`]; the codes themselves are clamped to `[0, m]`).
fn step_count(m: u32) -> f32 {
    m.max(1) as f32
}

/// `frame_step(o, hi, m)` on one lane (see the module doc).
pub fn frame_step(origin: f32, hi: f32, m: u32) -> f32 {
    let mf = step_count(m);
    let mut d = (hi as f64 - origin as f64) / mf as f64;
    if d < MIN_STEP {
        d = MIN_STEP;
    }
    let mut s = d as f32;
    if (s as f64) < d {
        s = next_up(s);
    }
    if mf.mul_add(s, origin) < hi {
        s = next_up(s);
    }
    if s.is_nan() {
        f32::from_bits(CANONICAL_NAN32)
    } else {
        s
    }
}

/// The quiet NaN every engine gives for an arithmetic NaN (`scion_ir::tree::scalar`).
const CANONICAL_NAN32: u32 = 0x7fc0_0000;

/// The largest `q ∈ [0, m]` with `pred(q)`, for a predicate true on a prefix of `[0, m]`
/// (`0` when it holds nowhere): 32 bit-by-bit steps from the top bit down.
pub(crate) fn last_true(m: u32, pred: impl Fn(u32) -> bool) -> u32 {
    let mut r = 0u32;
    for k in (0..32).rev() {
        let t = r | (1 << k);
        if t <= m && pred(t) {
            r = t;
        }
    }
    r
}

/// `a(v)`: the largest code whose plane is at or below `v`.
fn code_below(v: f32, origin: f32, step: f32, m: u32) -> u32 {
    last_true(m, |q| decode(q, origin, step) <= v)
}

/// `b(v)`: the smallest code whose plane is at or above `v`.
fn code_above(v: f32, origin: f32, step: f32, m: u32) -> u32 {
    // Not `D(q) ≥ v`: below `v`, or unordered (NaN), as `lo.not` of `lo.cmp ge` computes it.
    let below = |q: u32| {
        !matches!(
            decode(q, origin, step).partial_cmp(&v),
            Some(Ordering::Greater | Ordering::Equal)
        )
    };
    if !below(0) {
        return 0;
    }
    let r = last_true(m, below);
    if r < m {
        r + 1
    } else {
        m
    }
}

/// `quant_lo(v, o, s, m)` on one lane (see the module doc).
pub fn quant_lo(v: f32, origin: f32, step: f32, m: u32) -> u32 {
    code_below(v, origin, step, m).min(code_above(v, origin, step, m))
}

/// `quant_hi(v, o, s, m)` on one lane (see the module doc).
pub fn quant_hi(v: f32, origin: f32, step: f32, m: u32) -> u32 {
    code_above(v, origin, step, m)
}

/// The next `f32` toward `+inf`, as `lo.next_up` computes it.
fn next_up(x: f32) -> f32 {
    crate::interp::lo::next_f32(x, true)
}

/// How a layout stores node boxes, as far as the bits a traversal sees go. A quantized layout
/// widens every box to grid planes, so its bit-for-bit reference is the reference traversal of
/// the tree whose boxes are the decoded ones ([`Boxes::decoder`]), not of the exact tree.
/// Boxes are `[lo.x, lo.y, lo.z, hi.x, hi.y, hi.z]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Boxes {
    /// The logical tree's `f32` boxes, unchanged.
    Exact,
    /// 16-bit codes against one frame written from the root's box (`pbrt-q16`):
    /// `wlo = frame_origin(root.low)`, `wstep = frame_step(wlo, root.high, 65535)`, each box
    /// `quant_lo(low)` / `quant_hi(high)`, decoded with `fma(q, wstep, wlo)`.
    GlobalQ16,
    /// 10-bit snapped-grid codes against the root's box (`sg-eq`, [`super::snapped`]):
    /// `wlo = root.low`, `whi = root.high`, `bins = sg_bins(wlo, whi, 1023)`, each box
    /// `sg_code_up(low)` / `sg_code_down(high)`, decoded with directed rounding.
    SnappedQ10,
    /// 8-bit codes of a wide node's child boxes against the node's own frame over its occupied
    /// slots (`bvh8-q8*`, Embree's `QuantizedNode_t`): `o = frame_origin(lo)`,
    /// `s = frame_step(o, hi, 255)` of the union of the children's boxes, each child
    /// `quant_lo(low)` / `quant_hi(high)` ([`decode_children`]). The binary tree's boxes are
    /// not quantized ([`Boxes::decoder`] is `None`); the wide tree's child boxes are.
    NodeQ8,
    /// As [`Boxes::NodeQ8`] with 16-bit codes (`bvh8-q16*`).
    NodeQ16,
}

/// A map from a node's exact box to the box a layout's traversal sees ([`Boxes::decoder`]).
pub type BoxMap = Box<dyn Fn(&[f32; 6]) -> [f32; 6]>;

/// The codes' upper bound of [`Boxes::GlobalQ16`].
const Q16: u32 = 65535;

/// The codes' upper bound of [`Boxes::SnappedQ10`].
const Q10: u32 = 1023;

impl Boxes {
    /// The name in PTX kits and messages: `exact`, `global-q16`, `snapped-q10`, `node-q8`,
    /// `node-q16`.
    pub fn name(self) -> &'static str {
        match self {
            Boxes::Exact => "exact",
            Boxes::GlobalQ16 => "global-q16",
            Boxes::SnappedQ10 => "snapped-q10",
            Boxes::NodeQ8 => "node-q8",
            Boxes::NodeQ16 => "node-q16",
        }
    }

    /// The largest code of a layout that quantizes each wide node's children against the
    /// node's own frame (255 or 65535), `None` for the others.
    pub fn node_codes(self) -> Option<u32> {
        match self {
            Boxes::NodeQ8 => Some(255),
            Boxes::NodeQ16 => Some(Q16),
            _ => None,
        }
    }

    /// The boxes named `name` (see [`Boxes::name`]).
    pub fn from_name(name: &str) -> Option<Boxes> {
        [
            Boxes::Exact,
            Boxes::GlobalQ16,
            Boxes::SnappedQ10,
            Boxes::NodeQ8,
            Boxes::NodeQ16,
        ]
        .into_iter()
        .find(|b| b.name() == name)
    }

    /// For a tree whose root box is `root`, the map from a node's exact box to the box a
    /// traversal of this layout sees; `None` when that is the exact box itself.
    pub fn decoder(self, root: &[f32; 6]) -> Option<BoxMap> {
        match self {
            Boxes::Exact | Boxes::NodeQ8 | Boxes::NodeQ16 => None,
            Boxes::GlobalQ16 => {
                let origin: [f32; 3] = std::array::from_fn(|k| frame_origin(root[k]));
                let step: [f32; 3] =
                    std::array::from_fn(|k| frame_step(origin[k], root[k + 3], Q16));
                Some(Box::new(move |b: &[f32; 6]| {
                    std::array::from_fn(|i| {
                        let k = i % 3;
                        let (o, s) = (origin[k], step[k]);
                        let q = if i < 3 {
                            quant_lo(b[i], o, s, Q16)
                        } else {
                            quant_hi(b[i], o, s, Q16)
                        };
                        decode(q, o, s)
                    })
                }))
            }
            Boxes::SnappedQ10 => {
                use super::snapped::{decode_hi, decode_lo, sg_bins, sg_code_down, sg_code_up};
                let (wlo, whi) = (*root, *root);
                let bins: [f32; 3] = std::array::from_fn(|k| sg_bins(wlo[k], whi[k + 3], Q10));
                Some(Box::new(move |b: &[f32; 6]| {
                    std::array::from_fn(|i| {
                        let k = i % 3;
                        let (lo, hi) = (wlo[k], whi[k + 3]);
                        if i < 3 {
                            decode_lo(sg_code_up(b[i], lo, hi, Q10), lo, bins[k])
                        } else {
                            decode_hi(sg_code_down(b[i], lo, hi, Q10), hi, bins[k])
                        }
                    })
                }))
            }
        }
    }
}

/// The boxes a wide node quantized against its own frame stores for its children (codes up to
/// `m`): the frame over the occupied slots' boxes (an empty box, `low > high`, is skipped and
/// stays as it is), then each box's codes decoded. Conservative: each decoded box contains its
/// exact box.
pub fn decode_children(boxes: &[[f32; 6]], m: u32) -> Vec<[f32; 6]> {
    let empty = |b: &[f32; 6]| (0..3).any(|a| b[a] > b[a + 3]);
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for b in boxes.iter().filter(|b| !empty(b)) {
        for a in 0..3 {
            lo[a] = lo[a].min(b[a]);
            hi[a] = hi[a].max(b[a + 3]);
        }
    }
    let o = lo.map(frame_origin);
    let s: [f32; 3] = std::array::from_fn(|a| frame_step(o[a], hi[a], m));
    boxes
        .iter()
        .map(|b| {
            if empty(b) {
                return *b;
            }
            std::array::from_fn(|i| {
                let a = i % 3;
                let q = if i < 3 {
                    quant_lo(b[i], o[a], s[a], m)
                } else {
                    quant_hi(b[i], o[a], s[a], m)
                };
                decode(q, o[a], s[a])
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn children_decode_conservatively_in_their_frame() {
        let boxes = [
            [0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            [0.3, -2.5, 0.1, 0.7, -2.0, 0.1],
            [
                f32::INFINITY,
                f32::INFINITY,
                f32::INFINITY,
                -f32::INFINITY,
                -f32::INFINITY,
                -f32::INFINITY,
            ],
            [1e-3, 0.5, 0.99, 1e-3, 0.75, 1.0],
        ];
        for m in [255, 65535] {
            let d = decode_children(&boxes, m);
            assert_eq!(d[2], boxes[2], "an empty slot stays empty");
            for (e, d) in boxes.iter().zip(&d).filter(|(e, _)| e[0] <= e[3]) {
                assert!(
                    (0..3).all(|a| d[a] <= e[a] && d[a + 3] >= e[a + 3]),
                    "{e:?} {d:?}"
                );
            }
        }
        // Fewer bits, wider boxes.
        let (q8, q16) = (decode_children(&boxes, 255), decode_children(&boxes, 65535));
        assert!(q8[1][3] - q8[1][0] >= q16[1][3] - q16[1][0]);
    }

    fn encloses(lo: f32, hi: f32, wlo: f32, whi: f32) {
        let o = frame_origin(wlo);
        let s = frame_step(o, whi, 65535);
        let (ql, qh) = (quant_lo(lo, o, s, 65535), quant_hi(hi, o, s, 65535));
        assert!(ql <= qh, "{lo} {hi} in [{wlo}, {whi}]: {ql} > {qh}");
        assert!(decode(ql, o, s) <= lo, "{lo} in [{wlo}, {whi}]: {ql}");
        assert!(decode(qh, o, s) >= hi, "{hi} in [{wlo}, {whi}]: {qh}");
    }

    #[test]
    fn origins_round_down_to_zero_or_normal() {
        assert_eq!(frame_origin(1e-40).to_bits(), 0);
        assert_eq!(frame_origin(-0.0).to_bits(), 0);
        assert_eq!(frame_origin(-1e-40), -FLT_MIN);
        assert_eq!(frame_origin(FLT_MIN), FLT_MIN);
        assert_eq!(frame_origin(-3.5), -3.5);
        assert!(frame_origin(f32::NAN).is_nan());
    }

    #[test]
    fn edge_frames_enclose() {
        // Flat frame: the step floors at 2·FLT_MIN and every code decodes to the plane.
        let s = frame_step(5.0, 5.0, 65535);
        assert_eq!(s as f64, MIN_STEP);
        assert_eq!(
            (quant_lo(5.0, 5.0, s, 65535), quant_hi(5.0, 5.0, s, 65535)),
            (0, 0)
        );
        // The root box gets (0, M).
        let o = frame_origin(-2.0);
        let s = frame_step(o, 3.0, 65535);
        assert_eq!(
            (quant_lo(-2.0, o, s, 65535), quant_hi(3.0, o, s, 65535)),
            (0, 65535)
        );
        // Far from the origin with a tiny extent: plateaus, low code never passes the high one.
        encloses(1e6 + 0.25, 1e6 + 0.25, 1e6, 1e6 + 1.0);
        // Huge extents (f32 `hi - lo` overflows).
        encloses(-3e38, 3e38, -3.4e38, 3.4e38);
        encloses(1.0, 2.0, -f32::MAX, f32::MAX);
        // NaN planes give the whole frame.
        assert_eq!(quant_lo(f32::NAN, 0.0, 1.0, 9), 0);
        assert_eq!(quant_hi(f32::NAN, 0.0, 1.0, 9), 9);
    }

    /// Property: children decoded in their node's frame (`decode_children`, codes up to 255 and
    /// 65535) contain their exact boxes, for nodes of flat, degenerate (a point), huge, tiny and
    /// far-from-origin boxes and mixes of them, seeded xorshift draws.
    #[test]
    fn children_of_every_kind_of_box_decode_conservatively() {
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let mut unit = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut cases = 0;
        for round in 0..400 {
            let kind = round % 6;
            let (centre, scale) = match kind {
                0 => (0.0, 1.0),   // ordinary
                1 => (0.0, 1e-30), // tiny
                2 => (0.0, 1e37),  // huge
                3 => (1e7, 1e-2),  // far from the origin, small
                4 => (-3e5, 10.0), // far, negative
                _ => (unit() * 100.0, unit() * 1e3),
            };
            let slots = 1 + (round % 8);
            let mut boxes = Vec::new();
            for k in 0..slots {
                let mut b = [0f32; 6];
                for a in 0..3 {
                    let lo = centre + (unit() * 2.0 - 1.0) * scale;
                    let ext = match (k + round) % 4 {
                        0 => 0.0,                   // flat on this axis
                        1 => unit() * scale * 1e-6, // thin
                        _ => unit() * scale,
                    };
                    b[a] = lo;
                    b[a + 3] = lo + ext;
                }
                if (k + round) % 5 == 0 {
                    // Degenerate: a point.
                    b = [b[0], b[1], b[2], b[0], b[1], b[2]];
                }
                boxes.push(b);
            }
            for m in [255, 65535] {
                let d = decode_children(&boxes, m);
                for (e, d) in boxes.iter().zip(&d) {
                    assert!(
                        (0..3).all(|a| d[a] <= e[a] && d[a + 3] >= e[a + 3]),
                        "round {round} m {m}: {e:?} decoded as {d:?}"
                    );
                    cases += 1;
                }
            }
        }
        assert!(cases > 3000, "{cases}");
    }

    #[test]
    fn codes_are_tight_on_an_exact_grid() {
        // Step 1, origin 0: every integer plane is its own code.
        for v in [0.0f32, 1.0, 7.0, 100.0] {
            assert_eq!(quant_lo(v, 0.0, 1.0, 1000), v as u32);
            assert_eq!(quant_hi(v, 0.0, 1.0, 1000), v as u32);
        }
        assert_eq!(quant_lo(7.5, 0.0, 1.0, 1000), 7);
        assert_eq!(quant_hi(7.5, 0.0, 1.0, 1000), 8);
        assert_eq!(quant_hi(2000.0, 0.0, 1.0, 1000), 1000);
        assert_eq!(quant_lo(-1.0, 0.0, 1.0, 1000), 0);
        assert_eq!(quant_hi(5e9, 0.0, 1.0, u32::MAX), u32::MAX);
        assert_eq!(quant_lo(5e9, 0.0, 1.0, u32::MAX), u32::MAX);
    }
}
