//! A second algorithm through the C ABI: `library/algorithms/occluded.scion` (any hit) with the
//! pbrt and ptr layouts, compiled by Cranelift and LLVM -O3 to its exported entries
//! (`scion_L_sizes`, `scion_L_build`, `scion_L_root`, `scion_occluded_L`) and called as a C host
//! does. Its reference is the runtime's closest hit: a ray is occluded iff it has a closest hit
//! (docs/howto-add-an-algorithm.md).

mod c_entries;

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
