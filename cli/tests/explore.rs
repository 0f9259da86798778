//! `scion explore` and `scion tune` end to end on a small sweep: one CSV row per measurement
//! with the machine, commit and toolchain, answers checked, speed against error for the
//! quantized layout; a rerun skips what the file has; plots and their index are written; tune
//! picks the fastest, the fastest within a memory budget and the smallest within a slowdown
//! from the same measurements, and emits the chosen layout's header and object file.

use crate::common;

use common::{fails_with, scion, succeeds_with, text};
use std::path::PathBuf;

fn scratch(test: &str) -> PathBuf {
    common::scratch("explore", test)
}

fn rows(csv: &std::path::Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(csv)
        .unwrap()
        .lines()
        .map(|l| {
            // The builder's description is the only quoted field.
            let mut out = Vec::new();
            let mut cur = String::new();
            let mut quoted = false;
            for c in l.chars() {
                match c {
                    '"' => quoted = !quoted,
                    ',' if !quoted => out.push(std::mem::take(&mut cur)),
                    _ => cur.push(c),
                }
            }
            out.push(cur);
            out
        })
        .collect()
}

#[test]
fn a_sweep_writes_checked_rows_resumes_and_plots() {
    let dir = scratch("sweep");
    let csv = dir.join("r.csv");
    let plots = dir.join("plots");
    let args = [
        "explore",
        "--scenes",
        "teapot",
        "--layouts",
        "pbrt,pbrt-q16,bvh8",
        "--kinds",
        "closest-hit,closest-point",
        "--sizes",
        "2^12",
        "--runs",
        "1",
        "-o",
        csv.to_str().unwrap(),
        "--plots",
        plots.to_str().unwrap(),
    ];
    let o = scion(&args);
    // closest hit: 3 layouts × primary, secondary; closest point: 3 layouts × points.
    succeeds_with(&o, "9 measurements to make (0 already");
    let r = rows(&csv);
    assert_eq!(r.len(), 10, "a header and nine rows");
    let h = &r[0];
    let col = |name: &str| h.iter().position(|c| c == name).unwrap();
    for row in &r[1..] {
        assert_eq!(row.len(), h.len());
        assert_eq!(row[col("check")], "identical", "{row:?}");
        assert_eq!(row[col("scene")], "teapot");
        assert_eq!(row[col("n")], "4096");
        assert!(row[col("toolchain")].contains("LLVM 22"), "{row:?}");
        assert!(row[col("ns_per_query")].parse::<f64>().unwrap() > 0.0);
        let quantized = row[col("layout")] == "pbrt-q16" && row[col("kind")] == "closest-hit";
        let inflation = &row[col("area_inflation")];
        assert_eq!(!inflation.is_empty(), quantized, "{row:?}");
        if quantized {
            assert!(inflation.parse::<f64>().unwrap() >= 1.0);
        }
    }
    // A rerun measures nothing and keeps the rows.
    let o = scion(&args);
    succeeds_with(&o, "0 measurements to make (9 already");
    assert_eq!(rows(&csv).len(), 10);
    let index = std::fs::read_to_string(plots.join("index.md")).unwrap();
    assert!(
        index.contains("## teapot: closest-point (4096 points)"),
        "{index}"
    );
    assert!(index.contains("| pbrt |"), "{index}");
    let svg = std::fs::read_to_string(plots.join("teapot-closest-hit-primary-4096-llvm-O3-1.svg"))
        .unwrap();
    assert!(
        svg.starts_with("<svg") && svg.contains("pbrt-q16"),
        "an SVG naming the layouts"
    );
    assert!(plots
        .join("teapot-closest-hit-primary-4096-llvm-O3-1-error.svg")
        .exists());
    // Every figure is also a PNG (its text drawn with the embedded font).
    for stem in [
        "teapot-closest-hit-primary-4096-llvm-O3-1",
        "teapot-closest-hit-primary-4096-llvm-O3-1-error",
        "teapot-closest-point-points-4096-llvm-O3-1",
    ] {
        let png = std::fs::read(plots.join(format!("{stem}.png"))).unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{stem}.png is a PNG");
    }

    // Peers on the plots: their time scaled by the ratio to their anchor in their own run.
    let r = rows(&csv);
    let pbrt_ns: f64 = r[1..]
        .iter()
        .find(|row| {
            row[col("layout")] == "pbrt"
                && row[col("queries")] == "primary"
                && row[col("kind")] == "closest-hit"
        })
        .map(|row| row[col("ns_per_query")].parse().unwrap())
        .unwrap();
    let peers = dir.join("peers.csv");
    std::fs::write(
        &peers,
        "scene,kind,queries,n,threads,peer,bytes,triangles,ns_per_query,anchor,anchor_ns_per_query\n\
         teapot.obj,closest-hit,primary,4096,1,embree,99200,992,50.0,llvm-O3 pbrt,200.0\n\
         teapot.obj,closest-hit,primary,4096,1,tinybvh bvh8_cpu,,992,100.0,llvm-O3 pbrt,200.0\n\
         teapot.obj,closest-hit,primary,4096,2,other threads,99200,992,1.0,llvm-O3 pbrt,200.0\n",
    )
    .unwrap();
    let mut with_peers = args.to_vec();
    with_peers.extend(["--peers", peers.to_str().unwrap()]);
    succeeds_with(&scion(&with_peers), "plots ");
    let index = std::fs::read_to_string(plots.join("index.md")).unwrap();
    let embree = format!("| peer: embree | 100.0 | {:.1} | |", pbrt_ns * 0.25);
    let tiny = format!("| peer: tinybvh bvh8_cpu | ? | {:.1} | |", pbrt_ns * 0.5);
    assert!(index.contains(&embree), "{embree} in {index}");
    assert!(index.contains(&tiny), "{tiny} in {index}");
    assert!(!index.contains("other threads"), "{index}");
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, "scene,peer\nteapot,x\n").unwrap();
    let mut bad_args = args.to_vec();
    bad_args.extend(["--peers", bad.to_str().unwrap()]);
    fails_with(&scion(&bad_args), 1, "not a peers file");
    // A layout over blocks of four triangles or strand segments is not swept; the error says
    // which command measures it.
    for (layout, hint) in [
        ("bvh8-tri4", "scion trace --backend llvm --layout bvh8-tri4"),
        ("hair-bvh-strands", "scion strands trace"),
    ] {
        let mut a = args.to_vec();
        a[4] = layout;
        fails_with(&scion(&a), 2, hint);
    }
}

#[test]
fn a_gpu_sweep_runs_the_gpu_kernels() {
    let dir = scratch("gpu");
    let csv = dir.join("r.csv");
    let o = scion(&[
        "explore",
        "--scenes",
        "teapot",
        "--layouts",
        "pbrt,bvh8",
        "--kinds",
        "closest-hit,closest-point",
        "--rays",
        "primary",
        "--devices",
        "gpu-emulated",
        "--sizes",
        "2^12",
        "--runs",
        "1",
        "-o",
        csv.to_str().unwrap(),
    ]);
    succeeds_with(&o, "4 measurements to make");
    let r = rows(&csv);
    assert_eq!(r.len(), 5, "a header and four rows");
    let h = &r[0];
    let col = |name: &str| h.iter().position(|c| c == name).unwrap();
    for row in &r[1..] {
        assert_eq!(row[col("backend")], "gpu-emulated", "{row:?}");
        assert_eq!(row[col("check")], "identical", "{row:?}");
    }
    // `--devices gpu` measures on an NVIDIA GPU, or says there is none.
    let o = scion(&[
        "explore",
        "--scenes",
        "teapot",
        "--layouts",
        "pbrt",
        "--rays",
        "primary",
        "--devices",
        "gpu",
        "--sizes",
        "2^12",
        "--runs",
        "1",
        "-o",
        dir.join("gpu.csv").to_str().unwrap(),
    ]);
    if !o.status.success() {
        fails_with(&o, 1, "NVIDIA GPU");
    } else {
        let r = rows(&dir.join("gpu.csv"));
        assert!(r[1..].iter().all(|row| row.contains(&"ptx".to_string())));
    }
    // tune on the emulated GPU: chooses among what it measured there.
    let o = scion(&[
        "tune",
        "--scene",
        "teapot",
        "--layouts",
        "pbrt,bvh8",
        "--device",
        "gpu-emulated",
        "--n",
        "2^12",
        "--runs",
        "1",
        "--results",
        dir.join("tune.csv").to_str().unwrap(),
    ]);
    succeeds_with(&o, "choice       ");
    succeeds_with(&o, "gpu-emulated");
}

#[test]
fn tune_chooses_from_the_frontier_and_emits_it() {
    let dir = scratch("tune");
    let csv = dir.join("r.csv");
    let base = [
        "tune",
        "--scene",
        "teapot",
        "--layouts",
        "pbrt,pbrt-q16,ptr",
        "--n",
        "2^12",
        "--runs",
        "1",
        "--results",
        csv.to_str().unwrap(),
    ];
    let o = scion(&base);
    succeeds_with(&o, "choice       ");
    let out = text(&o.stdout);
    assert!(out.contains("(the fastest:"), "{out}");
    // The same measurements, a memory budget that only pbrt-q16 (45 bytes per triangle, pbrt 50) meets.
    let mut args = base.to_vec();
    args.extend(["--max-bytes-per-triangle", "48"]);
    let o = scion(&args);
    succeeds_with(&o, "0 measurements to make");
    succeeds_with(
        &o,
        "choice       pbrt-q16 (the fastest within 48 bytes per triangle",
    );
    // A slowdown of 100 times takes the smallest.
    let mut args = base.to_vec();
    args.extend(["--max-slowdown", "100"]);
    succeeds_with(
        &scion(&args),
        "choice       pbrt-q16 (the smallest within 100 times",
    );
    // Nothing fits in 1 byte per triangle.
    let mut args = base.to_vec();
    args.extend(["--max-bytes-per-triangle", "1"]);
    fails_with(&scion(&args), 1, "no layout fits in 1 bytes per triangle");
    // The choice's header and object file.
    for (emit, file) in [("header", "chosen.h"), ("obj", "chosen.o")] {
        let path = dir.join(file);
        let mut args = base.to_vec();
        args.extend([
            "--max-bytes-per-triangle",
            "48",
            "--emit",
            emit,
            "-o",
            path.to_str().unwrap(),
        ]);
        succeeds_with(&scion(&args), "output       ");
        let bytes = std::fs::read(&path).unwrap();
        match emit {
            "header" => assert!(
                String::from_utf8_lossy(&bytes).contains("PbrtQ16"),
                "the chosen layout's header"
            ),
            _ => assert_eq!(&bytes[..4], b"\x7fELF"),
        }
    }
    fails_with(
        &scion(&["tune", "--scene", "teapot", "--algorithm", "collide"]),
        2,
        "closest-hit, any-hit or closest-point",
    );
}
