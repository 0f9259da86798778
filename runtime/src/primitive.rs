//! Primitives: what a BVH's leaves hold. Triangles ([`Triangle`], the prelude's `Triangle`),
//! blocks of four triangles stored lane by lane ([`Triangle4`], the prelude's `Triangle4`:
//! Embree's `Triangle4`, tested four at a time) and strand segments ([`Segment`], the prelude's
//! `Segment`: a piece of a hair or fur curve with a radius at each end, paper §8.2).
//!
//! The builders, the logical tree and the references are generic over [`Primitive`]: a
//! primitive says its box, its id, the points and padding it lies within (for DOP-14 and
//! oriented bounds), and its ray test (the prelude's `hit_distance`, with exactly the prelude's
//! arithmetic). Generated code receives the primitives as an array of the prelude type's bytes
//! (`#[repr(C)]`, [`Primitive::TYPE_NAME`] names the type a layout's primitive array must hold).

use crate::geom::{Aabb, Ray, Triangle, Vec3};
use crate::reference::prelude;

/// The geometry a primitive lies within: the convex hull of `points[..n]` grown by a ball of
/// radius `pad` (`pad == 0` for a triangle: its corners; a segment's two ends and radius; a
/// block of four triangles: their twelve corners).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hull {
    /// The points (the first `n` are used).
    pub points: [Vec3; Hull::MAX_POINTS],
    /// How many of `points` there are.
    pub n: usize,
    /// The radius the hull is grown by (`>= 0`).
    pub pad: f32,
}

impl Hull {
    /// The most points a hull has (a block of four triangles' corners).
    pub const MAX_POINTS: usize = 12;

    /// The hull of `points` (1 to [`Hull::MAX_POINTS`]) grown by `pad`.
    pub fn new(points: &[Vec3], pad: f32) -> Hull {
        assert!(
            (1..=Hull::MAX_POINTS).contains(&points.len()),
            "a hull of {} points",
            points.len()
        );
        let mut all = [points[0]; Hull::MAX_POINTS];
        all[..points.len()].copy_from_slice(points);
        Hull {
            points: all,
            n: points.len(),
            pad,
        }
    }

    /// The points in use.
    pub fn points(&self) -> &[Vec3] {
        &self.points[..self.n]
    }
}

/// A primitive of a logical tree's leaves.
pub trait Primitive: Copy + Send + Sync + std::fmt::Debug + PartialEq + 'static {
    /// The prelude's record type of the primitive (`Triangle`, `Segment`): the element type of
    /// a layout's primitive array, whose bytes this type's `#[repr(C)]` form is.
    const TYPE_NAME: &'static str;

    /// A box containing the primitive (a triangle's is the exact `f32` min/max of its corners;
    /// a padded primitive's is rounded outward).
    fn bounds(&self) -> Aabb;

    /// The original index (the id results name).
    fn id(&self) -> u32;

    /// True when every coordinate (and radius) is finite.
    fn is_finite(&self) -> bool;

    /// What the primitive lies within (see [`Hull`]).
    fn hull(&self) -> Hull;

    /// The prelude's `hit_distance(ray, primitive)`: the hit distance in `(tmin, tmax)`, or
    /// `+inf`, bit for bit as generated code computes it.
    fn hit_distance(&self, ray: &Ray) -> f32;

    /// The hit distance and the id of what was hit: `(hit_distance, id)` for a primitive of
    /// one id; a block of several ([`Triangle4`]) answers for the nearest of them by the tie
    /// rule. The references compare hits with this.
    fn hit(&self, ray: &Ray) -> (f32, u32) {
        (self.hit_distance(ray), self.id())
    }
}

impl Primitive for Triangle {
    const TYPE_NAME: &'static str = "Triangle";

    fn bounds(&self) -> Aabb {
        Triangle::bounds(self)
    }

    fn id(&self) -> u32 {
        self.id
    }

    fn is_finite(&self) -> bool {
        Triangle::is_finite(self)
    }

    fn hull(&self) -> Hull {
        Hull::new(&[self.p0, self.p1, self.p2], 0.0)
    }

    fn hit_distance(&self, ray: &Ray) -> f32 {
        prelude::hit_distance(ray, self)
    }
}

/// A straight piece of a strand (the prelude's `Segment(p0, r0, p1, r1, id)`, 36 bytes): the
/// axis from `p0` to `p1`, with radius `r0` at `p0` and `r1` at `p1`, linear between. A ray
/// meets it as a flat ribbon that faces the ray (Embree's flat linear curves): see
/// [`prelude::hit_distance_segment`].
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// First end of the axis.
    pub p0: Vec3,
    /// Radius at `p0` (`>= 0`).
    pub r0: f32,
    /// Second end of the axis.
    pub p1: Vec3,
    /// Radius at `p1` (`>= 0`).
    pub r1: f32,
    /// Original segment index; `u32::MAX` is reserved for "no primitive".
    pub id: u32,
}

impl Segment {
    /// The segment with the given ends, radii and id.
    pub const fn new(p0: Vec3, r0: f32, p1: Vec3, r1: f32, id: u32) -> Segment {
        Segment { p0, r0, p1, r1, id }
    }
}

impl Primitive for Segment {
    const TYPE_NAME: &'static str = "Segment";

    /// The box of the two ends grown by the larger radius and by 2^-20 of the coordinates'
    /// magnitude (so that the hit distances the ribbon test computes, which are rounded, stay
    /// inside the boxes of the nodes above it), rounded outward.
    fn bounds(&self) -> Aabb {
        let pad = f64::from(self.r0.max(self.r1));
        let lo = self.p0.min(self.p1).to_array();
        let hi = self.p0.max(self.p1).to_array();
        let grow = |v: f32| pad + f64::from(v.abs()) * MARGIN;
        Aabb::new(
            Vec3::from_array(lo.map(|v| round_down(f64::from(v) - grow(v)))),
            Vec3::from_array(hi.map(|v| round_up(f64::from(v) + grow(v)))),
        )
    }

    fn id(&self) -> u32 {
        self.id
    }

    fn is_finite(&self) -> bool {
        self.p0.is_finite() && self.p1.is_finite() && self.r0.is_finite() && self.r1.is_finite()
    }

    fn hull(&self) -> Hull {
        Hull::new(&[self.p0, self.p1], self.r0.max(self.r1))
    }

    fn hit_distance(&self, ray: &Ray) -> f32 {
        prelude::hit_distance_segment(ray, self)
    }
}

pub use crate::triangle4::Triangle4;

/// The primitive types the runtime builds trees over: each one's prelude type name and the
/// byte size of its record (`#[repr(C)]`, 4-aligned). A layout's primitive array holds one
/// of them.
pub const PRIMITIVE_TYPES: [(&str, u64); 3] = [
    (Triangle::TYPE_NAME, std::mem::size_of::<Triangle>() as u64),
    (Segment::TYPE_NAME, std::mem::size_of::<Segment>() as u64),
    (
        Triangle4::TYPE_NAME,
        std::mem::size_of::<Triangle4>() as u64,
    ),
];

/// The relative margin of a segment's box (2^-20).
const MARGIN: f64 = 1.0 / 1_048_576.0;

/// The largest `f32` at most `x`.
pub(crate) fn round_down(x: f64) -> f32 {
    crate::bvh::dop14::round_down(x)
}

/// The smallest `f32` at least `x`.
pub(crate) fn round_up(x: f64) -> f32 {
    crate::bvh::dop14::round_up(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_segment_is_36_bytes_as_the_prelude_lays_it_out() {
        assert_eq!(std::mem::size_of::<Segment>(), 36);
        assert_eq!(std::mem::align_of::<Segment>(), 4);
    }

    #[test]
    fn a_segments_box_holds_both_ends_and_the_radius() {
        let s = Segment::new(
            Vec3::new(1.0, -2.0, 3.0),
            0.5,
            Vec3::new(4.0, 5.0, -6.0),
            0.25,
            7,
        );
        let b = Primitive::bounds(&s);
        assert!(b.low.x <= 0.5 && b.low.y <= -2.5 && b.low.z <= -6.5);
        assert!(b.high.x >= 4.5 && b.high.y >= 5.5 && b.high.z >= 3.5);
        assert!(b.low.x > 0.49 && b.high.z < 3.51);
    }
}
