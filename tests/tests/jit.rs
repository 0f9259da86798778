//! The JIT of each library layout through the runtime contract: buffer sizes per node as the
//! layout catalog says (pbrt 32 bytes, ptr 48), hits bit-identical to the reference, and a
//! traversal stack smaller than the tree reported as a stack overflow naming the first ray.

use scion_host::contract::{Best, LayoutCode, Packed, TraceFailure, STATUS_STACK_OVERFLOW};
use scion_host::jit::JitClosestHit;
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::{build_caterpillar, build_sah_binned, DeepSide, LogicalTree, SahOptions};
use scion_runtime::geom::{Ray, Vec3};
use scion_runtime::reference::{closest_hit_tree_stats, closest_hits_tree, TraversalStats};
use scion_runtime::scene::{gen, Scene};

#[test]
fn jit_layouts_pack_to_their_sizes_and_match_the_reference() {
    let scene = gen::random_soup(500, 0.1, 11);
    let tree = build_sah_binned(&scene.triangles, &SahOptions::default());
    let rays = scion_runtime::query::secondary_rays(scene.bounds(), 700, 5);
    let driver = BatchDriver::new(2).unwrap();
    let want = closest_hits_tree(&tree, &rays, &driver);
    for (stem, name, node_bytes) in [("pbrt", "LinearBVH", 32), ("ptr", "PtrBVH", 48)] {
        let code = JitClosestHit::compile(stem, name, None).unwrap();
        assert_eq!(code.layout(), name);
        let packed = Packed::new(&code, &tree).unwrap();
        let bufs = packed.buffers();
        let prims = 40 * tree.primitives.len();
        assert!(
            bufs.iter()
                .any(|b| b.len() == node_bytes * tree.nodes.len()),
            "{stem}: no buffer of {node_bytes} bytes per node: {:?}",
            bufs.iter().map(|b| b.len()).collect::<Vec<_>>()
        );
        assert!(bufs.iter().any(|b| b.len() == prims), "{stem}: primitives");
        for b in &bufs {
            assert_eq!(b.as_ptr() as usize % 64, 0);
        }
        let got = packed.trace(&code, &rays, &driver).unwrap();
        let same = got.iter().zip(&want).filter(|(g, w)| g.bit_eq(w)).count();
        assert_eq!(same, rays.len(), "{stem}: hits differ from the reference");
        assert!(got.iter().any(|h| h.is_hit()), "{stem}: no hits");
    }
}

/// The entries the reference traversal leaves pending at most for `ray`: a generated traversal
/// with a smaller stack overflows on it, one with at least that many does not.
fn pending(tree: &LogicalTree, ray: &Ray) -> u32 {
    let mut stats = TraversalStats::default();
    closest_hit_tree_stats(tree, ray, &mut stats);
    stats.max_pending as u32
}

/// A caterpillar tree (every interior node has a leaf on one side) over random triangles, and
/// the ray of 2000 random ones that leaves the most entries pending (near-first traversal
/// prunes most of a deep tree, so few rays need more than one or two).
fn deep_tree_and_ray() -> (Scene, LogicalTree, Ray) {
    let scene = gen::random_soup(64, 0.1, 9);
    let tree = build_caterpillar(&scene.triangles, DeepSide::Left);
    let rays = scion_runtime::query::secondary_rays(scene.bounds(), 2000, 3);
    let ray = *rays.iter().max_by_key(|r| pending(&tree, r)).expect("rays");
    (scene, tree, ray)
}

#[test]
fn a_small_stack_overflows_on_a_deep_tree_and_names_the_ray() {
    let (_, tree, deep) = deep_tree_and_ray();
    let away = Ray::new(Vec3::new(1e3, 1e3, 1e3), Vec3::new(1.0, 0.0, 0.0));
    let mut rays = vec![away; 200];
    rays[137] = deep;
    rays[180] = deep;
    let need = pending(&tree, &deep);
    assert!(need >= 2, "the ray leaves {need} entries pending");
    let driver = BatchDriver::new(2).unwrap();
    for (stem, name) in [("pbrt", "LinearBVH"), ("ptr", "PtrBVH")] {
        let code = JitClosestHit::compile(stem, name, Some(need - 1)).unwrap();
        assert_eq!(code.stack_limit(), Some(need as usize));
        let packed = Packed::new(&code, &tree).unwrap();
        let e = packed.trace(&code, &rays, &driver).unwrap_err();
        assert_eq!(
            e,
            TraceFailure {
                ray: 137,
                status: STATUS_STACK_OVERFLOW
            },
            "{stem}"
        );
        // A stack of exactly `need` entries holds the same traversal: the hits are the
        // reference's.
        let code = JitClosestHit::compile(stem, name, Some(need)).unwrap();
        let packed = Packed::new(&code, &tree).unwrap();
        let got = packed.trace(&code, &rays, &driver).unwrap();
        let want = closest_hits_tree(&tree, &rays, &driver);
        assert!(got.iter().zip(&want).all(|(g, w)| g.bit_eq(w)), "{stem}");
    }
}

#[test]
fn unknown_layouts_and_bad_stack_sizes_are_errors() {
    let e = JitClosestHit::compile("nope", "X", None).err().unwrap();
    assert!(e.contains("no library layout"), "{e}");
    let e = JitClosestHit::compile("pbrt", "NoSuchLayout", None)
        .err()
        .unwrap();
    assert!(e.contains("NoSuchLayout"), "{e}");
    let e = JitClosestHit::compile("pbrt", "LinearBVH", Some(0))
        .err()
        .unwrap();
    assert!(e.contains("stack"), "{e}");
}

/// The generated batch entry traces queries in order and stops at the first nonzero status,
/// leaving that query's result as the caller initialized it.
#[test]
fn the_batch_entry_stops_at_the_first_overflow() {
    let (_, tree, deep) = deep_tree_and_ray();
    let away = Ray::new(Vec3::new(1e3, 1e3, 1e3), Vec3::new(1.0, 0.0, 0.0));
    let mut rays = vec![away; 6];
    rays[3] = deep;
    let code = JitClosestHit::compile("ptr", "PtrBVH", Some(pending(&tree, &rays[3]) - 1)).unwrap();
    let packed = Packed::new(&code, &tree).unwrap();
    let mut results = vec![Best { t: 7.0, id: 9 }; 6];
    let status = code.batch(&packed.buffers(), &rays, &mut results);
    assert_eq!(status, STATUS_STACK_OVERFLOW);
    // Queries 0-2 missed (their records are kept as given: nothing closer than t = 7 was
    // found), query 3 overflowed and the batch stopped there.
    assert!(results.iter().all(|&r| r == Best { t: 7.0, id: 9 }));
    let mut one = vec![
        Best {
            t: f32::INFINITY,
            id: u32::MAX
        };
        3
    ];
    assert_eq!(code.batch(&packed.buffers(), &rays[..3], &mut one), 0);
    assert!(one.iter().all(|&r| r.id == u32::MAX));
}
