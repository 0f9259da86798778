//! Every library layout over triangles through the GPU pipeline emulated on the CPU (issue 15:
//! every Table 1 layout and case study "through Cranelift, LLVM and the emulated GPU
//! pipeline"): the layout's closest hit (`closest_hit` for the binary ones, `closest_hit8` for the
//! eight-wide ones, `closest_hit_dop14`, `closest_hit_hair`) compiled with the GPU entries for this
//! CPU by LLVM, the tree packed by its packing kernels and traced by `scion_cuda`'s own pipeline,
//! on the hard cases and every real scene, with secondary, primary, axis-parallel and feature
//! rays. Each hit is checked by `scion_host::hit_reference`'s rule against the reference of the
//! tree the layout traverses (binary or collapsed to its width, decoded boxes); layouts whose
//! traversal is that reference's (binary `BVH`, eight-wide `BVH8`) must match it on every ray,
//! the case studies (DOP-14 slabs, oriented hair nodes) may differ only where brute force's hit
//! is theirs and the reference's rounding lost it. Layouts over blocks of four triangles
//! (`bvh8-tri4`) pack the block tree and equal the eight-wide reference over the same blocks.
//! The differential table (tests/differential.rs) runs the binary GPU rows on more trees and
//! ray counts.

use scion_host::gpu_emu::EmulatedGpu;
use scion_host::hit_reference::{check_hits, Traversed};
use scion_host::jit::{Codegen, LoOptions};
use scion_host::library::{layout_names, resolve, Resolved};
use scion_host::quantized::Boxes;
use scion_runtime::batch::BatchDriver;
use scion_runtime::geom::{Hit, Ray};
use scion_runtime::scene::Scene;
use scion_tests::cases::{real_scene, RayKind, TreeKind, REAL_SCENES};

/// Rays of every kind, few per scene (the emulated kernels run one call per GPU thread).
fn rays(scene: &Scene, seed: u64) -> Vec<Ray> {
    let mut rays = RayKind::Secondary.rays(scene, 96, seed);
    rays.extend(RayKind::Primary.rays(scene, 64, seed));
    rays.extend(RayKind::Axis.rays(scene, 32, seed));
    rays.extend(RayKind::Features.rays(scene, 32, 0));
    rays
}

/// The GPU entries compiled for this CPU at -O3, with a traversal stack of 256 entries.
fn gpu_options() -> LoOptions {
    LoOptions {
        stack_size: Some(256),
        opt_level: 3,
        dsl_opt: true,
        target: scion_compiler::abi::EntryTarget::Gpu,
    }
}

/// The library layouts whose leaves hold `primitive`, resolved with their closest hit.
fn layouts_over(primitive: &str) -> Vec<(String, Resolved)> {
    layout_names()
        .into_iter()
        .filter_map(|name| {
            let r = resolve(&name, None).unwrap_or_else(|e| panic!("{name}: {e}"));
            (r.primitive == primitive).then_some((name, r))
        })
        .collect()
}

#[test]
fn every_library_layout_runs_through_the_emulated_gpu_pipeline() {
    let opts = gpu_options();
    let layouts = layouts_over("Triangle");
    assert!(
        layouts.len() >= 21,
        "{} layouts over triangles",
        layouts.len()
    );
    // Compiled on two threads, every other layout each (LLVM at -O3 is most of the setup).
    let compile = |k: usize| -> Vec<(usize, EmulatedGpu)> {
        layouts
            .iter()
            .enumerate()
            .skip(k)
            .step_by(2)
            .map(|(i, (name, r))| {
                let gpu = EmulatedGpu::compile_program(&r.program, &opts, Codegen::Llvm(3), 2)
                    .unwrap_or_else(|e| panic!("{name}: {e}"));
                (i, gpu)
            })
            .collect()
    };
    let mut compiled: Vec<(usize, EmulatedGpu)> = std::thread::scope(|s| {
        let other = s.spawn(|| compile(1));
        let mut mine = compile(0);
        mine.extend(other.join().expect("a compiling thread panicked"));
        mine
    });
    compiled.sort_by_key(|c| c.0);
    let pipelines: Vec<_> = compiled
        .into_iter()
        .map(|(i, gpu)| {
            gpu.into_pipeline()
                .unwrap_or_else(|e| panic!("{}: {e}", layouts[i].0))
        })
        .collect();
    let mut scenes = scion_runtime::scene::gen::hard_cases();
    for info in REAL_SCENES {
        scenes.push(real_scene(info.name).unwrap_or_else(|e| panic!("{e}")));
    }
    let driver = BatchDriver::new(2).unwrap();
    let (mut rows, mut checked, mut settled) = (0, 0, 0);
    for (i, scene) in scenes.iter().enumerate() {
        // Leaves of at most 4: the hair BVH counts at most 7 primitives per leaf.
        let tree = TreeKind::Sah4.build(scene);
        if tree.is_empty() {
            continue;
        }
        let rays = rays(scene, 40 + i as u64);
        // The reference hits of each traversed tree (boxes, arity), shared by the layouts that
        // traverse the same one.
        let mut references: Vec<((Boxes, u32), Vec<Hit>)> = Vec::new();
        for ((name, r), p) in layouts.iter().zip(&pipelines) {
            let packed = p
                .pack(&tree, tree.stats().depth)
                .unwrap_or_else(|e| panic!("{name} {}: {e}", scene.name));
            let on_device = p.upload_rays(&rays).unwrap();
            let got = p
                .trace(&packed, &on_device)
                .unwrap_or_else(|e| panic!("{name} {}: {e}", scene.name))
                .hits;
            let traversed = Traversed::of(r, &tree);
            let key = (traversed.boxes, traversed.arity);
            if !references.iter().any(|x| x.0 == key) {
                references.push((key, traversed.hits(&rays, &driver).unwrap()));
            }
            let want = &references
                .iter()
                .find(|x| x.0 == key)
                .expect("pushed above")
                .1;
            let agreement =
                check_hits(&got, want, &rays, &scene.triangles, traversed.name(), "ray")
                    .unwrap_or_else(|e| panic!("{name} {}: {e}", scene.name));
            if r.tree_type == "BVH" || r.tree_type == "BVH8" {
                assert_eq!(
                    agreement.exceptions,
                    0,
                    "{name} {}: its traversal is the {}'s",
                    scene.name,
                    traversed.name()
                );
            }
            settled += agreement.exceptions;
            checked += rays.len();
            rows += 1;
        }
    }
    assert!(rows >= layouts.len() * 20, "{rows} rows");
    // The case studies' exceptions are rare: at most one ray in a thousand.
    assert!(
        settled * 1000 <= checked,
        "{settled} of {checked} rays settled by brute force"
    );
    eprintln!("{rows} rows, {checked} rays, {settled} settled by brute force");
}

/// The layouts over blocks of four triangles (`Triangle4`: `bvh8-tri4`) the same way: the
/// block tree (`sah_block_tree`) packed by the packing kernels and traced by the emulated GPU
/// pipeline equals the runtime's eight-wide reference over the same blocks on every ray.
#[test]
fn blocks_of_four_run_through_the_emulated_gpu_pipeline() {
    use scion_runtime::bvh::wide::collapse;
    use scion_runtime::reference::closest_hit_wide;
    use scion_runtime::triangle4::sah_block_tree;
    let opts = gpu_options();
    let layouts = layouts_over("Triangle4");
    assert!(!layouts.is_empty(), "bvh8-tri4 is a library layout");
    let mut scenes = scion_runtime::scene::gen::hard_cases();
    for info in REAL_SCENES {
        scenes.push(real_scene(info.name).unwrap_or_else(|e| panic!("{e}")));
    }
    let mut rows = 0;
    for (name, r) in &layouts {
        let p = EmulatedGpu::compile_program(&r.program, &opts, Codegen::Llvm(3), 2)
            .and_then(EmulatedGpu::into_pipeline)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        for (i, scene) in scenes.iter().enumerate() {
            let blocks = sah_block_tree(&scene.triangles);
            if blocks.is_empty() {
                continue;
            }
            let rays = rays(scene, 70 + i as u64);
            let packed = p
                .pack(&blocks, blocks.stats().depth)
                .unwrap_or_else(|e| panic!("{name} {}: {e}", scene.name));
            // Blocks go to the device as their 160-byte records.
            assert_eq!(packed.sizes[1], 160 * blocks.primitives.len() as u64);
            let on_device = p.upload_rays(&rays).unwrap();
            let got = p.trace(&packed, &on_device).unwrap().hits;
            let wide = collapse::<8>(&blocks);
            for (k, (ray, got)) in rays.iter().zip(&got).enumerate() {
                let want = closest_hit_wide(&wide, &blocks.primitives, ray);
                assert!(
                    got.bit_eq(&want),
                    "{name} {} ray {k}: {got:?}, the wide reference over the blocks {want:?}",
                    scene.name
                );
            }
            rows += 1;
        }
    }
    assert!(rows >= 20, "{rows} rows");
}
