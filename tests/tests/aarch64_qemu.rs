//! AArch64 machine code, run. `scionc -O3 --emit=obj --target=aarch64 --entry closest_hit`
//! for every library layout is linked with `tests/replay/replay.c` by the AArch64 cross
//! compiler and run under qemu-user on recorded trees and rays: real scenes (primary,
//! secondary and feature rays) and every generated hard case (axis rays with signed zeros,
//! feature rays, secondary rays; SAH with leaves of 4, and median trees). Every hit must equal
//! the runtime's reference traversal bit for bit (a quantized layout's: of its decoded boxes).
//! Also: -O0 code, and the stack overflow status on a tree deeper than the default stack.
//!
//! Needs `aarch64-linux-gnu-gcc` (with the arm64 C library) and `qemu-aarch64`, which
//! scripts/setup.sh installs; without them the test prints one `skip:` line.

use scion_host::mem_interp::library_layouts;
use scion_host::oracle::tree_depth;
use scion_host::quantized::Boxes;
use scion_host::quantized::DecodedTree;
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::schema::{binary_bvh, LogicalBytes};
use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::{Hit, Ray, Vec3};
use scion_runtime::reference::{closest_hit_tree_stats, closest_hits_tree, TraversalStats};
use scion_runtime::scene::gen;
use scion_tests::cases::{real_scene, RayKind, TreeKind};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use tools::{build_tools, have, repo};

use crate::tools;

/// The traversal stack of the compiled code: the deepest hard case (depth 69) fits.
const STACK: u32 = 256;

/// One recorded tree and its rays.
struct Case {
    name: String,
    tree: LogicalTree,
    rays: Vec<Ray>,
}

fn cases() -> Vec<Case> {
    let mut out = Vec::new();
    for (scene, tree, kinds) in [
        (
            "teapot",
            TreeKind::Sah15,
            &[RayKind::Primary, RayKind::Secondary, RayKind::Features][..],
        ),
        ("bunny", TreeKind::Sah4, &[RayKind::Secondary][..]),
    ] {
        match real_scene(scene) {
            Ok(s) => {
                let t = tree.build(&s);
                for kind in kinds {
                    out.push(Case {
                        name: format!("{scene} {tree:?} {kind:?}"),
                        rays: kind.rays(&s, 3000, 7),
                        tree: t.clone(),
                    });
                }
            }
            Err(e) => println!("note: {scene}: {e}; generated scenes only"),
        }
    }
    for (i, s) in gen::hard_cases().iter().enumerate() {
        for tree in [TreeKind::Sah4, TreeKind::Median] {
            let t = tree.build(s);
            let mut rays = RayKind::Axis.rays(s, 200, i as u64);
            rays.extend(RayKind::Features.rays(s, 400, 0));
            rays.extend(RayKind::Secondary.rays(s, 200, i as u64));
            out.push(Case {
                name: format!("hard case {i} {tree:?}"),
                tree: t,
                rays,
            });
        }
    }
    out
}

/// The replay file of `tests/replay/replay.c`.
/// The nodes are in the shape of the prelude's `BVH`, the tree type of every library layout.
fn write_replay(path: &Path, tree: &LogicalTree, rays: &[Ray]) {
    let nodes = LogicalBytes::fill(tree, &binary_bvh()).expect("the runtime fills `BVH`");
    let mut b = b"SCNRPLY2".to_vec();
    let u = |b: &mut Vec<u8>, v: u32| b.extend_from_slice(&v.to_le_bytes());
    let f = |b: &mut Vec<u8>, v: f32| b.extend_from_slice(&v.to_le_bytes());
    for v in [
        nodes.node_count as u32,
        nodes.root,
        tree.primitives.len() as u32,
        rays.len() as u32,
        nodes.node_size as u32,
    ] {
        u(&mut b, v);
    }
    b.extend_from_slice(nodes.nodes());
    for t in &tree.primitives {
        for p in [t.p0, t.p1, t.p2] {
            [p.x, p.y, p.z].iter().for_each(|&x| f(&mut b, x));
        }
        u(&mut b, t.id);
    }
    for r in rays {
        for x in [
            r.origin.x, r.origin.y, r.origin.z, r.dir.x, r.dir.y, r.dir.z, r.tmin, r.tmax,
        ] {
            f(&mut b, x);
        }
    }
    std::fs::write(path, b).expect("write a replay file");
}

fn read_hits(path: &Path, n: usize) -> Vec<Hit> {
    let b = std::fs::read(path).expect("read the hits");
    assert_eq!(b.len(), 8 * n, "{}", path.display());
    let w = |i: usize| u32::from_le_bytes(b[i..i + 4].try_into().unwrap());
    (0..n)
        .map(|i| Hit::from_best(f32::from_bits(w(8 * i)), w(8 * i + 4)))
        .collect()
}

fn run(cmd: &mut Command) -> Output {
    cmd.output().unwrap_or_else(|e| panic!("{cmd:?}: {e}"))
}

fn text(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr)
}

/// Compiles layout `stem`/`name` for AArch64 at `opt` with `stack` entries and links the
/// replay driver; returns the executable.
fn replay_binary(
    scionc: &Path,
    dir: &Path,
    stem: &str,
    name: &str,
    opt: &str,
    stack: Option<u32>,
) -> PathBuf {
    let lib = repo().join("library");
    let sources = [
        lib.join("algorithms/closest_hit.scion"),
        lib.join(format!("layouts/{stem}.scion")),
    ];
    let tag = format!("{stem}{opt}-{}", stack.unwrap_or(64));
    let obj = dir.join(format!("{tag}.o"));
    let header = dir.join(format!("{tag}.h"));
    let exe = dir.join(format!("{tag}-replay"));
    for (emit, path, target) in [("obj", &obj, true), ("header", &header, false)] {
        let mut c = Command::new(scionc);
        c.arg(opt)
            .arg(format!("--emit={emit}"))
            .arg(format!("--layout={name}"))
            .arg("--entry=closest_hit")
            .args(&sources)
            .arg("-o")
            .arg(path);
        if target {
            c.arg("--target=aarch64");
            if let Some(s) = stack {
                c.arg(format!("--stack-size={s}"));
            }
        }
        let o = run(&mut c);
        assert!(
            o.status.success(),
            "scionc --emit={emit} {name}: {}",
            text(&o)
        );
    }
    let o = run(Command::new("aarch64-linux-gnu-gcc")
        .args([
            "-std=c11", "-O1", "-Wall", "-Wextra", "-Werror", "-static", "-include",
        ])
        .arg(&header)
        .arg(format!("-DLAYOUT={name}"))
        .arg(repo().join("tests/replay/replay.c"))
        .arg(&obj)
        .arg("-o")
        .arg(&exe));
    assert!(o.status.success(), "linking {name}: {}", text(&o));
    exe
}

#[test]
fn aarch64_code_matches_the_reference_under_qemu() {
    for tool in ["aarch64-linux-gnu-gcc", "qemu-aarch64"] {
        if !have(tool) {
            println!("skip: `{tool}` not found (scripts/setup.sh installs the AArch64 cross compiler and qemu-user)");
            return;
        }
    }
    let scionc = build_tools(false).join("scionc");
    let dir = std::env::temp_dir().join(format!("scion-aarch64-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let cases = cases();
    let driver = BatchDriver::new(2).unwrap();
    let inputs: Vec<PathBuf> = cases
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let p = dir.join(format!("case{i}.rply"));
            write_replay(&p, &c.tree, &c.rays);
            p
        })
        .collect();
    let mut runs: Vec<(&str, &str, Boxes, &str)> = library_layouts()
        .iter()
        .map(|&(s, n, b)| (s, n, b, "-O3"))
        .collect();
    runs.push(("pbrt", "LinearBVH", Boxes::Exact, "-O0"));
    runs.push(("ptr", "PtrBVH", Boxes::Exact, "-O0"));
    // Each layout is compiled, linked and run on its own (scionc, the cross linker and qemu are
    // separate processes), so the layouts run side by side, one per core: this test was the
    // suite's longest run on two cores.
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let next = std::sync::atomic::AtomicUsize::new(0);
    let counts = std::sync::Mutex::new((0usize, 0usize));
    let one = |(stem, name, boxes, opt): (&str, &str, Boxes, &str)| {
        let exe = replay_binary(&scionc, &dir, stem, name, opt, Some(STACK));
        let outputs: Vec<PathBuf> = (0..cases.len())
            .map(|i| dir.join(format!("{stem}{opt}-{i}.hits")))
            .collect();
        let mut c = Command::new("qemu-aarch64");
        c.arg(&exe);
        for (i, o) in inputs.iter().zip(&outputs) {
            c.arg(i).arg(o);
        }
        let o = run(&mut c);
        assert!(o.status.success(), "{name} {opt} under qemu: {}", text(&o));
        for (case, out) in cases.iter().zip(&outputs) {
            let got = read_hits(out, case.rays.len());
            let want = closest_hits_tree(&boxes.decoded_tree(&case.tree), &case.rays, &driver);
            for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                assert!(
                    g.bit_eq(w),
                    "{name} {opt} on AArch64, {}: ray {i} {:?}: got {g:?}, the reference {w:?}",
                    case.name,
                    case.rays[i]
                );
            }
            let mut n = counts.lock().unwrap();
            n.0 += got.len();
            n.1 += got.iter().filter(|h| h.is_hit()).count();
        }
    };
    std::thread::scope(|scope| {
        for _ in 0..threads.min(runs.len()) {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some(&r) = runs.get(k) else { break };
                one(r);
            });
        }
    });
    let (rays, hits) = *counts.lock().unwrap();
    println!(
        "aarch64: {rays} rays ({hits} hits) over {} cases, identical to the reference",
        cases.len()
    );

    // The default stack of 64 entries overflows on the deepest hard case, and says so: a ray
    // along the chain from its small end pushes the far child at every level before it hits
    // anything (the reference counts the entries it leaves pending).
    let deep = cases
        .iter()
        .position(|c| tree_depth(&c.tree) > 64)
        .expect("a hard case deeper than 64");
    let along = Ray::new(Vec3::new(-1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0));
    let mut stats = TraversalStats::default();
    closest_hit_tree_stats(&cases[deep].tree, &along, &mut stats);
    assert!(stats.max_pending > 64, "{stats:?}");
    let deep_input = dir.join("deep.rply");
    write_replay(&deep_input, &cases[deep].tree, &[along]);
    let exe = replay_binary(&scionc, &dir, "pbrt", "LinearBVH", "-O3", None);
    let o = run(Command::new("qemu-aarch64")
        .arg(&exe)
        .arg(&deep_input)
        .arg(dir.join("deep.hits")));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(
        text(&o).contains("the batch entry returned a status"),
        "{}",
        text(&o)
    );
    let _ = std::fs::remove_dir_all(&dir);
}
