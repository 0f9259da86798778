//! Transforms and instancing on a real scene: a rotated copy traced with rotated rays sees the
//! same hits (up to rounding), and instanced scenes build valid trees.

use crate::common;

use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::{build_sah_binned, SahOptions};
use scion_runtime::geom::{Ray, Vec3};
use scion_runtime::query::secondary_rays;
use scion_runtime::reference::closest_hits_tree;
use scion_runtime::scene::transform::grid_instances;
use scion_runtime::scene::{instances, load_obj, Transform};

#[test]
fn rotated_scene_and_rotated_rays_see_the_same_triangles() {
    let Some(dir) = common::scenes_dir() else {
        return;
    };
    let scene = load_obj(
        scion_runtime::scene::manifest::find("teapot")
            .unwrap()
            .path(&dir),
    )
    .unwrap();
    let rot = Transform {
        rotate_deg: [35.0, 22.0, 47.0],
        scale: 2.0,
        translate: [10.0, -3.0, 7.0],
    };
    let moved = rot.apply_scene(&scene);
    assert_eq!(moved.len(), scene.len());
    let driver = BatchDriver::sequential();
    let rays = secondary_rays(scene.bounds(), 400, 8);
    let moved_rays: Vec<Ray> = rays
        .iter()
        .map(|r| {
            let o = rot.apply(r.origin);
            let d = rot.apply(r.origin + r.dir) - o;
            Ray::new(o, d)
        })
        .collect();
    let a = closest_hits_tree(
        &build_sah_binned(&scene.triangles, &SahOptions::default()),
        &rays,
        &driver,
    );
    let b = closest_hits_tree(
        &build_sah_binned(&moved.triangles, &SahOptions::default()),
        &moved_rays,
        &driver,
    );
    let same = a.iter().zip(&b).filter(|(x, y)| x.prim == y.prim).count();
    // Rounding of the moved coordinates may flip rays that graze an edge.
    assert!(
        same >= rays.len() * 97 / 100,
        "{same} of {} agree",
        rays.len()
    );
    for (x, y) in a.iter().zip(&b) {
        if x.is_hit() && x.prim == y.prim {
            // Distances are in units of the (scaled) direction: equal up to rounding.
            assert!((x.t - y.t).abs() <= 1e-3 * x.t.max(1.0), "{x:?} vs {y:?}");
        }
    }
}

#[test]
fn instances_build_valid_trees() {
    let Some(dir) = common::scenes_dir() else {
        return;
    };
    let scene = load_obj(
        scion_runtime::scene::manifest::find("pine")
            .unwrap()
            .path(&dir),
    )
    .unwrap();
    let many = grid_instances(&scene, 8).unwrap();
    assert_eq!(many.len(), 8 * scene.len());
    let tree = build_sah_binned(&many.triangles, &SahOptions::default());
    tree.validate().unwrap();
    let two = instances(
        &scene,
        &[Transform::IDENTITY, Transform::translation(100.0, 0.0, 0.0)],
    )
    .unwrap();
    assert_eq!(two.triangles[scene.len()].id as usize, scene.len());
    assert_eq!(
        two.triangles[scene.len()].p0,
        scene.triangles[0].p0 + Vec3::new(100.0, 0.0, 0.0)
    );
}
