//! The hair BVH over strands (paper §8.2, layout catalog §6) end to end:
//! `library/layouts/hair_bvh_strands.scion` (the hair BVH's bytes, leaves of `Segment`s) packed
//! by its generated builder from the runtime's logical tree over segments, traced by
//! `library/algorithms/closest_hit_strands.scion` (the prelude's ribbon test) through the C
//! entries, by Cranelift and LLVM -O3, on the ribbon test's hard cases and a generated head of
//! hair. Without oriented nodes the hits are the runtime's four-wide reference's over the same
//! collapse, bit for bit; with them too, except where the reference's rounding pruned brute
//! force's hit and the oriented traversal found it. The reference itself is brute force's.

use crate::c_entries;

use scion_host::entries;
use scion_host::jit::Codegen;
use scion_host::mem_interp::Program;
use scion_runtime::bvh::oriented::OrientedOptions;
use scion_runtime::bvh::schema::LogicalBytes;
use scion_runtime::bvh::wide::collapse;
use scion_runtime::bvh::{build_median, build_sah_binned, LogicalTree, SahOptions};
use scion_runtime::geom::Hit;
use scion_runtime::primitive::Segment;
use scion_runtime::reference::{closest_hit_brute, closest_hit_tree, closest_hit_wide};
use scion_runtime::scene::strands::{generate, hard_cases, StrandOptions, StrandScene};
use scion_tests::cases::{assert_packed_records, strand_rays};

fn program() -> Program {
    c_entries::program(
        &[
            "library/algorithms/closest_hit_strands.scion",
            "library/layouts/hair_bvh_strands.scion",
        ],
        "HairStrandsBVH",
        "closest_hit_strands",
    )
}

fn scenes() -> Vec<StrandScene> {
    let mut s = hard_cases();
    s.push(generate(&StrandOptions {
        strands: 600,
        segments: 12,
        ..StrandOptions::default()
    }));
    s
}

fn trees(scene: &StrandScene) -> Vec<(&'static str, LogicalTree<Segment>)> {
    let sah4 = SahOptions {
        max_leaf: 4,
        ..SahOptions::default()
    };
    let sah7 = SahOptions {
        max_leaf: 7,
        ..SahOptions::default()
    };
    vec![
        ("sah-4", build_sah_binned(&scene.segments, &sah4)),
        ("sah-7", build_sah_binned(&scene.segments, &sah7)),
        ("median", build_median(&scene.segments)),
    ]
}

#[test]
fn the_reference_over_segments_is_brute_force() {
    let (mut compared, mut differ) = (0usize, 0usize);
    for (i, scene) in scenes().iter().enumerate() {
        let rays = strand_rays(scene, i as u64);
        let brute: Vec<Hit> = rays
            .iter()
            .map(|r| closest_hit_brute(&scene.segments, r))
            .collect();
        for (name, tree) in trees(scene) {
            tree.validate_with_cap(7).unwrap();
            for (r, want) in rays.iter().zip(&brute) {
                compared += 1;
                let got = closest_hit_tree(&tree, r);
                if !got.bit_eq(want) {
                    differ += 1;
                    eprintln!(
                        "{} {name} {r:?}: tree {got:?}, brute force {want:?}",
                        scene.name
                    );
                }
            }
        }
    }
    assert!(compared > 10_000, "{compared}");
    assert!(
        differ * 1000 <= compared,
        "{differ} of {compared} differ from brute force"
    );
}

#[test]
fn hair_bvh_over_strands_is_packed_and_traced_like_the_wide_reference() {
    let lo = c_entries::host_lo(&program());
    assert_eq!(lo.entry.logical.primitive, "Segment");
    let policies = [
        ("default", OrientedOptions::default()),
        (
            "every node",
            OrientedOptions {
                max_area_ratio: f64::INFINITY,
            },
        ),
        (
            "none",
            OrientedOptions {
                max_area_ratio: 0.0,
            },
        ),
    ];
    let (mut compared, mut exceptions, mut hits) = (0usize, 0usize, 0usize);
    let mut oriented_nodes = [0usize; 3];
    for codegen in [Codegen::Cranelift, Codegen::Llvm(3)] {
        let code = codegen.backend().jit(&lo.module).unwrap();
        for (i, scene) in scenes().iter().enumerate() {
            let rays = strand_rays(scene, i as u64);
            for (kind, tree) in trees(scene) {
                if tree.is_empty() {
                    continue;
                }
                let wide = collapse::<4>(&tree);
                let want: Vec<Hit> = rays
                    .iter()
                    .map(|r| closest_hit_wide(&wide, &tree.primitives, r))
                    .collect();
                for (p, (name, policy)) in policies.iter().enumerate() {
                    let bytes =
                        LogicalBytes::fill_oriented(&tree, &lo.entry.logical, policy).unwrap();
                    let count = |kind: u32| {
                        bytes
                            .nodes()
                            .chunks(bytes.node_size)
                            .filter(|n| u32::from_le_bytes(n[..4].try_into().unwrap()) == kind)
                            .count()
                    };
                    oriented_nodes[p] += count(1);
                    // Each record group holds its own kind's records (128-byte axis-aligned,
                    // 96-byte oriented) besides the 36-byte segments and the globals.
                    let records = 128 * count(0) + 96 * count(1) + 36 * tree.primitives.len();
                    let packed = entries::pack(&lo, code.as_ref(), &tree, &bytes).unwrap();
                    assert_packed_records(
                        &format!("{} {kind} {name}", scene.name),
                        packed.bytes(),
                        records,
                    );
                    let got = c_entries::closest_hits_bytes(
                        &lo,
                        code.as_ref(),
                        &tree,
                        &bytes,
                        "closest_hit_strands",
                        &rays,
                    );
                    for (k, ((ray, got), want)) in rays.iter().zip(&got).zip(&want).enumerate() {
                        compared += 1;
                        hits += usize::from(got.is_hit());
                        if got.bit_eq(want) {
                            continue;
                        }
                        let brute = closest_hit_brute(&scene.segments, ray);
                        assert!(
                            p != 2 && got.bit_eq(&brute) && !want.bit_eq(&brute),
                            "{codegen:?} {} {kind} {name} ray {k} {ray:?}: {got:?}, the wide \
                             reference {want:?}, brute force {brute:?}",
                            scene.name
                        );
                        exceptions += 1;
                    }
                }
            }
        }
    }
    assert!(compared > 50_000, "{compared} rays");
    assert!(
        hits * 10 > compared,
        "only {hits} of {compared} rays hit a strand"
    );
    assert!(
        exceptions * 1000 <= compared,
        "{exceptions} of {compared} rays differ from brute force"
    );
    assert!(oriented_nodes[0] > 0, "{oriented_nodes:?}");
    assert!(oriented_nodes[1] > oriented_nodes[0], "{oriented_nodes:?}");
    assert_eq!(oriented_nodes[2], 0, "{oriented_nodes:?}");
    eprintln!(
        "{compared} rays ({hits} hits), {exceptions} where the oriented traversal found brute \
         force's hit and the wide reference did not; OBB nodes (default, every node, none): \
         {oriented_nodes:?}"
    );
}

#[test]
fn too_big_a_leaf_and_triangles_are_refused_with_a_reason() {
    let lo = c_entries::host_lo(&program());
    let code = Codegen::Cranelift.backend().jit(&lo.module).unwrap();
    // Twelve copies of one segment cannot be split: one leaf of 12, more than the reference's
    // 3 count bits hold. The build says so.
    let v = scion_runtime::geom::Vec3::new;
    let copies: Vec<Segment> = (0..12)
        .map(|id| Segment::new(v(0.0, 0.0, 0.0), 0.1, v(1.0, 0.0, 0.0), 0.1, id))
        .collect();
    let big = build_sah_binned(&copies, &SahOptions::default());
    assert!(big.stats().max_leaf > 7);
    let bytes = LogicalBytes::fill(&big, &lo.entry.logical).unwrap();
    let e = entries::pack(&lo, code.as_ref(), &big, &bytes)
        .err()
        .expect("a build error");
    assert!(e.contains("status 1") || e.contains("build"), "{e}");
    // A triangle tree does not fill a layout of segments.
    let tris = scion_runtime::scene::gen::one_triangle();
    let t = build_sah_binned(&tris.triangles, &SahOptions::default());
    let e = LogicalBytes::fill(&t, &lo.entry.logical).unwrap_err();
    assert!(e.contains("`Segment`") && e.contains("`Triangle`"), "{e}");
}

#[test]
fn the_emulated_gpu_pipeline_traces_strands_like_the_wide_reference() {
    use scion_host::gpu_emu::EmulatedGpu;
    use scion_host::jit::LoOptions;
    let opts = LoOptions {
        stack_size: None,
        opt_level: 3,
        dsl_opt: true,
        target: scion_compiler::abi::EntryTarget::Gpu,
    };
    let mut compared = 0usize;
    for codegen in [Codegen::Llvm(3), Codegen::Cranelift] {
        let p = EmulatedGpu::compile_program(&program(), &opts, codegen, 2)
            .and_then(EmulatedGpu::into_pipeline)
            .unwrap();
        for (i, scene) in scenes().iter().enumerate() {
            let rays = strand_rays(scene, 100 + i as u64);
            let (_, tree) = trees(scene).remove(1);
            if tree.is_empty() {
                continue;
            }
            let wide = collapse::<4>(&tree);
            let packed = p.pack(&tree, tree.stats().depth).unwrap();
            // Segments go to the device as their 36-byte records.
            assert_eq!(
                packed.sizes[1],
                36 * tree.primitives.len() as u64,
                "{:?}",
                packed.sizes
            );
            let on_device = p.upload_rays(&rays).unwrap();
            let got = p.trace(&packed, &on_device).unwrap().hits;
            for (k, (ray, got)) in rays.iter().zip(&got).enumerate() {
                compared += 1;
                let want = closest_hit_wide(&wide, &tree.primitives, ray);
                let brute = closest_hit_brute(&scene.segments, ray);
                assert!(
                    got.bit_eq(&want) || (got.bit_eq(&brute) && !want.bit_eq(&brute)),
                    "{codegen:?} {} ray {k}: {got:?}, the wide reference {want:?}",
                    scene.name
                );
            }
        }
    }
    assert!(compared > 10_000, "{compared}");
}
