//! Binned SAH builder (Wald 2007, "On fast construction of SAH-based bounding volume
//! hierarchies"): triangles -> [`LogicalTree`] with leaves of at most `max_leaf` primitives.
//!
//! Each node bins its primitives' centroids into `bins` (32) equal slots along each axis of
//! the centroid box, sweeps the `bins - 1` planes per axis and evaluates the surface area
//! heuristic `Ct * A + Ci * (nL * AL + nR * AR)` against the leaf cost `Ci * n * A` (areas are
//! half surface areas in `f64`). The cheapest plane wins; equal costs go to the more balanced
//! split, then to the lower axis and plane, so the result is unique. A node becomes a leaf when
//! it holds at most `min_leaf` primitives, or at most `max_leaf` and the leaf is not dearer
//! than the best split. When no plane separates anything (all centroids coincide, or the
//! centroid box is too thin for the binning arithmetic), the node splits at the median of the
//! longest centroid axis instead, ordered by (centroid, id); so leaves never exceed `max_leaf`.
//!
//! Sequential and deterministic.

use super::{Decision, LogicalTree, TopDown, DEFAULT_MAX_LEAF};
use crate::geom::{Aabb, Triangle};

/// Parameters of the binned SAH builder.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SahOptions {
    /// Largest leaf (default 15, the shared cap; values below 1 count as 1).
    pub max_leaf: usize,
    /// Ranges of at most this many primitives always become leaves (default 1; values above
    /// `max_leaf` count as `max_leaf`).
    pub min_leaf: usize,
    /// Number of bins per axis (default 32; values below 2 count as 2).
    pub bins: usize,
    /// Cost of visiting an interior node, relative to `intersection_cost` (default 1).
    pub traversal_cost: f64,
    /// Cost of one primitive test (default 1).
    pub intersection_cost: f64,
}

impl Default for SahOptions {
    fn default() -> SahOptions {
        SahOptions {
            max_leaf: DEFAULT_MAX_LEAF,
            min_leaf: 1,
            bins: 32,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
        }
    }
}

/// The best plane found so far on one node.
#[derive(Clone, Copy)]
struct Plane {
    cost: f64,
    imbalance: usize,
    axis: usize,
    /// Primitives in bins `0..=bin` go left.
    bin: usize,
}

/// Builds a binned-SAH tree over `tris` (see the module documentation).
pub fn build_sah_binned(tris: &[Triangle], options: &SahOptions) -> LogicalTree {
    let max_leaf = options.max_leaf.max(1);
    let min_leaf = options.min_leaf.min(max_leaf);
    let bins = options.bins.max(2);
    let (ct, ci) = (options.traversal_cost, options.intersection_cost);
    let mut counts = vec![0usize; bins];
    let mut boxes = vec![Aabb::EMPTY; bins];
    let mut right_area = vec![0f64; bins];

    TopDown::new(tris).build(|td, begin, end, bounds, cbounds| {
        let n = end - begin;
        if n <= min_leaf {
            return Decision::Leaf;
        }
        let area = bounds.half_area();
        let leaf_cost = ci * n as f64 * area;
        let mut best: Option<Plane> = None;
        for axis in 0..3 {
            let Some((lo, scale)) = binning(cbounds, axis, bins) else {
                continue;
            };
            counts.fill(0);
            boxes.fill(Aabb::EMPTY);
            for &i in &td.order[begin..end] {
                let k = bin_of(td.centroids[i as usize][axis], lo, scale, bins);
                counts[k] += 1;
                boxes[k] = boxes[k].union(td.boxes[i as usize]);
            }
            // right_area[k]: area of bins k..bins.
            let mut acc = Aabb::EMPTY;
            for k in (1..bins).rev() {
                acc = acc.union(boxes[k]);
                right_area[k] = acc.half_area();
            }
            let mut left = Aabb::EMPTY;
            let mut nl = 0usize;
            for k in 0..bins - 1 {
                left = left.union(boxes[k]);
                nl += counts[k];
                if nl == 0 || nl == n {
                    continue;
                }
                let nr = n - nl;
                let cost =
                    ct * area + ci * (nl as f64 * left.half_area() + nr as f64 * right_area[k + 1]);
                let plane = Plane {
                    cost,
                    imbalance: nl.abs_diff(nr),
                    axis,
                    bin: k,
                };
                let better = match best {
                    None => true,
                    Some(b) => cost < b.cost || (cost == b.cost && plane.imbalance < b.imbalance),
                };
                if better {
                    best = Some(plane);
                }
            }
        }
        match best {
            Some(p) if n > max_leaf || p.cost < leaf_cost => {
                let (lo, scale) = binning(cbounds, p.axis, bins).expect("axis was binned");
                let range = &mut td.order[begin..end];
                let centroids = &td.centroids;
                let goes_left =
                    |i: u32| bin_of(centroids[i as usize][p.axis], lo, scale, bins) <= p.bin;
                Decision::Split(partition(range, goes_left))
            }
            Some(_) => Decision::Leaf,
            None if n <= max_leaf => Decision::Leaf,
            None => Decision::Split(td.median_split(begin, end, cbounds.longest_axis())),
        }
    })
}

/// The binning of `axis`: the centroid box's low end and `bins / extent`, or `None` when the
/// extent is zero (all centroids on one plane).
fn binning(cbounds: Aabb, axis: usize, bins: usize) -> Option<(f64, f64)> {
    let lo = cbounds.low[axis] as f64;
    let extent = cbounds.high[axis] as f64 - lo;
    (extent > 0.0).then(|| (lo, bins as f64 / extent))
}

/// The bin of a centroid coordinate, in `f64` (no overflow even for subnormal extents).
fn bin_of(c: f32, lo: f64, scale: f64, bins: usize) -> usize {
    (((c as f64 - lo) * scale) as usize).min(bins - 1)
}

/// Moves the elements for which `left` holds to the front; returns how many there are.
fn partition(v: &mut [u32], left: impl Fn(u32) -> bool) -> usize {
    let mut i = 0;
    let mut j = v.len();
    while i < j {
        if left(v[i]) {
            i += 1;
        } else {
            j -= 1;
            v.swap(i, j);
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::gen;

    #[test]
    fn hard_cases_validate_and_respect_the_cap() {
        for scene in gen::hard_cases() {
            for max_leaf in [1, 4, 15] {
                let opts = SahOptions {
                    max_leaf,
                    ..SahOptions::default()
                };
                let t = build_sah_binned(&scene.triangles, &opts);
                t.validate_with_cap(max_leaf)
                    .unwrap_or_else(|e| panic!("{} (max_leaf {max_leaf}): {e}", scene.name));
                assert_eq!(t.primitives.len(), scene.len());
            }
        }
    }

    #[test]
    fn coincident_centroids_fall_back_to_median() {
        let one = gen::one_triangle();
        let dup = gen::duplicated(&one, 100);
        let t = build_sah_binned(&dup.triangles, &SahOptions::default());
        t.validate().unwrap();
        let s = t.stats();
        assert!(s.max_leaf <= 15);
        // Median splits of 100 identical triangles: balanced, so shallow.
        assert!(s.depth <= 5, "depth {}", s.depth);
    }

    #[test]
    fn deep_chain_is_deep_and_build_is_deterministic() {
        let chain = gen::deep_chain(1000, 0.5);
        let a = build_sah_binned(&chain.triangles, &SahOptions::default());
        let b = build_sah_binned(&chain.triangles, &SahOptions::default());
        assert_eq!(a, b);
        a.validate().unwrap();
        assert!(a.stats().depth > 64, "depth {}", a.stats().depth);
    }
}
