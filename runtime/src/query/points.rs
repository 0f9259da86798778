//! Points of closest-point queries: `n` points uniform in a box, the generator of `scion run
//! --algorithm closest-point` and of the C library's `scion_uniform_points`.

use crate::geom::Vec3;

/// `n` points uniform in the box `[low, high]` (xorshift64 seeded by `seed`, 53-bit fractions).
pub fn uniform_points(low: Vec3, high: Vec3, n: usize, seed: u64) -> Vec<Vec3> {
    let mut x = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    let mut unit = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    let lerp = |a: f32, b: f32, t: f64| (f64::from(a) + (f64::from(b) - f64::from(a)) * t) as f32;
    (0..n)
        .map(|_| {
            Vec3::new(
                lerp(low.x, high.x, unit()),
                lerp(low.y, high.y, unit()),
                lerp(low.z, high.z, unit()),
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_lie_in_the_box_and_follow_the_seed() {
        let (lo, hi) = (Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 0.5, 3.0));
        let a = uniform_points(lo, hi, 100, 7);
        assert_eq!(a.len(), 100);
        assert!(a.iter().all(|p| p.x >= lo.x
            && p.x <= hi.x
            && p.y >= lo.y
            && p.y <= hi.y
            && p.z >= lo.z
            && p.z <= hi.z));
        assert_eq!(a, uniform_points(lo, hi, 100, 7));
        assert_ne!(a, uniform_points(lo, hi, 100, 8));
    }
}
