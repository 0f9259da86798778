//! Integration tests of the `scion` command: the happy path on a small OBJ file (reference,
//! interpreter and the JITs of pbrt, ptr and pbrt-q16 write the same hits file; rays files are read; a
//! JIT stack too small names the overflowing ray), and the user errors (a missing
//! scene, a NaN coordinate reported with file and line, bad flags, an
//! unknown layout, an empty scene, outputs onto inputs or into missing folders, too many threads
//! or rays, standard output that cannot be written) as clear messages with exit status 1 (2 for
//! a bad command line), never a panic.

use crate::common;

use common::{scion, soup, text, write, CUBE};
use scion_runtime::geom::{Ray, Vec3};
use scion_runtime::query::{read_hits, write_rays};
use std::path::PathBuf;

fn scratch(test: &str) -> PathBuf {
    common::scratch("cli", test)
}

#[test]
fn traces_and_writes_the_same_hits_with_every_interpreted_and_reference_backend() {
    let dir = scratch("happy");
    let scene = write(&dir, "cube.obj", CUBE);
    let mut files = Vec::new();
    for backend in ["reference", "interp", "brute", "mem-interp"] {
        let out = dir.join(format!("{backend}.hits")).display().to_string();
        let o = scion(&[
            "trace",
            "--scene",
            &scene,
            "--backend",
            backend,
            "--rays",
            "secondary",
            "--n",
            "100",
            "--runs",
            "1",
            "--threads",
            "2",
            "-o",
            &out,
        ]);
        let stdout = text(&o.stdout);
        assert!(o.status.success(), "{backend}: {}", text(&o.stderr));
        assert!(stdout.contains("triangles    12"), "{stdout}");
        assert!(stdout.contains("Mrays/s"), "{stdout}");
        assert!(stdout.contains("bytes/node"), "{stdout}");
        // Rays start inside the cube: every one hits a face.
        assert!(stdout.contains("hits         100 of 100 rays"), "{stdout}");
        assert!(
            text(&o.stderr).contains("scion: loading"),
            "progress goes to stderr"
        );
        files.push(std::fs::read(&out).unwrap());
    }
    assert_eq!(files[0].len(), 800);
    assert_eq!(files[0], files[1], "interp differs from reference");
    assert_eq!(files[0], files[2], "brute force differs from reference");
    assert_eq!(
        files[0], files[3],
        "mem-interp (pbrt) differs from reference"
    );
}

#[test]
fn reads_rays_files_and_times_by_the_paper_method() {
    let dir = scratch("raysfile");
    let scene = write(&dir, "cube.obj", CUBE);
    let rays_path = dir.join("in.rays");
    let rays = [
        Ray::new(Vec3::new(0.5, 0.5, -1.0), Vec3::new(0.0, 0.0, 1.0)),
        Ray::new(Vec3::new(5.0, 5.0, 5.0), Vec3::new(0.0, 1.0, 0.0)),
    ];
    write_rays(&rays_path, &rays).unwrap();
    let out = dir.join("out.hits");
    let o = scion(&[
        "trace",
        "--scene",
        &scene,
        "--layout",
        "ptr",
        "--rays-file",
        &rays_path.display().to_string(),
        "--builder",
        "median",
        "-o",
        &out.display().to_string(),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let stdout = text(&o.stdout);
    assert!(stdout.contains("mean of 5 of 9 runs"), "{stdout}");
    assert!(stdout.contains("median"), "{stdout}");
    assert!(stdout.contains("layout       none"), "{stdout}");
    let e = text(&o.stderr);
    assert!(
        e.contains("--layout is used by --backend jit|llvm|mem-interp only"),
        "{e}"
    );
    let hits = read_hits(&out).unwrap();
    assert_eq!(hits.len(), 2);
    assert_eq!(hits[0].t, 1.0);
    assert!(!hits[1].is_hit());
}

#[test]
fn a_missing_scene_is_an_error() {
    let o = scion(&["trace", "--scene", "/nonexistent/scene.obj", "--runs", "1"]);
    assert_eq!(o.status.code(), Some(1));
    let e = text(&o.stderr);
    assert!(e.contains("error: cannot load the scene"), "{e}");
    assert!(e.contains("/nonexistent/scene.obj"), "{e}");
    assert!(!e.contains("panicked"), "{e}");
}

#[test]
fn a_nan_coordinate_names_file_and_line() {
    let dir = scratch("nan");
    let scene = write(&dir, "nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n");
    let o = scion(&["trace", "--scene", &scene, "--runs", "1"]);
    assert_eq!(o.status.code(), Some(1));
    let e = text(&o.stderr);
    assert!(e.contains(&format!("{scene}:3:")), "{e}");
    assert!(o.stdout.is_empty(), "no results on error");
}

#[test]
fn bad_flags_are_usage_errors() {
    let dir = scratch("flags");
    let scene = write(&dir, "cube.obj", CUBE);
    for (args, want) in [
        (vec!["trace", "--scene", &scene, "--backend", "gpu"], "gpu"),
        (vec!["trace", "--scene", &scene, "--leaf-size", "16"], "16"),
        (
            vec!["trace", "--scene", &scene, "--rays", "tertiary"],
            "tertiary",
        ),
        (vec!["trace", "--scene", &scene, "--n", "-3"], "-3"),
        (vec!["trace", "--scene", &scene, "--runs", "0"], "0"),
        (vec!["trace", "--scene", &scene, "--n", "0"], "0"),
        (
            vec![
                "trace",
                "--scene",
                &scene,
                "--rays-file",
                "x.rays",
                "--n",
                "5",
            ],
            "cannot be used with",
        ),
        (vec!["trace"], "--scene"),
        (vec!["render"], "render"),
    ] {
        let o = scion(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let e = text(&o.stderr);
        assert!(e.contains(want), "{args:?}: {e}");
    }
}

#[test]
fn the_jit_writes_the_reference_hits_for_pbrt_ptr_and_the_quantized_layouts() {
    let dir = scratch("jit");
    let scene = write(&dir, "soup.obj", &soup(400));
    let run = |backend: &str, layout: &str, rays: &str| {
        let out = dir.join(format!("{backend}-{layout}-{rays}.hits"));
        let o = scion(&[
            "trace",
            "--scene",
            &scene,
            "--backend",
            backend,
            "--layout",
            layout,
            "--rays",
            rays,
            "--n",
            "3000",
            "--runs",
            "1",
            "-o",
            &out.display().to_string(),
        ]);
        assert!(
            o.status.success(),
            "{backend} {layout}: {}",
            text(&o.stderr)
        );
        (text(&o.stdout), std::fs::read(&out).unwrap())
    };
    for rays in ["primary", "secondary"] {
        let (_, want) = run("reference", "pbrt", rays);
        assert_eq!(want.len(), 3000 * 8);
        // The quantized layouts' conservative boxes visit more nodes and find the same hits on
        // these rays (ties and grazing rays are the differential table's business).
        for (layout, per_node) in [
            ("pbrt", "32.0 B/node"),
            ("ptr", "48.0 B/node"),
            ("pbrt-q16", "16.0 B/node"),
            ("sg-eq", "12.0 B/node"),
        ] {
            let (stdout, got) = run("jit", layout, rays);
            assert_eq!(got, want, "jit {layout} {rays} differs from reference");
            assert!(stdout.contains(per_node), "{stdout}");
            assert!(stdout.contains("backend      jit ("), "{stdout}");
            let (stdout, got) = run("llvm", layout, rays);
            assert_eq!(got, want, "llvm {layout} {rays} differs from reference");
            assert!(stdout.contains(per_node), "{stdout}");
            assert!(stdout.contains("backend      llvm -O3 ("), "{stdout}");
            assert!(stdout.contains("pack time    0."), "{stdout}");
            assert!(stdout.contains("Mrays/s"), "{stdout}");
        }
    }
}

#[test]
fn a_small_jit_stack_reports_the_overflowing_ray() {
    let dir = scratch("jitstack");
    let scene = write(&dir, "cube.obj", CUBE);
    let rays_path = dir.join("in.rays");
    // Rays 0-4 miss the scene's box (no push); ray 5 starts inside it.
    let away = Ray::new(Vec3::new(5.0, 5.0, 5.0), Vec3::new(0.0, 1.0, 0.0));
    let mut rays = vec![away; 8];
    rays[5] = Ray::new(Vec3::new(0.5, 0.5, 0.5), Vec3::new(0.0, 0.0, 1.0));
    rays[7] = rays[5];
    write_rays(&rays_path, &rays).unwrap();
    let args = |stack: &'static str| {
        let mut a = vec![
            "trace".to_string(),
            "--scene".into(),
            scene.clone(),
            "--backend".into(),
            "jit".into(),
            "--layout".into(),
            "pbrt".into(),
            "--builder".into(),
            "median".into(),
            "--rays-file".into(),
            rays_path.display().to_string(),
            "--runs".into(),
            "1".into(),
        ];
        if !stack.is_empty() {
            a.extend(["--stack-size".to_string(), stack.to_string()]);
        }
        a
    };
    let run = |a: Vec<String>| {
        let refs: Vec<&str> = a.iter().map(|s| s.as_str()).collect();
        scion(&refs)
    };
    let o = run(args("1"));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stdout));
    let e = text(&o.stderr);
    assert!(e.contains("ray 5: traversal stack overflow"), "{e}");
    // The default stack holds the cube's median tree.
    let o = run(args(""));
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stdout).contains("hits         2 of 8 rays"));
    // A zero-entry stack is a usage error.
    let o = run(args("0"));
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn the_jit_backend_rejects_unknown_layouts() {
    let dir = scratch("unknown_layout");
    let scene = write(&dir, "cube.obj", CUBE);
    let o = scion(&[
        "trace",
        "--scene",
        &scene,
        "--backend",
        "jit",
        "--layout",
        "btree",
    ]);
    assert_eq!(o.status.code(), Some(2), "a bad command line");
    let e = text(&o.stderr);
    assert!(e.contains("unknown layout `btree`"), "{e}");
    assert!(e.contains("pbrt-soaos"), "{e}");
}

#[test]
fn empty_scenes_need_a_rays_file() {
    let dir = scratch("empty");
    let scene = write(&dir, "empty.obj", "# nothing\n");
    let o = scion(&["trace", "--scene", &scene, "--runs", "1"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("no triangles"));

    let rays_path = dir.join("in.rays");
    write_rays(
        &rays_path,
        &[Ray::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0))],
    )
    .unwrap();
    for backend in ["reference", "interp"] {
        let o = scion(&[
            "trace",
            "--scene",
            &scene,
            "--backend",
            backend,
            "--rays-file",
            &rays_path.display().to_string(),
            "--runs",
            "1",
        ]);
        assert!(o.status.success(), "{backend}: {}", text(&o.stderr));
        assert!(text(&o.stdout).contains("hits         0 of 1 rays"));
    }
}

#[test]
fn a_bad_rays_file_is_an_error() {
    let dir = scratch("badrays");
    let scene = write(&dir, "cube.obj", CUBE);
    let rays = write(&dir, "bad.rays", "12345");
    let o = scion(&[
        "trace",
        "--scene",
        &scene,
        "--rays-file",
        &rays,
        "--runs",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = text(&o.stderr);
    assert!(
        e.contains("cannot read the rays") && e.contains("bad.rays"),
        "{e}"
    );
}

#[test]
fn stats_report_the_work_per_ray_of_the_binary_and_the_wide_trees() {
    let dir = scratch("stats");
    let scene = write(&dir, "cube.obj", CUBE);
    let o = scion(&[
        "trace",
        "--scene",
        &scene,
        "--backend",
        "reference",
        "--rays",
        "secondary",
        "--n",
        "64",
        "--runs",
        "1",
        "--leaf-size",
        "1",
        "--stats",
    ]);
    let stdout = text(&o.stdout);
    assert!(o.status.success(), "{}", text(&o.stderr));
    // Every ray starts inside the cube and hits one face; twelve one-triangle leaves.
    assert!(stdout.contains("work/ray "), "{stdout}");
    let line = |prefix: &str| {
        stdout
            .lines()
            .find(|l| l.starts_with(prefix))
            .unwrap_or_else(|| panic!("no `{prefix}` line in {stdout}"))
            .to_string()
    };
    // Twelve leaves under 11 binary interior nodes: fewer wide nodes, each of 2 to 8 slots.
    let w4 = line("4-wide");
    let w8 = line("8-wide");
    // "...per ray; N nodes (the tree collapsed, ...)"
    let nodes = |l: &str| -> usize {
        let tail = l.rsplit("; ").next().unwrap();
        tail.split_whitespace().next().unwrap().parse().unwrap()
    };
    assert!((2..=11).contains(&nodes(&w4)), "{w4}");
    assert!((1..=nodes(&w4)).contains(&nodes(&w8)), "{w4} / {w8}");
}

#[test]
fn outputs_are_checked_before_the_work_and_never_overwrite_an_input() {
    let dir = scratch("outputs");
    let scene = write(&dir, "cube.obj", CUBE);
    let before = std::fs::read(&scene).unwrap();
    // -o onto the scene: a bad command line, and the scene is untouched.
    let o = scion(&[
        "trace", "--scene", &scene, "--n", "16", "--runs", "1", "-o", &scene,
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("is the --scene file"),
        "{}",
        text(&o.stderr)
    );
    assert_eq!(std::fs::read(&scene).unwrap(), before);
    // -o onto the rays file, also through another spelling of its path.
    let rays = dir.join("in.rays");
    write_rays(
        &rays,
        &[Ray::new(
            Vec3::new(0.5, 0.5, -1.0),
            Vec3::new(0.0, 0.0, 1.0),
        )],
    )
    .unwrap();
    let other = format!("{}/./in.rays", dir.display());
    let o = scion(&[
        "trace",
        "--scene",
        &scene,
        "--rays-file",
        &rays.display().to_string(),
        "--runs",
        "1",
        "-o",
        &other,
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(
        text(&o.stderr).contains("--rays-file"),
        "{}",
        text(&o.stderr)
    );
    // An output in a missing folder fails before loading (no "loading" progress line).
    let missing = dir.join("no/such/folder/hits.bin").display().to_string();
    let o = scion(&[
        "trace", "--scene", &scene, "--n", "16", "--runs", "1", "-o", &missing,
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = text(&o.stderr);
    assert!(
        e.contains("cannot write -o") && !e.contains("scion: loading"),
        "{e}"
    );
    // A good output is written whole and leaves no temporary file.
    let out = dir.join("hits.bin").display().to_string();
    let o = scion(&[
        "trace", "--scene", &scene, "--n", "16", "--runs", "1", "-o", &out,
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(read_hits(&out).unwrap().len(), 16);
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert!(
        names.iter().all(|n| !n.to_string_lossy().starts_with('.')),
        "{names:?}"
    );
}

#[test]
fn resources_and_standard_output_are_checked() {
    let dir = scratch("resources");
    let scene = write(&dir, "cube.obj", CUBE);
    let o = scion(&[
        "trace",
        "--scene",
        &scene,
        "--threads",
        "100000",
        "--runs",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("--threads 100000"),
        "{}",
        text(&o.stderr)
    );
    // More rays than any test machine's memory: refused before allocating.
    let o = scion(&[
        "trace",
        "--scene",
        &scene,
        "--n",
        "4294967296",
        "--runs",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("GiB"), "{}", text(&o.stderr));
    // Standard output that cannot be written: an error, not a panic.
    if let Ok(full) = std::fs::OpenOptions::new().write(true).open("/dev/full") {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_scion"))
            .args(["trace", "--scene", &scene, "--n", "16", "--runs", "1"])
            .stdout(full)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(1));
        let e = text(&o.stderr);
        assert!(
            e.contains("cannot write the report to standard output") && !e.contains("panicked"),
            "{e}"
        );
    }
}

#[test]
fn library_scenes_by_name_and_compressed_scenes_load() {
    let o = scion(&["trace", "--scene", "teapot", "--n", "64", "--runs", "1"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stdout).contains("triangles    992"),
        "{}",
        text(&o.stdout)
    );
    let o = scion(&["trace", "--scene", "teapott", "--runs", "1"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stderr).contains("not a library scene (teapot, pine"),
        "{}",
        text(&o.stderr)
    );
    // A face of two vertices names its line.
    let dir = scratch("short_face");
    let scene = write(
        &dir,
        "short.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2\n",
    );
    let o = scion(&["trace", "--scene", &scene, "--runs", "1"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stderr).contains("short.obj:5: a face needs at least 3 vertices"),
        "{}",
        text(&o.stderr)
    );
}

#[test]
fn stats_of_a_quantized_layout_report_its_error_against_the_exact_boxes() {
    let dir = scratch("quant_stats");
    let scene = write(&dir, "soup.obj", &soup(400));
    let o = scion(&[
        "trace",
        "--scene",
        &scene,
        "--n",
        "2000",
        "--runs",
        "1",
        "--backend",
        "jit",
        "--layout",
        "sg-eq",
        "--stats",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(
        out.contains("contain the exact one (conservative: no hit can be lost)"),
        "{out}"
    );
    assert!(out.contains("error/ray    box tests +"), "{out}");
    // An exact layout has no such lines.
    let o = scion(&[
        "trace",
        "--scene",
        &scene,
        "--n",
        "200",
        "--runs",
        "1",
        "--backend",
        "jit",
        "--stats",
    ]);
    assert!(o.status.success() && !text(&o.stdout).contains("error/ray"));
}

/// Generated code's hits are compared with the reference by default: a correct layout says so,
/// an algorithm choosing its children as values agrees, one that skips far children is caught
/// (naming the ray), and `--no-check` skips the comparison.
#[test]
fn generated_hits_are_checked_against_the_reference() {
    let library = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../library/algorithms/closest_hit.scion"
    );
    let dir = scratch("check");
    let scene = write(&dir, "soup.obj", &soup(400));
    let base = [
        "trace",
        "--scene",
        &scene,
        "--rays",
        "secondary",
        "--n",
        "2000",
        "--runs",
        "1",
    ];
    for (backend, layout, which) in [
        ("jit", "pbrt", "the reference"),
        ("llvm", "pbrt-q16", "the reference"),
        ("llvm", "bvh8", "the eight-wide reference"),
    ] {
        let mut args = base.to_vec();
        args.extend(["--backend", backend, "--layout", layout]);
        let o = scion(&args);
        let out = text(&o.stdout);
        assert!(o.status.success(), "{layout}: {}", text(&o.stderr));
        assert!(
            out.contains(&format!(
                "check        identical to {which} on all 2000 rays"
            )),
            "{out}"
        );
    }
    // Closest hit choosing the near and far child as values (`tree.if` on tree values: a
    // select of node references) visits the same nodes in the same order.
    let source = std::fs::read_to_string(library).unwrap();
    let start = source.find("        let d: (f32, f32)").unwrap();
    let end = source.find("      | Leaf(").unwrap();
    let selects = format!(
        "{}{}{}",
        &source[..start],
        "        let d: (f32, f32) = distmin_pair(r, left.bounds, right.bounds, best[0]);
        let dl: f32 = d[0];
        let dr: f32 = d[1];
        let swap: bool = dr < dl;
        let near: BVH = if swap { right } else { left };
        let far: BVH = if swap { left } else { right };
        let dn: f32 = if swap { dr } else { dl };
        let df: f32 = if swap { dl } else { dr };
        if dn < inf {
          closest_hit_node(ray, r, near, dn, best);
          if df < inf { closest_hit_node(ray, r, far, df, best); }
        }
      }
",
        &source[end..]
    );
    let file = write(&dir, "selects.scion", &selects);
    for (backend, layout) in [("jit", "pbrt"), ("llvm", "ptr")] {
        let mut args = base.to_vec();
        args.extend([
            "--backend",
            backend,
            "--layout",
            layout,
            "--algorithm",
            &file,
        ]);
        let o = scion(&args);
        assert!(o.status.success(), "{}", text(&o.stderr));
        assert!(
            text(&o.stdout).contains("check        identical to the reference on all 2000 rays"),
            "{}",
            text(&o.stdout)
        );
    }
    // Closest hit that never enters a right child.
    let library = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../library/algorithms/closest_hit.scion"
    );
    let wrong = std::fs::read_to_string(library).unwrap().replace(
        "closest_hit_node(ray, r, right, dr, best);",
        "closest_hit_node(ray, r, left, dl, best);",
    );
    let file = write(&dir, "left_only.scion", &wrong);
    let mut args = base.to_vec();
    args.extend(["--backend", "llvm", "--algorithm", &file]);
    let o = scion(&args);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stdout));
    let e = text(&o.stderr);
    assert!(e.contains("the hit differs from the reference's"), "{e}");
    assert!(e.contains("--no-check"), "{e}");
    args.push("--no-check");
    let o = scion(&args);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(!text(&o.stdout).contains("check "));
}
