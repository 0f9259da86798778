//! Blocks of four triangles stored lane by lane: the prelude's `Triangle4` (Embree's
//! `Triangle4`, tinybvh's `BVHTri4Leaf`), a primitive a tree's leaves can hold so that a leaf
//! test is one four-lane test (`hit_block` in the prelude: four branch-free Möller-Trumbore lanes,
//! which LLVM vectorizes: `lit-tests/llvm/four-triangle-lanes.scion`).
//!
//! A block answers for the nearest of its four triangles by the tie rule (smallest `t`, then
//! smallest id), so a tree over blocks gives exactly the hits of a tree over the triangles.
//! A block of fewer than four repeats its last triangle (same corners, same id: the tie rule
//! makes the copy harmless). [`blocks_of`] groups a mesh's triangles into blocks of nearby
//! triangles: the leaves of a binned SAH tree of at most four triangles per leaf.

use crate::bvh::{build_sah_binned, LogicalTree, SahOptions};
use crate::geom::{Aabb, Ray, Triangle, Vec3};
use crate::primitive::{Hull, Primitive};
use crate::reference::prelude;

/// Four triangles, each coordinate of each corner an array over the four lanes (160 bytes,
/// `#[repr(C)]`, the prelude's `Triangle4(x0, y0, z0, x1, y1, z1, x2, y2, z2, id)` with
/// `f32[4]` and `u32[4]` fields).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle4 {
    /// `p0.x` of each lane.
    pub x0: [f32; 4],
    /// `p0.y` of each lane.
    pub y0: [f32; 4],
    /// `p0.z` of each lane.
    pub z0: [f32; 4],
    /// `p1.x` of each lane.
    pub x1: [f32; 4],
    /// `p1.y` of each lane.
    pub y1: [f32; 4],
    /// `p1.z` of each lane.
    pub z1: [f32; 4],
    /// `p2.x` of each lane.
    pub x2: [f32; 4],
    /// `p2.y` of each lane.
    pub y2: [f32; 4],
    /// `p2.z` of each lane.
    pub z2: [f32; 4],
    /// The id of each lane's triangle.
    pub id: [u32; 4],
}

impl Triangle4 {
    /// The block of `tris` (one to four), the last repeated into the lanes left.
    ///
    /// # Panics
    /// When `tris` is empty or longer than four.
    pub fn new(tris: &[Triangle]) -> Triangle4 {
        assert!(
            (1..=4).contains(&tris.len()),
            "a block of {} triangles",
            tris.len()
        );
        let t = |k: usize| tris[k.min(tris.len() - 1)];
        let lanes = |f: &dyn Fn(&Triangle) -> f32| [f(&t(0)), f(&t(1)), f(&t(2)), f(&t(3))];
        Triangle4 {
            x0: lanes(&|t| t.p0.x),
            y0: lanes(&|t| t.p0.y),
            z0: lanes(&|t| t.p0.z),
            x1: lanes(&|t| t.p1.x),
            y1: lanes(&|t| t.p1.y),
            z1: lanes(&|t| t.p1.z),
            x2: lanes(&|t| t.p2.x),
            y2: lanes(&|t| t.p2.y),
            z2: lanes(&|t| t.p2.z),
            id: [t(0).id, t(1).id, t(2).id, t(3).id],
        }
    }

    /// The triangle of lane `k` (`0..4`).
    pub fn lane(&self, k: usize) -> Triangle {
        Triangle::new(
            Vec3::new(self.x0[k], self.y0[k], self.z0[k]),
            Vec3::new(self.x1[k], self.y1[k], self.z1[k]),
            Vec3::new(self.x2[k], self.y2[k], self.z2[k]),
            self.id[k],
        )
    }

    /// The distinct triangles of the block, in lane order (a repeated last one once).
    pub fn triangles(&self) -> Vec<Triangle> {
        let mut out: Vec<Triangle> = Vec::with_capacity(4);
        for k in 0..4 {
            let t = self.lane(k);
            if out.last() != Some(&t) {
                out.push(t);
            }
        }
        out
    }
}

impl Primitive for Triangle4 {
    const TYPE_NAME: &'static str = "Triangle4";

    /// The union of the four triangles' exact boxes.
    fn bounds(&self) -> Aabb {
        (1..4).fold(self.lane(0).bounds(), |b, k| b.union(self.lane(k).bounds()))
    }

    /// The first lane's id (blocks partition a mesh, so it names the block).
    fn id(&self) -> u32 {
        self.id[0]
    }

    fn is_finite(&self) -> bool {
        (0..4).all(|k| self.lane(k).is_finite())
    }

    fn hull(&self) -> Hull {
        let mut pts = Vec::with_capacity(12);
        for k in 0..4 {
            let t = self.lane(k);
            pts.extend([t.p0, t.p1, t.p2]);
        }
        Hull::new(&pts, 0.0)
    }

    fn hit_distance(&self, ray: &Ray) -> f32 {
        self.hit(ray).0
    }

    fn hit(&self, ray: &Ray) -> (f32, u32) {
        prelude::hit_block(ray, self)
    }
}

/// The tree over blocks that is `tree` (a tree over triangles) with each leaf's triangles cut,
/// in order, into blocks of four (the last of one to four): the same nodes and boxes (a leaf's
/// box is the union of its blocks'), a leaf of `n` triangles holding `ceil(n / 4)` blocks. So a
/// traversal over blocks visits exactly the nodes a traversal of `tree` visits, and tests a
/// leaf's triangles four at a time. An error names an empty leaf.
pub fn block_tree(tree: &LogicalTree<Triangle>) -> Result<LogicalTree<Triangle4>, String> {
    let mut nodes = tree.nodes.clone();
    let mut primitives = Vec::new();
    for (i, node) in nodes.iter_mut().enumerate() {
        if !node.is_leaf() {
            continue;
        }
        let tris = tree.leaf_primitives(node);
        if tris.is_empty() {
            return Err(format!("leaf {i} holds no triangles"));
        }
        node.prim_offset = primitives.len() as u32;
        node.prim_count = tris.len().div_ceil(4) as u32;
        primitives.extend(tris.chunks(4).map(Triangle4::new));
    }
    Ok(LogicalTree {
        nodes,
        root: tree.root,
        primitives,
    })
}

/// Largest leaf of [`sah_block_tree`], in triangles: two blocks. Embree's leaves hold up to
/// seven blocks; against leaves of one block, two raised `bvh8-tri4` by 13 to 17 % on
/// fzk_haus and 8 to 16 % on dragon, a few per cent on most other library scenes, and lost
/// 1 to 3 % on bunny, suzanne and sponza (peers bench, one thread, 65,536 rays, same runs);
/// four blocks were slower than two (docs/performance-eight-wide.md, "Sixteenth session").
pub const BLOCK_TREE_MAX_LEAF: usize = 8;

/// The binned SAH tree over `tris` with leaves of at most [`BLOCK_TREE_MAX_LEAF`] triangles,
/// its leaves collapsed counting a leaf of `n` as `ceil(n / 4)` tests (`SahOptions::block`, as
/// Embree's SAH for `Triangle4` leaves: fuller leaves, fewer nodes), as a tree over blocks
/// ([`block_tree`]).
pub fn sah_block_tree(tris: &[Triangle]) -> LogicalTree<Triangle4> {
    let options = block_sah_options(BLOCK_TREE_MAX_LEAF);
    block_tree(&build_sah_binned(tris, &options)).expect("a binned SAH tree has no empty leaf")
}

/// The binned SAH's options for a tree whose leaves become blocks of four: leaves of at most
/// `max_leaf` triangles, a leaf of `n` counted as `ceil(n / 4)` tests.
pub fn block_sah_options(max_leaf: usize) -> SahOptions {
    SahOptions {
        max_leaf,
        block: 4,
        ..SahOptions::default()
    }
}

/// `tris` grouped into blocks of up to four nearby triangles: the blocks of
/// [`sah_block_tree`]'s leaves, in the tree's order. Every triangle is in exactly one block.
pub fn blocks_of(tris: &[Triangle]) -> Vec<Triangle4> {
    sah_block_tree(tris).primitives
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64 as Rng;

    fn tri(rng: &mut Rng, id: u32) -> Triangle {
        let mut p = || {
            Vec3::new(
                rng.next_f32() * 4.0 - 2.0,
                rng.next_f32() * 4.0 - 2.0,
                rng.next_f32() - 0.5,
            )
        };
        Triangle::new(p(), p(), p(), id)
    }

    #[test]
    fn a_block_is_160_bytes_as_the_prelude_lays_it_out() {
        assert_eq!(std::mem::size_of::<Triangle4>(), 160);
        assert_eq!(std::mem::align_of::<Triangle4>(), 4);
    }

    #[test]
    fn a_short_block_repeats_its_last_triangle() {
        let mut rng = Rng::new(3);
        let (a, b) = (tri(&mut rng, 7), tri(&mut rng, 9));
        let blk = Triangle4::new(&[a, b]);
        assert_eq!(blk.lane(0), a);
        assert_eq!([blk.lane(1), blk.lane(2), blk.lane(3)], [b, b, b]);
        assert_eq!(blk.triangles(), vec![a, b]);
        assert_eq!(blk.bounds(), a.bounds().union(b.bounds()));
        assert_eq!(
            blk.hull().points(),
            &[a.p0, a.p1, a.p2, b.p0, b.p1, b.p2, b.p0, b.p1, b.p2, b.p0, b.p1, b.p2]
        );
    }

    #[test]
    fn a_block_answers_for_its_nearest_triangle_by_the_tie_rule() {
        let mut rng = Rng::new(11);
        for round in 0..2000u32 {
            let n = 1 + (round % 4) as usize;
            let mut tris: Vec<Triangle> = (0..n as u32).map(|i| tri(&mut rng, 100 - i)).collect();
            if round % 5 == 0 && n > 1 {
                // Two triangles in one plane at one place: equal t, the smaller id wins.
                tris[n - 1] = Triangle::new(tris[0].p0, tris[0].p1, tris[0].p2, tris[n - 1].id);
            }
            let origin = Vec3::new(rng.next_f32() * 2.0 - 1.0, rng.next_f32() * 2.0 - 1.0, 3.0);
            let ray = Ray::new(
                origin,
                Vec3::new(rng.next_f32() * 0.2 - 0.1, rng.next_f32() * 0.2 - 0.1, -1.0),
            );
            let mut want = (f32::INFINITY, u32::MAX);
            for t in &tris {
                let h = prelude::hit_distance(&ray, t);
                if h < want.0 || (h == want.0 && h < f32::INFINITY && t.id < want.1) {
                    want = (h, t.id);
                }
            }
            let got = Triangle4::new(&tris).hit(&ray);
            assert_eq!(got.0.to_bits(), want.0.to_bits(), "round {round}");
            if want.0 < f32::INFINITY {
                assert_eq!(got.1, want.1, "round {round}");
            }
        }
    }

    #[test]
    fn blocks_partition_the_mesh_into_nearby_fours() {
        let mut rng = Rng::new(5);
        let tris: Vec<Triangle> = (0..1001).map(|i| tri(&mut rng, i)).collect();
        let blocks = blocks_of(&tris);
        let mut seen: Vec<u32> = blocks
            .iter()
            .flat_map(|b| b.triangles().into_iter().map(|t| t.id))
            .collect();
        seen.sort_unstable();
        assert_eq!(seen, (0..1001).collect::<Vec<u32>>());
        // Mostly full blocks: a leaf's triangles cut into fours.
        assert!(blocks.len() * 4 < 1001 * 2, "{} blocks", blocks.len());
        assert!(blocks_of(&[]).is_empty());
    }

    #[test]
    fn a_block_tree_keeps_the_nodes_and_boxes_and_cuts_big_leaves_into_blocks() {
        let mut rng = Rng::new(8);
        let tris: Vec<Triangle> = (0..500).map(|i| tri(&mut rng, i)).collect();
        let tree = build_sah_binned(
            &tris,
            &SahOptions {
                max_leaf: 4,
                ..SahOptions::default()
            },
        );
        let blocks = block_tree(&tree).unwrap();
        assert_eq!(blocks.nodes.len(), tree.nodes.len());
        blocks.validate().unwrap();
        for (a, b) in tree.nodes.iter().zip(&blocks.nodes) {
            assert_eq!((a.kind, a.bounds, a.child), (b.kind, b.bounds, b.child));
            if a.is_leaf() {
                assert_eq!(
                    blocks.leaf_primitives(b)[0].triangles(),
                    tree.leaf_primitives(a)
                );
                assert_eq!(blocks.leaf_primitives(b)[0].bounds().to_array(), a.bounds);
            }
        }
        // Leaves of more than four become several blocks, in order; the nodes stay.
        let big = build_sah_binned(
            &tris,
            &SahOptions {
                max_leaf: 15,
                min_leaf: 8,
                ..SahOptions::default()
            },
        );
        let blocks = block_tree(&big).unwrap();
        blocks.validate().unwrap();
        assert_eq!(blocks.nodes.len(), big.nodes.len());
        let mut several = 0;
        for (a, b) in big.nodes.iter().zip(&blocks.nodes) {
            assert_eq!((a.kind, a.bounds, a.child), (b.kind, b.bounds, b.child));
            if a.is_leaf() {
                let tris = big.leaf_primitives(a);
                let held = blocks.leaf_primitives(b);
                assert_eq!(held.len(), tris.len().div_ceil(4));
                let flat: Vec<Triangle> = held.iter().flat_map(|k| k.triangles()).collect();
                assert_eq!(flat, tris);
                several += usize::from(held.len() > 1);
            }
        }
        assert!(several > 0, "no leaf of more than four triangles");
    }
}
