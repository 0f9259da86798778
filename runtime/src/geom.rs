//! Geometry values shared by the whole runtime: `Vec3`, `Aabb`, `Triangle`, `Ray`, `Hit`.
//!
//! These are the Rust images of the prelude's record types (`library/prelude.scion`: `Ray`,
//! `AABB`, `Triangle`) and of the closest-hit result `(t, primitive id)` (paper §3, Figure 4).
//! Every type is `#[repr(C)]` with `f32` fields so that slices of them can be handed to
//! generated code as they are (architecture §5). Arithmetic here is plain IEEE `f32`, one
//! rounding per operation, no fused multiply-add: see `reference::prelude` for the exact
//! expression order the reference uses.

use std::ops::{Add, Index, Mul, Sub};

/// A 3-vector of `f32` (the prelude's `f32x3`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vec3 {
    /// First lane.
    pub x: f32,
    /// Second lane.
    pub y: f32,
    /// Third lane.
    pub z: f32,
}

impl Vec3 {
    /// The vector `(x, y, z)`.
    pub const fn new(x: f32, y: f32, z: f32) -> Vec3 {
        Vec3 { x, y, z }
    }

    /// The vector `(s, s, s)` (the prelude's `splat`).
    pub const fn splat(s: f32) -> Vec3 {
        Vec3 { x: s, y: s, z: s }
    }

    /// Lane-wise minimum; on a NaN lane the other operand (IEEE minNum, like the prelude's `min`).
    pub fn min(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x.min(o.x), self.y.min(o.y), self.z.min(o.z))
    }

    /// Lane-wise maximum; on a NaN lane the other operand (IEEE maxNum, like the prelude's `max`).
    pub fn max(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x.max(o.x), self.y.max(o.y), self.z.max(o.z))
    }

    /// Dot product evaluated as `(x*x' + y*y') + z*z'`, left to right, no FMA.
    pub fn dot(self, o: Vec3) -> f32 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Cross product `(y*z' - z*y', z*x' - x*z', x*y' - y*x')`, no FMA.
    pub fn cross(self, o: Vec3) -> Vec3 {
        Vec3::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }

    /// Lane-wise product.
    pub fn mul_lanes(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }

    /// Lane `axis` (0 = x, 1 = y, 2 = z).
    pub fn axis(self, axis: usize) -> f32 {
        self[axis]
    }

    /// True when every lane is finite (neither NaN nor ±inf).
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }

    /// The lanes as an array.
    pub fn to_array(self) -> [f32; 3] {
        [self.x, self.y, self.z]
    }

    /// The vector from an array.
    pub fn from_array(a: [f32; 3]) -> Vec3 {
        Vec3::new(a[0], a[1], a[2])
    }
}

impl Index<usize> for Vec3 {
    type Output = f32;
    fn index(&self, axis: usize) -> &f32 {
        match axis {
            0 => &self.x,
            1 => &self.y,
            2 => &self.z,
            _ => panic!("Vec3 lane {axis} out of range (0..3)"),
        }
    }
}

impl Add for Vec3 {
    type Output = Vec3;
    fn add(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl Sub for Vec3 {
    type Output = Vec3;
    fn sub(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl Mul<f32> for Vec3 {
    type Output = Vec3;
    fn mul(self, s: f32) -> Vec3 {
        Vec3::new(self.x * s, self.y * s, self.z * s)
    }
}

/// An axis-aligned box (the prelude's `AABB(low, high)`).
///
/// [`Aabb::EMPTY`] has `low = +inf`, `high = -inf`, so that the union with anything is that
/// thing; it is never stored in a tree.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub low: Vec3,
    /// Upper corner.
    pub high: Vec3,
}

impl Aabb {
    /// The identity of [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        low: Vec3::splat(f32::INFINITY),
        high: Vec3::splat(f32::NEG_INFINITY),
    };

    /// The box with the given corners.
    pub const fn new(low: Vec3, high: Vec3) -> Aabb {
        Aabb { low, high }
    }

    /// The smallest box holding `self` and `o`, by `f32` min/max (exact: no rounding).
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb::new(self.low.min(o.low), self.high.max(o.high))
    }

    /// The smallest box holding `self` and the point `p`.
    pub fn grow(self, p: Vec3) -> Aabb {
        Aabb::new(self.low.min(p), self.high.max(p))
    }

    /// True for [`Aabb::EMPTY`] and any box with `low > high` on some axis.
    pub fn is_empty(self) -> bool {
        !(self.low.x <= self.high.x && self.low.y <= self.high.y && self.low.z <= self.high.z)
    }

    /// `high - low`.
    pub fn extent(self) -> Vec3 {
        self.high - self.low
    }

    /// The center, computed in `f64` so that it does not overflow for huge boxes.
    pub fn center(self) -> Vec3 {
        let c = |lo: f32, hi: f32| ((lo as f64 + hi as f64) * 0.5) as f32;
        Vec3::new(
            c(self.low.x, self.high.x),
            c(self.low.y, self.high.y),
            c(self.low.z, self.high.z),
        )
    }

    /// Half the surface area, in `f64` (the SAH only compares areas, so the factor 2 is dropped).
    pub fn half_area(self) -> f64 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.extent();
        let (x, y, z) = (e.x as f64, e.y as f64, e.z as f64);
        x * y + y * z + z * x
    }

    /// The axis (0, 1, 2) with the largest extent; the first one on ties.
    pub fn longest_axis(self) -> usize {
        let e = self.extent();
        if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        }
    }

    /// True when `o` lies inside `self` (closed on both sides).
    pub fn contains(self, o: Aabb) -> bool {
        self.low.x <= o.low.x
            && self.low.y <= o.low.y
            && self.low.z <= o.low.z
            && o.high.x <= self.high.x
            && o.high.y <= self.high.y
            && o.high.z <= self.high.z
    }

    /// True when `self` and `o` share a point (closed intervals on every axis): the prelude's
    /// `intersects(AABB, AABB)`.
    pub fn overlaps(self, o: Aabb) -> bool {
        self.low.x <= o.high.x
            && o.low.x <= self.high.x
            && self.low.y <= o.high.y
            && o.low.y <= self.high.y
            && self.low.z <= o.high.z
            && o.low.z <= self.high.z
    }

    /// The flat form of the logical tree: `[lo.x, lo.y, lo.z, hi.x, hi.y, hi.z]`.
    pub fn to_array(self) -> [f32; 6] {
        [
            self.low.x,
            self.low.y,
            self.low.z,
            self.high.x,
            self.high.y,
            self.high.z,
        ]
    }

    /// The box from its flat form (see [`Aabb::to_array`]).
    pub fn from_array(a: [f32; 6]) -> Aabb {
        Aabb::new(Vec3::new(a[0], a[1], a[2]), Vec3::new(a[3], a[4], a[5]))
    }
}

/// A triangle with its original face index (the prelude's `Triangle(p0, p1, p2, id)`).
///
/// `id` is the index of the face in the scene file (after fan triangulation, see
/// `scene::load`), so results name the original face whatever order a builder or a layout
/// puts the primitives in.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// First corner.
    pub p0: Vec3,
    /// Second corner.
    pub p1: Vec3,
    /// Third corner.
    pub p2: Vec3,
    /// Original primitive index; `u32::MAX` is reserved for "no primitive".
    pub id: u32,
}

impl Triangle {
    /// The triangle with the given corners and id.
    pub const fn new(p0: Vec3, p1: Vec3, p2: Vec3, id: u32) -> Triangle {
        Triangle { p0, p1, p2, id }
    }

    /// The tight box of the three corners (f32 min/max, exact).
    pub fn bounds(&self) -> Aabb {
        Aabb::new(
            self.p0.min(self.p1).min(self.p2),
            self.p0.max(self.p1).max(self.p2),
        )
    }

    /// The centroid of the box, as builders use it (f64 midpoint, rounded once).
    pub fn centroid(&self) -> Vec3 {
        self.bounds().center()
    }

    /// True when all nine coordinates are finite.
    pub fn is_finite(&self) -> bool {
        self.p0.is_finite() && self.p1.is_finite() && self.p2.is_finite()
    }
}

/// A ray (the prelude's `Ray(origin, direction, tmin = 0, tmax = inf)`).
///
/// The direction need not be normalized; `t` is measured in units of the direction.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin.
    pub origin: Vec3,
    /// Direction (any length; zero and negative-zero lanes are allowed).
    pub dir: Vec3,
    /// Hits must have `t > tmin`.
    pub tmin: f32,
    /// Hits must have `t < tmax`.
    pub tmax: f32,
}

impl Ray {
    /// A ray with `tmin = 0` and `tmax = +inf`, the prelude's defaults.
    pub const fn new(origin: Vec3, dir: Vec3) -> Ray {
        Ray {
            origin,
            dir,
            tmin: 0.0,
            tmax: f32::INFINITY,
        }
    }
}

/// The closest-hit result: distance and original primitive id.
///
/// A miss is `t = +inf`, `prim = u32::MAX` ([`Hit::MISS`]). The algorithm itself starts from
/// `(ray.tmax, u32::MAX)` and so leaves `t = ray.tmax` on a miss; [`Hit::from_best`]
/// normalizes that so that results compare equal whatever the ray's `tmax`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Hit distance along the ray direction, `+inf` on a miss.
    pub t: f32,
    /// Original primitive id, `u32::MAX` on a miss.
    pub prim: u32,
}

impl Default for Hit {
    /// [`Hit::MISS`].
    fn default() -> Hit {
        Hit::MISS
    }
}

impl Hit {
    /// The miss value.
    pub const MISS: Hit = Hit {
        t: f32::INFINITY,
        prim: u32::MAX,
    };

    /// The result from the algorithm's `best` pair: a pair whose id is still `u32::MAX` is a miss.
    pub fn from_best(t: f32, prim: u32) -> Hit {
        if prim == u32::MAX {
            Hit::MISS
        } else {
            Hit { t, prim }
        }
    }

    /// True when the ray hit something.
    pub fn is_hit(&self) -> bool {
        self.prim != u32::MAX
    }

    /// Bit-exact equality (`t` compared by bits, so `-0.0 != 0.0` and NaN equals itself).
    pub fn bit_eq(&self, o: &Hit) -> bool {
        self.t.to_bits() == o.t.to_bits() && self.prim == o.prim
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ffi_sizes_match_the_file_records() {
        assert_eq!(std::mem::size_of::<Vec3>(), 12);
        assert_eq!(std::mem::size_of::<Triangle>(), 40);
        assert_eq!(std::mem::size_of::<Ray>(), 32);
        assert_eq!(std::mem::size_of::<Hit>(), 8);
    }

    #[test]
    fn union_is_min_max_and_empty_is_identity() {
        let a = Aabb::new(Vec3::new(0.0, 1.0, 2.0), Vec3::new(1.0, 2.0, 3.0));
        let b = Aabb::new(Vec3::new(-1.0, 1.5, 2.5), Vec3::new(0.5, 4.0, 2.75));
        let u = a.union(b);
        assert_eq!(u.low, Vec3::new(-1.0, 1.0, 2.0));
        assert_eq!(u.high, Vec3::new(1.0, 4.0, 3.0));
        assert_eq!(Aabb::EMPTY.union(a), a);
        assert!(Aabb::EMPTY.is_empty());
        assert!(!a.is_empty());
        assert!(u.contains(a) && u.contains(b));
        assert_eq!(Aabb::from_array(u.to_array()), u);
    }

    #[test]
    fn cross_and_dot_follow_the_right_hand_rule() {
        let x = Vec3::new(1.0, 0.0, 0.0);
        let y = Vec3::new(0.0, 1.0, 0.0);
        assert_eq!(x.cross(y), Vec3::new(0.0, 0.0, 1.0));
        assert_eq!(Vec3::new(1.0, 2.0, 3.0).dot(Vec3::new(4.0, 5.0, 6.0)), 32.0);
    }

    #[test]
    fn miss_normalization() {
        assert_eq!(Hit::from_best(7.0, u32::MAX), Hit::MISS);
        assert!(Hit::from_best(7.0, 3).is_hit());
        assert!(!Hit::MISS.is_hit());
        assert!(!Hit { t: 0.0, prim: 1 }.bit_eq(&Hit { t: -0.0, prim: 1 }));
    }
}
