//! Median-split builder with one primitive per leaf, as FCL builds its BVHs (FCL's
//! `BVSplitter` with `SPLIT_METHOD_MEDIAN`): triangles -> [`LogicalTree`].
//!
//! Each node splits its primitives at the median (left gets `n / 2`) along the longest axis
//! of the node's box, ordering by (centroid coordinate, id) so the split is unique; recursion
//! stops at single primitives. The tree is balanced: depth `ceil(log2 n) + 1`.

use super::{build_top_down, median_split, Decide, Decision, Item, LogicalTree};
use crate::geom::Aabb;
use crate::primitive::Primitive;

struct Median;

impl Decide for Median {
    fn decide(&self, items: &mut [Item], bounds: Aabb, _: Aabb, _: usize) -> Decision {
        if items.len() == 1 {
            Decision::Leaf
        } else {
            Decision::Split(median_split(items, bounds.longest_axis()))
        }
    }
}

/// Builds the median-split tree over `tris` (one primitive per leaf).
pub fn build_median<P: Primitive>(tris: &[P]) -> LogicalTree<P> {
    build_top_down(tris, &Median)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::gen;

    #[test]
    fn one_primitive_per_leaf_and_balanced() {
        for scene in gen::hard_cases() {
            let t = build_median(&scene.triangles);
            t.validate_with_cap(1)
                .unwrap_or_else(|e| panic!("{}: {e}", scene.name));
            let s = t.stats();
            assert_eq!(s.leaves, scene.len());
            if !scene.is_empty() {
                let expected = (scene.len() as f64).log2().ceil() as usize + 1;
                assert_eq!(s.depth, expected, "{}", scene.name);
            }
        }
    }
}
