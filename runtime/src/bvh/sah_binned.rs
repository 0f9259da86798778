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
//! The tree then goes through the insertion-based optimization ([`super::reinsert`]) and, when
//! leaves are tested in runs of `block` primitives (default 4), through the leaf collapse by that
//! cost ([`super::collapse`]).
//!
//! Deterministic: the same tree whatever the number of threads (see [`super`]).

use super::{build_top_down, median_split, Decide, Decision, Item, LogicalTree, DEFAULT_MAX_LEAF};
use crate::geom::Aabb;
use crate::primitive::Primitive;

/// Parameters of the binned SAH builder.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SahOptions {
    /// Largest leaf (default 15, the shared cap; values below 1 count as 1).
    pub max_leaf: usize,
    /// Ranges of at most this many primitives always become leaves (default 1; values above
    /// `max_leaf` count as `max_leaf`).
    pub min_leaf: usize,
    /// Number of bins per axis (default 32; clamped to `2..=MAX_BINS`).
    pub bins: usize,
    /// Cost of visiting an interior node, relative to `intersection_cost` (default 1).
    pub traversal_cost: f64,
    /// Cost of one primitive test (default 1).
    pub intersection_cost: f64,
    /// Passes of insertion-based optimization after the top-down build (default 32; 0 keeps
    /// the binned SAH tree as built; see [`super::reinsert`]).
    pub reinsertion_passes: usize,
    /// Primitives a leaf tests at once (default 4, as the library's closest hit tests a leaf's
    /// triangles in runs of four): the SAH counts a leaf of `n` as `ceil(n / block)` tests, so
    /// with blocks of four (`Triangle4` leaves, Embree's SAH for them) a leaf of four costs what
    /// a leaf of one does. The tree is built and optimized with leaves costed one primitive at a
    /// time, then collapsed by this cost ([`super::collapse`]). Values below 1 count as 1.
    pub block: usize,
}

impl Default for SahOptions {
    fn default() -> SahOptions {
        SahOptions {
            max_leaf: DEFAULT_MAX_LEAF,
            min_leaf: 1,
            bins: 32,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
            reinsertion_passes: 32,
            block: 4,
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

/// Most bins per axis (the per-node scratch lives on the stack).
pub const MAX_BINS: usize = 64;

/// The binned-SAH rule with its options resolved.
struct Sah {
    max_leaf: usize,
    min_leaf: usize,
    bins: usize,
    ct: f64,
    ci: f64,
}

/// Builds a binned-SAH tree over `tris` (see the module documentation).
pub fn build_sah_binned<P: Primitive>(tris: &[P], options: &SahOptions) -> LogicalTree<P> {
    let max_leaf = options.max_leaf.max(1);
    let block = options.block.max(1);
    // The top-down build and the optimization work on leaves costed one primitive at a time; a
    // block's leaves come from collapsing the optimized tree (`super::collapse`).
    let rule = Sah {
        max_leaf,
        min_leaf: options.min_leaf.min(max_leaf),
        bins: options.bins.clamp(2, MAX_BINS),
        ct: options.traversal_cost,
        ci: options.intersection_cost,
    };
    let mut tree = build_top_down(tris, &rule);
    super::reinsert::optimize(&mut tree, options.reinsertion_passes);
    if block > 1 {
        super::collapse::collapse(
            &mut tree,
            &super::collapse::CollapseCost {
                max_leaf,
                block,
                traversal_cost: options.traversal_cost,
                intersection_cost: options.intersection_cost,
            },
        );
    }
    tree
}

impl Decide for Sah {
    fn decide(&self, items: &mut [Item], bounds: Aabb, cbounds: Aabb, _: usize) -> Decision {
        let (bins, ct, ci) = (self.bins, self.ct, self.ci);
        let n = items.len();
        if n <= self.min_leaf {
            return Decision::Leaf;
        }
        let area = bounds.half_area();
        let leaf_cost = ci * n as f64 * area;
        let binnings = [0, 1, 2].map(|axis| binning(cbounds, axis, bins));
        // Per axis: bins of counts and boxes.
        let mut counts = [[0usize; MAX_BINS]; 3];
        let mut boxes = [[Aabb::EMPTY; MAX_BINS]; 3];
        // One pass over the primitives bins all three axes.
        for it in items.iter() {
            for (axis, b) in binnings.iter().enumerate() {
                if let Some((lo, scale)) = *b {
                    let k = bin_of(it.centroid.axis(axis), lo, scale, bins);
                    counts[axis][k] += 1;
                    boxes[axis][k] = boxes[axis][k].union(it.bounds);
                }
            }
        }
        let mut best: Option<Plane> = None;
        let mut right_area = [0f64; MAX_BINS];
        for axis in 0..3 {
            if binnings[axis].is_none() {
                continue;
            }
            let (counts, boxes) = (&counts[axis], &boxes[axis]);
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
            Some(p) if n > self.max_leaf || p.cost < leaf_cost => {
                let (lo, scale) = binnings[p.axis].expect("axis was binned");
                let goes_left =
                    |it: &Item| bin_of(it.centroid.axis(p.axis), lo, scale, bins) <= p.bin;
                Decision::Split(partition(items, goes_left))
            }
            Some(_) => Decision::Leaf,
            None if n <= self.max_leaf => Decision::Leaf,
            None => Decision::Split(median_split(items, cbounds.longest_axis())),
        }
    }
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
fn partition(v: &mut [Item], left: impl Fn(&Item) -> bool) -> usize {
    let mut i = 0;
    let mut j = v.len();
    while i < j {
        if left(&v[i]) {
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
    fn blocks_of_four_make_fuller_leaves_and_block_one_changes_nothing() {
        let scene = gen::random_soup(2000, 0.05, 7);
        let tris = &scene.triangles;
        let four = |block| SahOptions {
            max_leaf: 4,
            block,
            ..SahOptions::default()
        };
        let (plain, blocks) = (
            build_sah_binned(tris, &four(1)),
            build_sah_binned(tris, &four(4)),
        );
        assert_eq!(
            plain.nodes,
            build_sah_binned(tris, &four(0)).nodes,
            "block 0 counts as 1"
        );
        blocks.validate_with_cap(4).unwrap();
        let (p, b) = (plain.stats(), blocks.stats());
        // A leaf of four costs what a leaf of one does: fewer, fuller leaves.
        assert!(
            b.leaves * 10 < p.leaves * 8,
            "{} leaves against {}",
            b.leaves,
            p.leaves
        );
        assert!(
            tris.len() as f64 / b.leaves as f64 > 2.5,
            "{} leaves",
            b.leaves
        );
    }

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
    fn same_tree_on_any_number_of_threads() {
        let soup = gen::random_soup(3 * crate::bvh::PARALLEL_MIN as u32, 0.01, 8);
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                (
                    build_sah_binned(&soup.triangles, &SahOptions::default()),
                    crate::bvh::build_median(&soup.triangles),
                )
            })
        };
        let one = on(1);
        one.0.validate().unwrap();
        one.1.validate_with_cap(1).unwrap();
        assert_eq!(one, on(3));
    }

    #[test]
    fn deep_chain_is_deep_and_build_is_deterministic() {
        let chain = gen::deep_chain(1000, 0.5);
        let a = build_sah_binned(&chain.triangles, &SahOptions::default());
        let b = build_sah_binned(&chain.triangles, &SahOptions::default());
        assert_eq!(a, b);
        a.validate().unwrap();
        assert!(a.stats().depth > 64, "depth {}", a.stats().depth);
        assert!(a.stats().stack_needed >= 64, "{:?}", a.stats());
    }
}
