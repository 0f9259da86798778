//! Closest point queries by brute force: the reference of `library/algorithms/closest_point.scion`.
//!
//! [`closest_point_brute`] runs the prelude's arithmetic ([`triangle_distance`] is the
//! algorithm's `triangle_distance`, operation for operation: the closest point on the triangle in
//! `f64`, rounded to `f32`, clamped into the triangle's box, its squared distance in `f32`) over every triangle with the tie
//! rule (smaller squared distance, then smaller id). Both traversals of the algorithm must return
//! exactly its answer on every layout whose boxes contain their triangles: their pruning is exact
//! (a triangle's squared distance is never below its box's, see the algorithm file).
//! [`closest_point_f64`] is the same search in `f64`, the accuracy check of the `f32` answer.

use super::prelude::{max_num, min_num};
use super::v64::{add, axpy, dot, narrow, scale, sub, widen, V64};
use crate::geom::{Aabb, Triangle, Vec3};

/// The answer to one query: `best` of the algorithm file.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosestPoint {
    /// The distance to the nearest point (the search radius when none is within it).
    pub distance: f32,
    /// The nearest point's primitive id, `u32::MAX` when none is within the radius.
    pub prim: u32,
    /// The nearest point.
    pub point: Vec3,
}

impl ClosestPoint {
    /// What a caller passes in: the search radius, no primitive, the origin.
    pub fn start(radius: f32) -> ClosestPoint {
        ClosestPoint {
            distance: radius,
            prim: u32::MAX,
            point: Vec3::splat(0.0),
        }
    }

    /// The same bits in every field (NaN payloads and signed zeros included).
    pub fn bit_eq(&self, o: &ClosestPoint) -> bool {
        self.distance.to_bits() == o.distance.to_bits()
            && self.prim == o.prim
            && self.point.to_array().map(f32::to_bits) == o.point.to_array().map(f32::to_bits)
    }
}

fn lanes(a: Vec3, b: Vec3, f: impl Fn(f32, f32) -> f32) -> Vec3 {
    Vec3::new(f(a.x, b.x), f(a.y, b.y), f(a.z, b.z))
}

fn length_squared(v: Vec3) -> f32 {
    v.dot(v)
}

/// The prelude's `closest_point(p, box)`: `min(max(p, low), high)` lane by lane.
pub fn clamp_to_box(p: Vec3, b: &Aabb) -> Vec3 {
    lanes(lanes(p, b.low, max_num), b.high, min_num)
}

/// The prelude's `distance_squared(p, box)`.
pub fn box_distance_squared(p: Vec3, b: &Aabb) -> f32 {
    length_squared(clamp_to_box(p, b) - p)
}

fn closest_point_on_segment(p: V64, a: V64, b: V64) -> V64 {
    let ab = sub(b, a);
    let len2 = dot(ab, ab);
    if len2 == 0.0 {
        return a;
    }
    // minNum/maxNum, as the prelude's `min`/`max` (not `clamp`, which keeps a NaN).
    #[allow(clippy::manual_clamp)]
    let t = (dot(sub(p, a), ab) / len2).max(0.0).min(1.0);
    add(a, scale(ab, t))
}

fn nearer(p: V64, x: V64, y: V64) -> V64 {
    if dot(sub(y, p), sub(y, p)) < dot(sub(x, p), sub(x, p)) {
        y
    } else {
        x
    }
}

/// The prelude's `closest_point(p, tri)`: Ericson §5.1.5 (edges for a zero-area triangle) in
/// `f64` on the widened corners, rounded to `f32` at the end.
pub fn closest_point_on_triangle(p: Vec3, tri: &Triangle) -> Vec3 {
    narrow(closest_point_f64_ericson(
        widen(p),
        widen(tri.p0),
        widen(tri.p1),
        widen(tri.p2),
    ))
}

fn closest_point_f64_ericson(p: V64, a: V64, b: V64, c: V64) -> V64 {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = sub(p, b);
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let cp = sub(p, c);
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vc = d1 * d4 - d3 * d2;
    let vb = d5 * d2 - d1 * d6;
    let va = d3 * d6 - d5 * d4;
    let sum = va + vb + vc;
    if sum == 0.0 {
        let e0 = closest_point_on_segment(p, a, b);
        let e1 = closest_point_on_segment(p, b, c);
        let e2 = closest_point_on_segment(p, c, a);
        return nearer(p, nearer(p, e0, e1), e2);
    }
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return add(a, scale(ab, d1 / (d1 - d3)));
    }
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return add(a, scale(ac, d2 / (d2 - d6)));
    }
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return add(b, scale(sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
    }
    let inv = 1.0 / sum;
    add(add(a, scale(ab, vb * inv)), scale(ac, vc * inv))
}

/// The prelude's `bounds(tri)`.
pub fn triangle_box(tri: &Triangle) -> Aabb {
    Aabb::new(
        lanes(lanes(tri.p0, tri.p1, min_num), tri.p2, min_num),
        lanes(lanes(tri.p0, tri.p1, max_num), tri.p2, max_num),
    )
}

/// The algorithm's `triangle_distance(p, t)`: the squared distance and the point, clamped
/// into the triangle's box.
pub fn triangle_distance(p: Vec3, tri: &Triangle) -> (f32, Vec3) {
    let c = clamp_to_box(closest_point_on_triangle(p, tri), &triangle_box(tri));
    (length_squared(c - p), c)
}

/// The closest point of `tris` to `p` within `radius`, in the algorithm's `f32` arithmetic.
pub fn closest_point_brute(tris: &[Triangle], p: Vec3, radius: f32) -> ClosestPoint {
    let mut best = (radius * radius, u32::MAX, Vec3::splat(0.0));
    for t in tris {
        let (d, c) = triangle_distance(p, t);
        if d < best.0 || (d == best.0 && t.id < best.1) {
            best = (d, t.id, c);
        }
    }
    ClosestPoint {
        distance: best.0.sqrt(),
        prim: best.1,
        point: best.2,
    }
}

fn segment64(p: V64, a: V64, b: V64) -> V64 {
    let ab = sub(b, a);
    let len2 = dot(ab, ab);
    if len2 == 0.0 {
        return a;
    }
    axpy(a, ab, (dot(sub(p, a), ab) / len2).clamp(0.0, 1.0))
}

/// The distance from `p` to triangle `tri` in `f64`: the minimum of the distances to the three
/// edges and, when the projection of `p` falls inside, to the plane (no Voronoi-region
/// decisions, so no cancellation decides a region).
pub fn triangle_distance_f64(p: Vec3, tri: &Triangle) -> f64 {
    let (p, a, b, c) = (widen(p), widen(tri.p0), widen(tri.p1), widen(tri.p2));
    let mut best = f64::INFINITY;
    for (u, v) in [(a, b), (b, c), (c, a)] {
        let q = segment64(p, u, v);
        best = best.min(dot(sub(q, p), sub(q, p)));
    }
    let (ab, ac) = (sub(b, a), sub(c, a));
    let n = [
        ab[1] * ac[2] - ab[2] * ac[1],
        ab[2] * ac[0] - ab[0] * ac[2],
        ab[0] * ac[1] - ab[1] * ac[0],
    ];
    let nn = dot(n, n);
    if nn > 0.0 {
        let h = dot(sub(p, a), n) / nn;
        let q = axpy(p, n, -h);
        // Barycentric signs by the three sub-triangles' normals.
        let inside = [(a, b), (b, c), (c, a)].iter().all(|&(u, v)| {
            let e = sub(v, u);
            let w = sub(q, u);
            let cr = [
                e[1] * w[2] - e[2] * w[1],
                e[2] * w[0] - e[0] * w[2],
                e[0] * w[1] - e[1] * w[0],
            ];
            dot(cr, n) >= 0.0
        });
        if inside {
            best = best.min(dot(sub(q, p), sub(q, p)));
        }
    }
    best.sqrt()
}

/// The distance from `p` to the nearest of `tris` in `f64`, and the smallest id at that
/// distance (`u32::MAX` for no triangles).
pub fn closest_point_f64(tris: &[Triangle], p: Vec3) -> (f64, u32) {
    let mut best = (f64::INFINITY, u32::MAX);
    for t in tris {
        let d = triangle_distance_f64(p, t);
        if d < best.0 || (d == best.0 && t.id < best.1) {
            best = (d, t.id);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn f32_and_f64_agree_on_a_right_triangle() {
        let t = Triangle::new(
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            3,
        );
        for (p, want) in [
            (Vec3::new(0.25, 0.25, 2.0), 2.0),
            (Vec3::new(-1.0, -1.0, 0.0), 2f64.sqrt()),
            (Vec3::new(1.0, 1.0, 0.0), 0.5f64.sqrt()),
            (Vec3::new(0.5, -3.0, 4.0), 5.0),
        ] {
            let got = closest_point_brute(&[t], p, f32::INFINITY);
            assert_eq!(got.prim, 3);
            assert!(
                (f64::from(got.distance) - want).abs() < 1e-6,
                "{p:?}: {got:?}"
            );
            let (d, id) = closest_point_f64(&[t], p);
            assert_eq!(id, 3);
            assert!((d - want).abs() < 1e-12, "{p:?}: {d}");
        }
    }

    #[test]
    fn a_triangle_is_never_nearer_than_its_box() {
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let mut f = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            ((x >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * 8.0
        };
        for _ in 0..20_000 {
            let mut v = || Vec3::new(f(), f(), f());
            let t = Triangle::new(v(), v(), v(), 0);
            let p = v();
            let (d, _) = triangle_distance(p, &t);
            assert!(d >= box_distance_squared(p, &triangle_box(&t)));
        }
    }

    #[test]
    fn radius_and_ties() {
        let a = Triangle::new(
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            9,
        );
        let b = Triangle { id: 4, ..a };
        let p = Vec3::new(0.2, 0.2, 1.0);
        assert_eq!(closest_point_brute(&[a, b], p, f32::INFINITY).prim, 4);
        let none = closest_point_brute(&[a, b], p, 0.5);
        assert_eq!((none.prim, none.distance), (u32::MAX, 0.5));
    }
}
