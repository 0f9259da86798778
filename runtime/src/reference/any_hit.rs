//! The float64 oracle of any hit (shadow rays, `library/algorithms/occluded.scion`): whether a
//! ray meets a triangle strictly inside `(tmin, tmax)`, decided in `f64` on the widened inputs,
//! with the **margin** of that verdict: how far the deciding triangle is from the other answer.
//!
//! The `f32` test (the prelude's Möller-Trumbore, [`super::prelude::hit_distance`]) and generated
//! code agree bit for bit (tests/tests/occluded.rs); where the `f32` answer differs from the
//! `f64` one, the ray grazes an edge or a vertex, or meets a triangle within rounding of `tmin`
//! or `tmax`: the margin is then tiny, and `f64` is the side to believe
//! (tests/tests/occluded.rs counts the rays per scene and checks their margins).
//!
//! The margin of one triangle is a signed length, relative to the magnitude of the coordinates
//! involved (the scale of `f32`'s rounding): the smallest of the crossing point's distances to
//! the triangle's three edge lines (its barycentric coordinates times the heights) and of
//! `(t - tmin) |d|` and `(tmax - t) |d|`, times the cosine of the angle between the ray and the
//! triangle's normal (rounding moves the crossing point along the plane by about the error of
//! the ray's coordinates over that cosine), divided by the largest coordinate magnitude of the
//! corners, the origin and the crossing point. Positive for a hit, negative for a miss; near 0
//! the ray grazes an edge or a vertex, or meets the triangle within rounding of `tmin` or
//! `tmax`. A ray parallel to the triangle's plane (determinant 0 in `f64`) misses by its
//! distance from the plane (0 in the plane: grazing), and a triangle of no area by 0. The ray's
//! verdict is the triangle of largest margin: occluded when that is positive.

use super::v64::{cross, dot, sub, widen};
use crate::geom::{Ray, Triangle};

/// The `f64` verdict on one ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnyHitF64 {
    /// A triangle meets the ray strictly inside `(tmin, tmax)`.
    pub occluded: bool,
    /// The largest triangle margin (module docs): positive when occluded; `-inf` when no
    /// triangle's plane crosses the ray.
    pub margin: f64,
}

/// One triangle's margin for `ray` in `f64` (module docs).
pub fn hit_margin_f64(ray: &Ray, tri: &Triangle) -> f64 {
    let (p0, p1, p2) = (widen(tri.p0), widen(tri.p1), widen(tri.p2));
    let (o, d) = (widen(ray.origin), widen(ray.dir));
    let (e1, e2) = (sub(p1, p0), sub(p2, p0));
    let n = cross(e1, e2);
    let area2 = dot(n, n).sqrt();
    let magnitude = |v: [f64; 3]| v[0].abs().max(v[1].abs()).max(v[2].abs());
    let scale = [p0, p1, p2, o]
        .into_iter()
        .map(magnitude)
        .fold(f64::MIN_POSITIVE, f64::max);
    if area2 == 0.0 {
        return 0.0;
    }
    let pv = cross(d, e2);
    let det = dot(e1, pv);
    let tv = sub(o, p0);
    if det == 0.0 {
        return -(dot(tv, n).abs() / area2) / scale;
    }
    let qv = cross(tv, e1);
    let u = dot(tv, pv) / det;
    let v = dot(d, qv) / det;
    let t = dot(e2, qv) / det;
    let len = |v: [f64; 3]| dot(v, v).sqrt();
    let x = [o[0] + d[0] * t, o[1] + d[1] * t, o[2] + d[2] * t];
    let scale = scale.max(magnitude(x));
    let dl = len(d);
    let (tmin, tmax) = (f64::from(ray.tmin), f64::from(ray.tmax));
    let mut m = (u * area2 / len(e2))
        .min(v * area2 / len(e1))
        .min((1.0 - u - v) * area2 / len(sub(p2, p1)))
        .min((t - tmin) * dl);
    if tmax.is_finite() {
        m = m.min((tmax - t) * dl);
    }
    // Rounding moves the crossing point by about its distance from the origin over the cosine
    // of the angle between the ray and the plane: a ray at a grazing angle grazes too.
    let cosine = det.abs() / (area2 * dl);
    if m.is_nan() {
        f64::NEG_INFINITY
    } else {
        m * cosine / scale
    }
}

/// Whether any of `tris` meets `ray`, in `f64`, with the verdict's margin.
pub fn any_hit_f64(tris: &[Triangle], ray: &Ray) -> AnyHitF64 {
    let margin = tris
        .iter()
        .map(|t| hit_margin_f64(ray, t))
        .fold(f64::NEG_INFINITY, f64::max);
    AnyHitF64 {
        occluded: margin > 0.0,
        margin,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Vec3;

    fn unit() -> Triangle {
        Triangle::new(
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            0,
        )
    }

    #[test]
    fn margins_say_how_near_the_other_answer_is() {
        let down = |x: f32, y: f32, tmax: f32| {
            let mut r = Ray::new(Vec3::new(x, y, 1.0), Vec3::new(0.0, 0.0, -1.0));
            r.tmax = tmax;
            r
        };
        let t = [unit()];
        // Through (0.25, 0.25): a quarter from the legs, the origin's magnitude 1 the scale.
        let a = any_hit_f64(&t, &down(0.25, 0.25, f32::INFINITY));
        assert!(a.occluded && (a.margin - 0.25).abs() < 1e-9, "{a:?}");
        // Just outside the hypotenuse: a miss by a hair.
        let a = any_hit_f64(&t, &down(0.5, 0.500_001, f32::INFINITY));
        assert!(!a.occluded && a.margin > -2e-6 && a.margin < 0.0, "{a:?}");
        // Stopping short of the plane (t = 1): the distance decides.
        let a = any_hit_f64(&t, &down(0.25, 0.25, 0.5));
        assert!(!a.occluded && (a.margin + 0.5).abs() < 1e-9, "{a:?}");
        // Parallel to the plane, a unit above it.
        let r = Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::new(1.0, 0.0, 0.0));
        assert!((any_hit_f64(&t, &r).margin + 1.0).abs() < 1e-9);
        assert!(!any_hit_f64(&[], &r).occluded);
    }
}
