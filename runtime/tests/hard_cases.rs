//! Generated hard cases (architecture §6): every case of `scene::gen::hard_cases` and a few
//! transformed real-like scenes, with both builders and the caterpillar tree, against brute
//! force on primary, secondary and axis-parallel rays, plus hand-made rays that graze edges,
//! hit vertices, start on surfaces and run inside box faces.

use crate::common;

use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::{
    build_caterpillar, build_median, build_sah_binned, DeepSide, LogicalTree, SahOptions,
};
use scion_runtime::geom::{Hit, Ray, Vec3};
use scion_runtime::query::{axis_rays, primary_rays, secondary_rays};
use scion_runtime::reference::{closest_hit_brute, closest_hits_brute, closest_hits_tree};
use scion_runtime::scene::{gen, Scene};

fn trees(scene: &Scene) -> Vec<(&'static str, LogicalTree, usize)> {
    let four = SahOptions {
        max_leaf: 4,
        ..SahOptions::default()
    };
    vec![
        (
            "sah15",
            build_sah_binned(&scene.triangles, &SahOptions::default()),
            15,
        ),
        ("sah4", build_sah_binned(&scene.triangles, &four), 4),
        ("median", build_median(&scene.triangles), 1),
        (
            "caterpillar",
            build_caterpillar(&scene.triangles, DeepSide::Left),
            1,
        ),
    ]
}

/// Rays that stress edges and vertices: through every corner, every edge midpoint and the
/// centroid of every triangle, from outside the box, plus rays starting on the surface.
fn feature_rays(scene: &Scene, limit: usize) -> Vec<Ray> {
    let mut rays = Vec::new();
    let b = scene.bounds();
    if b.is_empty() {
        return rays;
    }
    let c = b.center();
    let e = b.extent();
    let span = e.x.max(e.y).max(e.z).max(f32::MIN_POSITIVE);
    let eye = c + Vec3::new(0.31, 0.57, 1.13) * (span * 2.0);
    let step = (scene.len() / limit.max(1)).max(1);
    for t in scene.triangles.iter().step_by(step) {
        let third = 1.0 / 3.0;
        let centroid = (t.p0 + t.p1 + t.p2) * third;
        for target in [
            t.p0,
            t.p1,
            t.p2,
            (t.p0 + t.p1) * 0.5,
            (t.p1 + t.p2) * 0.5,
            centroid,
        ] {
            rays.push(Ray::new(eye, target - eye));
            // Starting on the surface, leaving along an axis (zero lanes).
            rays.push(Ray::new(target, Vec3::new(0.0, 0.0, -1.0)));
            rays.push(Ray::new(target, Vec3::new(-0.0, 1.0, 0.0)));
        }
    }
    rays
}

fn check_scene(scene: &Scene, driver: &BatchDriver) -> usize {
    let b = scene.bounds();
    // Debug builds run a quarter of the rays.
    let k = if common::release() { 4 } else { 1 };
    let ray_sets = [
        ("primary", primary_rays(b, 6 * k as u32, 6 * k as u32, 11)),
        ("secondary", secondary_rays(b, 150 * k, 12)),
        ("axis", axis_rays(b, 75 * k, 13)),
        ("features", feature_rays(scene, 40 * k)),
    ];
    let trees = trees(scene);
    for (tname, tree, cap) in &trees {
        tree.validate_with_cap(*cap)
            .unwrap_or_else(|e| panic!("{} {tname}: {e}", scene.name));
    }
    let mut rounding = 0;
    for (kind, rays) in &ray_sets {
        let brute = closest_hits_brute(&scene.triangles, rays, driver);
        for (tname, tree, _) in &trees {
            let got = closest_hits_tree(tree, rays, driver);
            let what = format!("{} {tname} {kind}", scene.name);
            rounding += common::check_against_brute(&what, tree, rays, &got, &brute);
        }
    }
    rounding
}

#[test]
fn generated_hard_cases_agree_with_brute_force() {
    let driver = BatchDriver::new(0).unwrap();
    let mut rounding = 0;
    for scene in gen::hard_cases() {
        rounding += check_scene(&scene, &driver);
    }
    println!("generated hard cases: {rounding} rays pruned by rounding (all explained)");
}

#[test]
fn scale_extremes_are_consistent_but_lose_hits_outside_the_supported_range() {
    // The prelude's Moller-Trumbore computes cubes of coordinates: about 1e12 overflows
    // f32 (1e36 < 3.4e38 < 1e45), about 1e-13 underflows into subnormals. docs/runtime.md
    // states the supported range from these numbers.
    let driver = BatchDriver::new(0).unwrap();
    let soup = gen::random_soup(300, 0.2, 5);
    let base = {
        let rays = primary_rays(soup.bounds(), 32, 32, 1);
        let hits = closest_hits_brute(&soup.triangles, &rays, &driver);
        hits.iter().filter(|h| h.is_hit()).count()
    };
    assert!(base > 100);
    let mut report = Vec::new();
    for exp in [-15i32, -13, -12, -9, -6, 6, 9, 11, 12, 13, 15] {
        let factor = 10f64.powi(exp);
        let s = gen::scaled(&soup, factor);
        let rays = primary_rays(s.bounds(), 32, 32, 1);
        let brute = closest_hits_brute(&s.triangles, &rays, &driver);
        let tree = build_sah_binned(&s.triangles, &SahOptions::default());
        let got = closest_hits_tree(&tree, &rays, &driver);
        common::check_against_brute(&s.name, &tree, &rays, &got, &brute);
        let hits = brute.iter().filter(|h| h.is_hit()).count();
        report.push(format!("1e{exp}: {hits}/{base}"));
        if (-12..=11).contains(&exp) {
            // Inside the supported range the scaled scene shows (almost) the same picture.
            assert!(
                hits.abs_diff(base) <= base / 50,
                "1e{exp}: {hits} hits vs {base}"
            );
        }
        if exp == 15 {
            assert_eq!(
                hits, 0,
                "1e15: t's numerator overflows f32, every hit is lost"
            );
        }
    }
    println!(
        "hits of 32x32 primary rays on a scaled soup: {}",
        report.join(", ")
    );
}

#[test]
fn far_from_the_origin_hits_survive() {
    let driver = BatchDriver::new(0).unwrap();
    let grid = gen::quad_grid(8, 8);
    let mut base = 0;
    for offset in [0.0, 1e3, 1e5, 1e6] {
        let s = gen::translated(&grid, [offset, -offset, offset]);
        let rays = primary_rays(s.bounds(), 24, 24, 2);
        let brute = closest_hits_brute(&s.triangles, &rays, &driver);
        let tree = build_sah_binned(&s.triangles, &SahOptions::default());
        let got = closest_hits_tree(&tree, &rays, &driver);
        common::check_against_brute(&s.name, &tree, &rays, &got, &brute);
        let hits = brute.iter().filter(|h| h.is_hit()).count();
        if offset == 0.0 {
            base = hits;
            assert!(base > 100);
        }
        // The camera moves with the scene; rounding of the far coordinates may flip a few
        // rays near the grid's border or its shared edges.
        assert!(
            hits.abs_diff(base) <= base / 20,
            "offset {offset}: {hits} hits vs {base}"
        );
    }
}

#[test]
fn ties_on_duplicates_pick_the_smallest_id() {
    let grid = gen::quad_grid(4, 4);
    let dup = gen::duplicated(&grid, 4);
    let n = grid.len() as u32;
    for (name, tree, _) in trees(&dup) {
        for y in 0..8 {
            for x in 0..8 {
                let o = Vec3::new(x as f32 * 0.5 + 0.1, y as f32 * 0.5 + 0.2, 3.0);
                let r = Ray::new(o, Vec3::new(0.0, 0.0, -1.0));
                let h = scion_runtime::reference::closest_hit_tree(&tree, &r);
                assert_eq!(h, closest_hit_brute(&dup.triangles, &r), "{name}");
                assert!(
                    h.is_hit() && h.prim < n,
                    "{name}: {h:?} is not the first copy"
                );
                assert_eq!(h.t, 3.0);
            }
        }
    }
}

#[test]
fn empty_and_one_triangle() {
    let r = Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::new(0.0, 0.0, -1.0));
    for (_, tree, _) in trees(&gen::empty()) {
        assert!(tree.is_empty());
        assert_eq!(
            scion_runtime::reference::closest_hit_tree(&tree, &r),
            Hit::MISS
        );
    }
    for (_, tree, _) in trees(&gen::one_triangle()) {
        assert_eq!(tree.nodes.len(), 1);
        let h = scion_runtime::reference::closest_hit_tree(&tree, &r);
        assert_eq!(h, Hit { t: 1.0, prim: 0 });
    }
}
