//! Discrete oriented polytopes of 14 sides (DOP-14, Káčerik and Bittner 2024; layout catalog §5):
//! seven slabs `[min, max]` of `n · p` over a node's geometry, for the normals
//! `n0..n2 = x, y, z` and `n3..n6 = x+y+z, x+y−z, x−y+z, x−y−z`. In a logical node it is the
//! record `DOP14(lo1: f32x3, hi1: f32x3, lo2: f32x4, hi2: f32x4)`: the axis slabs (an AABB) then
//! the diagonal ones, 56 bytes.
//!
//! Conservative: the axis slabs are exact (`f32` min and max of the corners); a diagonal value
//! of a corner is summed in `f64` and widened by the sum's error bound before rounding to
//! `f32` outward (mins down, maxes up), so every slab contains the exact `n · p` of every corner
//! of every triangle below the node.

use super::logical::LogicalTree;
use crate::geom::{Triangle, Vec3};
use crate::primitive::Primitive;

/// The four diagonal normals, as signs of (y, z) with x positive.
pub const DIAGONALS: [(f64, f64); 4] = [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)];

/// A DOP-14 in the logical node's form.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dop14 {
    /// Minima of x, y, z.
    pub lo1: [f32; 3],
    /// Maxima of x, y, z.
    pub hi1: [f32; 3],
    /// Minima along the four diagonals.
    pub lo2: [f32; 4],
    /// Maxima along the four diagonals.
    pub hi2: [f32; 4],
}

impl Dop14 {
    /// The empty DOP (every min `+inf`, every max `-inf`): the union with anything is that.
    pub const EMPTY: Dop14 = Dop14 {
        lo1: [f32::INFINITY; 3],
        hi1: [f32::NEG_INFINITY; 3],
        lo2: [f32::INFINITY; 4],
        hi2: [f32::NEG_INFINITY; 4],
    };

    /// Slab-wise union (exact).
    pub fn union(&self, o: &Dop14) -> Dop14 {
        let mut r = *self;
        for k in 0..3 {
            r.lo1[k] = r.lo1[k].min(o.lo1[k]);
            r.hi1[k] = r.hi1[k].max(o.hi1[k]);
        }
        for k in 0..4 {
            r.lo2[k] = r.lo2[k].min(o.lo2[k]);
            r.hi2[k] = r.hi2[k].max(o.hi2[k]);
        }
        r
    }

    /// Grown to contain point `p`.
    pub fn grow(&self, p: Vec3) -> Dop14 {
        let mut r = *self;
        for (k, v) in [p.x, p.y, p.z].into_iter().enumerate() {
            r.lo1[k] = r.lo1[k].min(v);
            r.hi1[k] = r.hi1[k].max(v);
        }
        let (x, y, z) = (f64::from(p.x), f64::from(p.y), f64::from(p.z));
        // Three terms: the f64 sum is within 2 * 2^-53 of the sum of magnitudes.
        let err = (x.abs() + y.abs() + z.abs()) * f64::EPSILON;
        for (k, (sy, sz)) in DIAGONALS.into_iter().enumerate() {
            let s = x + sy * y + sz * z;
            r.lo2[k] = r.lo2[k].min(round_down(s - err));
            r.hi2[k] = r.hi2[k].max(round_up(s + err));
        }
        r
    }

    /// The DOP of triangles' corners.
    pub fn of_triangles(tris: &[Triangle]) -> Dop14 {
        tris.iter()
            .fold(Dop14::EMPTY, |d, t| d.grow(t.p0).grow(t.p1).grow(t.p2))
    }

    /// The DOP of primitives: their hulls' points (exactly as [`Dop14::of_triangles`] for
    /// triangles), grown by their padding where they have one.
    pub fn of_primitives<P: Primitive>(prims: &[P]) -> Dop14 {
        prims.iter().fold(Dop14::EMPTY, |acc, p| {
            let h = p.hull();
            let d = h.points().iter().fold(Dop14::EMPTY, |d, &q| d.grow(q));
            acc.union(&d.padded(h.pad))
        })
    }

    /// Every slab widened by `pad` (times the diagonal normals' length, sqrt 3), rounded
    /// outward; itself when `pad` is 0.
    fn padded(&self, pad: f32) -> Dop14 {
        if pad == 0.0 {
            return *self;
        }
        let p1 = f64::from(pad);
        // sqrt(3) rounded up, times a little more for the product's rounding.
        let p2 = f64::from(pad) * 1.732_050_808 * (1.0 + 4.0 * f64::EPSILON);
        let mut r = *self;
        for k in 0..3 {
            r.lo1[k] = round_down(f64::from(r.lo1[k]) - p1);
            r.hi1[k] = round_up(f64::from(r.hi1[k]) + p1);
        }
        for k in 0..4 {
            r.lo2[k] = round_down(f64::from(r.lo2[k]) - p2);
            r.hi2[k] = round_up(f64::from(r.hi2[k]) + p2);
        }
        r
    }

    /// The 14 floats in field order (`lo1`, `hi1`, `lo2`, `hi2`).
    pub fn to_array(&self) -> [f32; 14] {
        let mut a = [0.0; 14];
        a[..3].copy_from_slice(&self.lo1);
        a[3..6].copy_from_slice(&self.hi1);
        a[6..10].copy_from_slice(&self.lo2);
        a[10..].copy_from_slice(&self.hi2);
        a
    }
}

/// The largest `f32` at most `x`.
pub(crate) fn round_down(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) > x {
        -step_up(-f)
    } else {
        f
    }
}

/// The smallest `f32` at least `x`.
pub(crate) fn round_up(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) < x {
        step_up(f)
    } else {
        f
    }
}

/// The next `f32` toward `+inf` (`f32::next_up`, which the crate's minimum Rust does not have);
/// NaN and `+inf` stay.
fn step_up(f: f32) -> f32 {
    if f.is_nan() || f == f32::INFINITY {
        return f;
    }
    if f == 0.0 {
        return f32::from_bits(1);
    }
    let b = f.to_bits();
    f32::from_bits(if f > 0.0 { b + 1 } else { b - 1 })
}

/// Every node's DOP-14, by node index: a leaf's from its triangles, an interior node's the
/// union of its children's.
pub fn node_dops<P: Primitive>(tree: &LogicalTree<P>) -> Vec<Dop14> {
    let mut dops = vec![Dop14::EMPTY; tree.nodes.len()];
    if tree.is_empty() {
        return dops;
    }
    // Post-order without recursion (trees can be thousands deep).
    let mut work = vec![(tree.root, false)];
    while let Some((i, children_done)) = work.pop() {
        let n = &tree.nodes[i as usize];
        if n.is_leaf() {
            let (a, c) = (n.prim_offset as usize, n.prim_count as usize);
            dops[i as usize] = Dop14::of_primitives(&tree.primitives[a..a + c]);
        } else if children_done {
            dops[i as usize] = dops[n.child[0] as usize].union(&dops[n.child[1] as usize]);
        } else {
            work.push((i, true));
            work.extend(n.child.iter().map(|&c| (c, false)));
        }
    }
    dops
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{build_sah_binned, SahOptions};
    use crate::scene::gen;

    #[test]
    fn every_corner_is_inside_its_nodes_dop_exactly() {
        for scene in gen::hard_cases() {
            if !scene.triangles.iter().all(Triangle::is_finite) {
                continue;
            }
            let tree = build_sah_binned(&scene.triangles, &SahOptions::default());
            if tree.is_empty() {
                continue;
            }
            let dops = node_dops(&tree);
            for (i, n) in tree.nodes.iter().enumerate() {
                let d = &dops[i];
                // The axis slabs are the node's box.
                assert_eq!([d.lo1, d.hi1].concat(), n.bounds.to_vec(), "{}", scene.name);
                if !n.is_leaf() {
                    continue;
                }
                let (a, c) = (n.prim_offset as usize, n.prim_count as usize);
                for t in &tree.primitives[a..a + c] {
                    for p in [t.p0, t.p1, t.p2] {
                        for (k, (sy, sz)) in DIAGONALS.into_iter().enumerate() {
                            let terms = [f64::from(p.x), sy * f64::from(p.y), sz * f64::from(p.z)];
                            // lo <= exact sum <= hi, decided exactly.
                            let below = sign(&[terms[0], terms[1], terms[2], -f64::from(d.lo2[k])]);
                            let above = sign(&[terms[0], terms[1], terms[2], -f64::from(d.hi2[k])]);
                            assert!(
                                below >= 0 && above <= 0,
                                "{} node {i} diagonal {k}: {} .. {} vs {p:?}",
                                scene.name,
                                d.lo2[k],
                                d.hi2[k]
                            );
                        }
                    }
                }
            }
        }
    }

    fn two_sum(a: f64, b: f64) -> (f64, f64) {
        let s = a + b;
        let bb = s - a;
        (s, (a - (s - bb)) + (b - bb))
    }

    /// The sign of the exact sum of `terms` (Shewchuk's grow-expansion: the expansion is
    /// nonoverlapping, so its most significant nonzero term has the sum's sign).
    fn sign(terms: &[f64]) -> i32 {
        let mut e: Vec<f64> = Vec::new();
        for &b in terms {
            let mut q = b;
            let mut h = Vec::new();
            for &x in &e {
                let (s, lo) = two_sum(q, x);
                if lo != 0.0 {
                    h.push(lo);
                }
                q = s;
            }
            h.push(q);
            e = h;
        }
        match e.iter().rev().find(|x| **x != 0.0) {
            Some(x) if *x > 0.0 => 1,
            Some(_) => -1,
            None => 0,
        }
    }
}
