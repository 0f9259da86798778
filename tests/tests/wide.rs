//! Layouts whose nodes have arrays of children (`BVH4[4]`, `BVH8[8]`) through the JITs: the
//! runtime collapses its binary tree to their width, the generated builder packs it, and the
//! closest hit of LLVM's and Cranelift's code (the recursion over the children turned into a
//! loop over an explicit stack with deferred calls) is bit-identical to the runtime's wide
//! reference over the same collapsed tree (`reference::closest_hit_wide`), on the hard cases
//! and on real scenes, over SAH trees with leaves of 15 and of 4. (The binary traversal can
//! differ on rays grazing a box whose parent the rounding of the slab test misses: the wide
//! tree skips that parent's box.)

use scion_host::contract::{LayoutCode, Packed};
use scion_host::jit::{Codegen, JitClosestHit, JIT_OPT_LEVEL};
use scion_host::mem_interp::Program;
use scion_host::quantized::Boxes;
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::wide::collapse;
use scion_runtime::geom::Hit;
use scion_runtime::reference::closest_hit_wide;
use scion_runtime::scene::gen;
use scion_tests::cases::{real_scene, RayKind, TreeKind};
use std::path::PathBuf;

/// (input file under lit-tests/Inputs, layout, algorithm, bytes of a record, width, whether
/// every node has a record (else interior nodes only, leaves being references)).
const PROGRAMS: [(&str, &str, &str, usize, usize, bool); 2] = [
    (
        "bvh8_aos_layout.scion",
        "Bvh8Aos",
        "closest_hit8",
        224,
        8,
        false,
    ),
    ("wide4_layout.scion", "Wide4", "closest_hit4", 48, 4, true),
];

/// Records a layout places for `tree` collapsed to `width`: its interior nodes, or every node
/// (interior nodes, leaves and the empty leaf of each empty slot).
fn records(tree: &scion_runtime::bvh::LogicalTree, width: usize, every_node: bool) -> usize {
    let interior = match width {
        4 => collapse::<4>(tree).nodes.len(),
        _ => collapse::<8>(tree).nodes.len(),
    };
    match (every_node, interior) {
        (false, n) => n,
        (true, 0) => usize::from(!tree.is_empty()),
        // Every slot holds a node, and every node but the root sits in a slot.
        (true, n) => n * width + 1,
    }
}

/// The wide reference's hits over `tree` collapsed to `width` children, over the boxes the
/// layout stores (decoded with codes up to `quantized` when it quantizes per node).
fn wide_reference(
    tree: &scion_runtime::bvh::LogicalTree,
    rays: &[scion_runtime::geom::Ray],
    width: usize,
    quantized: Option<u32>,
) -> Vec<Hit> {
    match width {
        4 => {
            let w = collapse::<4>(tree);
            rays.iter()
                .map(|r| closest_hit_wide(&w, &tree.primitives, r))
                .collect()
        }
        8 => {
            let exact = collapse::<8>(tree);
            let boxes = match quantized {
                Some(255) => Boxes::NodeQ8,
                Some(_) => Boxes::NodeQ16,
                None => Boxes::Exact,
            };
            let w = scion_host::quantized::decoded_wide(boxes, &exact);
            rays.iter()
                .map(|r| closest_hit_wide(&w, &tree.primitives, r))
                .collect()
        }
        _ => panic!("no wide reference of width {width}"),
    }
}

fn program(file: &str, layout: &str, algorithm: &str) -> Program {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../lit-tests/Inputs")
        .join(file);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    Program {
        files: vec![(file.to_string(), text)],
        layout: layout.to_string(),
        algorithm: algorithm.to_string(),
    }
}

/// A wide layout and its closest hit, with what the test checks of its packing.
struct Wide {
    program: Program,
    /// Bytes of one record of its node group.
    node_bytes: usize,
    /// Children per node.
    width: usize,
    /// Whether every node (leaves too) has a record.
    every_node: bool,
    /// The largest code of a layout quantizing per node (`None`: exact boxes).
    code_max: Option<u32>,
}

/// Every library layout of `BVH8` (the registry's: a new file joins without an edit), with its
/// record size from the compiled entries' buffer plan, and the other shapes of `lit-tests/Inputs`
/// (an array-of-structures eight-wide node, a four-wide tree with records for every node).
fn wide_programs() -> Vec<Wide> {
    let mut out = Vec::new();
    for &(stem, _) in scion_host::library::LAYOUT_FILES {
        let Ok(r) = scion_host::library::resolve(stem, None) else {
            continue;
        };
        if r.tree_type != "BVH8" {
            continue;
        }
        let lo = scion_host::jit::program_lo(
            &r.program,
            &scion_host::jit::LoOptions {
                stack_size: Some(512),
                opt_level: JIT_OPT_LEVEL,
                dsl_opt: true,
                target: scion_compiler::abi::EntryTarget::Host,
            },
        )
        .unwrap_or_else(|e| panic!("{stem}: {e}"));
        let nodes = lo.entry.buffers.iter().find(|b| b.name == "nodes");
        let node_bytes = nodes
            .unwrap_or_else(|| panic!("{stem}: no nodes buffer"))
            .stride;
        // How the registry says the layout stores boxes (read from its builds), against what
        // its name says.
        let code_max = r.boxes.node_codes();
        let named = if stem.contains("_q8") {
            Some(255)
        } else if stem.contains("_q16") {
            Some(65535)
        } else {
            None
        };
        assert_eq!(code_max, named, "{stem}: {:?}", r.boxes);
        out.push(Wide {
            program: r.program,
            node_bytes: node_bytes as usize,
            width: 8,
            every_node: false,
            code_max,
        });
    }
    assert_eq!(out.len(), 10, "Table 1's ten eight-wide layouts");
    for (file, layout, algorithm, node_bytes, width, every_node) in PROGRAMS {
        out.push(Wide {
            program: program(file, layout, algorithm),
            node_bytes,
            width,
            every_node,
            code_max: None,
        });
    }
    out
}

#[test]
fn wide_layouts_match_the_wide_reference() {
    let driver = BatchDriver::new(2).unwrap();
    let mut scenes = gen::hard_cases();
    // Real scenes (as the differential rows: the repository's `scenes/` or `SCION_SCENES`).
    for name in ["teapot", "pine"] {
        scenes.push(real_scene(name).unwrap_or_else(|e| panic!("real scene {name}: {e}")));
    }
    for w in wide_programs() {
        let (layout, node_bytes, width, every_node) = (
            w.program.layout.as_str(),
            w.node_bytes,
            w.width,
            w.every_node,
        );
        for codegen in [Codegen::Cranelift, Codegen::Llvm(3)] {
            let code = JitClosestHit::compile_program(
                &w.program,
                // Unordered visits push up to width - 1 entries per level, and some hard
                // cases are deep; a stack too small is reported (the error names the ray).
                Some(512),
                JIT_OPT_LEVEL,
                true,
                codegen,
            )
            .unwrap_or_else(|e| panic!("{layout} {codegen:?}: {e}"));
            // The deferred calls push every child of a node: no depth bound is claimed.
            assert_eq!(code.stack_limit(), None, "{layout}");
            let mut hits = 0;
            for (i, scene) in scenes.iter().enumerate() {
                for kind in [TreeKind::Sah15, TreeKind::Sah4] {
                    let tree = kind.build(scene);
                    let mut rays = RayKind::Secondary.rays(scene, 300, i as u64);
                    rays.extend(RayKind::Axis.rays(scene, 100, i as u64));
                    rays.extend(RayKind::Features.rays(scene, 200, 0));
                    let want = wide_reference(&tree, &rays, width, w.code_max);
                    let packed = Packed::new(&code, &tree)
                        .unwrap_or_else(|e| panic!("{layout} {codegen:?} scene {i}: {e}"));
                    if !tree.is_empty() {
                        // The node buffer holds exactly the records placed (an indirect group
                        // is sized by the nodes of the variants that reach it).
                        let want = node_bytes * records(&tree, width, every_node);
                        let sizes: Vec<usize> = packed.buffers().iter().map(|b| b.len()).collect();
                        assert!(
                            sizes.contains(&want),
                            "{layout} scene {i}: no buffer of {want} bytes: {sizes:?}"
                        );
                    }
                    let got = packed
                        .trace(&code, &rays, &driver)
                        .unwrap_or_else(|e| panic!("{layout} {codegen:?} scene {i}: {e}"));
                    for (k, (g, w)) in got.iter().zip(&want).enumerate() {
                        assert!(
                            g.bit_eq(w),
                            "{layout} {codegen:?} scene {i} {kind:?} ray {k} {:?}: got {g:?}, \
                             reference {w:?}, brute force {:?}",
                            rays[k],
                            (
                                scion_runtime::reference::closest_hit_brute(
                                    &scene.triangles,
                                    &rays[k]
                                ),
                                scion_runtime::reference::why_pruned(&tree, &rays[k], g.prim, g.t)
                            )
                        );
                    }
                    hits += got.iter().filter(|h| h.is_hit()).count();
                }
            }
            assert!(hits > 1000, "{layout} {codegen:?}: only {hits} hits");
        }
    }
}

/// A tree beyond a Table 1 layout's reference fields is refused with the layout's name, not
/// packed wrong: the compressed-index layouts keep a leaf's count in 4 bits of a 32-bit
/// reference (layout catalog §4: 28 bits of index, 4 of count), so a leaf of 16 triangles
/// does not fit them, while `bvh8` (a 32-bit count) takes it and traces it like the reference.
#[test]
fn a_leaf_beyond_a_layouts_count_bits_is_refused_by_its_build() {
    use scion_runtime::bvh::{build_sah_binned, SahOptions};
    use scion_runtime::geom::{Ray, Triangle, Vec3};
    // Sixteen copies of one triangle: no split separates them, so with leaves of up to 16 the
    // SAH builder makes one leaf of 16.
    let v = Vec3::new;
    let tris: Vec<Triangle> = (0..16)
        .map(|id| Triangle::new(v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0), id))
        .collect();
    let opts = SahOptions {
        max_leaf: 16,
        ..SahOptions::default()
    };
    let tree = build_sah_binned(&tris, &opts);
    assert_eq!(tree.stats().max_leaf, 16);
    let driver = BatchDriver::new(1).unwrap();
    for (stem, fits) in [
        ("bvh8_q8_ci", false),
        ("bvh8_q16_ci_align16", false),
        ("bvh8", true),
    ] {
        let r = scion_host::library::resolve(stem, None).unwrap();
        let code = JitClosestHit::compile_program(
            &r.program,
            Some(512),
            JIT_OPT_LEVEL,
            true,
            Codegen::Cranelift,
        )
        .unwrap_or_else(|e| panic!("{stem}: {e}"));
        match Packed::new(&code, &tree) {
            Err(e) => {
                assert!(!fits, "{stem}: {e}");
                assert!(
                    e.contains(&format!("does not fit layout `{}`", r.program.layout)),
                    "{stem}: {e}"
                );
            }
            Ok(packed) => {
                assert!(fits, "{stem} packed a leaf of 16 into a 4-bit count");
                // The ray through the triangles' interior hits the one with the smallest id.
                let ray = Ray::new(v(0.25, 0.25, 1.0), v(0.0, 0.0, -1.0));
                let hits = packed.trace(&code, &[ray], &driver).unwrap();
                assert_eq!(hits, vec![Hit { t: 1.0, prim: 0 }], "{stem}");
            }
        }
    }
}
