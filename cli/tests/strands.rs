//! `scion strands`: a seeded head of hair written as a `.hair` file (the same bytes for the same
//! options), traced through the hair BVH over strands by Cranelift and LLVM with every hit
//! checked against the reference, and the user errors (a triangle layout for strands, a strand
//! scene for `scion trace`, a file that is not `.hair`) as clear messages.

use crate::common;

use common::{scion, text};

#[test]
fn generated_strands_trace_to_the_reference_through_both_code_generators() {
    let dir = common::scratch("strands", "trace");
    let a = dir.join("a.hair").display().to_string();
    let b = dir.join("b.hair").display().to_string();
    for out in [&a, &b] {
        let o = scion(&[
            "strands",
            "generate",
            "--strands",
            "300",
            "--segments",
            "8",
            "--seed",
            "5",
            "-o",
            out,
        ]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        assert!(
            text(&o.stdout).contains("2400 segments"),
            "{}",
            text(&o.stdout)
        );
    }
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    for backend in ["jit", "llvm"] {
        for rays in ["primary", "secondary"] {
            let o = scion(&[
                "strands",
                "trace",
                "--scene",
                &a,
                "--backend",
                backend,
                "--rays",
                rays,
                "--n",
                "4000",
                "--runs",
                "1",
                "--threads",
                "2",
            ]);
            let out = text(&o.stdout);
            assert!(
                o.status.success(),
                "{backend} {rays}: {}{out}",
                text(&o.stderr)
            );
            assert!(out.contains("segments     2400"), "{out}");
            assert!(
                out.contains("check        identical to the reference on all 4000 rays"),
                "{out}"
            );
            let hits: usize = out
                .lines()
                .find_map(|l| l.strip_prefix("hits         "))
                .and_then(|l| l.split_whitespace().next())
                .and_then(|n| n.parse().ok())
                .unwrap();
            assert!(hits > 40, "{backend} {rays}: {hits} hits");
        }
    }
}

#[test]
fn strand_scenes_and_layouts_are_not_mixed_up() {
    let dir = common::scratch("strands", "errors");
    let hair = dir.join("h.hair").display().to_string();
    let o = scion(&[
        "strands",
        "generate",
        "--strands",
        "10",
        "--segments",
        "2",
        "-o",
        &hair,
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let o = scion(&["strands", "trace", "--scene", &hair, "--layout", "pbrt"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("its leaves hold `Triangle`s"),
        "{}",
        text(&o.stderr)
    );
    let o = scion(&["trace", "--scene", &hair]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("scion strands trace"),
        "{}",
        text(&o.stderr)
    );
    let obj = common::write(&dir, "cube.obj", common::CUBE);
    let o = scion(&["strands", "trace", "--scene", &obj]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stderr).contains("not a .hair file"),
        "{}",
        text(&o.stderr)
    );
    let o = scion(&[
        "trace",
        "--scene",
        &obj,
        "--backend",
        "llvm",
        "--layout",
        "hair-bvh-strands",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("its leaves hold `Segment`s"),
        "{}",
        text(&o.stderr)
    );
    let o = scion(&["layouts", "--names", "--primitive", "Segment"]);
    assert_eq!(text(&o.stdout).trim(), "hair-bvh-strands");
}
