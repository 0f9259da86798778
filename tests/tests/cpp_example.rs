//! examples/cpp end to end: `make` builds the C++ program with g++ against the object of
//! `scionc -O3 --emit=obj --layout L --entry closest_hit` and `libscion_runtime.a`, runs it on
//! a real scene, and the checksum it prints must equal the Rust path's (the runtime's
//! reference closest hits of the same tree and rays, `hits_checksum`, what `scion trace`
//! prints), for pbrt (primary rays) and ptr (secondary rays). The program also checks every hit against the reference itself
//! and exits nonzero on a mismatch. The collision program (`collide.cpp`, two trees and a sink
//! of pairs through the C ABI) finds the Rust reference's pairs on the same layouts.
//!
//! It builds `scionc` and the runtime's static library with the `cargo` that runs the test
//! (release profile). Skips with a clear line when g++ or make is missing.

use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::{build_sah_binned, SahOptions};
use scion_runtime::query::{hits_checksum, primary_rays_n, secondary_rays};
use scion_runtime::reference::closest_hits_tree;
use scion_runtime::reference::collide::{collide_sweep, rotated};
use scion_runtime::scene::{load_obj, manifest::scenes_dir};
use std::path::Path;
use std::process::Command;
use tools::{build_tools, have, repo};

use crate::tools;

const RAYS: u64 = 20_000;
const SEED: u64 = 3;

/// The checksum of the Rust path for `scene`: binned SAH with the defaults, the primary (or
/// secondary) rays of `scion trace --n RAYS --seed SEED`, the reference closest hits.
fn rust_checksum(scene: &Path, kind: &str) -> u64 {
    let s = load_obj(scene).unwrap();
    let tree = build_sah_binned(&s.triangles, &SahOptions::default());
    let rays = match kind {
        "primary" => primary_rays_n(s.bounds(), RAYS, SEED).unwrap(),
        _ => secondary_rays(s.bounds(), RAYS as usize, SEED),
    };
    let hits = closest_hits_tree(&tree, &rays, &BatchDriver::new(2).unwrap());
    assert!(hits.iter().any(|h| h.is_hit()), "the rays miss the scene");
    hits_checksum(&hits)
}

#[test]
fn cpp_example_prints_the_rust_checksum() {
    for tool in ["g++", "make"] {
        if !have(tool) {
            eprintln!("skip: `{tool}` not found; examples/cpp is not built");
            return;
        }
    }
    let scenes = scenes_dir().expect("the repository's scenes/ folder (or SCION_SCENES)");
    let target = build_tools(true);
    let build = std::env::temp_dir().join(format!("scion-cpp-example-{}", std::process::id()));
    // (layout, its file, the closest hit and its tree type, scene, rays): `Bvh8Tri4`'s tree
    // type holds blocks of four triangles, which `scion_tree_view` cuts the tree's leaves into
    // (its schema's `primitive`); the collision program runs on the binary layouts.
    for (layout, file, entry, tree, scene, kind) in [
        (
            "LinearBVH",
            "pbrt",
            "closest_hit",
            "BVH",
            "teapot",
            "primary",
        ),
        ("PtrBVH", "ptr", "closest_hit", "BVH", "pine", "secondary"),
        (
            "Bvh8Tri4",
            "bvh8_tri4",
            "closest_hit8_tri4",
            "BVH8T4",
            "pine",
            "secondary",
        ),
    ] {
        let scene = scion_runtime::scene::manifest::find(scene)
            .unwrap()
            .path(&scenes);
        // `make TARGET` in examples/cpp with the tools under test, this layout and scene.
        let make = |target_name: &str, more: &[String]| {
            Command::new("make")
                .current_dir(repo().join("examples/cpp"))
                .arg(target_name)
                .arg(format!("BUILD={}", build.display()))
                .arg(format!("SCIONC={}", target.join("scionc").display()))
                .arg(format!("RUNTIME_LIB_DIR={}", target.display()))
                .arg(format!("LAYOUT={layout}"))
                .arg(format!("LAYOUT_FILE={file}"))
                .arg(format!("SCENE={}", scene.display()))
                .arg("CXX=g++")
                .args(more)
                .output()
                .expect("runs make")
        };
        let out = make(
            "run",
            &[
                format!("N={RAYS}"),
                format!("SEED={SEED}"),
                "THREADS=3".into(),
                format!("RAYS={kind}"),
                format!("ENTRY={entry}"),
                format!("TREE={tree}"),
            ],
        );
        let stdout = String::from_utf8_lossy(&out.stdout);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            out.status.success(),
            "{layout}: make run failed\n{stdout}\n{stderr}"
        );
        let printed = stdout
            .lines()
            .find_map(|l| l.strip_prefix("checksum: "))
            .unwrap_or_else(|| panic!("{layout}: no checksum line in\n{stdout}"));
        let printed = u64::from_str_radix(printed.trim(), 16).expect("a hex checksum");
        assert_eq!(
            printed,
            rust_checksum(&scene, kind),
            "{layout}: the C++ checksum differs from the Rust path's\n{stdout}"
        );
        assert!(stdout.contains("mismatches: 0"), "{stdout}");
        if tree != "BVH" {
            continue;
        }
        // The collision program over the same layout: two trees, a sink of pairs too small at
        // first (so the entry runs twice), the pairs equal to the Rust reference.
        let out = make("run-collide", &["CAPACITY=7".into()]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            out.status.success(),
            "{layout}: make run-collide failed\n{stdout}\n{stderr}"
        );
        let tris = load_obj(&scene).unwrap().triangles;
        let want = collide_sweep(&tris, &rotated(&tris, [60.0, 70.0, 10.0]));
        assert!(
            stdout.contains(&format!("pairs: {} (2 calls", want.len())),
            "{layout}: {stdout}"
        );
        assert!(stdout.contains("mismatches: 0"), "{stdout}");
    }
    let _ = std::fs::remove_dir_all(&build);
}
