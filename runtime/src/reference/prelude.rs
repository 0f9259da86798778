//! The geometric tests of `library/prelude.scion` in Rust, with exactly the prelude's
//! arithmetic: the same operations, in the same order, each rounded once to `f32`.
//!
//! This is what makes the reference bit-identical to generated code (architecture §6). Rules
//! that generated code must follow too:
//! - No fused multiply-add contraction: `a * b + c` is two roundings. Rust never contracts
//!   (it has no `-ffast-math`); LLVM and Cranelift backends must not set `contract` or
//!   fast-math flags on these operations, and PTX must use `mul.rn`/`add.rn` (which nvcc and
//!   LLVM's NVPTX backend otherwise fuse into `fma.rn`).
//! - `min`/`max` are IEEE 754 minNum/maxNum: when one operand is NaN the other is returned
//!   (`f32::min`/`f32::max` in Rust, `llvm.minnum`/`llvm.maxnum`, `min.f32`/`max.f32` in PTX).
//!   An axis with an infinite `1/d` (zero or tiny direction lane) gets `inv = +inf` and is
//!   decided by the origin's position ([`slab_axis`]): the `0 * inf = NaN` of an origin on a
//!   plane becomes the inside answer, so no distance of the slab test is NaN.
//! - `dot(a, b) = (a.x*b.x + a.y*b.y) + a.z*b.z`, left to right;
//!   `cross(a, b) = (a.y*b.z - a.z*b.y, a.z*b.x - a.x*b.z, a.x*b.y - a.y*b.x)`.
//! - Division is IEEE division (`1.0 / d`), never a reciprocal approximation.
//! - The widening factor is the literal `1.0000004` rounded to `f32` (`1 + 3 * 2^-23`).

use crate::geom::{Aabb, Ray, Triangle, Vec3};
use crate::primitive::{Segment, Triangle4};
use std::cmp::Ordering;

/// `1.0000004` as the prelude writes it, rounded to `f32`.
pub const FAR_WIDENING: f32 = 1.000_000_4;

/// The prelude's `SlabRay`: what every box test of one traversal shares, computed once per ray
/// by [`slab_ray`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlabRay {
    /// The ray's origin.
    pub origin: Vec3,
    /// `1 / direction` lane-wise, `+inf` on an axis the ray does not move along.
    pub inv: Vec3,
    /// `max(ray.tmin, -inf)`: the ray's `tmin`, `-inf` when it is NaN.
    pub tmin: f32,
    /// `min(ray.tmax, inf)`: the ray's `tmax`, `+inf` when it is NaN.
    pub tmax: f32,
}

/// The prelude's `slab_inv(d)`: `1 / d`, or `+inf` when that is infinite (`d` is zero or tiny).
#[inline]
pub fn slab_inv(d: f32) -> f32 {
    let inv = 1.0 / d;
    if inv.abs() == f32::INFINITY {
        f32::INFINITY
    } else {
        inv
    }
}

/// The prelude's `slab_ray(ray)`.
#[inline]
pub fn slab_ray(ray: &Ray) -> SlabRay {
    let d = ray.dir;
    SlabRay {
        origin: ray.origin,
        inv: Vec3::new(slab_inv(d.x), slab_inv(d.y), slab_inv(d.z)),
        tmin: max_num(ray.tmin, f32::NEG_INFINITY),
        tmax: min_num(ray.tmax, f32::INFINITY),
    }
}

/// One axis of the prelude's `slab_interval`: `(near, far)`, never NaN. `(plane - o) * inf`
/// is NaN when the origin lies on the plane of an axis the ray does not move along; the
/// `max(.., -inf)` / `min(.., inf)` make that the inside answer.
#[inline]
pub fn slab_axis(lo: f32, hi: f32, o: f32, inv: f32) -> (f32, f32) {
    let t0 = max_num((lo - o) * inv, f32::NEG_INFINITY);
    let t1 = min_num((hi - o) * inv, f32::INFINITY);
    (min_num(t0, t1), max_num(t0, t1))
}

/// The prelude's `slab_span(r, box)`: `(enter, far)`, the entry distance and the exit distance
/// widened by [`FAR_WIDENING`], not clipped at any bound.
#[inline]
pub fn slab_span_of(r: &SlabRay, b: &Aabb) -> (f32, f32) {
    let o = r.origin;
    let x = slab_axis(b.low.x, b.high.x, o.x, r.inv.x);
    let y = slab_axis(b.low.y, b.high.y, o.y, r.inv.y);
    let z = slab_axis(b.low.z, b.high.z, o.z, r.inv.z);
    let enter = max_num(max_num(x.0, y.0), max_num(z.0, r.tmin));
    (enter, min_num(x.1, min_num(y.1, z.1)) * FAR_WIDENING)
}

/// The prelude's `slab_interval(r, box, tmax)`: `(enter, exit)` with `exit <= tmax`; the ray
/// meets the box iff `enter <= exit` (false when either is NaN).
#[inline]
pub fn slab_interval_of(r: &SlabRay, b: &Aabb, tmax: f32) -> (f32, f32) {
    let (enter, far) = slab_span_of(r, b);
    (enter, min_num(far, tmax))
}

/// The prelude's `distmin(r, box, tmax)`: the entry distance when the ray meets the box before
/// `tmax`, else `+inf` (`enter <= min(far, tmax)` as two compares; a NaN `tmax` is ignored, as
/// `min` ignores it).
#[inline]
// `!(tmax < enter)` is not `tmax >= enter`: it is true for a NaN `tmax`, as the prelude's is.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn distmin_of(r: &SlabRay, b: &Aabb, tmax: f32) -> f32 {
    let (enter, far) = slab_span_of(r, b);
    if enter <= far && !(tmax < enter) {
        enter
    } else {
        f32::INFINITY
    }
}

/// The prelude's `slab_interval(ray, box)`: `slab_interval(slab_ray(ray), box, ray.tmax)`.
#[inline]
pub fn slab_interval(ray: &Ray, b: &Aabb) -> (f32, f32) {
    slab_interval_of(&slab_ray(ray), b, ray.tmax)
}

/// The language's float `min`: the non-NaN operand when one is NaN, else the smaller, and the
/// first operand on ties (so `min(+0, -0)` is `+0`), exactly as the interpreters and the JIT.
#[inline]
pub fn min_num(a: f32, b: f32) -> f32 {
    if a.is_nan() {
        b
    } else if b.is_nan() || b >= a {
        a
    } else {
        b
    }
}

/// The language's float `max`: as [`min_num`], the larger, first operand on ties.
#[inline]
pub fn max_num(a: f32, b: f32) -> f32 {
    if a.is_nan() {
        b
    } else if b.is_nan() || b <= a {
        a
    } else {
        b
    }
}

/// The prelude's `intersects(ray, box)`.
#[inline]
pub fn intersects_box(ray: &Ray, b: &Aabb) -> bool {
    let (enter, exit) = slab_interval(ray, b);
    enter <= exit
}

/// The prelude's `distmin(ray, box)`: the entry distance, or `+inf` on a miss.
#[inline]
pub fn distmin_box(ray: &Ray, b: &Aabb) -> f32 {
    distmin_of(&slab_ray(ray), b, ray.tmax)
}

/// The prelude's `hit_distance(ray, tri)` (Moller-Trumbore): the hit distance in
/// `(tmin, tmax)`, or `+inf`. A zero determinant (parallel ray or zero-area triangle) misses.
#[inline]
// `u < 0.0 || u > 1.0` is not `!(0.0..=1.0).contains(&u)`: a NaN `u` passes the prelude's test.
#[allow(clippy::manual_range_contains)]
pub fn hit_distance(ray: &Ray, tri: &Triangle) -> f32 {
    let e1 = tri.p1 - tri.p0;
    let e2 = tri.p2 - tri.p0;
    let pv = ray.dir.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 {
        return f32::INFINITY;
    }
    let inv_det = 1.0 / det;
    let tv = ray.origin - tri.p0;
    let u = tv.dot(pv) * inv_det;
    if u < 0.0 || u > 1.0 {
        return f32::INFINITY;
    }
    let qv = tv.cross(e1);
    let v = ray.dir.dot(qv) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return f32::INFINITY;
    }
    let t = e2.dot(qv) * inv_det;
    if t > ray.tmin && t < ray.tmax {
        return t;
    }
    f32::INFINITY
}

/// The prelude's `hit_key(t, id)`: `(t, id)` as one integer ordered as the pair by the tie rule
/// (`t`'s bits mapped to unsigned order after `-0 -> +0`; `t` is never NaN).
#[inline]
pub fn hit_key(t: f32, id: u32) -> u64 {
    let b = (t + 0.0).to_bits();
    let o = if b >= 0x8000_0000 {
        !b
    } else {
        b | 0x8000_0000
    };
    (u64::from(o) << 32) | u64::from(id)
}

/// The prelude's `hit_of_key(k)`: the `(t, id)` of a [`hit_key`].
#[inline]
pub fn hit_of_key(k: u64) -> (f32, u32) {
    let o = (k >> 32) as u32;
    let b = if o >= 0x8000_0000 {
        o & 0x7FFF_FFFF
    } else {
        !o
    };
    (f32::from_bits(b), k as u32)
}

/// The prelude's `hit_block(ray, block)`: the nearest of a [`Triangle4`]'s four triangles by the
/// tie rule, `(t, id)`: the smallest [`hit_key`] of the lanes' `hit_distance`s (the prelude
/// computes every lane without early exits: the same values). All four missing gives
/// `(inf, smallest id)`.
#[inline]
pub fn hit_block(ray: &Ray, b: &Triangle4) -> (f32, u32) {
    let key = |k: usize| hit_key(hit_distance(ray, &b.lane(k)), b.id[k]);
    hit_of_key(key(0).min(key(1)).min(key(2).min(key(3))))
}

/// The prelude's `hit_distance(ray, segment)`: the ray against a strand segment as a flat
/// ribbon facing the ray (Embree's flat linear curve). With `a = p0 - o` and `b = p1 - p0`
/// split into their parts across the ray's direction (`ap`, `bp`), the axis point nearest the
/// ray's line is at `u = clamp(-ap·bp / bp·bp, 0, 1)` (0 when `bp` is zero: a segment seen end
/// on); the ray hits when that point is within the radius `r0 + (r1 - r0) u` of the line, at
/// the distance of its projection, `t = (a + u b)·d / d·d`, when that is in `(tmin, tmax)`.
/// A zero direction misses.
#[inline]
// `max(0).min(1)` is not `clamp`: a NaN `u` (a segment of infinite extent) becomes 0 here, as
// the prelude's minNum/maxNum make it, where `clamp` would keep the NaN.
#[allow(clippy::manual_clamp)]
pub fn hit_distance_segment(ray: &Ray, s: &Segment) -> f32 {
    let d = ray.dir;
    let dd = d.dot(d);
    if dd == 0.0 {
        return f32::INFINITY;
    }
    let a = s.p0 - ray.origin;
    let b = s.p1 - s.p0;
    let ap = a - d * (a.dot(d) / dd);
    let bp = b - d * (b.dot(d) / dd);
    let bb = bp.dot(bp);
    let u = if bb > 0.0 {
        (-ap.dot(bp) / bb).max(0.0).min(1.0)
    } else {
        0.0
    };
    let q = ap + bp * u;
    let r = s.r0 + (s.r1 - s.r0) * u;
    if q.dot(q) > r * r {
        return f32::INFINITY;
    }
    let t = (a + b * u).dot(d) / dd;
    if t > ray.tmin && t < ray.tmax {
        return t;
    }
    f32::INFINITY
}

/// The prelude's `0.00000095367431640625` (2^-20), the diagonal test's margin per unit of
/// magnitude.
pub const DIAGONAL_MARGIN: f32 = 1.0 / 1_048_576.0;

/// The prelude's `diagonals(p)`: `(x+y+z, x+y-z, x-y+z, x-y-z)`, left to right.
#[inline]
pub fn diagonals(p: Vec3) -> [f32; 4] {
    [
        p.x + p.y + p.z,
        p.x + p.y - p.z,
        p.x - p.y + p.z,
        p.x - p.y - p.z,
    ]
}

/// The prelude's `hmax`: the lanes folded left to right by `max` (minNum semantics).
fn hmax4(v: [f32; 4]) -> f32 {
    max_num(max_num(max_num(v[0], v[1]), v[2]), v[3])
}

/// The prelude's `distmin(ray, r, dop, tmax)`: the axis slabs' entry distance unless the
/// conservative diagonal test separates the ray's piece inside them from the DOP.
pub fn distmin_dop14(ray: &Ray, r: &SlabRay, dop: &crate::bvh::dop14::Dop14, tmax: f32) -> f32 {
    let b = Aabb::new(Vec3::from_array(dop.lo1), Vec3::from_array(dop.hi1));
    let (t0, t1) = slab_interval_of(r, &b, tmax);
    // A miss: not `t0 <= t1` (false too when either is NaN).
    if !matches!(t0.partial_cmp(&t1), Some(Ordering::Less | Ordering::Equal)) {
        return f32::INFINITY;
    }
    if t0.abs() < f32::INFINITY && t1.abs() < f32::INFINITY {
        let o = diagonals(ray.origin);
        let d = diagonals(ray.dir);
        let s0: [f32; 4] = std::array::from_fn(|k| o[k] + d[k] * t0);
        let s1: [f32; 4] = std::array::from_fn(|k| o[k] + d[k] * t1);
        let hsum_abs = |v: Vec3| v.x.abs() + v.y.abs() + v.z.abs();
        let reach = hsum_abs(ray.origin) + max_num(t0.abs(), t1.abs()) * hsum_abs(ray.dir);
        let e = reach * DIAGONAL_MARGIN;
        let above: [f32; 4] = std::array::from_fn(|k| min_num(s0[k], s1[k]) - e - dop.hi2[k]);
        let below: [f32; 4] = std::array::from_fn(|k| dop.lo2[k] - (max_num(s0[k], s1[k]) + e));
        if hmax4(above) > 0.0 || hmax4(below) > 0.0 {
            return f32::INFINITY;
        }
    }
    t0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widening_literal_is_three_ulps_above_one() {
        assert_eq!(FAR_WIDENING.to_bits(), 1.0f32.to_bits() + 3);
    }

    #[test]
    fn zero_direction_lanes_and_rays_in_box_faces() {
        let b = Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 1.0));
        // Origin strictly inside the slab 0 <= x <= 1 with dir.x = 0: t0.x = -inf, t1.x = +inf.
        let r = Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::new(0.0, 0.0, 1.0));
        assert!(intersects_box(&r, &b));
        assert_eq!(distmin_box(&r, &b), 1.0);
        // Origin ON the slab plane x = 0 (or x = 1) with dir.x = 0: the lane is decided by
        // position, so a ray lying in a box face counts as inside.
        let r = Ray::new(Vec3::new(0.0, 0.5, -1.0), Vec3::new(0.0, 0.0, 1.0));
        assert!(intersects_box(&r, &b));
        assert_eq!(distmin_box(&r, &b), 1.0);
        let r = Ray::new(Vec3::new(1.0, 0.5, -1.0), Vec3::new(0.0, 0.0, 1.0));
        assert!(intersects_box(&r, &b));
        // Negative zero direction: inv = -inf, still inside the slab.
        let r = Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::new(-0.0, -0.0, 1.0));
        assert!(intersects_box(&r, &b));
        // Outside the slab with a zero lane: a miss.
        let r = Ray::new(Vec3::new(2.0, 0.5, -1.0), Vec3::new(0.0, 0.0, 1.0));
        assert!(!intersects_box(&r, &b));
        assert_eq!(distmin_box(&r, &b), f32::INFINITY);
    }

    #[test]
    fn moller_trumbore_hits_and_misses() {
        let t = Triangle::new(
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            0,
        );
        let down = Vec3::new(0.0, 0.0, -1.0);
        assert_eq!(
            hit_distance(&Ray::new(Vec3::new(0.25, 0.25, 2.0), down), &t),
            2.0
        );
        assert_eq!(
            hit_distance(&Ray::new(Vec3::new(0.75, 0.75, 2.0), down), &t),
            f32::INFINITY
        );
        // Behind the origin, and at t == tmax: misses.
        assert_eq!(
            hit_distance(&Ray::new(Vec3::new(0.25, 0.25, -2.0), down), &t),
            f32::INFINITY
        );
        let mut r = Ray::new(Vec3::new(0.25, 0.25, 2.0), down);
        r.tmax = 2.0;
        assert_eq!(hit_distance(&r, &t), f32::INFINITY);
        // Parallel ray and zero-area triangle: det == 0.
        let side = Vec3::new(1.0, 0.0, 0.0);
        assert_eq!(
            hit_distance(&Ray::new(Vec3::new(-1.0, 0.25, 0.0), side), &t),
            f32::INFINITY
        );
        let flat = Triangle::new(t.p0, t.p1, Vec3::new(2.0, 0.0, 0.0), 1);
        assert_eq!(
            hit_distance(&Ray::new(Vec3::new(0.5, 0.0, 2.0), down), &flat),
            f32::INFINITY
        );
    }
}
