//! The peer library `obvhs` as contenders: its PLOC BVH2 (with parallel reinsertion, the
//! library's `medium_build` preset) and its compressed wide BVH8 (CWBVH, 80-byte nodes, built
//! from the same BVH2), each traversed by the library's own closest-hit traversal with its own
//! ray-triangle test. Input: the workload's triangles; output: hits in the runtime's convention
//! (original primitive id, `t`), so they compare with Scion's (the trees and the triangle test
//! differ, so a few `t` may differ in the last bits).

use obvhs::bvh2::builder::build_bvh2_from_tris;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::{Ray as ORay, RayHit};
use obvhs::triangle::Triangle as OTriangle;
use obvhs::BvhBuildParams;
use scion_bench::Contender;
use scion_runtime::batch::BatchDriver;
use scion_runtime::geom::{Hit, Ray, Triangle, Vec3};
use std::time::{Duration, Instant};

fn v(p: Vec3) -> glam::Vec3A {
    glam::Vec3A::new(p.x, p.y, p.z)
}

fn convert(tris: &[Triangle]) -> Vec<OTriangle> {
    tris.iter()
        .map(|t| OTriangle {
            v0: v(t.p0),
            v1: v(t.p1),
            v2: v(t.p2),
        })
        .collect()
}

fn oray(r: &Ray) -> ORay {
    ORay::new(v(r.origin), v(r.dir), r.tmin, r.tmax)
}

fn hit(h: &RayHit, found: bool, ids: &[u32], tris: &[Triangle]) -> Hit {
    if !found {
        return Hit::MISS;
    }
    Hit {
        t: h.t,
        prim: tris[ids[h.primitive_id as usize] as usize].id,
    }
}

/// A tree obvhs traverses with its own closest-hit traversal.
trait Traversable: Send + Sync {
    fn closest(&self, ray: ORay, hit: &mut RayHit, tris: &[OTriangle]) -> bool;
    fn primitive_indices(&self) -> &[u32];
    fn node_bytes(&self) -> usize;
}

/// The same three methods for both obvhs trees (their fields and traversal share names).
macro_rules! traversable {
    ($($t:ty),*) => {$(
        impl Traversable for $t {
            fn closest(&self, ray: ORay, hit: &mut RayHit, tris: &[OTriangle]) -> bool {
                self.ray_traverse(ray, hit, |r, id| {
                    tris[self.primitive_indices[id] as usize].intersect(r)
                })
            }
            fn primitive_indices(&self) -> &[u32] {
                &self.primitive_indices
            }
            fn node_bytes(&self) -> usize {
                std::mem::size_of_val(self.nodes.as_slice())
            }
        }
    )*};
}

traversable!(obvhs::bvh2::Bvh2, obvhs::cwbvh::CwBvh);

/// The contender named `name` over the tree `build` makes from the converted triangles (its
/// time is the setup).
fn contender<'a, B: Traversable + 'a>(
    name: &str,
    tris: &'a [Triangle],
    driver: &'a BatchDriver,
    build: impl FnOnce(&[OTriangle], &mut Duration) -> B,
) -> Contender<'a> {
    let otris = convert(tris);
    let mut core_time = Duration::ZERO;
    let start = Instant::now();
    let bvh = build(&otris, &mut core_time);
    let setup = start.elapsed();
    let bytes = bvh.node_bytes()
        + std::mem::size_of_val(bvh.primitive_indices())
        + std::mem::size_of_val(otris.as_slice());
    Contender {
        name: name.into(),
        bytes: Some(bytes),
        setup,
        subset: None,
        trace: Box::new(move |rays: &[Ray]| {
            Ok(driver.map(rays, |r| {
                let mut h = RayHit::none();
                let found = bvh.closest(oray(r), &mut h, &otris);
                hit(&h, found, bvh.primitive_indices(), tris)
            }))
        }),
    }
}

/// The BVH2 contender.
pub fn bvh2<'a>(tris: &'a [Triangle], driver: &'a BatchDriver) -> Contender<'a> {
    contender("obvhs bvh2", tris, driver, |t, time| {
        build_bvh2_from_tris(t, BvhBuildParams::medium_build(), time)
    })
}

/// The CWBVH contender.
pub fn cwbvh<'a>(tris: &'a [Triangle], driver: &'a BatchDriver) -> Contender<'a> {
    contender("obvhs cwbvh", tris, driver, |t, time| {
        build_cwbvh_from_tris(t, BvhBuildParams::medium_build(), time)
    })
}

/// The BVH2 obvhs's `medium_build` makes over `tris`, as a logical tree (for `--builders`): a
/// node with primitives is a leaf over `primitive_indices[first_index..][..prim_count]`, an
/// inner node's children are `first_index` and `first_index + 1`.
pub fn logical_tree(tris: &[Triangle]) -> Result<scion_runtime::bvh::LogicalTree, String> {
    use scion_bench::foreign_tree::{logical_tree, Shape};
    let otris = convert(tris);
    let mut time = Duration::ZERO;
    let bvh = build_bvh2_from_tris(&otris, BvhBuildParams::medium_build(), &mut time);
    logical_tree(tris, 0, |i| {
        let n = &bvh.nodes[i as usize];
        if n.prim_count > 0 {
            let first = n.first_index as usize;
            Shape::Leaf(&bvh.primitive_indices[first..first + n.prim_count as usize])
        } else {
            Shape::Interior(n.first_index, n.first_index + 1)
        }
    })
}
