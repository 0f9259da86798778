//! Collision detection between two triangle sets (paper §9.3.3): every pair `(a.id, b.id)`
//! whose triangles' boxes overlap (closed intervals) and that the prelude's separating-axis
//! test (`intersects(Triangle, Triangle)` in `library/prelude.scion`) does not separate.
//!
//! [`triangles_intersect`] is that test in the prelude's `f64` arithmetic (same operations), so
//! it answers as generated code does. The set does
//! not depend on any tree: a tree's boxes contain its triangles' boxes, so a traversal that
//! prunes on box overlap and tests every pair of triangles in overlapping leaves, box first,
//! finds exactly these pairs. [`collide_sweep`] finds them without a tree (sort and sweep on
//! `x`); [`collide_brute`] tests all pairs (small inputs); [`rotated`] makes the paper's
//! rotated copy of a scene.

use super::v64::{cross, dot, sub, widen, V64};
use crate::geom::{Aabb, Triangle, Vec3};

/// The prelude's `intersects(Triangle, Triangle)`: no candidate axis separates them (face
/// normals, the nine edge-edge cross products, the six in-plane edge normals), in `f64`: every
/// corner widened exactly, every difference, product and sum rounded to `f64` (finite `f32`
/// inputs cannot overflow it, so nothing is NaN and the order of the `min`/`max` folds does not
/// matter). Generated code computes exactly this.
pub fn triangles_intersect(a: &Triangle, b: &Triangle) -> bool {
    let pa = [widen(a.p0), widen(a.p1), widen(a.p2)];
    let pb = [widen(b.p0), widen(b.p1), widen(b.p2)];
    let separated = |axis: V64| {
        let (amin, amax) = pa
            .iter()
            .map(|&p| dot(axis, p))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), d| {
                (l.min(d), h.max(d))
            });
        let (bmin, bmax) = pb
            .iter()
            .map(|&p| dot(axis, p))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), d| {
                (l.min(d), h.max(d))
            });
        amax < bmin || bmax < amin
    };
    let ea = [sub(pa[1], pa[0]), sub(pa[2], pa[1]), sub(pa[0], pa[2])];
    let eb = [sub(pb[1], pb[0]), sub(pb[2], pb[1]), sub(pb[0], pb[2])];
    let na = cross(ea[0], ea[1]);
    let nb = cross(eb[0], eb[1]);
    let mut axes = vec![na, nb];
    for ei in ea {
        for ej in eb {
            axes.push(cross(ei, ej));
        }
    }
    axes.extend(ea.iter().map(|&e| cross(na, e)));
    axes.extend(eb.iter().map(|&e| cross(nb, e)));
    !axes.into_iter().any(separated)
}

/// Whether the pair collides as the collision traversal decides it: boxes first, then the
/// separating-axis test.
pub fn pair_collides(a: &Triangle, b: &Triangle) -> bool {
    a.bounds().overlaps(b.bounds()) && triangles_intersect(a, b)
}

/// Every colliding pair `(a.id, b.id)`, by testing all pairs: sorted, without repeats.
pub fn collide_brute(a: &[Triangle], b: &[Triangle]) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    for ta in a {
        for tb in b {
            if pair_collides(ta, tb) {
                out.push((ta.id, tb.id));
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// Every colliding pair `(a.id, b.id)`, sorted, without repeats: the same set as
/// [`collide_brute`], by sorting both sets' boxes on their low `x` and sweeping, so only pairs
/// whose `x` intervals overlap are tested.
pub fn collide_sweep(a: &[Triangle], b: &[Triangle]) -> Vec<(u32, u32)> {
    // Events: (low x, side, index); on equal low x either order finds the pair, since the
    // one inserted second sees the first still active (closed intervals).
    let boxes_a: Vec<Aabb> = a.iter().map(Triangle::bounds).collect();
    let boxes_b: Vec<Aabb> = b.iter().map(Triangle::bounds).collect();
    let mut events: Vec<(f32, bool, usize)> = (0..a.len())
        .map(|i| (boxes_a[i].low.x, false, i))
        .chain((0..b.len()).map(|j| (boxes_b[j].low.x, true, j)))
        .collect();
    events.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
    let (mut active_a, mut active_b): (Vec<usize>, Vec<usize>) = (Vec::new(), Vec::new());
    let mut out = Vec::new();
    for (x, in_b, i) in events {
        active_a.retain(|&k| boxes_a[k].high.x >= x);
        active_b.retain(|&k| boxes_b[k].high.x >= x);
        if in_b {
            for &k in &active_a {
                if boxes_a[k].overlaps(boxes_b[i]) && triangles_intersect(&a[k], &b[i]) {
                    out.push((a[k].id, b[i].id));
                }
            }
            active_b.push(i);
        } else {
            for &k in &active_b {
                if boxes_a[i].overlaps(boxes_b[k]) && triangles_intersect(&a[i], &b[k]) {
                    out.push((a[i].id, b[k].id));
                }
            }
            active_a.push(i);
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// The copy of `triangles` rotated by `degrees = (α, β, γ)` about the centre `c` of their box:
/// `c + Rz(γ) Ry(β) Rx(α) (p − c)`, computed in `f64` and rounded to `f32`; ids are kept.
pub fn rotated(triangles: &[Triangle], degrees: [f64; 3]) -> Vec<Triangle> {
    let bounds = triangles
        .iter()
        .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
    let c = [
        (f64::from(bounds.low.x) + f64::from(bounds.high.x)) / 2.0,
        (f64::from(bounds.low.y) + f64::from(bounds.high.y)) / 2.0,
        (f64::from(bounds.low.z) + f64::from(bounds.high.z)) / 2.0,
    ];
    // `Rz(γ) Ry(β) Rx(α)`, as scene transforms build it.
    let [a, b, g] = degrees;
    let r = crate::scene::transform::Transform::rotation(a, b, g).rotation_matrix();
    let turn = |p: Vec3| {
        let d = [
            f64::from(p.x) - c[0],
            f64::from(p.y) - c[1],
            f64::from(p.z) - c[2],
        ];
        let q: [f64; 3] =
            std::array::from_fn(|i| c[i] + r[i][0] * d[0] + r[i][1] * d[1] + r[i][2] * d[2]);
        Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32)
    };
    triangles
        .iter()
        .map(|t| Triangle::new(turn(t.p0), turn(t.p1), turn(t.p2), t.id))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(p: [[f32; 3]; 3], id: u32) -> Triangle {
        let v = |a: [f32; 3]| Vec3::new(a[0], a[1], a[2]);
        Triangle::new(v(p[0]), v(p[1]), v(p[2]), id)
    }

    #[test]
    fn crossing_touching_and_apart() {
        let a = tri([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]], 0);
        // Pierces a's plane inside a.
        let pierce = tri([[0.5, 0.5, -1.0], [0.5, 0.5, 1.0], [1.0, 0.2, 1.0]], 1);
        // Touches a at one corner.
        let touch = tri([[2.0, 0.0, 0.0], [3.0, 0.0, 1.0], [3.0, 1.0, 1.0]], 2);
        // Above a, parallel.
        let above = tri([[0.0, 0.0, 1.0], [2.0, 0.0, 1.0], [0.0, 2.0, 1.0]], 3);
        // Coplanar, beside a's hypotenuse but not touching (only the in-plane axes see it).
        let beside = tri([[2.0, 2.0, 0.0], [1.1, 2.0, 0.0], [2.0, 1.1, 0.0]], 4);
        assert!(triangles_intersect(&a, &pierce));
        assert!(triangles_intersect(&a, &touch));
        assert!(!triangles_intersect(&a, &above));
        assert!(!triangles_intersect(&a, &beside));
        assert!(a.bounds().overlaps(beside.bounds()));
    }

    #[test]
    fn a_hair_apart_is_apart() {
        let a = tri([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]], 0);
        let pierce = tri([[0.5, 0.5, -1.0], [0.5, 0.5, 1.0], [1.0, 0.2, 1.0]], 1);
        let above = tri([[0.0, 0.0, 1.0], [2.0, 0.0, 1.0], [0.0, 2.0, 1.0]], 3);
        assert!(triangles_intersect(&a, &pierce));
        assert!(!triangles_intersect(&a, &above));
        // A triangle a hair above the plane of `a`: f32's products cannot tell, f64's can.
        let hair = tri([[0.5, 0.5, 1e-7], [1.0, 0.5, 1e-7], [0.5, 1.0, 2e-7]], 4);
        assert!(!triangles_intersect(&a, &hair));
    }

    #[test]
    fn sweep_finds_what_brute_force_finds() {
        // A grid of small triangles against its copy turned about the centre.
        let mut a = Vec::new();
        for i in 0..12 {
            for j in 0..12 {
                let (x, y) = (i as f32 * 0.5, j as f32 * 0.5);
                let z = ((i * 7 + j * 3) % 5) as f32 * 0.1;
                a.push(tri(
                    [[x, y, z], [x + 0.6, y, z + 0.2], [x, y + 0.6, z - 0.1]],
                    a.len() as u32,
                ));
            }
        }
        let b = rotated(&a, [60.0, 70.0, 10.0]);
        let want = collide_brute(&a, &b);
        assert!(!want.is_empty());
        assert_eq!(collide_sweep(&a, &b), want);
        // Itself: every triangle touches itself.
        let own = collide_sweep(&a, &a);
        assert!(a.iter().all(|t| own.binary_search(&(t.id, t.id)).is_ok()));
        assert_eq!(own, collide_brute(&a, &a));
    }

    #[test]
    fn rotation_about_the_centre_keeps_the_box_centre_and_ids() {
        let a = vec![tri([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 2.0]], 9)];
        let turned = rotated(&a, [0.0, 0.0, 90.0]);
        assert_eq!(turned[0].id, 9);
        // About the centre (1, 1, 1): (0, 0, 0) -> (2, 0, 0) for a quarter turn about z.
        let p = turned[0].p0;
        assert!(
            (p.x - 2.0).abs() < 1e-6 && p.y.abs() < 1e-6 && p.z.abs() < 1e-6,
            "{p:?}"
        );
    }
}
