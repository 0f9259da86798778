//! `scion render`: a picture of a scene, traced through any layout and backend, for the docs and
//! for checking by eye. One primary ray through the centre of each pixel from the camera every
//! `scion trace --rays primary` uses (`scion_runtime::query::Camera::framing` from `VIEW_FROM`,
//! the scene's box filling the view), closest hit through the layout's compiled entries (the
//! registry's, as `scion run`), every hit checked against the reference traversal, then each
//! pixel shaded from the hit triangle's geometric normal:
//!
//! * `normals`: the normal's components mapped from [-1, 1] to [0, 255] (the triangle's
//!   orientation, front or back alike);
//! * `diffuse`: a grey lit from the camera, `0.15 + 0.85 |cos|` of the angle between the ray
//!   and the normal.
//!
//! Misses are a dark grey. The picture depends only on the hits, so every layout and backend that
//! returns the reference's hits draws the same bytes (cli/tests/render.rs compares them). PNG
//! through plotters' bitmap backend (8-bit RGB).

use crate::io::outln;
use crate::trace::{build_with, progress, secs};
use crate::{CliError, RenderArgs, RunBackend, ShadingArg};
use plotters::prelude::{BitMapBackend, Color, DrawingBackend, RGBColor};
use scion_host::hit_reference::Traversed;
use scion_host::jit::Codegen;
use scion_host::library::{resolve_kind, QueryKind};
use scion_host::queries::Queries;
use scion_runtime::batch::BatchDriver;
use scion_runtime::geom::{Hit, Ray, Triangle};
use scion_runtime::query::rays::VIEW_FROM;
use scion_runtime::query::Camera;
use scion_runtime::scene::load_obj;
use std::time::Instant;

/// The background of a pixel whose ray hits nothing.
const BACKGROUND: [u8; 3] = [38, 38, 44];

/// Runs `scion render`.
pub fn run(args: &RenderArgs) -> Result<(), CliError> {
    let layout = args.layout.as_deref().unwrap_or("pbrt");
    let resolved = resolve_kind(layout, args.algorithm.as_deref(), QueryKind::ClosestHit)
        .map_err(CliError::usage)?;
    crate::trace::over_triangles(&resolved, layout)?;
    let p = &resolved.program;
    let codegen = match args.backend {
        RunBackend::Jit => Codegen::Cranelift,
        RunBackend::Llvm => Codegen::Llvm(3),
    };
    let entries = crate::trace::compile_entries(p, codegen, args.stack_size)?;
    progress(&format!("loading {}", args.scene.display()));
    let scene =
        load_obj(&args.scene).map_err(|e| CliError::new(format!("cannot load the scene: {e}")))?;
    let tree = build_with(&scene, args.builder, args.leaf_size);
    progress(&format!("packing the tree into layout `{}`", p.layout));
    let packed = entries.pack(&tree).map_err(CliError::new)?;

    let (w, h) = (args.width, args.height);
    let cam = Camera::framing(scene.bounds(), VIEW_FROM, w, h);
    let rays: Vec<Ray> = (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .map(|(i, j)| {
            cam.ray(
                (f64::from(i) + 0.5) / f64::from(w),
                (f64::from(j) + 0.5) / f64::from(h),
            )
        })
        .collect();
    let queries = Queries::rays(QueryKind::ClosestHit, rays);
    let driver = BatchDriver::new(args.threads).map_err(CliError::new)?;
    progress(&format!("tracing {w}x{h} primary rays"));
    let t = Instant::now();
    let mut results = queries.initial_results();
    entries
        .run(&packed, &queries.bytes, &mut results, &driver)
        .map_err(|e| CliError::new(format!("{}: {e}", p.algorithm)))?;
    let trace_time = t.elapsed();
    let check = queries
        .check(
            &scene.triangles,
            Traversed::of(&resolved, &tree),
            &results,
            0,
            &driver,
        )
        .map_err(CliError::new)?;
    let hits: Vec<Hit> = results
        .chunks_exact(8)
        .map(|r| {
            let word = |k: usize| u32::from_le_bytes(r[k..k + 4].try_into().unwrap());
            Hit::from_best(f32::from_bits(word(0)), word(4))
        })
        .collect();
    let by_id = triangles_by_id(&scene.triangles);
    let pixels: Vec<[u8; 3]> = hits
        .iter()
        .zip(&queries.rays)
        .map(|(hit, ray)| {
            let tri = hit
                .is_hit()
                .then(|| by_id.get(hit.prim as usize).copied().flatten())
                .flatten();
            match tri {
                Some(tri) => shade(args.shading, ray, tri),
                None => BACKGROUND,
            }
        })
        .collect();
    write_png(&args.output, w, h, &pixels)?;
    let hit_pixels = hits.iter().filter(|h| h.is_hit()).count();
    outln!("scene        {}", args.scene.display());
    outln!("triangles    {}", scene.len());
    outln!(
        "layout       {} ({} bytes packed)",
        p.layout,
        packed.bytes()
    );
    outln!(
        "image        {} ({w}x{h}, {} shading, {hit_pixels} of {} pixels hit)",
        args.output.display(),
        args.shading.name(),
        w * h
    );
    outln!("trace time   {}", secs(trace_time));
    outln!("check        {check}");
    Ok(())
}

/// The scene's triangles indexed by their face id (hits name ids, not positions).
fn triangles_by_id(tris: &[Triangle]) -> Vec<Option<&Triangle>> {
    let n = tris.iter().map(|t| t.id as usize + 1).max().unwrap_or(0);
    let mut out = vec![None; n];
    for t in tris {
        out[t.id as usize] = Some(t);
    }
    out
}

/// The colour of a pixel whose ray hits `tri`.
fn shade(shading: ShadingArg, ray: &Ray, tri: &Triangle) -> [u8; 3] {
    let n = (tri.p1 - tri.p0).cross(tri.p2 - tri.p0);
    let len = n.dot(n).sqrt();
    if len <= 0.0 || !len.is_finite() {
        return [255, 0, 255];
    }
    let n = n * (1.0 / len);
    let byte = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    match shading {
        ShadingArg::Normals => [
            byte(0.5 * (n.x + 1.0)),
            byte(0.5 * (n.y + 1.0)),
            byte(0.5 * (n.z + 1.0)),
        ],
        ShadingArg::Diffuse => {
            let d = ray.dir;
            let cos = (n.dot(d) / d.dot(d).sqrt()).abs();
            let g = byte(0.15 + 0.85 * cos);
            [g, g, g]
        }
    }
}

/// Writes `pixels` (row by row from the top) as an 8-bit RGB PNG.
fn write_png(path: &std::path::Path, w: u32, h: u32, pixels: &[[u8; 3]]) -> Result<(), CliError> {
    let fail = |e: String| CliError::new(format!("cannot write {}: {e}", path.display()));
    let mut img = BitMapBackend::new(path, (w, h));
    for (k, px) in pixels.iter().enumerate() {
        let (x, y) = ((k as u32 % w) as i32, (k as u32 / w) as i32);
        img.draw_pixel((x, y), RGBColor(px[0], px[1], px[2]).to_backend_color())
            .map_err(|e| fail(e.to_string()))?;
    }
    img.present().map_err(|e| fail(e.to_string()))
}
