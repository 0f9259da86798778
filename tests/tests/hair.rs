//! The hair BVH (paper §8.2, layout catalog §6) end to end: `library/layouts/hair_bvh.scion`, a
//! four-wide tree of three variants (axis-aligned nodes, nodes whose children share one
//! quantized orientation, leaves) behind 64-bit tagged references, packed by its generated
//! builder from the runtime's logical tree (`scion_runtime::bvh::oriented` orients the nodes)
//! and traced by `library/algorithms/closest_hit_hair.scion` through the C entries, by Cranelift
//! and LLVM -O3. Without oriented nodes the hits are the runtime's four-wide reference's over
//! the same collapse, bit for bit; with them (the default rule, and every node but the root)
//! they are too, except where the reference's rounding exception pruned brute force's hit and
//! the oriented traversal, pruning by other entry distances, found it.

use crate::c_entries;

use scion_host::jit::Codegen;
use scion_host::mem_interp::Program;
use scion_runtime::bvh::oriented::OrientedOptions;
use scion_runtime::bvh::schema::LogicalBytes;
use scion_runtime::bvh::wide::collapse;
use scion_runtime::geom::Hit;
use scion_runtime::reference::{closest_hit_brute, closest_hit_wide};
use scion_tests::cases::{hard_and_real, mixed_rays, TreeKind};

fn program() -> Program {
    c_entries::program(
        &[
            "library/algorithms/closest_hit_hair.scion",
            "library/layouts/hair_bvh.scion",
        ],
        "HairBVH",
        "closest_hit_hair",
    )
}

/// Oriented node kind in the logical nodes of `bytes` (kind 1 is `OBBNode`).
fn kinds(bytes: &LogicalBytes) -> [usize; 3] {
    let mut n = [0; 3];
    for node in bytes.nodes().chunks(bytes.node_size) {
        let k = u32::from_le_bytes(node[..4].try_into().unwrap()) as usize;
        n[k.min(2)] += 1;
    }
    n
}

#[test]
fn hair_bvh_is_packed_and_traced_like_the_wide_reference() {
    let lo = c_entries::host_lo(&program());
    let strides: Vec<(String, u64)> = lo
        .entry
        .buffers
        .iter()
        .map(|b| (b.name.clone(), b.stride))
        .collect();
    // The catalog's record sizes: 128-byte AABB nodes, 96-byte OBB nodes.
    assert!(strides.contains(&("aabb_nodes".into(), 128)), "{strides:?}");
    assert!(strides.contains(&("obb_nodes".into(), 96)), "{strides:?}");
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
    let (mut compared, mut exceptions) = (0usize, 0usize);
    let mut oriented_nodes = [0usize; 3];
    for codegen in [Codegen::Cranelift, Codegen::Llvm(3)] {
        let code = codegen.backend().jit(&lo.module).unwrap();
        for (i, scene) in hard_and_real(&["teapot", "suzanne"]).iter().enumerate() {
            // Leaves of at most 7 primitives (the reference's count bits).
            for kind in [TreeKind::Sah4, TreeKind::Median] {
                let tree = kind.build(scene);
                if tree.is_empty() {
                    continue;
                }
                let rays = mixed_rays(scene, i as u64);
                // The runtime's four-wide reference over the same collapse, nearest first.
                let wide = collapse::<4>(&tree);
                let want: Vec<Hit> = rays
                    .iter()
                    .map(|r| closest_hit_wide(&wide, &tree.primitives, r))
                    .collect();
                for (p, (name, policy)) in policies.iter().enumerate() {
                    let bytes =
                        LogicalBytes::fill_oriented(&tree, &lo.entry.logical, policy).unwrap();
                    oriented_nodes[p] += kinds(&bytes)[1];
                    let hits = c_entries::closest_hits_bytes(
                        &lo,
                        code.as_ref(),
                        &tree,
                        &bytes,
                        "closest_hit_hair",
                        &rays,
                    );
                    for (k, ((ray, got), want)) in rays.iter().zip(&hits).zip(&want).enumerate() {
                        compared += 1;
                        if got.bit_eq(want) {
                            continue;
                        }
                        // Without oriented nodes the traversal is the wide reference's. With
                        // them it prunes by other entry distances, so the rounding exception
                        // strikes elsewhere: a difference is brute force's hit, which the
                        // reference pruned.
                        let brute = closest_hit_brute(&scene.triangles, ray);
                        assert!(
                            p != 2 && got.bit_eq(&brute) && !want.bit_eq(&brute),
                            "{codegen:?} {} {kind:?} {name} ray {k} {ray:?}: {got:?}, the wide \
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
        exceptions * 1000 <= compared,
        "{exceptions} of {compared} rays differ from brute force"
    );
    // Each policy did what it says: some nodes oriented by default, more with every node,
    // none with none.
    assert!(oriented_nodes[0] > 0, "{oriented_nodes:?}");
    assert!(oriented_nodes[1] > oriented_nodes[0], "{oriented_nodes:?}");
    assert_eq!(oriented_nodes[2], 0, "{oriented_nodes:?}");
    eprintln!(
        "{compared} rays, {exceptions} where the oriented traversal found brute force's hit and \
         the wide reference did not; OBB nodes (default, every \
         node, none): {oriented_nodes:?}"
    );
}
