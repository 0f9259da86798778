//! Ray generators: a scene box and a seed -> rays, reproducibly (SplitMix64, [`crate::rng`]).
//!
//! - [`primary_rays`]: a pinhole camera outside the box looking at its center, one jittered
//!   ray per pixel of a `width x height` image, row by row from the top-left (coherent rays,
//!   the paper's "primary" workload).
//! - [`secondary_rays`]: origins uniform in the box, directions uniform on the sphere
//!   (incoherent rays, the paper's "secondary" workload).
//! - [`axis_rays`]: hard case: origins uniform in the box, directions along one axis with the
//!   other lanes `+0.0` or `-0.0` at random.
//!
//! All have `tmin = 0` and `tmax = +inf`. Geometry is computed in `f64` and rounded once to
//! `f32`; directions are unit length up to that rounding.

use crate::geom::{Aabb, Ray, Vec3};
use crate::rng::SplitMix64;

/// A pinhole camera (in `f64`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: [f64; 3],
    /// Unit view direction.
    pub forward: [f64; 3],
    /// Unit image-plane right vector.
    pub right: [f64; 3],
    /// Unit image-plane up vector.
    pub up: [f64; 3],
    /// `tan(vertical fov / 2)`.
    pub tan_half_fov: f64,
    /// Width / height.
    pub aspect: f64,
}

/// Vertical field of view of [`Camera::framing`], in degrees.
pub const FOV_DEG: f64 = 45.0;
/// Direction from the box center to the eye used by [`primary_rays`] (normalized there):
/// in front (+z), a little to the right and above.
pub const VIEW_FROM: [f64; 3] = [0.35, 0.3, 1.0];

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: [f64; 3]) -> [f64; 3] {
    let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}
fn to_vec3(a: [f64; 3]) -> Vec3 {
    Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32)
}

impl Camera {
    /// A camera at `center + d * from` looking at the center of `bounds`, with `d` chosen so
    /// that the box's bounding sphere fits the vertical field of view. An empty box counts as
    /// the unit cube around the origin; a box of zero size gets radius 1.
    pub fn framing(bounds: Aabb, from: [f64; 3], width: u32, height: u32) -> Camera {
        let b = if bounds.is_empty() {
            Aabb::new(Vec3::splat(-0.5), Vec3::splat(0.5))
        } else {
            bounds
        };
        let lo = b.low.to_array().map(f64::from);
        let hi = b.high.to_array().map(f64::from);
        let center = [0, 1, 2].map(|i| (lo[i] + hi[i]) * 0.5);
        let e = sub(hi, lo);
        let mut radius = 0.5 * (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt();
        if radius.is_nan() || radius <= 0.0 {
            radius = 1.0;
        }
        let half = (FOV_DEG.to_radians() * 0.5).tan();
        let half_angle = (FOV_DEG.to_radians() * 0.5).sin();
        let dist = radius / half_angle * 1.05;
        let from = norm(from);
        let eye = [0, 1, 2].map(|i| center[i] + dist * from[i]);
        let forward = [-from[0], -from[1], -from[2]];
        let world_up = if forward[0].abs() < 1e-9 && forward[2].abs() < 1e-9 {
            [0.0, 0.0, 1.0]
        } else {
            [0.0, 1.0, 0.0]
        };
        let right = norm(cross(forward, world_up));
        let up = cross(right, forward);
        Camera {
            eye,
            forward,
            right,
            up,
            tan_half_fov: half,
            aspect: width.max(1) as f64 / height.max(1) as f64,
        }
    }

    /// The ray through image point `(sx, sy)` in `[0, 1]^2` (`(0, 0)` = top-left).
    pub fn ray(&self, sx: f64, sy: f64) -> Ray {
        let px = (sx * 2.0 - 1.0) * self.tan_half_fov * self.aspect;
        let py = (1.0 - sy * 2.0) * self.tan_half_fov;
        let d = norm([0, 1, 2].map(|i| self.forward[i] + px * self.right[i] + py * self.up[i]));
        Ray::new(to_vec3(self.eye), to_vec3(d))
    }
}

/// `width * height` primary rays framing `bounds` from [`VIEW_FROM`], ray `j * width + i`
/// through pixel `(i, j)` jittered uniformly within the pixel.
pub fn primary_rays(bounds: Aabb, width: u32, height: u32, seed: u64) -> Vec<Ray> {
    let cam = Camera::framing(bounds, VIEW_FROM, width, height);
    let mut rng = SplitMix64::new(seed);
    let mut rays = Vec::with_capacity(width as usize * height as usize);
    for j in 0..height {
        for i in 0..width {
            let sx = (i as f64 + rng.next_f64()) / width as f64;
            let sy = (j as f64 + rng.next_f64()) / height as f64;
            rays.push(cam.ray(sx, sy));
        }
    }
    rays
}

/// `n` primary rays as `scion trace --rays primary --n N` makes them: the smallest image of
/// about `n` pixels (`w = ceil(sqrt n)` columns, `ceil(n / w)` rows) from [`primary_rays`],
/// then its first `n` pixels in raster order. `None` when `n` is 0 or above `2^32`.
pub fn primary_rays_n(bounds: Aabb, n: u64, seed: u64) -> Option<Vec<Ray>> {
    if n == 0 || n > 1 << 32 {
        return None;
    }
    let w = (n as f64).sqrt().ceil().max(1.0) as u64;
    let h = n.div_ceil(w).max(1);
    let mut r = primary_rays(bounds, u32::try_from(w).ok()?, u32::try_from(h).ok()?, seed);
    r.truncate(n as usize);
    Some(r)
}

/// A point uniform in `bounds` (the unit cube around the origin when empty).
fn point_in(bounds: Aabb, rng: &mut SplitMix64) -> Vec3 {
    let b = if bounds.is_empty() {
        Aabb::new(Vec3::splat(-0.5), Vec3::splat(0.5))
    } else {
        bounds
    };
    let lane = |lo: f32, hi: f32, rng: &mut SplitMix64| rng.range_f64(lo as f64, hi as f64) as f32;
    // Rounding to f32 can land on `hi` itself: clamp so the point stays inside.
    Vec3::new(
        lane(b.low.x, b.high.x, rng).min(b.high.x),
        lane(b.low.y, b.high.y, rng).min(b.high.y),
        lane(b.low.z, b.high.z, rng).min(b.high.z),
    )
}

/// `count` incoherent rays: origins uniform in `bounds`, directions uniform on the sphere.
pub fn secondary_rays(bounds: Aabb, count: usize, seed: u64) -> Vec<Ray> {
    let mut rng = SplitMix64::new(seed);
    (0..count)
        .map(|_| {
            let origin = point_in(bounds, &mut rng);
            let z = 1.0 - 2.0 * rng.next_f64();
            let phi = std::f64::consts::TAU * rng.next_f64();
            let r = (1.0 - z * z).max(0.0).sqrt();
            Ray::new(origin, to_vec3([r * phi.cos(), r * phi.sin(), z]))
        })
        .collect()
}

/// `count` axis-parallel rays: origins uniform in `bounds`, direction `±e_k` for a random
/// axis `k`, the two other lanes `+0.0` or `-0.0` at random.
pub fn axis_rays(bounds: Aabb, count: usize, seed: u64) -> Vec<Ray> {
    let mut rng = SplitMix64::new(seed);
    (0..count)
        .map(|_| {
            let origin = point_in(bounds, &mut rng);
            let bits = rng.next_u64();
            let axis = (bits % 3) as usize;
            let mut d = [0f32; 3];
            for (k, lane) in d.iter_mut().enumerate() {
                let negative = bits >> (8 + k) & 1 == 1;
                let magnitude = if k == axis { 1.0 } else { 0.0 };
                *lane = if negative { -magnitude } else { magnitude };
            }
            Ray::new(origin, Vec3::from_array(d))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> Aabb {
        Aabb::new(Vec3::new(-1.0, 2.0, 3.0), Vec3::new(1.0, 3.0, 7.0))
    }

    #[test]
    fn primary_rays_n_are_the_first_pixels_of_the_smallest_image() {
        let b = unit_box();
        // 10 rays: a 4 x 3 image, its first 10 pixels.
        let r = primary_rays_n(b, 10, 5).unwrap();
        let full = primary_rays(b, 4, 3, 5);
        assert_eq!(r.len(), 10);
        assert!(r.iter().zip(&full).all(|(a, b)| a == b));
        assert!(primary_rays_n(b, 0, 5).is_none());
        assert!(primary_rays_n(b, (1 << 32) + 1, 5).is_none());
    }

    #[test]
    fn primary_rays_start_outside_and_look_at_the_box() {
        let b = unit_box();
        let rays = primary_rays(b, 16, 12, 3);
        assert_eq!(rays.len(), 192);
        assert_eq!(rays, primary_rays(b, 16, 12, 3));
        assert_ne!(rays, primary_rays(b, 16, 12, 4));
        let c = b.center();
        for r in &rays {
            assert!(!b.contains(Aabb::new(r.origin, r.origin)));
            assert!(((r.dir.dot(r.dir)) - 1.0).abs() < 1e-5);
            assert_eq!((r.tmin, r.tmax), (0.0, f32::INFINITY));
            // Every ray points roughly towards the center.
            assert!(r.dir.dot(c - r.origin) > 0.0);
        }
    }

    #[test]
    fn secondary_rays_start_inside_with_unit_directions() {
        let b = unit_box();
        let rays = secondary_rays(b, 500, 9);
        let mut mean = Vec3::default();
        for r in &rays {
            assert!(b.contains(Aabb::new(r.origin, r.origin)));
            assert!(((r.dir.dot(r.dir)) - 1.0).abs() < 1e-5);
            mean = mean + r.dir;
        }
        // Uniform on the sphere: the mean direction is near zero.
        assert!(mean.dot(mean).sqrt() / 500.0 < 0.15);
    }

    #[test]
    fn axis_rays_have_signed_zero_lanes() {
        let rays = axis_rays(unit_box(), 200, 1);
        let neg_zero = rays
            .iter()
            .flat_map(|r| r.dir.to_array())
            .filter(|x| *x == 0.0 && x.is_sign_negative())
            .count();
        assert!(neg_zero > 0);
        for r in &rays {
            assert_eq!(r.dir.to_array().iter().filter(|x| **x != 0.0).count(), 1);
        }
    }
}
