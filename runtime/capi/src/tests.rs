//! The C functions called as C calls them, on a real scene (`teapot`; a generated OBJ file
//! when the scenes folder is not found): the results equal the Rust runtime's, and every error is a
//! status with a message.

use super::*;
use rt::batch::BatchDriver;
use rt::bvh::{build_sah_binned, SahOptions};
use rt::query::{hits_checksum, primary_rays_n};
use rt::reference::closest_hits_tree;
use rt::scene::{load_obj, manifest::scenes_dir};
use std::ffi::{c_char, CStr, CString};
use std::path::PathBuf;

fn scene_path() -> PathBuf {
    if let Some(d) = scenes_dir() {
        return rt::scene::manifest::find("teapot").unwrap().path(&d);
    }
    eprintln!("no scenes/ folder (SCION_SCENES points elsewhere?); using a generated OBJ file");
    let p = std::env::temp_dir().join(format!("scion-capi-{}.obj", std::process::id()));
    let mut text = String::new();
    for i in 0..50 {
        let x = i as f32 * 0.1;
        text.push_str(&format!(
            "v {x} 0 0\nv {x} 1 0\nv {x} 0 1\nf {} {} {}\n",
            3 * i + 1,
            3 * i + 2,
            3 * i + 3
        ));
    }
    std::fs::write(&p, text).unwrap();
    p
}

fn msg(buf: &[c_char]) -> String {
    // SAFETY: the library NUL-terminates its messages inside the buffer.
    unsafe { CStr::from_ptr(buf.as_ptr()) }
        .to_string_lossy()
        .into_owned()
}

#[test]
fn the_c_path_matches_the_rust_path() {
    let path = scene_path();
    let cpath = CString::new(path.to_str().unwrap()).unwrap();
    let mut err = [0 as c_char; 256];
    let mut scene: *mut ScionScene = std::ptr::null_mut();
    // SAFETY: valid string, out pointer and buffer.
    let s = unsafe { scion_scene_load(cpath.as_ptr(), &mut scene, err.as_mut_ptr(), err.len()) };
    assert_eq!(s, SCION_RT_OK, "{}", msg(&err));
    let rust_scene = load_obj(&path).unwrap();
    // SAFETY: a live handle.
    assert_eq!(
        unsafe { scion_scene_triangle_count(scene) },
        rust_scene.len() as u64
    );

    let mut tree: *mut ScionTree = std::ptr::null_mut();
    // SAFETY: a live handle and an out pointer.
    let s = unsafe { scion_tree_build(scene, 0, &mut tree, err.as_mut_ptr(), err.len()) };
    assert_eq!(s, SCION_RT_OK, "{}", msg(&err));
    let rust_tree = build_sah_binned(&rust_scene.triangles, &SahOptions::default());
    let mut view = ScionTreeView {
        nodes: std::ptr::null(),
        node_count: 0,
        root: 0,
        prims: std::ptr::null(),
        prim_count: 0,
    };
    // SAFETY: a live handle and an out pointer.
    let binary = rt::bvh::schema::binary_bvh();
    let schema = ScionLogicalSchema {
        node_size: binary.node_size,
        node_align: binary.node_align,
        interior: binary.interior,
        leaf: binary.leaf,
        arity: binary.arity,
        field_count: binary.fields.len() as u32,
        fields: binary.fields.as_ptr(),
        primitive: SCION_PRIM_TRIANGLE,
    };
    // SAFETY: a live handle, a schema with its fields, and an out pointer.
    let s = unsafe { scion_tree_view(tree, &schema, &mut view, err.as_mut_ptr(), err.len()) };
    assert_eq!(s, SCION_RT_OK);
    assert_eq!(view.node_count as usize, rust_tree.nodes.len());
    assert_eq!(view.prim_count as usize, rust_tree.primitives.len());
    assert_eq!(view.root, rust_tree.root);
    let expect = rt::bvh::schema::LogicalBytes::fill(&rust_tree, &binary).unwrap();
    // SAFETY: the view points into bytes the live tree keeps.
    let nodes = unsafe { std::slice::from_raw_parts(view.nodes, expect.nodes().len()) };
    assert_eq!(nodes, expect.nodes());
    // A schema the runtime cannot fill is refused with a message.
    let bad = ScionLogicalSchema {
        node_size: 3,
        ..schema
    };
    // SAFETY: as above.
    let s = unsafe { scion_tree_view(tree, &bad, &mut view, err.as_mut_ptr(), err.len()) };
    assert_ne!(s, SCION_RT_OK);
    assert!(msg(&err).contains("node size 3"), "{}", msg(&err));

    // The same schema over blocks of four: the tree's leaves cut into `Triangle4`s, the nodes
    // those of `triangle4::block_tree` (a leaf's count in blocks), the triangle view unchanged.
    let blocks = rt::triangle4::block_tree(&rust_tree).unwrap();
    let over_blocks = ScionLogicalSchema {
        primitive: SCION_PRIM_TRIANGLE4,
        ..schema
    };
    let mut bview = view;
    // SAFETY: as above.
    let s = unsafe { scion_tree_view(tree, &over_blocks, &mut bview, err.as_mut_ptr(), err.len()) };
    assert_eq!(s, SCION_RT_OK, "{}", msg(&err));
    assert_eq!(bview.prim_count as usize, blocks.primitives.len());
    assert!(bview.prim_count < view.prim_count);
    let mut block_schema = binary.clone();
    block_schema.primitive = "Triangle4".to_string();
    let expect = rt::bvh::schema::LogicalBytes::fill(&blocks, &block_schema).unwrap();
    // SAFETY: the view points into bytes the live tree keeps.
    let nodes = unsafe { std::slice::from_raw_parts(bview.nodes, expect.nodes().len()) };
    assert_eq!(nodes, expect.nodes());
    // SAFETY: `prims` holds `prim_count` blocks of 160 bytes.
    let prims = unsafe {
        std::slice::from_raw_parts(
            bview.prims.cast::<rt::Triangle4>(),
            bview.prim_count as usize,
        )
    };
    assert_eq!(prims, &blocks.primitives[..]);
    // Strands, and a primitive the runtime does not know, are refused with a message.
    for (primitive, says) in [(SCION_PRIM_SEGMENT, "ScionSegment"), (7, "primitive is 7")] {
        let bad = ScionLogicalSchema {
            primitive,
            ..schema
        };
        // SAFETY: as above.
        let s = unsafe { scion_tree_view(tree, &bad, &mut bview, err.as_mut_ptr(), err.len()) };
        assert_ne!(s, SCION_RT_OK);
        assert!(msg(&err).contains(says), "{}", msg(&err));
    }

    let n = 3001u64;
    let mut rays = vec![ScionRay::default(); n as usize];
    // SAFETY: `rays` has room for `n`.
    let s =
        unsafe { scion_primary_rays(scene, n, 7, rays.as_mut_ptr(), err.as_mut_ptr(), err.len()) };
    assert_eq!(s, SCION_RT_OK, "{}", msg(&err));
    let rust_rays = primary_rays_n(rust_scene.bounds(), n, 7).unwrap();
    assert!(rays
        .iter()
        .zip(&rust_rays)
        .all(|(a, b)| *a == ScionRay::from(*b)));

    let mut hits = vec![ScionHit::default(); n as usize];
    // SAFETY: `rays` and `hits` hold `n` elements.
    let s = unsafe {
        scion_reference_closest_hits(
            tree,
            rays.as_ptr(),
            n,
            2,
            hits.as_mut_ptr(),
            err.as_mut_ptr(),
            err.len(),
        )
    };
    assert_eq!(s, SCION_RT_OK, "{}", msg(&err));
    let want = closest_hits_tree(&rust_tree, &rust_rays, &BatchDriver::new(2).unwrap());
    assert!(hits
        .iter()
        .zip(&want)
        .all(|(h, w)| h.t.to_bits() == w.t.to_bits() && h.prim == w.prim));
    assert!(hits.iter().any(|h| h.prim != u32::MAX), "no hits");
    // SAFETY: `hits` holds `n` hits.
    assert_eq!(
        unsafe { scion_hits_checksum(hits.as_ptr(), n) },
        hits_checksum(&want)
    );

    let miss = scion_hit_from_best(5.0, u32::MAX);
    assert_eq!((miss.t, miss.prim), (f32::INFINITY, u32::MAX));
    assert_eq!(scion_hit_from_best(2.5, 3), ScionHit { t: 2.5, prim: 3 });

    // SAFETY: live handles, freed once; NULL is allowed.
    unsafe {
        scion_tree_free(tree);
        scion_scene_free(scene);
        scion_tree_free(std::ptr::null_mut());
        scion_scene_free(std::ptr::null_mut());
    }
}

#[test]
fn errors_are_statuses_with_messages() {
    let mut err = [0 as c_char; 256];
    let mut scene: *mut ScionScene = std::ptr::null_mut();
    let missing = CString::new("/nonexistent/scene.obj").unwrap();
    // SAFETY: valid arguments; the file does not exist.
    let s = unsafe { scion_scene_load(missing.as_ptr(), &mut scene, err.as_mut_ptr(), err.len()) };
    assert_eq!(s, SCION_RT_ERR_SCENE);
    assert!(
        msg(&err).contains("/nonexistent/scene.obj"),
        "{}",
        msg(&err)
    );
    assert!(scene.is_null());
    // SAFETY: NULL arguments are reported, never dereferenced.
    let s = unsafe { scion_scene_load(std::ptr::null(), &mut scene, err.as_mut_ptr(), err.len()) };
    assert_eq!(s, SCION_RT_ERR_ARGUMENT);
    assert!(msg(&err).contains("NULL"));
    let mut tree: *mut ScionTree = std::ptr::null_mut();
    // SAFETY: as above.
    let s = unsafe { scion_tree_build(std::ptr::null(), 0, &mut tree, std::ptr::null_mut(), 0) };
    assert_eq!(s, SCION_RT_ERR_ARGUMENT);
    // SAFETY: NULL hits are the empty list.
    assert_eq!(
        unsafe { scion_hits_checksum(std::ptr::null(), 5) },
        hits_checksum(&[])
    );
}

#[test]
fn closest_points_and_collision_match_the_rust_path() {
    use rt::reference::closest_point::closest_point_brute;
    use rt::reference::collide::{collide_sweep, rotated};
    let path = scene_path();
    let cpath = CString::new(path.to_str().unwrap()).unwrap();
    let mut err = [0 as c_char; 256];
    let mut scene: *mut ScionScene = std::ptr::null_mut();
    // SAFETY: valid string, out pointer and buffer.
    let s = unsafe { scion_scene_load(cpath.as_ptr(), &mut scene, err.as_mut_ptr(), err.len()) };
    assert_eq!(s, SCION_RT_OK, "{}", msg(&err));
    let rust = load_obj(&path).unwrap();

    // Points uniform in the box, and their closest points by brute force.
    let n = 300usize;
    let mut points = vec![0f32; 3 * n];
    // SAFETY: room for `n` points.
    let s = unsafe {
        scion_uniform_points(
            scene,
            n as u64,
            5,
            points.as_mut_ptr(),
            err.as_mut_ptr(),
            err.len(),
        )
    };
    assert_eq!(s, SCION_RT_OK, "{}", msg(&err));
    let b = rust.bounds();
    let want_points = rt::query::points::uniform_points(b.low, b.high, n, 5);
    let flat: Vec<f32> = want_points.iter().flat_map(|p| p.to_array()).collect();
    assert_eq!(points, flat);
    let mut out = vec![ScionClosestPoint::default(); n];
    // SAFETY: `points` and `out` hold `n` elements.
    let s = unsafe {
        scion_reference_closest_points(
            scene,
            points.as_ptr(),
            n as u64,
            2,
            out.as_mut_ptr(),
            err.as_mut_ptr(),
            err.len(),
        )
    };
    assert_eq!(s, SCION_RT_OK, "{}", msg(&err));
    for (o, p) in out.iter().zip(&want_points) {
        let w = closest_point_brute(&rust.triangles, *p, f32::INFINITY);
        assert_eq!(
            (o.distance.to_bits(), o.prim, o.point),
            (w.distance.to_bits(), w.prim, w.point.to_array())
        );
    }

    // The rotated copy and the pairs, through a sink too small at first.
    let mut copy: *mut ScionScene = std::ptr::null_mut();
    // SAFETY: a live handle and an out pointer.
    let s = unsafe {
        scion_scene_rotated(
            scene,
            60.0,
            70.0,
            10.0,
            &mut copy,
            err.as_mut_ptr(),
            err.len(),
        )
    };
    assert_eq!(s, SCION_RT_OK, "{}", msg(&err));
    let want = collide_sweep(
        &rust.triangles,
        &rotated(&rust.triangles, [60.0, 70.0, 10.0]),
    );
    assert!(!want.is_empty());
    let mut count = 0u64;
    let mut pairs = vec![[0u32; 2]; 2];
    // SAFETY: live handles; `pairs` has room for 2.
    let s = unsafe {
        scion_reference_collide(
            scene,
            copy,
            pairs.as_mut_ptr(),
            2,
            &mut count,
            err.as_mut_ptr(),
            err.len(),
        )
    };
    assert_eq!(s, SCION_RT_OK, "{}", msg(&err));
    assert_eq!(count, want.len() as u64);
    pairs.resize(count as usize, [0; 2]);
    // SAFETY: as above, `pairs` now has room for all.
    let s = unsafe {
        scion_reference_collide(
            scene,
            copy,
            pairs.as_mut_ptr(),
            count,
            &mut count,
            err.as_mut_ptr(),
            err.len(),
        )
    };
    assert_eq!(s, SCION_RT_OK, "{}", msg(&err));
    let got: Vec<(u32, u32)> = pairs.iter().map(|p| (p[0], p[1])).collect();
    assert_eq!(got, want);
    // Bad arguments are statuses with messages.
    // SAFETY: NULL is reported, never dereferenced.
    let s = unsafe {
        scion_reference_collide(
            scene,
            std::ptr::null(),
            pairs.as_mut_ptr(),
            1,
            &mut count,
            err.as_mut_ptr(),
            err.len(),
        )
    };
    assert_eq!(s, SCION_RT_ERR_ARGUMENT);
    assert!(msg(&err).contains("must not be NULL"), "{}", msg(&err));
    // SAFETY: as above.
    let s = unsafe {
        scion_scene_rotated(
            scene,
            f64::NAN,
            0.0,
            0.0,
            &mut copy,
            err.as_mut_ptr(),
            err.len(),
        )
    };
    assert_eq!(s, SCION_RT_ERR_ARGUMENT);
    // SAFETY: live handles, freed once.
    unsafe {
        scion_scene_free(copy);
        scion_scene_free(scene);
    }
}
