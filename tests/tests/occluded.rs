//! A second algorithm through the C ABI: `library/algorithms/occluded.scion` (any hit) with the
//! pbrt and ptr layouts, compiled by Cranelift and LLVM -O3 to its exported entries
//! (`scion_L_sizes`, `scion_L_build`, `scion_L_root`, `scion_occluded_L`) and called as a C host
//! does. Its reference is the runtime's closest hit: a ray is occluded iff it has a closest hit
//! (docs/howto-add-an-algorithm.md).

use crate::c_entries;

use scion_host::jit::Codegen;
use scion_host::mem_interp::{layout_source, Program};
use scion_runtime::batch::BatchDriver;
use scion_runtime::reference::closest_hits_tree;
use scion_runtime::scene::gen;
use scion_tests::cases::{real_scene, RayKind, TreeKind};
use std::path::PathBuf;

fn program(stem: &str, layout: &str) -> Program {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../library/algorithms");
    let alg = std::fs::read_to_string(dir.join("occluded.scion")).expect("occluded.scion");
    Program {
        files: vec![
            ("occluded.scion".to_string(), alg),
            (
                format!("{stem}.scion"),
                layout_source(stem).expect("a library layout").to_string(),
            ),
        ],
        layout: layout.to_string(),
        algorithm: "occluded".to_string(),
    }
}

#[test]
fn occluded_is_having_a_closest_hit() {
    let driver = BatchDriver::new(2).unwrap();
    let mut scenes = gen::hard_cases();
    if let Ok(s) = real_scene("teapot") {
        scenes.push(s);
    }
    for (stem, layout) in [("pbrt", "LinearBVH"), ("ptr", "PtrBVH")] {
        let lo = c_entries::host_lo(&program(stem, layout));
        assert_eq!(
            lo.entry.result.size, 4,
            "the result record is the u32 `hit`"
        );
        for codegen in [Codegen::Cranelift, Codegen::Llvm(3)] {
            let code = codegen.backend().jit(&lo.module).unwrap();
            let mut occluded_rays = 0;
            for (i, scene) in scenes.iter().enumerate() {
                let tree = TreeKind::Sah4.build(scene);
                if tree.is_empty() {
                    continue;
                }
                let mut rays = RayKind::Secondary.rays(scene, 300, i as u64);
                rays.extend(RayKind::Features.rays(scene, 200, 0));
                // Shadow rays stop short: half of them end halfway.
                for r in rays.iter_mut().step_by(2) {
                    r.tmax = 0.5;
                }
                let want: Vec<u32> = closest_hits_tree(&tree, &rays, &driver)
                    .iter()
                    .map(|h| u32::from(h.is_hit()))
                    .collect();
                let mut hits = vec![0u32; rays.len()];
                let status =
                    c_entries::run_batch(&lo, code.as_ref(), &tree, "occluded", &rays, &mut hits);
                assert_eq!(status, 0, "{layout}: batch status");
                for (k, (g, w)) in hits.iter().zip(&want).enumerate() {
                    assert_eq!(g, w, "{layout} {codegen:?} scene {i} ray {k} {:?}", rays[k]);
                }
                occluded_rays += hits.iter().filter(|&&h| h == 1).count();
            }
            assert!(
                occluded_rays > 500,
                "{layout} {codegen:?}: {occluded_rays} occluded rays"
            );
        }
    }
}

/// The float64 oracle (`scion_runtime::reference::any_hit`): where the `f32` answer (the
/// reference's, which every layout and backend equals above) differs from `f64`'s, the ray
/// grazes: its verdict's margin is within rounding (below 1e-5, relative to the coordinates'
/// magnitude, module docs of `any_hit`). Prints, per scene, how many rays differ and that `f64`
/// is the side believed. Scenes and rays outside the `f32` test's range are counted apart:
/// coordinates beyond 1e12 and scenes smaller than 1e-9 (its `t` is a product of three lengths
/// over a product of two, and products of three lengths overflow `f32` past about 7e12 and
/// underflow it for edges near 1e-13).
#[test]
fn occluded_agrees_with_float64_except_on_grazing_rays() {
    use scion_runtime::reference::any_hit::any_hit_f64;
    let driver = BatchDriver::new(2).unwrap();
    let mut scenes = gen::hard_cases();
    for name in ["teapot", "pine"] {
        if let Ok(s) = real_scene(name) {
            scenes.push(s);
        }
    }
    let (mut total, mut differ, mut out_of_range) = (0, 0, 0);
    let (mut total_random, mut differ_random) = (0, 0);
    for (i, scene) in scenes.iter().enumerate() {
        let tree = TreeKind::Sah4.build(scene);
        if tree.is_empty() {
            continue;
        }
        // Random rays, then rays aimed at vertices and edges (grazing by design).
        let mut rays = RayKind::Secondary.rays(scene, 400, i as u64);
        let random = rays.len();
        rays.extend(RayKind::Features.rays(scene, 400, 0));
        for r in rays.iter_mut().step_by(2) {
            r.tmax = 0.5;
        }
        let f32_hits = closest_hits_tree(&tree, &rays, &driver);
        let mut here = 0;
        let b = scene.bounds();
        let big = |v: scion_runtime::geom::Vec3| v.x.abs().max(v.y.abs()).max(v.z.abs()) > 1e12;
        let e = b.extent();
        let scene_big = big(b.low) || big(b.high) || e.x.max(e.y).max(e.z) < 1e-9;
        for (k, (r, h)) in rays.iter().zip(&f32_hits).enumerate() {
            if scene_big || big(r.origin) {
                out_of_range += 1;
                continue;
            }
            if k < random {
                total_random += 1;
            }
            let o = any_hit_f64(&scene.triangles, r);
            if o.occluded != h.is_hit() {
                assert!(
                    o.margin.abs() < 1e-5,
                    "{} ray {k} {r:?}: f32 says {}, f64 says {} by a margin of {:e}",
                    scene.name,
                    h.is_hit(),
                    o.occluded,
                    o.margin
                );
                here += 1;
                if k < random {
                    differ_random += 1;
                }
            }
        }
        if here > 0 {
            eprintln!(
                "{}: {here} of {} rays differ from float64, all grazing (float64 believed)",
                scene.name,
                rays.len()
            );
        }
        total += rays.len();
        differ += here;
    }
    eprintln!(
        "{differ} of {total} rays differ from float64, {differ_random} of the {total_random} \
         random ones ({out_of_range} with coordinates beyond 1e12 or in scenes below 1e-9 not \
         compared)"
    );
    assert!(total > 5_000, "{total} rays");
    assert!(
        differ_random * 200 < total_random,
        "{differ_random} of {total_random} random rays differ"
    );
}
