//! Real scenes (the repository's scenes/): every file loads with the documented triangle count, both
//! builders give valid trees, and the reference traversal agrees with brute force bit for bit
//! on primary, secondary and axis-parallel rays. Scenes above 100 k triangles (engine,
//! cruiser, dragon) run only in optimized builds (`cargo test --release`), to keep debug test
//! time low.

use crate::common;

use std::time::Instant;

use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::{build_median, build_sah_binned, SahOptions};
use scion_runtime::geom::Ray;
use scion_runtime::query::{axis_rays, primary_rays, secondary_rays};
use scion_runtime::reference::{closest_hits_brute, closest_hits_tree};
use scion_runtime::scene::{load_obj, manifest};

/// How many rays of each kind to check against brute force: about `budget` triangle tests.
fn ray_count(triangles: usize) -> usize {
    let budget: usize = if common::release() {
        100_000_000
    } else {
        2_000_000
    };
    (budget / triangles.max(1)).clamp(16, 1024)
}

/// Loads scene `name`, builds both trees and compares traversal with brute force.
fn check_real_scene(name: &str) {
    let Some(dir) = common::scenes_dir() else {
        return;
    };
    let expected = manifest::find(name).expect("listed scene").triangles;
    if expected > 100_000 && !common::release() {
        println!(
            "SKIPPED in debug builds: {name} ({expected} triangles); run cargo test --release"
        );
        return;
    }
    let driver = BatchDriver::new(0).unwrap();
    {
        let start = Instant::now();
        let scene = load_obj(manifest::find(name).expect("listed scene").path(&dir))
            .unwrap_or_else(|e| panic!("{e}"));
        let load = start.elapsed();
        assert_eq!(scene.len(), expected, "{name}: triangle count");
        assert!(scene
            .triangles
            .iter()
            .enumerate()
            .all(|(i, t)| t.id as usize == i));

        let start = Instant::now();
        let sah = build_sah_binned(&scene.triangles, &SahOptions::default());
        let build = start.elapsed();
        sah.validate()
            .unwrap_or_else(|e| panic!("{name} (SAH): {e}"));
        let median = build_median(&scene.triangles);
        median
            .validate_with_cap(1)
            .unwrap_or_else(|e| panic!("{name} (median): {e}"));
        let stats = sah.stats();

        let n = ray_count(scene.len());
        let side = (n as f64).sqrt().ceil() as u32;
        let bounds = scene.bounds();
        let kinds: [(&str, Vec<Ray>); 3] = [
            ("primary", primary_rays(bounds, side, side, 1)),
            ("secondary", secondary_rays(bounds, n, 2)),
            ("axis", axis_rays(bounds, n / 4 + 1, 3)),
        ];
        let mut hits = 0;
        let mut rounding = 0;
        for (kind, rays) in &kinds {
            let brute = closest_hits_brute(&scene.triangles, rays, &driver);
            let tree = closest_hits_tree(&sah, rays, &driver);
            let by_median = closest_hits_tree(&median, rays, &driver);
            rounding += common::check_against_brute(
                &format!("{name} {kind} SAH"),
                &sah,
                rays,
                &tree,
                &brute,
            );
            rounding += common::check_against_brute(
                &format!("{name} {kind} median"),
                &median,
                rays,
                &by_median,
                &brute,
            );
            hits += brute.iter().filter(|h| h.is_hit()).count();
        }
        println!(
            "{name}: {} triangles, load {:.2?}, SAH build {:.2?} ({} nodes, depth {}, SAH cost {:.1}), \
             {} rays x 2 trees agree but {} (pruned by rounding), {} hits",
            scene.len(),
            load,
            build,
            stats.nodes,
            stats.depth,
            stats.sah_cost,
            kinds.iter().map(|(_, r)| r.len()).sum::<usize>(),
            rounding,
            hits
        );
    }
}

macro_rules! real_scene_tests {
    ($($name:ident),* $(,)?) => {
        $(
            #[test]
            fn $name() {
                check_real_scene(stringify!($name));
            }
        )*

        #[test]
        fn every_listed_scene_has_a_test() {
            let tested = [$(stringify!($name)),*];
            for scene in manifest::REAL_SCENES {
                assert!(tested.contains(&scene.name), "no test for {}", scene.name);
            }
        }
    };
}

real_scene_tests!(
    teapot,
    pine,
    suzanne,
    balloon,
    fzk_haus,
    sponza_dabrovic,
    bunny,
    engine,
    cruiser_cg57,
    dragon,
);
