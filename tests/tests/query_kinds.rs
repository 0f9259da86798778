//! The differential table of query kinds: every entry of a batched kind the library declares
//! over the binary `BVH` (`QueryKind`: closest hit, any hit, closest point depth first and best
//! first) × every library layout of that tree type × both code generators (Cranelift, LLVM
//! -O3) × scenes (the finite hard cases and two real scenes) × trees (binned SAH with leaves
//! of 4, median split), through the generic runner of C entries (`scion_host::entries`) and
//! the table's references and equality (`scion_host::queries`): hits against the reference
//! traversal of the tree the layout traverses, bit for bit; closest points against float32
//! brute force, bit for bit. A new layout file or a new entry of a known kind joins the table
//! without editing it.

use scion_host::entries::Entries;
use scion_host::hit_reference::Traversed;
use scion_host::jit::Codegen;
use scion_host::library::{library_entries, resolve_kind, QueryKind, LAYOUT_FILES};
use scion_host::queries::{uniform_points, Queries};
use scion_runtime::batch::BatchDriver;
use scion_runtime::geom::Triangle;
use scion_runtime::query::{primary_rays_n, secondary_rays};
use scion_runtime::scene::{gen, Scene};
use scion_tests::cases::{real_scene, TreeKind};

fn scenes() -> Vec<Scene> {
    let mut scenes: Vec<Scene> = gen::hard_cases()
        .into_iter()
        .filter(|s| !s.is_empty() && s.triangles.iter().all(Triangle::is_finite))
        .collect();
    for name in ["teapot", "pine"] {
        scenes.push(real_scene(name).unwrap_or_else(|e| panic!("{name}: {e}")));
    }
    scenes
}

/// The queries of `kind` for `scene`: primary and secondary rays, or points uniform in the
/// box grown by a fifth on each side.
fn queries(kind: QueryKind, scene: &Scene, seed: u64) -> Queries {
    let b = scene.bounds();
    match kind {
        QueryKind::ClosestPoint => {
            let e = b.extent() * 0.2;
            Queries::points(uniform_points(b.low - e, b.high + e, 96, seed))
        }
        _ => {
            let mut rays = primary_rays_n(b, 96, seed).unwrap();
            rays.extend(secondary_rays(b, 64, seed + 1));
            Queries::rays(kind, rays)
        }
    }
}

#[test]
fn every_kind_layout_and_backend_answers_as_its_reference() {
    let scenes = scenes();
    let driver = BatchDriver::new(2).unwrap();
    let mut rows = 0;
    // Every entry the library declares over the binary `BVH`: the case studies' own trees
    // (DOP-14 bounds, oriented wide nodes) and the eight-wide ones are filled from other
    // logical trees by the runtime; they have their own tests (dop14.rs, hair.rs, wide.rs).
    let entries = library_entries().unwrap();
    let mut covered = std::collections::BTreeSet::new();
    let rows_of = entries
        .iter()
        .filter(|(_, tree, kind)| tree == "BVH" && QueryKind::BATCHED.contains(kind));
    for (entry, _, kind) in rows_of {
        let kind = *kind;
        for &(stem, _) in LAYOUT_FILES {
            // Layouts of another tree type have no row.
            let Ok(resolved) = resolve_kind(stem, Some(entry), kind) else {
                continue;
            };
            if resolved.tree_type != "BVH" {
                continue;
            }
            covered.insert(entry.clone());
            for codegen in [Codegen::Cranelift, Codegen::Llvm(3)] {
                let entries = Entries::compile(&resolved.program, codegen, Some(4096))
                    .unwrap_or_else(|e| panic!("{stem} {kind:?} {codegen:?}: {e}"));
                for (i, scene) in scenes.iter().enumerate() {
                    for tree_kind in [TreeKind::Sah4, TreeKind::Median] {
                        let tree = tree_kind.build(scene);
                        let q = queries(kind, scene, i as u64 + 1);
                        let packed = entries.pack(&tree).unwrap();
                        let mut results = q.initial_results();
                        entries
                            .run(&packed, &q.bytes, &mut results, &driver)
                            .unwrap_or_else(|e| panic!("{stem} {kind:?} {}: {e}", scene.name));
                        let traversed = Traversed::of(&resolved, &tree);
                        let verdict = q
                            .check(&scene.triangles, traversed, &results, usize::MAX, &driver)
                            .unwrap_or_else(|e| {
                                panic!(
                                    "{stem} {} {codegen:?} scene {} ({tree_kind:?}): {e}",
                                    kind.name(),
                                    scene.name
                                )
                            });
                        // A binary layout's code returns exactly its reference's answers: no
                        // answer is settled by brute force.
                        assert!(
                            !verdict.contains("brute force's hits"),
                            "{stem} {} {codegen:?} scene {}: {verdict}",
                            kind.name(),
                            scene.name
                        );
                        rows += 1;
                    }
                }
            }
        }
    }
    // 4 entries (closest hit, any hit, two closest points) × 9 BVH layouts × 2 generators ×
    // scenes × 2 trees.
    assert!(rows >= 4 * 9 * 2 * 2 * 10, "{rows} rows");
    for want in [
        "closest_hit",
        "occluded",
        "closest_point_query",
        "closest_point_best_first",
    ] {
        assert!(covered.contains(want), "{want} has no row: {covered:?}");
    }
}

/// The GPU pipeline over every kind: the GPU entries (`scion_A_L_kernel` and the packing
/// kernels) compiled for this CPU and launched as grids of host threads
/// (`scion_host::gpu_emu`), the tree packed on the emulated device, the query records uploaded
/// and the batch kernel run through `scion_cuda`'s own pipeline (`run_queries`): the same
/// answers as the reference, for each kind on layouts with exact, quantized and pointer
/// references.
#[test]
fn every_kind_runs_through_the_gpu_pipeline_as_its_reference() {
    use scion_compiler::abi::EntryTarget;
    use scion_host::gpu_emu::EmulatedGpu;
    use scion_host::jit::LoOptions;
    let mut scenes = scenes();
    scenes.truncate(3);
    scenes.push(real_scene("teapot").unwrap());
    let driver = BatchDriver::new(2).unwrap();
    let mut rows = 0;
    for kind in QueryKind::BATCHED {
        for stem in ["pbrt", "ptr", "pbrt-q16"] {
            let resolved = resolve_kind(stem, None, kind).unwrap();
            let opts = LoOptions {
                stack_size: Some(4096),
                opt_level: 3,
                dsl_opt: true,
                target: EntryTarget::Gpu,
            };
            let gpu = EmulatedGpu::compile_program(&resolved.program, &opts, Codegen::Llvm(3), 2)
                .unwrap_or_else(|e| panic!("{stem} {kind:?}: {e}"));
            let sig = gpu.entry().unwrap().clone();
            let pipeline = gpu.into_pipeline().unwrap();
            for (i, scene) in scenes.iter().enumerate() {
                let tree = TreeKind::Sah4.build(scene);
                let q = queries(kind, scene, i as u64 + 7);
                assert_eq!(q.record_sizes(), (sig.query.size, sig.result.size));
                let packed = pipeline.pack(&tree, tree.stats().depth).unwrap();
                let (qs, rs) = (sig.query.size as usize, sig.result.size as usize);
                let on_device = pipeline.upload_queries(&q.bytes, qs, rs).unwrap();
                let (results, _) = pipeline
                    .run_queries(&packed, &on_device, &q.initial_results())
                    .unwrap_or_else(|e| panic!("{stem} {kind:?} {}: {e}", scene.name));
                let traversed = Traversed::of(&resolved, &tree);
                let verdict = q
                    .check(&scene.triangles, traversed, &results, usize::MAX, &driver)
                    .unwrap_or_else(|e| panic!("{stem} {} {}: {e}", kind.name(), scene.name));
                assert!(!verdict.contains("brute force's hits"), "{stem}: {verdict}");
                rows += 1;
            }
        }
    }
    assert_eq!(rows, 3 * 3 * 4);
}
