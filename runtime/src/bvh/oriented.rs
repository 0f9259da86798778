//! Oriented child boxes for wide nodes: the hair BVH's OBB nodes (paper §8.2, layout catalog
//! §6; Woop et al. 2014). The four children of such a node share one orientation, stored as
//! the catalog stores it: an integer matrix `M` whose rows are the frame's axes times 127,
//! rounded (entries in -127..=127, so `i8` columns hold it exactly). A child's box is the box
//! of its triangles' corners mapped by `M` (so it is in units 127 times the scene's), computed
//! in `f64` and rounded outward to `f32`: `{x | M·x ∈ box}` contains every triangle of the
//! child, whatever rounding the mapping had.
//!
//! The orientation is the principal axes of the node's triangle corners (a Jacobi eigen
//! decomposition of their covariance), and a node keeps it only where it pays: when the
//! children's oriented boxes have less surface than their axis-aligned ones by the factor
//! [`OrientedOptions::max_area_ratio`] (areas in `M`-space divided by 127²).

use super::dop14::{round_down, round_up};
use super::logical::LogicalTree;
use crate::geom::{Aabb, Triangle, Vec3};
use crate::primitive::Primitive;

/// The scale of the quantized orientation (the catalog's `round(127·R)`).
pub const ORIENTATION_SCALE: f64 = 127.0;

/// A quantized orientation: `rows[i]` is axis `i` times 127, rounded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Orientation {
    /// The integer matrix `M`, by rows.
    pub rows: [[i32; 3]; 3],
}

impl Orientation {
    /// The identity frame (axis-aligned, scaled by 127).
    pub const IDENTITY: Orientation = Orientation {
        rows: [[127, 0, 0], [0, 127, 0], [0, 0, 127]],
    };

    /// Column `j` of `M` as floats (`vx`, `vy`, `vz` of the logical `OBB`): what multiplies a
    /// point's coordinate `j`.
    pub fn column(&self, j: usize) -> Vec3 {
        Vec3::new(
            self.rows[0][j] as f32,
            self.rows[1][j] as f32,
            self.rows[2][j] as f32,
        )
    }

    /// `M·p` in `f64`, each coordinate with a bound on its rounding error (three products
    /// of a 7-bit integer and an `f32` are exact; the two additions round).
    fn apply(&self, p: Vec3) -> [(f64, f64); 3] {
        let q = [f64::from(p.x), f64::from(p.y), f64::from(p.z)];
        self.rows.map(|r| {
            let terms = [0, 1, 2].map(|j| f64::from(r[j]) * q[j]);
            let s = terms[0] + terms[1] + terms[2];
            let mag = terms[0].abs() + terms[1].abs() + terms[2].abs();
            (s, mag * f64::EPSILON)
        })
    }

    /// The box of `tris`' corners in `M`-space, rounded outward ([`Aabb::EMPTY`] for none).
    pub fn bounds(&self, tris: &[Triangle]) -> Aabb {
        self.bounds_of(tris)
    }

    /// The box of primitives in `M`-space, rounded outward ([`Aabb::EMPTY`] for none): their
    /// hulls' points mapped, each row grown by the hull's padding times the row's length
    /// (for triangles, exactly [`Orientation::bounds`]).
    pub fn bounds_of<P: Primitive>(&self, prims: &[P]) -> Aabb {
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        let norms = self.rows.map(|r| {
            let sq: i32 = r.iter().map(|v| v * v).sum();
            // Rounded up: the square root of an integer, with room for its rounding.
            f64::from(sq).sqrt() * (1.0 + 4.0 * f64::EPSILON)
        });
        for t in prims {
            let h = t.hull();
            let pad = f64::from(h.pad);
            for &p in h.points() {
                for (k, (s, e)) in self.apply(p).into_iter().enumerate() {
                    let g = e + pad * norms[k];
                    lo[k] = lo[k].min(round_down(s - g));
                    hi[k] = hi[k].max(round_up(s + g));
                }
            }
        }
        if lo[0] > hi[0] {
            return Aabb::EMPTY;
        }
        Aabb::new(Vec3::from_array(lo), Vec3::from_array(hi))
    }

    /// The principal axes of `points` quantized, or `None` when there are fewer than two
    /// distinct points (no direction to prefer).
    pub fn principal(points: &[Vec3]) -> Option<Orientation> {
        if points.len() < 2 {
            return None;
        }
        let n = points.len() as f64;
        let mut mean = [0.0f64; 3];
        for p in points {
            for (k, x) in p.to_array().iter().enumerate() {
                mean[k] += f64::from(*x) / n;
            }
        }
        let mut c = [[0.0f64; 3]; 3];
        for p in points {
            let d = p.to_array().map(f64::from);
            for i in 0..3 {
                for j in 0..3 {
                    c[i][j] += (d[i] - mean[i]) * (d[j] - mean[j]);
                }
            }
        }
        let scale = c[0][0] + c[1][1] + c[2][2];
        if !(scale.is_finite() && scale > 0.0) {
            return None;
        }
        let axes = jacobi_axes(c.map(|r| r.map(|x| x / scale)));
        let mut rows = [[0i32; 3]; 3];
        for (i, a) in axes.iter().enumerate() {
            rows[i] = a.map(|x| (x * ORIENTATION_SCALE).round().clamp(-127.0, 127.0) as i32);
        }
        (det(&rows) != 0).then_some(Orientation { rows })
    }
}

fn det(m: &[[i32; 3]; 3]) -> i64 {
    let m = m.map(|r| r.map(i64::from));
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Unit eigenvectors of the symmetric `a`, largest eigenvalue first (cyclic Jacobi).
fn jacobi_axes(mut a: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _sweep in 0..32 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        if off < 1e-15 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q].abs() < 1e-300 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // a <- Jᵀ a J, v <- v J, J the rotation in the (p, q) plane.
            for row in &mut a {
                let (akp, akq) = (row[p], row[q]);
                row[p] = c * akp - s * akq;
                row[q] = s * akp + c * akq;
            }
            let (rp, rq) = (a[p], a[q]);
            a[p] = std::array::from_fn(|k| c * rp[k] - s * rq[k]);
            a[q] = std::array::from_fn(|k| s * rp[k] + c * rq[k]);
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| a[j][j].total_cmp(&a[i][i]));
    order.map(|k| [v[0][k], v[1][k], v[2][k]])
}

/// When a wide node takes an orientation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrientedOptions {
    /// A node is oriented when its children's oriented boxes have at most this fraction of
    /// the surface of their axis-aligned boxes: 0 never orients, `f64::INFINITY` orients
    /// every node that has an orientation.
    pub max_area_ratio: f64,
}

impl Default for OrientedOptions {
    /// Orient where it removes at least 15 % of the children's surface.
    fn default() -> Self {
        OrientedOptions {
            max_area_ratio: 0.85,
        }
    }
}

/// An oriented wide node: its orientation and each slot's box in `M`-space.
#[derive(Clone, Debug, PartialEq)]
pub struct OrientedNode {
    /// The shared orientation.
    pub orientation: Orientation,
    /// Per slot, the box of its triangles mapped by `M`.
    pub boxes: Vec<Aabb>,
}

/// The primitives under binary node `n`.
fn subtree_primitives<P: Primitive>(tree: &LogicalTree<P>, n: u32, out: &mut Vec<P>) {
    let mut work = vec![n];
    while let Some(i) = work.pop() {
        let node = &tree.nodes[i as usize];
        if node.is_leaf() {
            let s = node.prim_offset as usize;
            out.extend_from_slice(&tree.primitives[s..s + node.prim_count as usize]);
        } else {
            work.extend(node.child);
        }
    }
}

/// The oriented form of the wide node whose children are binary nodes `slots`, when
/// `options` prefer it to the axis-aligned one.
pub fn fit<P: Primitive>(
    tree: &LogicalTree<P>,
    slots: &[u32],
    options: &OrientedOptions,
) -> Option<OrientedNode> {
    if options.max_area_ratio <= 0.0 {
        return None;
    }
    let per_slot: Vec<Vec<P>> = slots
        .iter()
        .map(|&c| {
            let mut v = Vec::new();
            subtree_primitives(tree, c, &mut v);
            v
        })
        .collect();
    let corners: Vec<Vec3> = per_slot
        .iter()
        .flatten()
        .flat_map(|t| {
            let h = t.hull();
            h.points().to_vec()
        })
        .collect();
    let orientation = Orientation::principal(&corners)?;
    let boxes: Vec<Aabb> = per_slot.iter().map(|t| orientation.bounds_of(t)).collect();
    let s2 = ORIENTATION_SCALE * ORIENTATION_SCALE;
    let oriented: f64 = boxes.iter().map(|b| b.half_area() / s2).sum();
    let aligned: f64 = slots
        .iter()
        .map(|&c| tree.nodes[c as usize].aabb().half_area())
        .sum();
    (oriented.is_finite() && oriented <= options.max_area_ratio * aligned)
        .then_some(OrientedNode { orientation, boxes })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn principal_axes_of_a_tilted_line_come_first() {
        // Points along (1, 1, 0) with a little spread in z.
        let pts: Vec<Vec3> = (0..50)
            .map(|i| {
                let t = i as f32;
                Vec3::new(t, t, (i % 3) as f32 * 0.1)
            })
            .collect();
        let o = Orientation::principal(&pts).unwrap();
        assert_eq!(o.rows[0].map(i32::abs), [90, 90, 0], "{o:?}");
        assert_eq!(o.rows[1].map(i32::abs)[2], 127, "{o:?}");
    }

    #[test]
    fn oriented_boxes_contain_every_corner_exactly() {
        let tris: Vec<Triangle> = (0..200)
            .map(|i| {
                let t = i as f32 * 0.37;
                let p = Vec3::new(t * 3.0 + 1e6, t * 2.0 - 7.5, (t * 0.1).sin());
                Triangle::new(
                    p,
                    p + Vec3::new(0.3, 0.1, 0.0),
                    p + Vec3::new(0.0, 0.2, 0.05),
                    i,
                )
            })
            .collect();
        let corners: Vec<Vec3> = tris.iter().flat_map(|t| [t.p0, t.p1, t.p2]).collect();
        let o = Orientation::principal(&corners).unwrap();
        let b = o.bounds(&tris);
        for p in corners {
            // The three products are exact in f64; their sum with its exact error.
            for (k, r) in o.rows.iter().enumerate() {
                let terms = [0, 1, 2].map(|j| f64::from(r[j]) * f64::from(p.to_array()[j]));
                let (s, e) = two_sum3(terms);
                let lo = f64::from(b.low.axis(k));
                let hi = f64::from(b.high.axis(k));
                assert!(lo <= s && (s > lo || e >= 0.0), "{k}: {lo} vs {s}+{e}");
                assert!(hi >= s && (s < hi || e <= 0.0), "{k}: {hi} vs {s}+{e}");
            }
        }
    }

    /// `a + b + c` as a rounded sum and its exact error.
    fn two_sum3(t: [f64; 3]) -> (f64, f64) {
        let two = |a: f64, b: f64| {
            let s = a + b;
            let bb = s - a;
            (s, (a - (s - bb)) + (b - bb))
        };
        let (s1, e1) = two(t[0], t[1]);
        let (s2, e2) = two(s1, t[2]);
        (s2, e1 + e2)
    }

    #[test]
    fn a_thin_diagonal_node_is_oriented_and_an_axis_aligned_one_is_not() {
        use crate::bvh::{build_sah_binned, SahOptions};
        let diag = |i: u32, off: f32| {
            let t = i as f32;
            let p = Vec3::new(t, t + off, 0.0);
            Triangle::new(
                p,
                p + Vec3::new(0.5, 0.5, 0.0),
                p + Vec3::new(0.5, 0.5, 0.01),
                i,
            )
        };
        let tris: Vec<Triangle> = (0..64).map(|i| diag(i, 0.0)).collect();
        let tree = build_sah_binned(&tris, &SahOptions::default());
        let slots = super::super::wide::open(&tree, tree.root, 4);
        let node = fit(&tree, &slots, &OrientedOptions::default()).expect("oriented");
        assert_eq!(node.boxes.len(), slots.len());
        let flat: Vec<Triangle> = (0..64)
            .map(|i| {
                let p = Vec3::new(i as f32, 0.0, 0.0);
                Triangle::new(
                    p,
                    p + Vec3::new(1.0, 0.0, 0.0),
                    p + Vec3::new(0.0, 1.0, 0.0),
                    i,
                )
            })
            .collect();
        let tree = build_sah_binned(&flat, &SahOptions::default());
        let slots = super::super::wide::open(&tree, tree.root, 4);
        assert!(fit(&tree, &slots, &OrientedOptions::default()).is_none());
        assert!(fit(
            &tree,
            &slots,
            &OrientedOptions {
                max_area_ratio: 0.0
            }
        )
        .is_none());
    }
}
