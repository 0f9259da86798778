//! `scion trace` and `scion run` with `--layout bvh8-tri4`: a layout whose leaves hold blocks
//! of four triangles (`Triangle4`) traced from the library's registry by Cranelift, LLVM and
//! the emulated GPU pipeline, on primary and secondary rays and trees of every builder: every
//! hit checked against the eight-wide reference over the same blocks, the hits written equal
//! to the reference traversal's over the triangles, `--stats` reporting the blocks' work, and
//! the errors (a backend that does not trace blocks, `scion run` on a GPU, a stack too small)
//! as clear messages.

use crate::common;

use common::{scion, soup, text, write};
use std::path::PathBuf;

fn scratch(test: &str) -> PathBuf {
    common::scratch("blocks", test)
}

#[test]
fn blocks_of_four_are_traced_checked_and_hit_the_triangles() {
    let dir = scratch("trace");
    let scene = write(&dir, "soup.obj", &soup(600));
    let run = |backend: &str, layout: &str, rays: &str, extra: &[&str]| {
        let out = dir.join(format!("{backend}-{layout}-{rays}-{}.hits", extra.join("")));
        let mut args = vec![
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
        ];
        let path = out.display().to_string();
        args.extend(["-o", &path]);
        args.extend(extra);
        let o = scion(&args);
        assert!(
            o.status.success(),
            "{backend} {layout} {extra:?}: {}",
            text(&o.stderr)
        );
        (text(&o.stdout), std::fs::read(&out).unwrap())
    };
    for rays in ["primary", "secondary"] {
        let (_, want) = run("reference", "pbrt", rays, &[]);
        // The GPU kernels over the same block tree, emulated on this CPU.
        let (stdout, got) = run(
            "reference",
            "bvh8-tri4",
            rays,
            &["--device", "gpu-emulated"],
        );
        assert!(
            stdout.contains(
                "check        identical to the eight-wide reference over the same blocks on \
                 all 3000 rays"
            ),
            "{stdout}"
        );
        assert!(got == want, "gpu-emulated {rays}: hits differ");
        // `scion run`'s closest hit over the same blocks writes the same records.
        let out = dir.join(format!("run-{rays}.hits")).display().to_string();
        let o = scion(&[
            "run",
            "--algorithm",
            "closest-hit",
            "--layout",
            "bvh8-tri4",
            "--scene",
            &scene,
            "--rays",
            rays,
            "--n",
            "3000",
            "--runs",
            "1",
            "-o",
            &out,
        ]);
        assert!(o.status.success(), "run {rays}: {}", text(&o.stderr));
        assert!(
            text(&o.stdout).contains("identical to the eight-wide reference over the same blocks"),
            "{}",
            text(&o.stdout)
        );
        assert!(
            std::fs::read(&out).unwrap() == want,
            "run {rays}: hits differ"
        );
        for backend in ["jit", "llvm"] {
            for extra in [
                &["--stats"][..],
                &["--builder", "median"],
                &["--leaf-size", "15"],
            ] {
                let (stdout, got) = run(backend, "bvh8-tri4", rays, extra);
                assert!(
                    stdout.contains(
                        "check        identical to the eight-wide reference over the same blocks \
                         on all 3000 rays"
                    ),
                    "{stdout}"
                );
                // The blocks answer for their triangles: on this scene's rays no rounding
                // exception separates them from the binary reference (a fixed scene and seed).
                assert!(got == want, "{backend} {rays} {extra:?}: hits differ");
                if extra == ["--stats"] {
                    assert!(stdout.contains("collapsed for blocks of four"), "{stdout}");
                    assert!(stdout.contains("leaves <= 8"), "{stdout}");
                    assert!(stdout.contains("block tests per ray"), "{stdout}");
                }
            }
        }
    }
}

#[test]
fn backends_and_stacks_that_cannot_trace_blocks_are_clear_errors() {
    let dir = scratch("errors");
    let scene = write(&dir, "soup.obj", &soup(600));
    let base = [
        "trace",
        "--scene",
        &scene,
        "--layout",
        "bvh8-tri4",
        "--runs",
        "1",
    ];
    let mut args = base.to_vec();
    args.extend(["--backend", "mem-interp"]);
    let o = scion(&args);
    assert!(!o.status.success());
    let e = text(&o.stderr);
    assert!(e.contains("`bvh8-tri4` for --backend mem-interp"), "{e}");
    assert!(!e.contains("panicked"), "{e}");
    // `scion run` runs blocks on the CPU; its GPU path says which command runs their kernels.
    let o = scion(&[
        "run",
        "--algorithm",
        "closest-hit",
        "--layout",
        "bvh8-tri4",
        "--scene",
        &scene,
        "--device",
        "gpu-emulated",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stdout));
    assert!(text(&o.stderr).contains("scion trace --device gpu-emulated"));
    let mut args = base.to_vec();
    args.extend([
        "--backend",
        "llvm",
        "--stack-size",
        "1",
        "--rays",
        "secondary",
    ]);
    let o = scion(&args);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o.stdout));
    let e = text(&o.stderr);
    assert!(e.contains("stack overflowed"), "{e}");
    assert!(e.contains("--stack-size"), "{e}");
}
