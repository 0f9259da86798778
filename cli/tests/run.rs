//! `scion run` and `scion trace --layout FILE` end to end: a layout file the library does not
//! have traces to the reference's hits through both JITs and the emulated GPU kernels; every
//! query kind `scion run` knows answers as its reference (closest hits as `scion trace`'s);
//! requests that do not fit are usage errors that name what exists.

use crate::common;

use common::{fails_with, scion, soup, succeeds_with, text, write};
use scion_runtime::query::read_hits;
use std::path::PathBuf;

fn scratch(test: &str) -> PathBuf {
    common::scratch("run", test)
}

/// A layout the library does not have, written by a user: PBRT's fields in another order
/// (count first, then the overlay, then the box), 64-byte aligned nodes.
const USER_LAYOUT: &str = "
layout Mine(I: u32) {
  P: u32; N: u32; primitives: Triangle[P];
  group nodes[size=N, align=64] by I {
    nprims: u16;
    2;
    split nprims {
      > 0 -> Leaf { p_o: u32; data = primitives[p_o : p_o + nprims]; };
      0 -> Interior { c_o: u32; left = I + 1; right = I + c_o; };
    };
    bounds: AABB;
  };
};
build Mine[order=pre] {
  build Interior(bounds: AABB, left: BVH, right: BVH) {
    build bounds; build nprims = 0; build left;
    let R: u32 = build right;
    build c_o = R - this;
    return this;
  };
  build Leaf(bounds: AABB, nprims: u16, data: Triangle[nprims]) {
    build bounds; build nprims; build p_o = append(data, nprims);
    return this;
  };
};
";

#[test]
fn any_layout_file_traces_to_the_reference_hits() {
    let dir = scratch("user_layout");
    let scene = write(&dir, "soup.obj", &soup(300));
    let layout = write(&dir, "mine.scion", USER_LAYOUT);
    let reference = dir.join("ref.hits").display().to_string();
    let o = scion(&[
        "trace", "--scene", &scene, "--n", "4096", "--runs", "1", "-o", &reference,
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    for backend in ["jit", "llvm"] {
        let out = dir.join(format!("{backend}.hits")).display().to_string();
        let o = scion(&[
            "trace",
            "--scene",
            &scene,
            "--n",
            "4096",
            "--runs",
            "1",
            "--backend",
            backend,
            "--layout",
            &layout,
            "-o",
            &out,
        ]);
        assert!(o.status.success(), "{backend}: {}", text(&o.stderr));
        assert!(text(&o.stdout).contains("Mine"), "{}", text(&o.stdout));
        assert_eq!(
            read_hits(&out).unwrap(),
            read_hits(&reference).unwrap(),
            "{backend}"
        );
    }
    // The GPU kernels of the same file, emulated on the CPU, checked against the reference.
    let o = scion(&[
        "trace",
        "--scene",
        &scene,
        "--n",
        "2048",
        "--runs",
        "1",
        "--device",
        "gpu-emulated",
        "--layout",
        &layout,
    ]);
    succeeds_with(&o, "identical to the reference on all 2048 rays");
    // The library's algorithms by name, a layout and algorithm that do not fit, a missing
    // layout in a file.
    let jit = |layout: &str, more: &[&str]| {
        let base = [
            "trace",
            "--scene",
            &scene,
            "--runs",
            "1",
            "--backend",
            "jit",
            "--layout",
        ];
        scion(&[&base[..], &[layout], more].concat())
    };
    let o = jit(&layout, &["--n", "64", "--algorithm", "closest_hit"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let o = jit(&layout, &["--algorithm", "closest_hit_dop14"]);
    fails_with(&o, 2, "realizes `BVH`");
    let o = jit(&format!("{layout}:Yours"), &[]);
    fails_with(&o, 2, "declares no layout `Yours`");
}

#[test]
fn run_answers_every_query_kind_and_checks_it_against_its_reference() {
    let dir = scratch("run");
    let scene = write(&dir, "soup.obj", &soup(300));
    // Closest points, on two layouts: the same answers, written as 20-byte records.
    let mut files = Vec::new();
    for layout in ["pbrt", "sg-eq"] {
        let out = dir.join(format!("{layout}.points")).display().to_string();
        let o = scion(&[
            "run",
            "--algorithm",
            "closest-point",
            "--scene",
            &scene,
            "--layout",
            layout,
            "--n",
            "500",
            "--runs",
            "1",
            "--backend",
            "jit",
            "-o",
            &out,
        ]);
        assert!(o.status.success(), "{layout}: {}", text(&o.stderr));
        let stdout = text(&o.stdout);
        assert!(
            stdout.contains("closest_point_query (closest-point, BVH)"),
            "{stdout}"
        );
        assert!(
            stdout.contains("identical to brute force on 500 of 500"),
            "{stdout}"
        );
        files.push(std::fs::read(&out).unwrap());
    }
    assert_eq!(files[0].len(), 500 * 20);
    assert_eq!(files[0], files[1]);
    // The same queries through the GPU pipeline, its kernels emulated on this CPU.
    let out = dir.join("gpu.points").display().to_string();
    let o = scion(&[
        "run",
        "--algorithm",
        "closest-point",
        "--scene",
        &scene,
        "--n",
        "500",
        "--runs",
        "3",
        "--device",
        "gpu-emulated",
        "-o",
        &out,
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let stdout = text(&o.stdout);
    assert!(
        stdout.contains("device       emulated on the CPU"),
        "{stdout}"
    );
    assert!(
        stdout.contains("identical to brute force on 500 of 500"),
        "{stdout}"
    );
    assert_eq!(std::fs::read(&out).unwrap(), files[0]);
    let o = scion(&[
        "run",
        "--algorithm",
        "collide",
        "--scene",
        &scene,
        "--device",
        "gpu-emulated",
    ]);
    fails_with(&o, 2, "collide runs on the CPU");
    // The best-first traversal by its name, points from a file.
    let points = dir.join("in.points");
    let bytes: Vec<u8> = [[0.5f32, 0.5, 0.5], [2.0, -1.0, 3.0]]
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    std::fs::write(&points, bytes).unwrap();
    let o = scion(&[
        "run",
        "--algorithm",
        "closest_point_best_first",
        "--scene",
        &scene,
        "--queries-file",
        &points.display().to_string(),
        "--runs",
        "1",
        "--stack-size",
        "4096",
    ]);
    succeeds_with(&o, "identical to brute force on 2 of 2");
    // Any hit and closest hit; the closest hits equal scion trace's.
    let o = scion(&[
        "run",
        "--algorithm",
        "any-hit",
        "--scene",
        &scene,
        "--n",
        "300",
        "--runs",
        "1",
    ]);
    succeeds_with(&o, "occluded (any-hit, BVH)");
    let hits = dir.join("run.hits").display().to_string();
    let o = scion(&[
        "run",
        "--algorithm",
        "closest-hit",
        "--scene",
        &scene,
        "--n",
        "300",
        "--runs",
        "1",
        "-o",
        &hits,
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let traced = dir.join("trace.hits").display().to_string();
    let o = scion(&[
        "trace", "--scene", &scene, "--n", "300", "--runs", "1", "-o", &traced,
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(read_hits(&hits).unwrap(), read_hits(&traced).unwrap());
    // Bad requests: no such entry, a points file of the wrong size, a kind the layout's type
    // has no entry of.
    let o = scion(&["run", "--algorithm", "nearest", "--scene", &scene]);
    fails_with(&o, 2, "not an entry of a known query kind");
    std::fs::write(&points, [0u8; 13]).unwrap();
    let o = scion(&[
        "run",
        "--algorithm",
        "closest-point",
        "--scene",
        &scene,
        "--queries-file",
        &points.display().to_string(),
    ]);
    fails_with(&o, 1, "12-byte points");
    let o = scion(&[
        "run",
        "--algorithm",
        "any-hit",
        "--scene",
        &scene,
        "--layout",
        "hair-bvh",
    ]);
    fails_with(&o, 2, "no any-hit entry traverses `Hair`");
}

#[test]
fn run_collides_a_scene_with_its_rotated_copy() {
    use scion_runtime::reference::collide::{collide_sweep, rotated};
    let dir = scratch("collide");
    let scene = write(&dir, "soup.obj", &soup(400));
    let tris = scion_runtime::scene::load_obj(std::path::Path::new(&scene))
        .unwrap()
        .triangles;
    let want = collide_sweep(&tris, &rotated(&tris, [60.0, 70.0, 10.0]));
    assert!(!want.is_empty());
    let want_bytes: Vec<u8> = want
        .iter()
        .flat_map(|&(a, b)| [a.to_le_bytes(), b.to_le_bytes()])
        .flatten()
        .collect();
    // Both code generators, an exact and a quantized layout: the same pairs file.
    for (layout, backend) in [("pbrt", "llvm"), ("pbrt-q16", "jit"), ("ptr", "jit")] {
        let out = dir.join(format!("{layout}.pairs")).display().to_string();
        let o = scion(&[
            "run",
            "--algorithm",
            "collide",
            "--scene",
            &scene,
            "--layout",
            layout,
            "--backend",
            backend,
            "--runs",
            "3",
            "-o",
            &out,
        ]);
        assert!(o.status.success(), "{layout}: {}", text(&o.stderr));
        let stdout = text(&o.stdout);
        assert!(stdout.contains("collide (collide, BVH)"), "{stdout}");
        assert!(
            stdout.contains(&format!("pairs        {}", want.len())),
            "{stdout}"
        );
        assert!(stdout.contains("identical to the reference"), "{stdout}");
        assert_eq!(std::fs::read(&out).unwrap(), want_bytes, "{layout}");
    }
    // Another rotation is another copy.
    let o = scion(&[
        "run",
        "--algorithm",
        "collide",
        "--scene",
        &scene,
        "--rotate",
        "0,0,90",
        "--runs",
        "1",
    ]);
    succeeds_with(&o, "rotation     (0, 0, 90) degrees");
    // Bad requests: two angles, a stack too small for the pairs of subtrees, a layout whose
    // tree type has no collision entry.
    let o = scion(&[
        "run",
        "--algorithm",
        "collide",
        "--scene",
        &scene,
        "--rotate",
        "60,70",
    ]);
    fails_with(&o, 2, "expected three angles");
    let o = scion(&[
        "run",
        "--algorithm",
        "collide",
        "--scene",
        &scene,
        "--stack-size",
        "1",
        "--runs",
        "1",
    ]);
    fails_with(&o, 1, "stack overflowed");
    let o = scion(&[
        "run",
        "--algorithm",
        "collide",
        "--scene",
        &scene,
        "--layout",
        "bvh8",
    ]);
    fails_with(&o, 2, "no collide entry traverses `BVH8`");
}

#[test]
fn a_tree_beyond_a_layouts_fields_is_an_error_not_a_wrong_tree() {
    // The hair BVH keeps a leaf's count in 3 bits of its reference: leaves of up to 15
    // triangles (the SAH default) do not fit, leaves of up to 7 do.
    let dir = scratch("limits");
    let mut obj = String::new();
    // 40 triangles stacked on one spot: the SAH builder cannot split them below its cap.
    for i in 0..40 {
        let z = i as f32 * 1e-3;
        obj += &format!(
            "v 0 0 {z}\nv 1 0 {z}\nv 0 1 {z}\nf {} {} {}\n",
            3 * i + 1,
            3 * i + 2,
            3 * i + 3
        );
    }
    let scene = write(&dir, "stack.obj", &obj);
    let args = [
        "trace",
        "--scene",
        &scene,
        "--n",
        "256",
        "--runs",
        "1",
        "--backend",
        "jit",
        "--layout",
        "hair-bvh",
    ];
    let o = scion(&args);
    fails_with(&o, 1, "does not fit layout `HairBVH`");
    let reference = dir.join("ref.hits").display().to_string();
    let o = scion(&[
        "trace",
        "--scene",
        &scene,
        "--n",
        "256",
        "--runs",
        "1",
        "--leaf-size",
        "7",
        "-o",
        &reference,
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = dir.join("hair.hits").display().to_string();
    let o = scion(&[&args[..], &["--leaf-size", "7", "-o", &out]].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(read_hits(&out).unwrap(), read_hits(&reference).unwrap());
}

/// Every layout `scion layouts` lists traces teapot's primary rays through `scion trace
/// --backend llvm` (its own closest hit, LLVM -O3 for this CPU: the eight-wide ones as vector
/// code) to the reference's hits: the registry, the CLI and the generated code end to end.
/// Leaves of at most 7 primitives, for the hair BVH's 3 count bits, for every row and the
/// reference alike.
#[test]
fn every_library_layout_traces_teapot_to_the_reference_hits() {
    let dir = scratch("every_layout");
    let common_args = [
        "trace",
        "--scene",
        "teapot",
        "--n",
        "4096",
        "--runs",
        "1",
        "--leaf-size",
        "7",
    ];
    let reference = dir.join("ref.hits").display().to_string();
    let o = scion(&[&common_args[..], &["-o", &reference]].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));
    let want = read_hits(&reference).unwrap();
    // The layouts over triangles (hair-bvh-strands holds strand segments: cli/tests/strands.rs).
    let o = scion(&["layouts", "--names", "--primitive", "Triangle"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let names = text(&o.stdout);
    let names: Vec<&str> = names.lines().collect();
    assert!(names.len() >= 21, "{names:?}");
    for name in names {
        let out = dir.join(format!("{name}.hits")).display().to_string();
        let o = scion(
            &[
                &common_args[..],
                &["--backend", "llvm", "--layout", name, "-o", &out],
            ]
            .concat(),
        );
        assert!(o.status.success(), "{name}: {}", text(&o.stderr));
        assert_eq!(read_hits(&out).unwrap(), want, "{name}");
        // The same layout's GPU kernels, emulated on this CPU through the GPU pipeline
        // (`scion run`'s closest hit writes the hits file's records).
        let gpu = dir.join(format!("{name}.gpu")).display().to_string();
        let o = scion(&[
            "run",
            "--device",
            "gpu-emulated",
            "--algorithm",
            "closest-hit",
            "--layout",
            name,
            "--scene",
            "teapot",
            "--n",
            "4096",
            "--runs",
            "1",
            "--leaf-size",
            "7",
            "-o",
            &gpu,
        ]);
        assert!(
            o.status.success(),
            "{name} gpu-emulated: {}",
            text(&o.stderr)
        );
        assert_eq!(read_hits(&gpu).unwrap(), want, "{name} gpu-emulated");
    }
}

/// Wide layouts are checked against the reference of their width: on fzk_haus's secondary rays
/// the eight-wide tree's hits differ from the binary reference's on a few rays grazing
/// axis-aligned walls (neither is wrong: docs/runtime.md), which `scion run` once reported as
/// wrong answers; the hair BVH's oriented nodes find brute force's hit where the four-wide
/// reference's rounding pruned it, which the check settles by brute force.
#[test]
fn wide_layouts_are_checked_against_the_reference_of_their_width() {
    let base = [
        "--scene",
        "fzk_haus",
        "--rays",
        "secondary",
        "--n",
        "65536",
        "--runs",
        "1",
        "--leaf-size",
        "7",
    ];
    for (layout, device) in [("bvh8", "cpu"), ("bvh8-q8-ci", "gpu-emulated")] {
        let o = scion(
            &[
                &[
                    "run",
                    "--algorithm",
                    "closest-hit",
                    "--layout",
                    layout,
                    "--device",
                    device,
                ],
                &base[..],
            ]
            .concat(),
        );
        succeeds_with(
            &o,
            "identical to the eight-wide reference on all 65536 queries",
        );
    }
    let o = scion(
        &[
            &["trace", "--backend", "llvm", "--layout", "hair-bvh"],
            &base[..],
        ]
        .concat(),
    );
    succeeds_with(
        &o,
        "are brute force's hits, which the reference's rounding pruned",
    );
    assert!(text(&o.stdout).contains("identical to the four-wide reference on"));
}

/// `SCION_JIT_CPU` names the CPU the LLVM JIT compiles for: the baseline x86-64 (SSE2 only) or
/// AArch64's generic CPU, which every host of its architecture runs, traces an eight-wide and a
/// binary layout to the hits of the host CPU's code, bit for bit.
#[test]
fn the_llvm_jit_compiles_for_the_cpu_scion_jit_cpu_names() {
    let dir = scratch("jit_cpu");
    let baseline = if cfg!(target_arch = "aarch64") {
        "generic"
    } else {
        "x86-64"
    };
    for layout in ["pbrt", "bvh8"] {
        let mut hits = Vec::new();
        for cpu in ["", baseline] {
            let out = dir
                .join(format!("{layout}-{cpu}.hits"))
                .display()
                .to_string();
            let args = [
                "trace",
                "--scene",
                "teapot",
                "--rays",
                "secondary",
                "--n",
                "2048",
                "--runs",
                "1",
                "--backend",
                "llvm",
                "--layout",
                layout,
                "-o",
                &out,
            ];
            let o = std::process::Command::new(env!("CARGO_BIN_EXE_scion"))
                .args(args)
                .env("SCION_JIT_CPU", cpu)
                .output()
                .expect("run scion");
            succeeds_with(&o, "identical to the");
            hits.push(read_hits(&out).unwrap());
        }
        assert_eq!(hits[0], hits[1], "{layout}");
    }
    // The name reaches LLVM: one it does not know is reported (and ignored) by LLVM itself.
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_scion"))
        .args([
            "trace",
            "--scene",
            "teapot",
            "--n",
            "64",
            "--runs",
            "1",
            "--backend",
            "llvm",
        ])
        .env("SCION_JIT_CPU", "not-a-cpu")
        .output()
        .expect("run scion");
    assert!(text(&o.stderr).contains("'not-a-cpu' is not a recognized processor"));
}
