//! A second algorithm through the C ABI: `library/algorithms/occluded.scion` (any hit) with the
//! pbrt and ptr layouts, compiled by Cranelift and LLVM -O3 to its exported entries
//! (`scion_L_sizes`, `scion_L_build`, `scion_L_root`, `scion_occluded_L`) and called as a C host
//! does. Its reference is the runtime's closest hit: a ray is occluded iff it has a closest hit
//! (docs/howto-add-an-algorithm.md).

// Calling the generated C entry points needs unsafe (each call carries its SAFETY note).
#![allow(unsafe_code)]

use scion_compiler::abi::EntryTarget;
use scion_host::contract::LogicalTreeView;
use scion_host::jit::{program_lo, Codegen, LoOptions};
use scion_host::mem_interp::{layout_source, Program};
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::schema::LogicalBytes;
use scion_runtime::geom::Ray;
use scion_runtime::reference::closest_hits_tree;
use scion_runtime::scene::gen;
use scion_tests::cases::{real_scene, RayKind, TreeKind};
use std::path::PathBuf;

type SizesFn = unsafe extern "C" fn(*const LogicalTreeView, *mut u64);
type BuildFn = unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> i32;
type RootIdxFn = unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> u32;
type RootPtrFn = unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> *const u8;
type BatchIdxFn =
    unsafe extern "C" fn(*const *const u8, *const Ray, *mut u32, u64, u64, u32) -> i32;
type BatchPtrFn =
    unsafe extern "C" fn(*const *const u8, *const Ray, *mut u32, u64, u64, *const u8) -> i32;

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

/// 64-byte aligned zeroed bytes (at least one block, so every buffer has a real address).
fn aligned(size: usize) -> (Vec<u8>, usize) {
    let bytes = vec![0u8; size + 128];
    let off = bytes.as_ptr().align_offset(64);
    (bytes, off)
}

#[test]
fn occluded_is_having_a_closest_hit() {
    let driver = BatchDriver::new(2).unwrap();
    let mut scenes = gen::hard_cases();
    if let Ok(s) = real_scene("teapot") {
        scenes.push(s);
    }
    for (stem, layout) in [("pbrt", "LinearBVH"), ("ptr", "PtrBVH")] {
        let lo = program_lo(
            &program(stem, layout),
            &LoOptions {
                // The hard cases include a chain a thousand nodes deep.
                stack_size: Some(4096),
                opt_level: 3,
                dsl_opt: true,
                target: EntryTarget::Host,
            },
        )
        .unwrap_or_else(|e| panic!("{layout}: {e}"));
        assert_eq!(
            lo.entry.result.size, 4,
            "the result record is the u32 `hit`"
        );
        for codegen in [Codegen::Cranelift, Codegen::Llvm(3)] {
            let code = codegen.backend().jit(&lo.module).unwrap();
            let f = |name: String| {
                code.function_ptr(&name)
                    .unwrap_or_else(|| panic!("no `@{name}`"))
            };
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
                let bytes = LogicalBytes::fill(&tree, &lo.entry.logical).unwrap();
                let view = LogicalTreeView::new(&tree, &bytes).unwrap();
                // SAFETY: the entries have the signatures of docs/c-abi.md for this layout's
                // reference type (u32 for LinearBVH, ptr for PtrBVH); the view describes the
                // live tree; every buffer has the size `sizes` gave and is 64-byte aligned;
                // `rays` and `hits` have `n` elements.
                let hits = unsafe {
                    let sizes = std::mem::transmute::<*const u8, SizesFn>(f(format!(
                        "scion_{layout}_sizes"
                    )));
                    let build = std::mem::transmute::<*const u8, BuildFn>(f(format!(
                        "scion_{layout}_build"
                    )));
                    let count = lo.entry.buffers.len();
                    let mut sz = vec![0u64; count];
                    sizes(&view, sz.as_mut_ptr());
                    let mut bufs: Vec<(Vec<u8>, usize)> =
                        sz.iter().map(|&s| aligned(s as usize)).collect();
                    let table: Vec<*mut u8> = bufs
                        .iter_mut()
                        .map(|(b, o)| b.as_mut_ptr().add(*o))
                        .collect();
                    assert_eq!(build(&view, table.as_ptr()), 0, "{layout}: build");
                    let ctable: Vec<*const u8> = table.iter().map(|&p| p as *const u8).collect();
                    let n = rays.len() as u64;
                    let mut hits = vec![0u32; rays.len()];
                    let status = if layout == "PtrBVH" {
                        let root = std::mem::transmute::<*const u8, RootPtrFn>(f(format!(
                            "scion_{layout}_root"
                        )));
                        let batch = std::mem::transmute::<*const u8, BatchPtrFn>(f(format!(
                            "scion_occluded_{layout}"
                        )));
                        let r = root(&view, table.as_ptr());
                        batch(ctable.as_ptr(), rays.as_ptr(), hits.as_mut_ptr(), 0, n, r)
                    } else {
                        let root = std::mem::transmute::<*const u8, RootIdxFn>(f(format!(
                            "scion_{layout}_root"
                        )));
                        let batch = std::mem::transmute::<*const u8, BatchIdxFn>(f(format!(
                            "scion_occluded_{layout}"
                        )));
                        let r = root(&view, table.as_ptr());
                        batch(ctable.as_ptr(), rays.as_ptr(), hits.as_mut_ptr(), 0, n, r)
                    };
                    assert_eq!(status, 0, "{layout}: batch status");
                    hits
                };
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
