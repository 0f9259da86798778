//! The GPU pipeline emulated on the CPU (`scion_host::gpu_emu`, docs/gpu.md): the kernels of
//! `scion trace --device gpu` compiled for the host and driven by `scion_cuda`'s own pipeline
//! pack the tree to the sizes of the layout catalog and trace bit for bit like the reference,
//! with either code generator; a small traversal stack is the overflow status; the empty tree
//! and no rays need no launch; launches with the wrong arguments or an unknown kernel are the
//! errors a CUDA launch gives. The differential table (tests/differential.rs) runs the same
//! backend on every scene and hard case.

use scion_cuda::trace::GpuPipeline;
use scion_cuda::{CudaError, Grid, KernelArg, Launcher};
use scion_host::gpu_emu::EmulatedGpu;
use scion_host::jit::{Codegen, LoOptions};
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::{build_caterpillar, build_sah_binned, DeepSide, LogicalTree, SahOptions};
use scion_runtime::geom::{Hit, Ray, Vec3};
use scion_runtime::reference::{closest_hit_tree_stats, closest_hits_tree, TraversalStats};
use scion_runtime::scene::gen;

fn options(stack: Option<u32>) -> LoOptions {
    LoOptions {
        stack_size: stack,
        opt_level: 3,
        dsl_opt: true,
        target: scion_compiler::abi::EntryTarget::Gpu,
    }
}

fn pipeline(stem: &str, layout: &str, stack: Option<u32>, cg: Codegen) -> GpuPipeline<EmulatedGpu> {
    EmulatedGpu::compile(stem, layout, &options(stack), cg, 2)
        .unwrap_or_else(|e| panic!("{stem}: {e}"))
        .into_pipeline()
        .unwrap_or_else(|e| panic!("{stem}: {e}"))
}

fn trace(
    p: &GpuPipeline<EmulatedGpu>,
    tree: &LogicalTree,
    rays: &[Ray],
) -> Result<Vec<Hit>, CudaError> {
    let packed = p.pack(tree, tree.stats().depth)?;
    let on_device = p.upload_rays(rays)?;
    Ok(p.trace(&packed, &on_device)?.hits)
}

#[test]
fn emulated_kernels_pack_to_the_catalog_sizes_and_match_the_reference() {
    let scene = gen::random_soup(500, 0.1, 11);
    let tree = build_sah_binned(&scene.triangles, &SahOptions::default());
    // 700 rays: two full blocks of 256 and a partial one, whose idle threads must not write.
    let rays = scion_runtime::query::secondary_rays(scene.bounds(), 700, 5);
    let want = closest_hits_tree(&tree, &rays, &BatchDriver::new(2).unwrap());
    for (stem, name, node_bytes) in [("pbrt", "LinearBVH", 32u64), ("ptr", "PtrBVH", 48)] {
        for cg in [Codegen::Llvm(3), Codegen::Cranelift] {
            let p = pipeline(stem, name, None, cg);
            assert_eq!(p.launcher().layout(), name);
            assert_eq!(p.launcher().buffers(), ["globals", "primitives", "nodes"]);
            assert_eq!(
                p.launcher().kernel_names().len(),
                4,
                "{:?}",
                p.launcher().kernel_names()
            );
            let packed = p.pack(&tree, tree.stats().depth).unwrap();
            assert_eq!(packed.sizes[1], 40 * tree.primitives.len() as u64, "{stem}");
            assert_eq!(
                packed.sizes[2],
                node_bytes * tree.nodes.len() as u64,
                "{stem}"
            );
            for b in &packed.buffers {
                assert_eq!(p.launcher().address(b).0 % 256, 0);
            }
            let on_device = p.upload_rays(&rays).unwrap();
            let (got, times) = p.trace_runs(&packed, &on_device, 2).unwrap();
            assert_eq!(times.len(), 2);
            let same = got.iter().zip(&want).filter(|(g, w)| g.bit_eq(w)).count();
            assert_eq!(
                same,
                rays.len(),
                "{stem} {cg:?}: hits differ from the reference"
            );
            assert!(got.iter().any(|h| h.is_hit()), "{stem}: no hits");
        }
    }
}

#[test]
fn a_small_stack_is_the_overflow_status() {
    // A chain-like tree, and the ray of 2000 random ones that leaves the most entries pending
    // on the traversal stack (the reference counts them): a stack one entry smaller overflows.
    let scene = gen::random_soup(64, 0.1, 9);
    let tree = build_caterpillar(&scene.triangles, DeepSide::Left);
    let pending = |r: &Ray| {
        let mut stats = TraversalStats::default();
        closest_hit_tree_stats(&tree, r, &mut stats);
        stats.max_pending as u32
    };
    let deep = *scion_runtime::query::secondary_rays(scene.bounds(), 2000, 3)
        .iter()
        .max_by_key(|r| pending(r))
        .expect("rays");
    let need = pending(&deep);
    assert!(need >= 2, "{need}");
    let rays = vec![deep; 3];
    let p = pipeline("pbrt", "LinearBVH", Some(need - 1), Codegen::Llvm(3));
    let e = trace(&p, &tree, &rays).unwrap_err();
    assert!(matches!(e, CudaError::Status { status: 1, .. }), "{e:?}");
    assert!(e.to_string().contains("traversal stack overflow"), "{e}");
    // The same tree with a stack as deep as it traces.
    let p = pipeline("pbrt", "LinearBVH", Some(128), Codegen::Llvm(3));
    let want = closest_hits_tree(&tree, &rays, &BatchDriver::new(1).unwrap());
    let got = trace(&p, &tree, &rays).unwrap();
    assert!(got.iter().zip(&want).all(|(g, w)| g.bit_eq(w)));
}

#[test]
fn the_empty_tree_and_no_rays_need_no_launch() {
    let p = pipeline("ptr", "PtrBVH", None, Codegen::Llvm(3));
    let rays = vec![Ray::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)); 5];
    let hits = trace(
        &p,
        &LogicalTree::<scion_runtime::geom::Triangle>::empty(),
        &rays,
    )
    .unwrap();
    assert!(hits.iter().all(|h| h.bit_eq(&Hit::MISS)));
    let scene = gen::random_soup(20, 0.1, 3);
    let tree = build_sah_binned(&scene.triangles, &SahOptions::default());
    assert!(trace(&p, &tree, &[]).unwrap().is_empty());
}

#[test]
fn bad_launches_are_the_errors_of_a_cuda_launch() {
    let gpu =
        EmulatedGpu::compile("pbrt", "LinearBVH", &options(None), Codegen::Cranelift, 1).unwrap();
    let kernel = "scion_closest_hit_LinearBVH_kernel";
    assert_eq!(gpu.params(kernel).unwrap(), [8, 8, 8, 8, 4, 8]);
    let e = gpu
        .run(kernel, Grid::SINGLE, &[KernelArg::U64(0)])
        .unwrap_err();
    assert!(matches!(e, CudaError::BadArguments { .. }), "{e:?}");
    assert!(e.to_string().contains("takes 6 parameters, 1 given"), "{e}");
    let e = gpu.run("scion_nope_kernel", Grid::SINGLE, &[]).unwrap_err();
    assert!(matches!(e, CudaError::MissingKernel { .. }), "{e:?}");
    assert!(e.to_string().contains(kernel), "{e}");
    // A zero-byte buffer is a valid, aligned allocation; reads past a buffer are refused.
    let b = gpu.alloc("empty", 0).unwrap();
    assert_eq!(gpu.address(&b).0 % 256, 0);
    let e = gpu.download::<u32>(&b, 1).unwrap_err();
    assert!(
        e.to_string().contains("`empty`, which holds 0 bytes"),
        "{e}"
    );
    let b = gpu.upload("words", &[1u32, 2, 3]).unwrap();
    assert_eq!(gpu.download::<u32>(&b, 3).unwrap(), [1, 2, 3]);
    assert!(gpu.write(&b, &[0u64; 2]).is_err());
}
