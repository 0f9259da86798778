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

/// The BVH2 contender.
pub fn bvh2<'a>(tris: &'a [Triangle], driver: &'a BatchDriver) -> Contender<'a> {
    let otris = convert(tris);
    let mut core_time = Duration::ZERO;
    let start = Instant::now();
    let bvh = build_bvh2_from_tris(&otris, BvhBuildParams::medium_build(), &mut core_time);
    let setup = start.elapsed();
    let bytes = std::mem::size_of_val(bvh.nodes.as_slice())
        + std::mem::size_of_val(bvh.primitive_indices.as_slice())
        + std::mem::size_of_val(otris.as_slice());
    Contender {
        name: "obvhs bvh2".into(),
        bytes: Some(bytes),
        setup,
        subset: None,
        trace: Box::new(move |rays: &[Ray]| {
            Ok(driver.map(rays, |r| {
                let mut h = RayHit::none();
                let found = bvh.ray_traverse(oray(r), &mut h, |ray, id| {
                    otris[bvh.primitive_indices[id] as usize].intersect(ray)
                });
                hit(&h, found, &bvh.primitive_indices, tris)
            }))
        }),
    }
}

/// The CWBVH contender.
pub fn cwbvh<'a>(tris: &'a [Triangle], driver: &'a BatchDriver) -> Contender<'a> {
    let otris = convert(tris);
    let mut core_time = Duration::ZERO;
    let start = Instant::now();
    let bvh = build_cwbvh_from_tris(&otris, BvhBuildParams::medium_build(), &mut core_time);
    let setup = start.elapsed();
    let bytes = std::mem::size_of_val(bvh.nodes.as_slice())
        + std::mem::size_of_val(bvh.primitive_indices.as_slice())
        + std::mem::size_of_val(otris.as_slice());
    Contender {
        name: "obvhs cwbvh".into(),
        bytes: Some(bytes),
        setup,
        subset: None,
        trace: Box::new(move |rays: &[Ray]| {
            Ok(driver.map(rays, |r| {
                let mut h = RayHit::none();
                let found = bvh.ray_traverse(oray(r), &mut h, |ray, id| {
                    otris[bvh.primitive_indices[id] as usize].intersect(ray)
                });
                hit(&h, found, &bvh.primitive_indices, tris)
            }))
        }),
    }
}
