//! `scion render` end to end: the same picture, byte for byte, through the binary pbrt layout,
//! the pointer layout, the eight-wide bvh8 and the quantized pbrt-q16, with Cranelift and LLVM;
//! a real PNG of the size asked for, with hit and missed pixels; bad requests are usage errors.

use crate::common;

use common::{fails_with, scion, succeeds_with, text};
use std::path::PathBuf;

fn scratch(test: &str) -> PathBuf {
    common::scratch("render", test)
}

/// The PNG's width and height from its header (signature, then the IHDR chunk).
fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "a PNG signature");
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |k: usize| u32::from_be_bytes(bytes[k..k + 4].try_into().unwrap());
    (be(16), be(20))
}

#[test]
fn every_layout_and_backend_draws_the_same_picture() {
    let dir = scratch("same");
    let mut first: Option<Vec<u8>> = None;
    for (layout, backend) in [
        ("pbrt", "llvm"),
        ("pbrt", "jit"),
        ("ptr", "llvm"),
        ("bvh8", "llvm"),
        ("pbrt-q16", "jit"),
    ] {
        let out = dir.join(format!("{layout}-{backend}.png"));
        let o = scion(&[
            "render",
            "--scene",
            "teapot",
            "--layout",
            layout,
            "--backend",
            backend,
            "--width",
            "96",
            "--height",
            "72",
            "-o",
            out.to_str().unwrap(),
        ]);
        // bvh8 against the eight-wide reference (scion_host::hit_reference).
        let reference = match layout {
            "bvh8" => "eight-wide reference",
            _ => "reference",
        };
        succeeds_with(
            &o,
            &format!("check        identical to the {reference} on all"),
        );
        let stdout = text(&o.stdout);
        let hit: usize = stdout
            .split(", ")
            .find_map(|w| w.split(" of ").next()?.parse().ok())
            .unwrap_or_else(|| panic!("no hit count in {stdout}"));
        assert!(
            hit > 500 && hit < 96 * 72,
            "{layout}: {hit} pixels hit: the teapot fills part of the view"
        );
        let png = std::fs::read(&out).unwrap();
        assert_eq!(png_size(&png), (96, 72));
        match &first {
            None => first = Some(png),
            Some(f) => assert!(*f == png, "{layout} {backend}: another picture than pbrt's"),
        }
    }
    // Another shading is another picture.
    let out = dir.join("diffuse.png");
    let o = scion(&[
        "render",
        "--scene",
        "teapot",
        "--width",
        "96",
        "--height",
        "72",
        "--shading",
        "diffuse",
        "-o",
        out.to_str().unwrap(),
    ]);
    succeeds_with(&o, "diffuse shading");
    assert!(std::fs::read(&out).unwrap() != first.unwrap());
}

#[test]
fn bad_requests_are_usage_errors() {
    let out = scratch("bad").join("x.png");
    let o = scion(&[
        "render",
        "--scene",
        "teapot",
        "--layout",
        "btree",
        "-o",
        out.to_str().unwrap(),
    ]);
    fails_with(&o, 2, "unknown layout `btree`");
    let o = scion(&["render", "--scene", "teapot", "--width", "0", "-o", "x.png"]);
    fails_with(&o, 2, "--width");
}
