//! The host side of the runtime contract with a hand-written layout: buffers are allocated once
//! per plan entry, aligned and exactly sized; a build status and a traversal stack overflow
//! are errors naming the status and the first failing ray; the empty tree never reaches code.

use crate::common;

use common::{Flat32, STACK};
use scion_host::contract::{
    Best, BufferSpec, LayoutCode, LogicalInput, Packed, TraceFailure, STATUS_STACK_OVERFLOW,
};
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::{build_sah_binned, LogicalTree, SahOptions};
use scion_runtime::geom::{Ray, Vec3};
use scion_runtime::reference::{closest_hit_tree_stats, closest_hits_tree, TraversalStats};
use scion_runtime::scene::gen;

#[test]
fn buffers_are_sized_aligned_and_hits_match_the_reference() {
    let scene = gen::random_soup(300, 0.1, 5);
    let tree = build_sah_binned(&scene.triangles, &SahOptions::default());
    let packed = Packed::new(&Flat32, &tree).unwrap();
    let bufs = packed.buffers();
    assert_eq!(bufs.len(), 2);
    assert_eq!(bufs[0].len(), 32 * tree.nodes.len());
    assert_eq!(bufs[1].len(), 40 * tree.primitives.len());
    assert_eq!(packed.bytes(), bufs[0].len() + bufs[1].len());
    for (b, spec) in bufs.iter().zip(&packed.specs) {
        assert_eq!(b.as_ptr() as usize % spec.align, 0, "{}", spec.name);
    }
    let rays = scion_runtime::query::secondary_rays(scene.bounds(), 500, 3);
    let driver = BatchDriver::new(2).unwrap();
    let got = packed.trace(&Flat32, &rays, &driver).unwrap();
    let want = closest_hits_tree(&tree, &rays, &driver);
    assert!(got.iter().zip(&want).all(|(g, w)| g.bit_eq(w)));
    assert!(got.iter().any(|h| h.is_hit()));
}

#[test]
fn a_stack_overflow_names_the_first_failing_ray() {
    // A chain of triangles shrinking toward the origin gives a tree deeper than the stack; a
    // ray along the chain from its small end pushes the far child at every level before it
    // hits anything (the reference counts the entries it leaves pending).
    let scene = gen::deep_chain(1000, 0.5);
    let opts = SahOptions {
        max_leaf: 4,
        ..SahOptions::default()
    };
    let tree = build_sah_binned(&scene.triangles, &opts);
    let packed = Packed::new(&Flat32, &tree).unwrap();
    let along = Ray::new(Vec3::new(-1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0));
    let mut stats = TraversalStats::default();
    closest_hit_tree_stats(&tree, &along, &mut stats);
    assert!(stats.max_pending as usize > STACK, "{stats:?}");
    // 200 rays that miss the root's box (the chain spans y in about ±6e29), except rays 150
    // and 190.
    let away = Ray::new(Vec3::new(0.0, -1e31, 0.0), Vec3::new(1.0, 0.0, 0.0));
    let mut rays = vec![away; 200];
    rays[150] = along;
    rays[190] = along;
    let driver = BatchDriver::new(2).unwrap();
    let e = packed.trace(&Flat32, &rays, &driver).unwrap_err();
    assert_eq!(
        e,
        TraceFailure {
            ray: 150,
            status: STATUS_STACK_OVERFLOW
        }
    );
    let text = e.to_string();
    assert!(
        text.starts_with("ray 150: traversal stack overflow"),
        "{text}"
    );
    // Without the deep ray the same batch succeeds.
    let ok = packed.trace(&Flat32, &rays[..150], &driver).unwrap();
    assert!(ok.iter().all(|h| !h.is_hit()));
}

/// A layout whose build always fails.
struct Refuses;

impl LayoutCode for Refuses {
    fn layout(&self) -> String {
        "refuses".into()
    }
    fn buffers(&self) -> Vec<BufferSpec> {
        vec![BufferSpec {
            name: "all".into(),
            align: 64,
        }]
    }
    fn sizes(&self, input: &LogicalInput<'_>, sizes: &mut [u64]) {
        sizes[0] = input.tree.nodes.len() as u64;
    }
    fn build(&self, _: &LogicalInput<'_>, buffers: &mut [&mut [u8]]) -> i32 {
        assert_eq!(buffers[0].as_ptr() as usize % 64, 0);
        3
    }
    fn batch(&self, _: &[&[u8]], _: &[Ray], _: &mut [Best]) -> i32 {
        panic!("never called after a failed build")
    }
}

#[test]
fn build_statuses_and_the_empty_tree() {
    let scene = gen::one_triangle();
    let tree = build_sah_binned(&scene.triangles, &SahOptions::default());
    let e = Packed::new(&Refuses, &tree).err().expect("build fails");
    assert!(e.contains("@refuses.build failed with status 3"), "{e}");

    // The empty tree packs nothing and every ray misses, without calling the code.
    let packed = Packed::new(
        &Refuses,
        &LogicalTree::<scion_runtime::geom::Triangle>::empty(),
    )
    .unwrap();
    assert_eq!(packed.bytes(), 0);
    let rays = [Ray::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0))];
    let hits = packed
        .trace(&Refuses, &rays, &BatchDriver::sequential())
        .unwrap();
    assert!(!hits[0].is_hit());
}

/// The tree header matches the offsets of design note §3.1 on 64-bit targets.
#[test]
#[cfg(target_pointer_width = "64")]
fn logical_tree_view_abi() {
    use scion_host::contract::LogicalTreeView;
    use scion_runtime::bvh::schema::{binary_bvh, LogicalBytes};
    use scion_runtime::geom::Triangle;
    use std::mem::{offset_of, size_of};
    assert_eq!(size_of::<LogicalTreeView>(), 32);
    assert_eq!(offset_of!(LogicalTreeView, nodes), 0);
    assert_eq!(offset_of!(LogicalTreeView, node_count), 8);
    assert_eq!(offset_of!(LogicalTreeView, root), 12);
    assert_eq!(offset_of!(LogicalTreeView, prims), 16);
    assert_eq!(offset_of!(LogicalTreeView, prim_count), 24);
    assert_eq!(size_of::<Triangle>(), 40);
    let scene = gen::one_triangle();
    let tree = build_sah_binned(&scene.triangles, &SahOptions::default());
    let bytes = LogicalBytes::fill(&tree, &binary_bvh()).unwrap();
    let v = LogicalTreeView::new(&tree, &bytes).unwrap();
    assert_eq!((v.node_count, v.root, v.prim_count), (1, 0, 1));
    assert_eq!(v.nodes, bytes.nodes().as_ptr());
}
