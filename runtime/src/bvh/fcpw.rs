//! FCPW's tree builder (Sawhney's FCPW, its `Sbvh` with the surface-area heuristic, which the
//! paper's closest-point comparison reimplements, §9.3.2): triangles -> [`LogicalTree`],
//! written from FCPW's description and behaviour, to compare traversals on the tree FCPW
//! builds rather than on Scion's own.
//!
//! Top down; a range becomes a leaf when it has at most `leaf_size` triangles (FCPW's default
//! 4) or sits at depth `max_depth` (FCPW stops at 62). Otherwise, on each axis where the range's
//! box is at least 1e-6 wide, the box is cut into `buckets` equal slices (default 8), each
//! triangle goes to the slice of its centroid, and every cut between slices that leaves
//! triangles on both sides is priced `(n_left * area(left) + n_right * area(right)) /
//! area(range)` with the boxes of the triangles on each side: the cheapest cut wins (the first
//! one met on ties, axes in order x, y, z), whatever its price (no comparison with a leaf's, as
//! FCPW). Triangles whose centroid is below the cut's coordinate go left. With no cut priced,
//! the range is cut at the middle of its centroids' box on that box's longest axis; a cut that
//! leaves one side empty becomes a median split by count along the same axis (FCPW halves the
//! range in its current order; the median by (centroid, id) is the deterministic reading). So
//! unlike [`super::build_sah_binned`] it bins the range's box rather than its centroids' box,
//! uses 8 slices rather than 32, and has no leaf cost, no traversal cost and no reinsertion.

use super::{build_top_down, median_split, Decide, Decision, Item, LogicalTree};
use crate::geom::Aabb;
use crate::primitive::Primitive;

/// The builder's parameters, FCPW's defaults by default.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FcpwOptions {
    /// Ranges of at most this many triangles become leaves (default 4; at least 1).
    pub leaf_size: usize,
    /// Slices per axis (default 8; at least 2).
    pub buckets: usize,
    /// Ranges at this depth become leaves whatever their size (default 62; the root is 0).
    pub max_depth: usize,
}

impl Default for FcpwOptions {
    fn default() -> FcpwOptions {
        FcpwOptions {
            leaf_size: 4,
            buckets: 8,
            max_depth: 62,
        }
    }
}

struct Fcpw(FcpwOptions);

/// The box's surface area (any constant factor would do: only ratios are compared).
fn area(b: Aabb) -> f64 {
    b.half_area()
}

impl Decide for Fcpw {
    fn decide(&self, items: &mut [Item], bounds: Aabb, cbounds: Aabb, depth: usize) -> Decision {
        let n = items.len();
        if n <= self.0.leaf_size.max(1) || depth >= self.0.max_depth {
            return Decision::Leaf;
        }
        let nb = self.0.buckets.max(2);
        let extent = bounds.extent();
        let parent = area(bounds);
        // (cost, axis, coordinate) of the cheapest cut.
        let mut best: Option<(f64, usize, f32)> = None;
        let mut counts = vec![0usize; nb];
        let mut boxes = vec![Aabb::EMPTY; nb];
        for axis in 0..3 {
            let e = extent.axis(axis);
            if e < 1e-6 {
                continue;
            }
            let low = bounds.low.axis(axis);
            let width = e / nb as f32;
            counts.fill(0);
            boxes.fill(Aabb::EMPTY);
            for it in items.iter() {
                let k = ((it.centroid.axis(axis) - low) / width) as i64;
                let k = k.clamp(0, nb as i64 - 1) as usize;
                counts[k] += 1;
                boxes[k] = boxes[k].union(it.bounds);
            }
            // right[k]: the box and count of slices k.. .
            let mut right = vec![(Aabb::EMPTY, 0usize); nb + 1];
            for k in (0..nb).rev() {
                right[k] = (right[k + 1].0.union(boxes[k]), right[k + 1].1 + counts[k]);
            }
            let (mut left, mut nl) = (Aabb::EMPTY, 0usize);
            for b in 1..nb {
                left = left.union(boxes[b - 1]);
                nl += counts[b - 1];
                let (rbox, nr) = right[b];
                if nl == 0 || nr == 0 {
                    continue;
                }
                let cost = (nl as f64 * area(left) + nr as f64 * area(rbox)) / parent;
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, low + b as f32 * width));
                }
            }
        }
        let (axis, coord) = match best {
            Some((_, axis, coord)) => (axis, coord),
            None => {
                let axis = cbounds.longest_axis();
                (
                    axis,
                    (cbounds.low.axis(axis) + cbounds.high.axis(axis)) * 0.5,
                )
            }
        };
        // Partition in place: centroids below the coordinate first.
        let mut mid = 0;
        for i in 0..n {
            if items[i].centroid.axis(axis) < coord {
                items.swap(i, mid);
                mid += 1;
            }
        }
        if mid == 0 || mid == n {
            mid = median_split(items, axis);
        }
        Decision::Split(mid)
    }
}

/// Builds FCPW's tree over `tris` with `options`.
pub fn build_fcpw<P: Primitive>(tris: &[P], options: &FcpwOptions) -> LogicalTree<P> {
    build_top_down(tris, &Fcpw(*options))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::gen;

    #[test]
    fn valid_trees_with_small_leaves_on_every_hard_case() {
        for scene in gen::hard_cases() {
            let o = FcpwOptions::default();
            let t = build_fcpw(&scene.triangles, &o);
            let s = t.stats();
            if scene.is_empty() {
                continue;
            }
            // Leaves above leaf_size only where the depth ran out.
            if s.depth <= o.max_depth {
                t.validate_with_cap(o.leaf_size)
                    .unwrap_or_else(|e| panic!("{}: {e}", scene.name));
            } else {
                t.validate_with_cap(u16::MAX as usize)
                    .unwrap_or_else(|e| panic!("{}: {e}", scene.name));
            }
            assert!(
                s.depth <= o.max_depth + 1,
                "{}: depth {}",
                scene.name,
                s.depth
            );
            assert_eq!(
                t.primitives.len(),
                scene.len(),
                "{}: every triangle once",
                scene.name
            );
        }
    }

    #[test]
    fn deterministic() {
        let scene = gen::hard_cases()
            .into_iter()
            .max_by_key(|s| s.len())
            .unwrap();
        let a = build_fcpw(&scene.triangles, &FcpwOptions::default());
        let b = build_fcpw(&scene.triangles, &FcpwOptions::default());
        assert_eq!(a.nodes.len(), b.nodes.len());
        assert!(a
            .primitives
            .iter()
            .zip(&b.primitives)
            .all(|(x, y)| x.id == y.id));
    }
}
