//! Closest point queries (`library/algorithms/closest_point.scion`) through the C ABI: the
//! depth-first traversal (nearer child first) and the best-first one (`order by d`, a priority
//! queue), compiled for every library layout by Cranelift and LLVM -O3 to their exported entries
//! and called as a C host does; on the eight-wide layouts, `closest_point8.scion`'s nearest-first
//! traversal of `BVH8`. Every answer must be brute force's bit for bit
//! (`scion_runtime::reference::closest_point_brute`, the same f32 arithmetic): the pruning is
//! exact on every layout whose boxes contain their triangles, quantized ones included. The f32
//! answers are then checked against float64 brute force: the distance within a bound relative to
//! the scene's size, and the triangle the nearest one or one as near within that bound.

use crate::c_entries;

use scion_host::jit::Codegen;
use scion_host::library::{resolve_kind, QueryKind};
use scion_host::mem_interp::Program;
use scion_runtime::geom::{Triangle, Vec3};
use scion_runtime::reference::closest_point::{
    closest_point_brute, closest_point_f64, triangle_distance_f64, ClosestPoint,
};
use scion_runtime::scene::{gen, Scene};
use scion_tests::cases::{real_scene, TreeKind};

/// The library program answering closest points over layout `stem` with `entry`.
fn program(stem: &str, entry: &str) -> Program {
    let r = resolve_kind(stem, None, QueryKind::ClosestPoint).expect("a closest-point entry");
    Program {
        algorithm: entry.to_string(),
        ..r.program
    }
}

/// Query points for `scene`: uniform in its box grown by a fifth on each side, far outside it,
/// and on its features (corners, edge midpoints, and just off centroids), where several
/// triangles are at the same distance.
fn points(scene: &Scene, n: usize, seed: u64) -> Vec<Vec3> {
    let b = scene.bounds();
    let mut x = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    let mut unit = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    let e = b.extent();
    let lerp =
        |lo: f32, ext: f32, t: f64| (f64::from(lo) + f64::from(ext) * (1.4 * t - 0.2)) as f32;
    let mut out = Vec::new();
    for _ in 0..n {
        out.push(Vec3::new(
            lerp(b.low.x, e.x, unit()),
            lerp(b.low.y, e.y, unit()),
            lerp(b.low.z, e.z, unit()),
        ));
    }
    let c = b.center();
    let far = e.x.max(e.y).max(e.z).max(1.0) * 10.0;
    out.push(c + Vec3::new(far, 0.0, 0.0));
    out.push(c - Vec3::new(0.0, far, far));
    let step = (scene.triangles.len() / (n / 4).max(1)).max(1);
    for t in scene.triangles.iter().step_by(step) {
        out.push(t.p0);
        out.push((t.p1 + t.p2) * 0.5);
        out.push(t.centroid() + Vec3::new(0.0, 0.0, 1e-3));
    }
    out.retain(|p| p.is_finite());
    out
}

fn scenes() -> Vec<Scene> {
    let mut scenes: Vec<Scene> = gen::hard_cases()
        .into_iter()
        .filter(|s| s.triangles.iter().all(Triangle::is_finite))
        .collect();
    if let Ok(s) = real_scene("teapot") {
        scenes.push(s);
    }
    scenes
}

/// Runs `entry` compiled for `layout` by `codegen` on every scene; returns the answers per
/// scene.
fn run(stem: &str, entry: &str, codegen: Codegen, cases: &[Case]) -> Vec<Vec<ClosestPoint>> {
    let program = program(stem, entry);
    let layout = &program.layout;
    let lo = c_entries::host_lo(&program);
    assert_eq!(lo.entry.query.size, 12, "the query is the point");
    assert_eq!(
        lo.entry.result.size, 20,
        "the result is (distance, id, point)"
    );
    let code = codegen.backend().jit(&lo.module).unwrap();
    let mut all = Vec::new();
    for case in cases {
        let mut results: Vec<ClosestPoint> = case
            .points
            .iter()
            .enumerate()
            // Every seventh query searches within a radius only.
            .map(|(k, _)| {
                ClosestPoint::start(if k % 7 == 3 {
                    case.radius
                } else {
                    f32::INFINITY
                })
            })
            .collect();
        let status = c_entries::run_batch(
            &lo,
            code.as_ref(),
            &case.tree,
            entry,
            &case.points,
            &mut results,
        );
        assert_eq!(status, 0, "{layout} {entry}: batch status");
        all.push(results);
    }
    all
}

struct Case {
    scene: Scene,
    tree: scion_runtime::bvh::LogicalTree,
    points: Vec<Vec3>,
    radius: f32,
    want: Vec<ClosestPoint>,
}

fn cases() -> Vec<Case> {
    scenes()
        .into_iter()
        .enumerate()
        .filter_map(|(i, scene)| {
            // Scion's binned SAH tree and FCPW's, on alternate scenes.
            let kind = if i % 2 == 0 {
                TreeKind::Sah4
            } else {
                TreeKind::Fcpw
            };
            let tree = kind.build(&scene);
            if tree.is_empty() {
                return None;
            }
            let points = points(&scene, 120, i as u64 + 1);
            let e = scene.bounds().extent();
            let radius = 0.05 * e.x.max(e.y).max(e.z);
            let want = points
                .iter()
                .enumerate()
                .map(|(k, &p)| {
                    let r = if k % 7 == 3 { radius } else { f32::INFINITY };
                    closest_point_brute(&scene.triangles, p, r)
                })
                .collect();
            Some(Case {
                scene,
                tree,
                points,
                radius,
                want,
            })
        })
        .collect()
}

#[test]
fn both_traversals_are_brute_force_on_every_layout() {
    let cases = cases();
    assert!(cases.len() >= 10, "{} scenes", cases.len());
    let mut checked = 0;
    let mut others = Vec::new();
    // Every library layout with a closest-point entry over its type (the registry's, so a new
    // file is covered): both traversals of the prelude's BVH, `closest_point8` of BVH8,
    // `closest_point_dop14` of the DOP-14 tree, `closest_point_hair` of the hair BVH.
    for &(stem, _) in scion_host::library::LAYOUT_FILES {
        let Ok(r) = resolve_kind(stem, None, QueryKind::ClosestPoint) else {
            continue;
        };
        let entries: &[&str] = match r.tree_type.as_str() {
            // The depth-first traversal on the two unquantized layouts of each reference type.
            "BVH" if matches!(stem, "pbrt" | "ptr") => {
                &["closest_point_best_first", "closest_point_query"]
            }
            "BVH" => &["closest_point_best_first"],
            other => {
                others.push(other.to_string());
                &[r.program.algorithm.as_str()][..]
            }
        };
        for &entry in entries {
            for codegen in [Codegen::Cranelift, Codegen::Llvm(3)] {
                let got = run(stem, entry, codegen, &cases);
                for (case, got) in cases.iter().zip(&got) {
                    for (k, (g, w)) in got.iter().zip(&case.want).enumerate() {
                        assert!(
                            g.bit_eq(w),
                            "{stem} {entry} {codegen:?} scene {} point {k} {:?}: got {g:?}, \
                             brute force {w:?}",
                            case.scene.name,
                            case.points[k]
                        );
                    }
                    checked += got.len();
                }
            }
        }
    }
    let wide = others.iter().filter(|t| *t == "BVH8").count();
    assert!(
        wide >= 3,
        "{wide} eight-wide layouts with a closest-point entry"
    );
    assert!(
        others.iter().any(|t| t == "DopBVH") && others.iter().any(|t| t == "Hair"),
        "the DOP-14 split and hair layouts: {others:?}"
    );
    assert!(checked > 10_000, "{checked} answers");
}

/// The f32 answers against float64 brute force: the distance within `1e-5` of the scene's size
/// plus the point's distance from it, plus four f32 ulps of the largest coordinate (a scene far
/// from the origin has coarse coordinates), and the triangle as near as the nearest within that.
#[test]
fn brute_force_is_within_the_f64_bound() {
    let mut worst = 0.0f64;
    let mut overflowed = 0;
    let mut checked = 0;
    for case in cases() {
        let b = case.scene.bounds();
        let size = f64::from(b.extent().x.max(b.extent().y).max(b.extent().z)).max(1e-30);
        for (k, (p, w)) in case.points.iter().zip(&case.want).enumerate() {
            if k % 7 == 3 {
                continue;
            }
            let (d64, id64) = closest_point_f64(&case.scene.triangles, *p);
            let magnitude = [b.low, b.high, *p]
                .iter()
                .flat_map(|v| v.to_array())
                .fold(0.0f64, |a, x| a.max(f64::from(x.abs())));
            let reach = size + d64;
            let tol = 1e-5 * reach + 4.0 * f64::from(f32::EPSILON) * magnitude;
            if magnitude.powi(4) * 64.0 > f64::from(f32::MAX) || size.powi(4) < 1e-36 {
                // Coordinates beyond about 1e9, or a scene smaller than about 1e-9: the
                // products of the f32 triangle test overflow or underflow (documented in the
                // algorithm file).
                overflowed += 1;
                continue;
            }

            let err = (f64::from(w.distance) - d64).abs();
            worst = worst.max(err / tol);
            checked += 1;
            assert!(
                err <= tol,
                "scene {} point {k} {p:?}: f32 {} vs f64 {d64} (id {} vs {id64})",
                case.scene.name,
                w.distance,
                w.prim
            );
            if w.prim != id64 {
                let t = case
                    .scene
                    .triangles
                    .iter()
                    .find(|t| t.id == w.prim)
                    .expect("a scene triangle");
                let dt = triangle_distance_f64(*p, t);
                assert!(
                    dt - d64 <= tol,
                    "scene {} point {k}: triangle {} at {dt} but {id64} at {d64}",
                    case.scene.name,
                    w.prim
                );
            }
        }
    }
    assert!(checked > 1500, "{checked} points checked");
    eprintln!(
        "{checked} points: largest f32 error {worst:.3} of the bound; {overflowed} points \
         outside the f32 test's range"
    );
}
