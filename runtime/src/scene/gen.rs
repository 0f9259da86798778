//! Procedural hard-case scenes for tests (architecture §6): parameters -> [`Scene`].
//!
//! Each generator is deterministic and numbers its triangles `0..n` in output order. The cases:
//! one triangle, empty, a grid of axis-aligned quads (flat boxes, shared edges, exact ties),
//! three axis-aligned planes, degenerate triangles (zero area: collinear corners, repeated
//! corners, a point), slivers, duplicates, a deep chain (triangles shrinking geometrically so a
//! binned SAH tree gets very deep), a random soup, and any scene scaled (e.g. by `1e-15` or
//! `1e15`) or moved far from the origin.

use super::transform::{instances, Transform};
use super::Scene;
use crate::geom::{Triangle, Vec3};
use crate::rng::SplitMix64;

fn numbered(name: &str, corners: Vec<[Vec3; 3]>) -> Scene {
    let triangles = corners
        .into_iter()
        .enumerate()
        .map(|(i, [a, b, c])| Triangle::new(a, b, c, i as u32))
        .collect();
    Scene::new(name, triangles)
}

/// One triangle in the plane `z = 0`.
pub fn one_triangle() -> Scene {
    numbered(
        "one_triangle",
        vec![[
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ]],
    )
}

/// No triangles.
pub fn empty() -> Scene {
    Scene::new("empty", Vec::new())
}

/// `nx * ny` unit quads in the plane `z = 0`, two triangles each sharing the diagonal.
pub fn quad_grid(nx: u32, ny: u32) -> Scene {
    let mut tris = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = (i as f32, j as f32);
            let a = Vec3::new(x, y, 0.0);
            let b = Vec3::new(x + 1.0, y, 0.0);
            let c = Vec3::new(x + 1.0, y + 1.0, 0.0);
            let d = Vec3::new(x, y + 1.0, 0.0);
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
    }
    numbered(&format!("quad_grid_{nx}x{ny}"), tris)
}

/// Three `n x n` quad grids in the planes `x = 0`, `y = 0` and `z = 0`, meeting at the origin.
pub fn axis_planes(n: u32) -> Scene {
    let grid = quad_grid(n, n);
    let mut tris = Vec::new();
    for t in &grid.triangles {
        tris.push([t.p0, t.p1, t.p2]);
    }
    let swap_yz = |p: Vec3| Vec3::new(p.x, p.z, p.y);
    let swap_xz = |p: Vec3| Vec3::new(p.z, p.y, p.x);
    for t in &grid.triangles {
        tris.push([swap_yz(t.p0), swap_yz(t.p1), swap_yz(t.p2)]);
    }
    for t in &grid.triangles {
        tris.push([swap_xz(t.p0), swap_xz(t.p1), swap_xz(t.p2)]);
    }
    numbered(&format!("axis_planes_{n}"), tris)
}

/// Zero-area triangles (collinear distinct corners, a repeated corner, all corners equal)
/// mixed with ordinary ones on a 4 x 4 pattern, so that rays both hit and graze them.
pub fn degenerate() -> Scene {
    let mut tris = Vec::new();
    for j in 0..4 {
        for i in 0..4 {
            let o = Vec3::new(i as f32 * 2.0, j as f32 * 2.0, (i + j) as f32 * 0.25);
            let p = |x: f32, y: f32, z: f32| o + Vec3::new(x, y, z);
            match (i + 4 * j) % 4 {
                0 => tris.push([p(0.0, 0.0, 0.0), p(1.0, 1.0, 0.0), p(2.0, 2.0, 0.0)]),
                1 => tris.push([p(0.0, 0.0, 0.0), p(1.5, 0.0, 0.0), p(1.5, 0.0, 0.0)]),
                2 => tris.push([p(0.5, 0.5, 0.0), p(0.5, 0.5, 0.0), p(0.5, 0.5, 0.0)]),
                _ => tris.push([p(0.0, 0.0, 0.0), p(0.0, 1.5, 0.0), p(0.0, 3.0, 0.0)]),
            }
            tris.push([p(0.0, 0.0, -0.5), p(1.5, 0.0, -0.5), p(0.0, 1.5, -0.5)]);
        }
    }
    numbered("degenerate", tris)
}

/// `n` long thin triangles (length 10, width `1e-5`) fanned around the origin, plus one
/// ordinary triangle behind them.
pub fn slivers(n: u32) -> Scene {
    let mut tris = Vec::new();
    for k in 0..n {
        let a = k as f64 / n as f64 * std::f64::consts::PI;
        let (s, c) = a.sin_cos();
        let dir = Vec3::new((10.0 * c) as f32, (10.0 * s) as f32, 0.0);
        let side = Vec3::new((-1e-5 * s) as f32, (1e-5 * c) as f32, k as f32 * 1e-3);
        let o = Vec3::new(0.0, 0.0, k as f32 * 1e-3);
        tris.push([o, o + dir, o + dir + side]);
    }
    tris.push([
        Vec3::new(-12.0, -12.0, -1.0),
        Vec3::new(12.0, -12.0, -1.0),
        Vec3::new(0.0, 12.0, -1.0),
    ]);
    numbered(&format!("slivers_{n}"), tris)
}

/// `copies` copies of `scene` at the same place; copy `k` of triangle `i` has id
/// `k * scene.len() + i`, so equal hit distances are decided by the id rule.
pub fn duplicated(scene: &Scene, copies: usize) -> Scene {
    let mut s = instances(scene, &vec![Transform::IDENTITY; copies])
        .expect("duplicated: too many triangles for u32 ids");
    s.name = format!("{}_dup{copies}", scene.name);
    s
}

/// A chain of up to `n` triangles along the x axis whose sizes and distances to the origin
/// shrink by `ratio` (in `(0, 1)`) each step: triangle `k` sits at `x = s_k = 2^100 * ratio^k`
/// with size `s_k / 2`, and the chain stops before `s_k < 1e-35` (so sizes stay normal `f32`
/// numbers: 217 triangles for ratio 0.5). The centroids crowd towards the origin, so
/// each binned-SAH split peels off only the few largest triangles and the tree gets very deep
/// (depth about 70 with 32 bins and ratio 0.5, deeper than a 64-entry traversal stack). The chain spans
/// 65 decades, far beyond the range where the prelude's `f32` ray-triangle test is accurate
/// (see docs/runtime.md): it is a builder and stack-depth case, not a hit-accuracy case.
pub fn deep_chain(n: u32, ratio: f64) -> Scene {
    assert!(
        ratio > 0.0 && ratio < 1.0,
        "deep_chain: ratio must be in (0, 1)"
    );
    let mut tris = Vec::new();
    let mut s = 2f64.powi(100);
    for _ in 0..n {
        if s < 1e-35 {
            break;
        }
        let x = s as f32;
        let h = (s * 0.5) as f32;
        tris.push([
            Vec3::new(x, -h, 0.0),
            Vec3::new(x + h, h, 0.0),
            Vec3::new(x, h, h),
        ]);
        s *= ratio;
    }
    numbered(&format!("deep_chain_{n}"), tris)
}

/// `n` random triangles with corners within `size` of a random center in the unit cube.
pub fn random_soup(n: u32, size: f32, seed: u64) -> Scene {
    let mut rng = SplitMix64::new(seed);
    let mut tris = Vec::new();
    for _ in 0..n {
        let c = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        let mut corner = || {
            c + Vec3::new(
                (rng.next_f32() - 0.5) * size,
                (rng.next_f32() - 0.5) * size,
                (rng.next_f32() - 0.5) * size,
            )
        };
        tris.push([corner(), corner(), corner()]);
    }
    numbered(&format!("random_soup_{n}"), tris)
}

/// `scene` scaled uniformly by `factor` about the origin (ids kept).
pub fn scaled(scene: &Scene, factor: f64) -> Scene {
    let mut s = Transform::scaling(factor).apply_scene(scene);
    s.name = format!("{}_scaled_{factor:e}", scene.name);
    s
}

/// `scene` moved by `offset` (ids kept).
pub fn translated(scene: &Scene, offset: [f64; 3]) -> Scene {
    let mut s = Transform::translation(offset[0], offset[1], offset[2]).apply_scene(scene);
    s.name = format!("{}_moved", scene.name);
    s
}

/// Every generated hard case at a size fit for unit tests, with a name.
pub fn hard_cases() -> Vec<Scene> {
    let soup = random_soup(500, 0.1, 1);
    vec![
        one_triangle(),
        empty(),
        quad_grid(16, 16),
        axis_planes(6),
        degenerate(),
        slivers(64),
        duplicated(&quad_grid(4, 4), 3),
        duplicated(&soup, 2),
        deep_chain(1000, 0.5),
        soup.clone(),
        scaled(&soup, 1e-15),
        scaled(&soup, 1e15),
        scaled(&soup, 1e-6),
        scaled(&soup, 1e6),
        translated(&soup, [1e6, -1e6, 1e6]),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_positions_and_coordinates_finite() {
        for s in hard_cases() {
            for (i, t) in s.triangles.iter().enumerate() {
                assert!(t.is_finite(), "{}: triangle {i} not finite", s.name);
                if !s.name.contains("dup") {
                    assert_eq!(t.id as usize, i, "{}", s.name);
                }
            }
        }
    }

    #[test]
    fn shapes() {
        assert_eq!(quad_grid(3, 2).len(), 12);
        assert_eq!(axis_planes(2).len(), 24);
        assert_eq!(deep_chain(1000, 0.5).len(), 217);
        let d = duplicated(&one_triangle(), 4);
        assert_eq!(d.len(), 4);
        assert_eq!(d.triangles[3].id, 3);
        assert_eq!(d.triangles[3].p1, d.triangles[0].p1);
    }
}
