//! `cargo bench -p scion-bench --bench closest_point -- [OPTIONS]`: closest-point queries
//! (issue 16) of Scion's generated code against parry3d (its `TriMesh`'s point projection), on
//! one scene and one set of points, one thread each, the paper's timing method; FCPW (a Python
//! package) runs from scripts/bench-closest-point.sh on the inputs this writes, and its answers
//! are read back here to be checked with the others.
//!
//! Scion: the library's closest-point entry over each layout of `--layouts` (default
//! `pbrt,bvh8,pbrt@fcpw`: `closest_point.scion`'s `closest_point_query` over the binary pbrt
//! layout, `closest_point8.scion`'s `closest_point8` over the eight-wide bvh8), LLVM -O3,
//! through its C entries on the batch driver with one thread, the tree built by the runtime's
//! binned SAH (leaves of up to `--max-leaf`, 15; collapsed to eight children for the wide
//! layouts), or with `LAYOUT@fcpw` by FCPW's builder (`scion_runtime::bvh::fcpw`, leaves of up
//! to 4), the paper's set-up (§9.3.2: FCPW's layout and tree, Scion's traversal). parry3d: `TriMesh::new` over the same
//! triangles (three vertices each), `project_local_point_and_get_location(p, false)` per point.
//! Points: `scion run --algorithm closest-point`'s, uniform in the scene's box (`--n`, `--seed`).
//!
//! Accuracy, on the first `--check` points (default 2048) against float64 brute force
//! (`scion_runtime::reference::closest_point::closest_point_f64`): the largest distance error of
//! each side, and how many answers name another triangle than float64 at a distance more than
//! 1e-6 of the scene's size away from float64's (a wrong triangle, not a tie).
//!
//! Options: `--scene PATH|NAME` (default bunny), `--n N` (65536), `--seed S` (1), `--runs R`
//! (9), `--layouts L[@fcpw],...` (pbrt,bvh8,pbrt@fcpw), `--check K` (2048), `--max-leaf M` (Scion's tree's largest leaf,
//! 15), `--inputs DIR` (write `DIR/tris.bin` and
//! `DIR/points.bin` and stop), `--peer NAME=FILE` (also check a peer's 20-byte answers, e.g.
//! FCPW's; repeatable). Prints `key value` lines (`scion_ms LAYOUT MS` per layout).

use parry3d::math::Vec3 as PVec3;
use parry3d::query::PointQueryWithLocation;
use parry3d::shape::TriMesh;
use scion_host::entries::Entries;
use scion_host::jit::Codegen;
use scion_host::library::{resolve_kind, QueryKind};
use scion_host::queries::{closest_point_from, Queries};
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::{build_fcpw, build_sah_binned, FcpwOptions, SahOptions};
use scion_runtime::query::points::uniform_points;
use scion_runtime::reference::closest_point::closest_point_f64;
use scion_runtime::scene::load_obj;
use scion_runtime::timing::{measure_with, TimingPlan};
use std::path::PathBuf;
use std::process::ExitCode;

struct Args {
    scene: PathBuf,
    n: usize,
    seed: u64,
    runs: usize,
    layouts: Vec<String>,
    check: usize,
    inputs: Option<PathBuf>,
    peers: Vec<(String, PathBuf)>,
    max_leaf: usize,
}

fn parse() -> Result<Args, String> {
    let mut a = Args {
        scene: PathBuf::from("bunny"),
        n: 65536,
        seed: 1,
        runs: 9,
        layouts: vec!["pbrt".into(), "bvh8".into(), "pbrt@fcpw".into()],
        check: 2048,
        inputs: None,
        peers: Vec::new(),
        max_leaf: SahOptions::default().max_leaf,
    };
    let mut it = std::env::args().skip(1).filter(|s| s != "--bench");
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or(format!("{flag} needs a value"));
        let num = |v: String| {
            v.parse::<usize>()
                .map_err(|_| format!("{flag}: `{v}` is not a count"))
        };
        match flag.as_str() {
            "--scene" => a.scene = PathBuf::from(value()?),
            "--n" => a.n = num(value()?)?,
            "--seed" => a.seed = num(value()?)? as u64,
            "--runs" => a.runs = num(value()?)?.max(1),
            "--layouts" | "--layout" => a.layouts = value()?.split(',').map(String::from).collect(),
            "--check" => a.check = num(value()?)?,
            "--inputs" => a.inputs = Some(PathBuf::from(value()?)),
            "--max-leaf" => a.max_leaf = num(value()?)?.clamp(1, 15),
            "--peer" => {
                let v = value()?;
                let (name, file) = v.split_once('=').ok_or("--peer NAME=FILE")?;
                a.peers.push((name.to_string(), PathBuf::from(file)));
            }
            _ => return Err(format!("unknown option {flag}")),
        }
    }
    a.scene = scion_runtime::scene::manifest::resolve(&a.scene)?;
    Ok(a)
}

fn plan(runs: usize) -> TimingPlan {
    let drop = (runs - 1) / 4;
    TimingPlan {
        warmup: 1,
        runs,
        drop_low: drop,
        drop_high: drop,
    }
}

/// (distance, face id) answers of one contender.
type Answers = Vec<(f32, u32)>;

/// The largest distance error against float64 and the wrong triangles (not ties) on the first
/// `k` points.
fn accuracy(answers: &Answers, want: &[(f64, u32)], size: f64) -> (f64, usize) {
    let mut worst = 0.0f64;
    let mut wrong = 0;
    for (&(d, id), &(wd, wid)) in answers.iter().zip(want) {
        let err = (f64::from(d) - wd).abs();
        worst = worst.max(err);
        if id != wid && err > 1e-6 * size {
            wrong += 1;
        }
    }
    (worst, wrong)
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("closest_point: {e}");
            ExitCode::from(1)
        }
    }
}

fn run() -> Result<(), String> {
    let a = parse()?;
    let scene = load_obj(&a.scene).map_err(|e| e.to_string())?;
    let b = scene.bounds();
    let points = uniform_points(b.low, b.high, a.n, a.seed);
    if let Some(dir) = &a.inputs {
        std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
        let pts: Vec<u8> = points
            .iter()
            .flat_map(|p| p.to_array())
            .flat_map(f32::to_le_bytes)
            .collect();
        std::fs::write(
            dir.join("tris.bin"),
            scion_bench::records::triangle_records(&scene.triangles),
        )
        .map_err(|e| e.to_string())?;
        std::fs::write(dir.join("points.bin"), pts).map_err(|e| e.to_string())?;
        return Ok(());
    }
    let driver = BatchDriver::new(1)?;
    let plan = plan(a.runs);

    // Scion, each layout.
    let tree = build_sah_binned(
        &scene.triangles,
        &SahOptions {
            max_leaf: a.max_leaf,
            // closest_point tests a leaf's triangles one at a time: no collapse for runs of four.
            block: 1,
            ..SahOptions::default()
        },
    );
    let q = Queries::points(points.clone());
    let init = q.initial_results();
    let fcpw_tree = build_fcpw(&scene.triangles, &FcpwOptions::default());
    let mut scion = Vec::new();
    for spec in &a.layouts {
        let (layout, tree) = match spec.split_once('@') {
            None => (spec.as_str(), &tree),
            Some((layout, "fcpw")) => (layout, &fcpw_tree),
            Some(_) => {
                return Err(format!(
                    "--layouts: `{spec}`: the tree is LAYOUT or LAYOUT@fcpw"
                ))
            }
        };
        let resolved = resolve_kind(layout, None, QueryKind::ClosestPoint)?;
        let entries = Entries::compile(&resolved.program, Codegen::Llvm(3), None)?;
        let packed = entries.pack(tree)?;
        let mut results = init.clone();
        let time = measure_with(&plan, || {
            results.copy_from_slice(&init);
            entries
                .run(&packed, &q.bytes, &mut results, &driver)
                .expect("the closest-point entry runs");
        });
        let answers: Answers = results
            .chunks_exact(20)
            .map(|r| {
                let c = closest_point_from(r);
                (c.distance, c.prim)
            })
            .collect();
        scion.push((spec.clone(), time, answers));
    }

    // parry3d.
    let mut vertices = Vec::with_capacity(3 * scene.len());
    for t in &scene.triangles {
        for p in [t.p0, t.p1, t.p2] {
            vertices.push(PVec3::new(p.x, p.y, p.z));
        }
    }
    let indices: Vec<[u32; 3]> = (0..scene.len() as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    let mesh = TriMesh::new(vertices, indices).map_err(|e| format!("parry3d: {e:?}"))?;
    let mut parry: Answers = vec![(0.0, 0); points.len()];
    let parry_time = measure_with(&plan, || {
        for (o, p) in parry.iter_mut().zip(&points) {
            let v = PVec3::new(p.x, p.y, p.z);
            let (proj, (tri, _)) = mesh.project_local_point_and_get_location(v, false);
            *o = ((proj.point - v).length(), scene.triangles[tri as usize].id);
        }
    });

    // Float64 on the first points, and the answers checked.
    let k = a.check.min(points.len());
    let want: Vec<(f64, u32)> = points[..k]
        .iter()
        .map(|&p| closest_point_f64(&scene.triangles, p))
        .collect();
    let e = b.extent();
    let size = f64::from(e.x.max(e.y).max(e.z));
    let ms = |t: std::time::Duration| t.as_secs_f64() * 1e3;
    println!("triangles {}", scene.len());
    println!("points {}", points.len());
    // Every layout's answers are brute force's, so they are equal to each other bit for bit.
    let differing = scion
        .iter()
        .skip(1)
        .map(|(_, _, ans)| {
            ans.iter()
                .zip(&scion[0].2)
                .filter(|(x, y)| x.0.to_bits() != y.0.to_bits() || x.1 != y.1)
                .count()
        })
        .sum::<usize>();
    println!("scion_layouts_differ {differing}");
    let mut rows = Vec::new();
    for (layout, time, answers) in scion {
        println!("scion_ms {layout} {:.4}", ms(time.mean));
        rows.push((format!("scion:{layout}"), answers));
    }
    println!("parry_ms {:.4}", ms(parry_time.mean));
    rows.push(("parry".to_string(), parry));
    for (name, file) in &a.peers {
        let b = std::fs::read(file).map_err(|e| format!("{}: {e}", file.display()))?;
        let ans: Answers = b
            .chunks_exact(20)
            .map(|r| {
                let c = closest_point_from(r);
                (c.distance, c.prim)
            })
            .collect();
        if ans.len() != points.len() {
            return Err(format!(
                "{}: {} answers for {} points",
                file.display(),
                ans.len(),
                points.len()
            ));
        }
        rows.push((name.clone(), ans));
    }
    for (name, ans) in &rows {
        let (worst, wrong) = accuracy(&ans[..k].to_vec(), &want, size);
        println!("{name}_error {worst:.3e} wrong {wrong} of {k}");
    }
    Ok(())
}
