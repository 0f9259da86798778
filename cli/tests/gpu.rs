//! `scion ptx` and `scion trace --device gpu`: the PTX of closest hit for pbrt, ptr (and pbrt-q16,
//! whose box decoder is an explicit `fma.rn.f32`) has the
//! kernels of docs/design/backends.md §1 with the parameters the CUDA runtime passes (the
//! reference a `u32` for pbrt, a 64-bit address for ptr), no FMA contraction, and the asked
//! architecture; without a GPU, `--device gpu` is one clear error line and exit status 1; with
//! one, the GPU's hits are the reference's for both layouts (else one `skip:` line).

use crate::common;

use common::{scion, text, CUBE};
use scion_cuda::kit::PtxKit;
use scion_cuda::ptx;
use scion_cuda::trace::{
    check_ptx_kernels, packing_stack, per_level_frame, stack_frames, KernelNames, RootRef,
    MAX_PACK_STACK,
};
use scion_cuda::CudaError;
use scion_ir::tree::quant::Boxes;
use std::path::PathBuf;

fn scratch(test: &str) -> PathBuf {
    common::scratch("gpu", test)
}

/// `scion ptx --layout layout [--cpu cpu]` into `dir`, read back as a kit.
fn make_kit(dir: &std::path::Path, layout: &str, cpu: Option<&str>) -> PtxKit {
    let path = dir.join(format!("{layout}-{}.ptx", cpu.unwrap_or("default")));
    let mut args = vec!["ptx", "--layout", layout, "-o", path.to_str().unwrap()];
    if let Some(cpu) = cpu {
        args.extend(["--cpu", cpu]);
    }
    let o = scion(&args);
    assert!(o.status.success(), "{}", text(&o.stderr));
    PtxKit::parse(&std::fs::read_to_string(&path).unwrap()).unwrap()
}

fn kernel_shapes(kit: &PtxKit) -> Result<RootRef, CudaError> {
    check_ptx_kernels(&kit.ptx, &KernelNames::new(&kit.layout, &kit.algorithm))
}

#[test]
fn ptx_kits_have_the_contract_kernels() {
    let dir = scratch("kits");
    for (layout, name, root) in [
        ("pbrt", "LinearBVH", RootRef::U32),
        ("ptr", "PtrBVH", RootRef::U64),
    ] {
        let kit = make_kit(&dir, layout, None);
        assert_eq!(
            (kit.layout.as_str(), kit.algorithm.as_str()),
            (name, "closest_hit")
        );
        assert_eq!(kit.buffers, ["globals", "primitives", "nodes"], "{layout}");
        assert_eq!(kit.boxes, Boxes::Exact, "{layout}");
        assert_eq!(kernel_shapes(&kit).unwrap(), root, "{layout}");
        assert_eq!(ptx::directive(&kit.ptx, ".target"), Some("sm_90"));
        // The reference's arithmetic: one rounding per operation, no contraction.
        assert!(!kit.ptx.contains("fma."), "{layout}: FMA in the PTX");
        assert!(kit.ptx.contains("mul.rn.f32"), "{layout}");
    }
    // pbrt-q16 decodes its boxes with an explicit fused multiply-add (layout catalog §2.4):
    // `fma.rn.f32` is there on purpose, and nothing else is contracted into one.
    let kit = make_kit(&dir, "pbrt-q16", None);
    assert_eq!(
        (kit.layout.as_str(), kit.algorithm.as_str()),
        ("PbrtQ16", "closest_hit")
    );
    assert_eq!(kit.buffers, ["globals", "primitives", "nodes"]);
    // Its reference is the traversal of the decoded boxes, also where no LLVM is (scion-gpu).
    assert_eq!(kit.boxes, Boxes::GlobalQ16);
    assert_eq!(kernel_shapes(&kit).unwrap(), RootRef::U32);
    assert!(kit.ptx.contains("fma.rn.f32"), "pbrt-q16: no decoder FMA");
    assert!(
        !kit.ptx.contains("fma.rn.ftz"),
        "pbrt-q16: flush-to-zero decoder"
    );
    // sg-eq decodes with directed rounding: one PTX instruction each, never flushed to zero.
    let kit = make_kit(&dir, "sg-eq", None);
    assert_eq!(kit.layout, "SgEq");
    assert_eq!(kit.boxes, Boxes::SnappedQ10);
    for op in ["mul.rm.f32", "add.rm.f32", "sub.rp.f32"] {
        assert!(kit.ptx.contains(op), "sg-eq: no {op}");
    }
    assert!(!kit.ptx.contains(".ftz"), "sg-eq: flush-to-zero decoder");
    let kit = make_kit(&dir, "pbrt", Some("sm_80"));
    assert_eq!(ptx::directive(&kit.ptx, ".target"), Some("sm_80"));
}

/// Without a GPU, NVIDIA's offline assembler (CUDA 13.5's ptxas, installed by
/// scripts/setup.sh) still checks what the driver's JIT will see: the kit of every library
/// layout assembles for sm_90, and its verbose log (the format of the JIT log the packing
/// stack is sized from) names the four kernels and the recursive node functions' frames.
#[test]
fn ptxas_assembles_the_kits_and_its_log_sizes_the_packing_stack() {
    let Some(ptxas) = scion_cuda::ptxas::find() else {
        println!("skip: no ptxas (scripts/setup.sh installs CUDA 13.5's into ~/.cache/scion)");
        return;
    };
    let dir = scratch("ptxas");
    for layout in [
        "pbrt",
        "ptr",
        "pbrt-q16",
        "pbrt-align16",
        "pbrt-soaos",
        "sg-eq",
    ] {
        let kit = make_kit(&dir, layout, None);
        let log = scion_cuda::ptxas::assemble(&ptxas, &kit.ptx, "sm_90")
            .unwrap_or_else(|e| panic!("{layout}: {e}"));
        let names = KernelNames::new(&kit.layout, &kit.algorithm);
        let kernels = [
            names.sizes.as_str(),
            names.build.as_str(),
            names.root.as_str(),
            names.batch.as_str(),
        ];
        let frames = stack_frames(&log);
        for k in kernels {
            assert!(
                frames.iter().any(|(f, _)| f == k),
                "{layout}: no {k} in\n{log}"
            );
        }
        // `@L.node` recurses, so it is a function of its own with a frame on the stack.
        let per_level = per_level_frame(&log, &kernels)
            .unwrap_or_else(|| panic!("{layout}: no function frames in\n{log}"));
        assert!(per_level > 0, "{layout}: {log}");
        // A 64-level tree packs within the stack the runtime may ask for.
        assert!(
            packing_stack(64, Some(per_level), 1024) < MAX_PACK_STACK,
            "{layout}"
        );
    }
    // The architecture asked for is the one assembled.
    let kit = make_kit(&dir, "ptr", Some("sm_80"));
    let log = scion_cuda::ptxas::assemble(&ptxas, &kit.ptx, "sm_80").unwrap();
    assert!(log.contains("for 'sm_80'"), "{log}");
    // And a PTX ptxas cannot take is an error with its diagnostics.
    let e = scion_cuda::ptxas::assemble(&ptxas, ".version 7.8\n.target sm_90\nbogus;\n", "sm_90")
        .unwrap_err();
    assert!(e.starts_with("ptxas rejected the PTX"), "{e}");
}

#[test]
fn unknown_layouts_are_errors() {
    let dir = scratch("unknown");
    let o = scion(&[
        "ptx",
        "--layout",
        "nope",
        "-o",
        dir.join("x.ptx").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "a bad command line");
    let err = text(&o.stderr);
    assert!(
        err.contains("error: unknown layout `nope` for the GPU"),
        "{err}"
    );
    assert!(
        err.contains("layouts a kit holds: pbrt, pbrt-align16") && err.contains("sg-eq-align16"),
        "{err}"
    );
    // A kit holds the binary closest hit (scion-gpu checks it against the binary reference);
    // an eight-wide layout runs on the GPU only within `scion trace --device gpu|gpu-emulated`.
    let o = scion(&[
        "ptx",
        "--layout",
        "bvh8",
        "-o",
        dir.join("x.ptx").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "a bad command line");
    let err = text(&o.stderr);
    assert!(err.contains("a PTX kit holds `closest_hit`"), "{err}");
    assert!(err.contains("without --emit-ptx runs it"), "{err}");
    // `scion layouts` says which layouts a kit holds and which the GPU path runs.
    let names = |flag: &str| {
        let o = scion(&["layouts", flag, "--names"]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        text(&o.stdout)
            .lines()
            .map(String::from)
            .collect::<Vec<_>>()
    };
    let (kit, gpu) = (names("--kit"), names("--gpu"));
    assert!(
        kit.contains(&"pbrt".into()) && kit.contains(&"sg-eq-align16".into()),
        "{kit:?}"
    );
    assert!(!kit.contains(&"bvh8".into()), "{kit:?}");
    for name in ["pbrt", "bvh8", "bvh8-q8-ci", "dop14-split", "bvh8-tri4"] {
        assert!(gpu.contains(&name.into()), "{name}: {gpu:?}");
    }
    assert!(!gpu.contains(&"hair-bvh-strands".into()), "{gpu:?}");
    assert!(kit.iter().all(|k| gpu.contains(k)), "{kit:?} {gpu:?}");
}

#[test]
fn device_gpu_traces_like_the_reference_or_says_why_not() {
    let dir = scratch("trace");
    let scene = dir.join("cube.obj");
    std::fs::write(&scene, CUBE).unwrap();
    let scene = scene.to_str().unwrap();
    for layout in ["pbrt", "ptr", "pbrt-q16"] {
        let kit = dir.join(format!("{layout}.ptx"));
        let hits = dir.join(format!("{layout}.hits"));
        let o = scion(&[
            "trace",
            "--device",
            "gpu",
            "--scene",
            scene,
            "--layout",
            layout,
            "--rays",
            "secondary",
            "--n",
            "1000",
            "--runs",
            "3",
            "--emit-ptx",
            kit.to_str().unwrap(),
            "-o",
            hits.to_str().unwrap(),
        ]);
        let (out, err) = (text(&o.stdout), text(&o.stderr));
        assert!(!err.contains("panicked"), "{err}");
        if o.status.success() {
            assert!(
                out.contains("check        identical to the reference on all 1000 rays"),
                "{out}"
            );
            assert!(out.contains("Mrays/s"), "{out}");
            assert!(kit.exists() && hits.exists());
            // The kit written runs again, read from the file.
            let o = scion(&[
                "trace",
                "--device",
                "gpu",
                "--scene",
                scene,
                "--ptx",
                kit.to_str().unwrap(),
                "--rays",
                "secondary",
                "--n",
                "1000",
                "--runs",
                "1",
            ]);
            assert!(o.status.success(), "{}", text(&o.stderr));
            continue;
        }
        assert_eq!(o.status.code(), Some(1), "{err}");
        let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error: ")).collect();
        assert_eq!(errors.len(), 1, "{err}");
        let reason = errors[0].trim_start_matches("error: ");
        assert!(
            reason.starts_with("no CUDA driver")
                || reason.starts_with("no CUDA device")
                || reason.starts_with("the CUDA driver is too old"),
            "{err}"
        );
        println!("skip: {reason} [scion trace --device gpu --layout {layout}]");
    }
}

/// `--device gpu-emulated`: the GPU kernels run on this CPU through the GPU pipeline, every hit
/// checked against the reference, with the checksum and hits file of the CPU backends.
#[test]
fn device_gpu_emulated_traces_like_the_cpu() {
    let dir = scratch("emulated");
    let scene = dir.join("cube.obj");
    std::fs::write(&scene, CUBE).unwrap();
    let scene = scene.to_str().unwrap();
    let common = [
        "trace",
        "--scene",
        scene,
        "--rays",
        "secondary",
        "--n",
        "1000",
        "--runs",
        "3",
    ];
    let cpu = scion(&[&common[..], &["--backend", "llvm"]].concat());
    assert!(cpu.status.success(), "{}", text(&cpu.stderr));
    let checksum = |out: &str| {
        out.lines()
            .find(|l| l.starts_with("checksum: "))
            .unwrap_or_else(|| panic!("no checksum in {out}"))
            .to_string()
    };
    let want = checksum(&text(&cpu.stdout));
    // The binary layouts and, checked against the reference of their width, wide ones.
    for layout in [
        "pbrt",
        "ptr",
        "pbrt-q16",
        "sg-eq",
        "bvh8",
        "bvh8-q8-ci",
        "dop14-split",
    ] {
        let hits = dir.join(format!("{layout}.hits"));
        let o = scion(
            &[
                &common[..],
                &[
                    "--device",
                    "gpu-emulated",
                    "--layout",
                    layout,
                    "-o",
                    hits.to_str().unwrap(),
                ],
            ]
            .concat(),
        );
        let (out, err) = (text(&o.stdout), text(&o.stderr));
        assert!(o.status.success(), "{layout}: {err}");
        let reference = match layout.starts_with("bvh8") {
            true => "eight-wide reference",
            false => "reference",
        };
        assert!(
            out.contains(&format!(
                "check        identical to the {reference} on all 1000 rays"
            )),
            "{out}"
        );
        assert!(out.contains("device       emulated on the CPU"), "{out}");
        assert!(
            out.contains("backend      gpu-emulated (closest_hit"),
            "{out}"
        );
        assert!(out.contains("Mrays/s"), "{out}");
        // On the cube the quantized layouts' wider boxes change no hit: one checksum for all.
        assert_eq!(checksum(&out), want, "{layout}");
        assert_eq!(std::fs::metadata(&hits).unwrap().len(), 8 * 1000);
        assert!(err.contains("on the emulated GPU"), "{err}");
    }
    // A stack smaller than the tree is the kernel's overflow status, one error line.
    let o = scion(
        &[
            &common[..],
            &[
                "--device",
                "gpu-emulated",
                "--builder",
                "median",
                "--stack-size",
                "1",
            ],
        ]
        .concat(),
    );
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains(
            "error: GPU: kernel `scion_closest_hit_LinearBVH_kernel`: traversal stack overflow"
        ),
        "{err}"
    );
    assert!(err.contains("try a larger --stack-size"), "{err}");
    let o = scion(
        &[
            &common[..],
            &["--device", "gpu-emulated", "--layout", "nope"],
        ]
        .concat(),
    );
    assert_eq!(o.status.code(), Some(2), "a bad command line");
    assert!(text(&o.stderr).contains("error: unknown layout `nope` for the GPU"));
}

/// scripts/gpu-check.sh, the one command of the GPU check, run end to end without a GPU
/// (`GPU_CHECK_DEVICE=gpu-emulated`) on a kit of the `scion` under test and two small scenes:
/// every trace is found identical (its `check` line read, not the `checksum:` line before it),
/// any hit and closest point run through `scion run --device` and check, and the summary and
/// the table for docs/benchmarks.md are written.
#[test]
fn gpu_check_script_passes_on_the_emulated_device() {
    let dir = scratch("gpu-check");
    let kit = dir.join("kit");
    std::fs::create_dir_all(kit.join("bin")).unwrap();
    std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_scion"), kit.join("bin/scion")).unwrap();
    std::fs::write(kit.join("COMMIT"), "test\n").unwrap();
    let scenes = dir.join("scenes");
    std::fs::create_dir_all(&scenes).unwrap();
    std::fs::write(scenes.join("cube.obj"), CUBE).unwrap();
    // A 6 x 6 grid of quads, bent along x: 72 triangles.
    let mut grid = String::new();
    for j in 0..7 {
        for i in 0..7 {
            grid += &format!("v {i} {j} {}\n", (i * i) as f32 * 0.1);
        }
    }
    for j in 0..6 {
        for i in 0..6 {
            let v = j * 7 + i + 1;
            grid += &format!("f {} {} {} {}\n", v, v + 1, v + 8, v + 7);
        }
    }
    std::fs::write(scenes.join("grid.obj"), grid).unwrap();
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scripts/gpu-check.sh");
    let results = dir.join("results");
    let run = |device: &str| {
        std::process::Command::new("bash")
            .arg(&script)
            .env("GPU_KIT", &kit)
            .env("SCION_SCENES", &scenes)
            .env("GPU_CHECK_N", "400")
            .env("GPU_CHECK_RUNS", "1")
            .env("GPU_CHECK_DEVICE", device)
            .env("OUT", &results)
            .output()
            .expect("run bash")
    };
    let o = run("gpu-emulated");
    let (out, err) = (text(&o.stdout), text(&o.stderr));
    assert!(o.status.success(), "{out}\n{err}");
    let summary = std::fs::read_to_string(results.join("summary.txt")).unwrap();
    assert!(
        summary.contains(
            "gpu-check: 16 of 16 traces identical to the reference; 0 not run (budget spent; \
             a failure for pbrt and ptr); 0 test binaries failed; 0 runs of other query kinds \
             failed"
        ),
        "{summary}"
    );
    // Any hit and closest point through `scion run --device`, on both scenes.
    let kinds: Vec<&str> = summary
        .lines()
        .filter(|l| l.contains(" any-hit ") || l.contains(" closest-point "))
        .collect();
    assert_eq!(kinds.len(), 4, "{summary}");
    assert!(
        kinds.iter().all(|l| l.contains("ok: identical")),
        "{summary}"
    );
    assert!(
        summary.contains("gpu-check: emulated on the CPU"),
        "{summary}"
    );
    let table = std::fs::read_to_string(results.join("benchmarks.md")).unwrap();
    let rows: Vec<&str> = table
        .lines()
        .filter(|l| l.starts_with("| cube ") || l.starts_with("| grid "))
        .collect();
    assert_eq!(rows.len(), 4, "{table}");
    assert!(
        rows.iter()
            .any(|r| r.starts_with("| cube | 12 | primary |")),
        "{table}"
    );
    assert!(
        rows.iter()
            .any(|r| r.starts_with("| grid | 72 | secondary |")),
        "{table}"
    );
    assert!(rows.iter().all(|r| !r.contains("(!)")), "{table}");
    assert!(table.contains("closest hit, 400 rays"), "{table}");
    // The sweep on the device: every kit layout on both scenes, checked, with its plots.
    let csv = std::fs::read_to_string(results.join("explore/results.csv")).unwrap();
    let swept: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(swept.len(), 8, "{csv}");
    assert!(
        swept
            .iter()
            .all(|r| r.contains(",gpu-emulated,") && r.contains(",identical,")),
        "{csv}"
    );
    assert!(results.join("explore/index.md").exists());
    let tsv = std::fs::read_to_string(results.join("traces.tsv")).unwrap();
    assert_eq!(
        tsv.lines().filter(|l| l.ends_with("\tok")).count(),
        16,
        "{tsv}"
    );
    // A device it does not know is a usage error.
    let o = run("tpu");
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("GPU_CHECK_DEVICE must be gpu or gpu-emulated"));
}
