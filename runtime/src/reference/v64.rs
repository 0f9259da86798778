//! Three-lane `f64` vectors for the references' float64 arithmetic: the prelude's `f64x3`
//! operations (each lane rounded once, left to right, no fusing), and the float64 oracles
//! built on them (closest points, collisions, any hit).

use crate::geom::Vec3;

/// `(x, y, z)` in `f64`.
pub type V64 = [f64; 3];

/// `v` widened exactly.
pub fn widen(v: Vec3) -> V64 {
    [f64::from(v.x), f64::from(v.y), f64::from(v.z)]
}

/// `v` rounded to `f32`, lane by lane.
pub fn narrow(v: V64) -> Vec3 {
    Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)
}

/// `a + b`, lane by lane.
pub fn add(a: V64, b: V64) -> V64 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `a - b`, lane by lane.
pub fn sub(a: V64, b: V64) -> V64 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// The prelude's `dot`: left to right.
pub fn dot(a: V64, b: V64) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The cross product `a × b`.
pub fn cross(a: V64, b: V64) -> V64 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The prelude's `scale64(v, s)`.
pub fn scale(v: V64, s: f64) -> V64 {
    [v[0] * s, v[1] * s, v[2] * s]
}

/// `a + d * t`, lane by lane.
pub fn axpy(a: V64, d: V64, t: f64) -> V64 {
    [a[0] + d[0] * t, a[1] + d[1] * t, a[2] + d[2] * t]
}
