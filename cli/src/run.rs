//! `scion run`: any algorithm of a known query kind, compiled for any layout, on a scene.
//!
//! The algorithm and layout are resolved by the registry (`scion_host::library::resolve_kind`:
//! a kind name such as `closest-point` takes the library's entry of that kind over the type the
//! layout realizes; a function name or `PATH.scion[:FUNCTION]` names one), compiled to the
//! layout's C entries (`scion_host::entries`), packed by the generated `build` and run over
//! blocks of queries on the batch driver's threads, timed by the paper's method. The query
//! kinds table below says, per kind, how queries are made or read, how a result starts, what
//! the reference answer is and how a result is written; every answer is compared with the
//! reference (all of them, or for closest point the first `CHECKED_POINTS` against brute
//! force) and a difference is an error.

use crate::io::outln;
use crate::trace::{build_with, progress, secs, significant, timed};
use crate::{CliError, RunArgs};
use scion_host::entries::Entries;
use scion_host::jit::Codegen;
use scion_host::library::{resolve_kind, QueryKind, Resolved};
use scion_host::quantized::DecodedTree;
use scion_runtime::batch::BatchDriver;
use scion_runtime::geom::{Hit, Ray, Vec3};
use scion_runtime::query::{
    axis_rays, hits_checksum, io::rays_to_bytes, primary_rays_n, read_rays, secondary_rays,
};
use scion_runtime::reference::closest_hits_tree;
use scion_runtime::reference::closest_point::{closest_point_brute, ClosestPoint};
use scion_runtime::scene::{load_obj, Scene};
use std::time::Instant;

/// How many closest-point answers are checked against brute force (each costs a pass over
/// every triangle).
pub const CHECKED_POINTS: usize = 4096;

/// The kind `--algorithm` names, and the program.
fn resolve(args: &RunArgs) -> Result<(QueryKind, Resolved), CliError> {
    let layout = args.layout.as_deref().unwrap_or("pbrt");
    let a = args.algorithm.as_str();
    if let Some(kind) = QueryKind::ALL.into_iter().find(|k| k.name() == a) {
        let r = resolve_kind(layout, None, kind).map_err(CliError::usage)?;
        return Ok((kind, r));
    }
    let mut why = Vec::new();
    for kind in QueryKind::ALL {
        match resolve_kind(layout, Some(a), kind) {
            Ok(r) => return Ok((kind, r)),
            Err(e) => why.push(format!(
                "as {}: {}",
                kind.name(),
                e.lines().next().unwrap_or("")
            )),
        }
    }
    let kinds: Vec<&str> = QueryKind::ALL.iter().map(|k| k.name()).collect();
    Err(CliError::usage(format!(
        "--algorithm {a}: not an entry of a known query kind ({})",
        kinds.join(", ")
    ))
    .note(why.join("\n        ")))
}

/// Runs `scion run`.
pub fn run(args: &RunArgs) -> Result<(), CliError> {
    let (kind, resolved) = resolve(args)?;
    let p = &resolved.program;
    let codegen = match args.backend {
        crate::RunBackend::Jit => Codegen::Cranelift,
        crate::RunBackend::Llvm => Codegen::Llvm(3),
    };
    progress(&format!(
        "compiling {} ({}) for layout `{}`",
        p.algorithm,
        kind.name(),
        p.layout
    ));
    let entries = Entries::compile(p, codegen, args.stack_size).map_err(|e| {
        CliError::new(format!(
            "cannot compile {} for `{}`: {e}",
            p.algorithm, p.layout
        ))
    })?;
    let sig = entries.sig();
    progress(&format!("loading {}", args.scene.display()));
    let t = Instant::now();
    let scene =
        load_obj(&args.scene).map_err(|e| CliError::new(format!("cannot load the scene: {e}")))?;
    let load_time = t.elapsed();
    let tree = build_with(&scene, args.builder, args.leaf_size);
    let driver = BatchDriver::new(args.threads).map_err(CliError::new)?;
    let queries = Queries::make(kind, &scene, args)?;
    let init = queries.initial_results();
    if queries.bytes.len() as u64 != queries.n as u64 * sig.query.size
        || init.len() as u64 != queries.n as u64 * sig.result.size
    {
        return Err(CliError::new(format!(
            "`{}`'s records are {} and {} bytes, not those of a {} query",
            p.algorithm,
            sig.query.size,
            sig.result.size,
            kind.name()
        )));
    }
    progress(&format!("packing the tree into layout `{}`", p.layout));
    let packed = entries.pack(&tree).map_err(CliError::new)?;
    progress(&format!("running {} queries", queries.n));
    let (results, timing) = timed(args.runs, || {
        let mut r = init.clone();
        entries
            .run(&packed, &queries.bytes, &mut r, &driver)
            .map_err(|e| CliError::new(format!("{}: {e}", p.algorithm)))?;
        Ok(r)
    })?;
    progress("checking the answers against the reference");
    let traversed = resolved.boxes.decoded_tree(&tree);
    let check = queries.check(&scene, &traversed, &results, &driver)?;

    outln!("scene        {}", args.scene.display());
    outln!("triangles    {}", scene.len());
    outln!(
        "algorithm    {} ({}, {})",
        p.algorithm,
        kind.name(),
        resolved.tree_type
    );
    outln!(
        "layout       {} ({} bytes packed)",
        p.layout,
        packed.bytes()
    );
    outln!("load time    {}", secs(load_time));
    outln!("compile time {}", secs(entries.compile_time));
    outln!("pack time    {}", secs(packed.pack_time));
    outln!("queries      {} {}", queries.n, queries.source);
    outln!(
        "time         {} (mean of the middle runs, paper method)",
        secs(timing.mean)
    );
    outln!(
        "throughput   {} Mqueries/s ({:.1} ns/query)",
        significant(timing.queries_per_second(queries.n) / 1e6),
        timing.ns_per_query(queries.n)
    );
    outln!("checksum: {:016x}", fnv1a(&results));
    outln!("check        {check}");
    if let Some(path) = &args.output {
        crate::io::write_whole(path, &results)
            .map_err(|e| CliError::new(format!("cannot write {}: {e}", path.display())))?;
        outln!("output       {} ({} bytes)", path.display(), results.len());
    }
    Ok(())
}

/// 64-bit FNV-1a of `bytes` (the hits checksum's hash, over any result records).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// The queries of a run, as the entry's query records.
struct Queries {
    kind: QueryKind,
    n: usize,
    bytes: Vec<u8>,
    rays: Vec<Ray>,
    points: Vec<Vec3>,
    source: String,
}

impl Queries {
    /// Generated or read queries of `kind` (rays for hits, points for closest points).
    fn make(kind: QueryKind, scene: &Scene, args: &RunArgs) -> Result<Queries, CliError> {
        let b = scene.bounds();
        let n = usize::try_from(args.n).map_err(|_| CliError::usage("--n: too many queries"))?;
        if args.queries_file.is_none() && scene.is_empty() {
            return Err(CliError::new(
                "the scene has no triangles, so there is no box to place generated queries in",
            )
            .note("give them with --queries-file"));
        }
        let mut q = Queries {
            kind,
            n: 0,
            bytes: Vec::new(),
            rays: Vec::new(),
            points: Vec::new(),
            source: String::new(),
        };
        match kind {
            QueryKind::ClosestHit | QueryKind::AnyHit => {
                q.rays = match &args.queries_file {
                    Some(path) => {
                        q.source = format!("(rays from {})", path.display());
                        read_rays(path)
                            .map_err(|e| CliError::new(format!("cannot read the rays: {e}")))?
                    }
                    None => {
                        q.source = format!("({} rays, seed {})", args.rays.name(), args.seed);
                        match args.rays {
                            crate::RaysArg::Primary => primary_rays_n(b, n as u64, args.seed)
                                .ok_or_else(|| {
                                    CliError::usage(format!("--n {n}: not a ray count"))
                                })?,
                            crate::RaysArg::Secondary => secondary_rays(b, n, args.seed),
                            crate::RaysArg::Axis => axis_rays(b, n, args.seed),
                        }
                    }
                };
                q.n = q.rays.len();
                q.bytes = rays_to_bytes(&q.rays);
            }
            QueryKind::ClosestPoint => {
                q.points = match &args.queries_file {
                    Some(path) => {
                        q.source = format!("(points from {})", path.display());
                        read_points(path)?
                    }
                    None => {
                        q.source =
                            format!("(points uniform in the scene's box, seed {})", args.seed);
                        uniform_points(b.low, b.high, n, args.seed)
                    }
                };
                q.n = q.points.len();
                q.bytes = q
                    .points
                    .iter()
                    .flat_map(|p| [p.x, p.y, p.z])
                    .flat_map(f32::to_le_bytes)
                    .collect();
            }
        }
        Ok(q)
    }

    /// The result records a query starts from.
    fn initial_results(&self) -> Vec<u8> {
        match self.kind {
            QueryKind::ClosestHit => self
                .rays
                .iter()
                .flat_map(|r| {
                    let mut b = r.tmax.to_le_bytes().to_vec();
                    b.extend_from_slice(&u32::MAX.to_le_bytes());
                    b
                })
                .collect(),
            QueryKind::AnyHit => vec![0; self.n * 4],
            QueryKind::ClosestPoint => (0..self.n)
                .flat_map(|_| closest_point_bytes(&ClosestPoint::start(f32::INFINITY)))
                .collect(),
        }
    }

    /// Compares `results` with the reference on `traversed` (the tree the layout traverses);
    /// `Err` names the first difference.
    fn check(
        &self,
        scene: &Scene,
        traversed: &scion_runtime::bvh::LogicalTree,
        results: &[u8],
        driver: &BatchDriver,
    ) -> Result<String, CliError> {
        let word = |i: usize| u32::from_le_bytes(results[i..i + 4].try_into().unwrap());
        let differ = |i: usize, got: String, want: String| {
            Err(CliError::new(format!(
                "query {i}: the answer differs from the reference: got {got}, reference {want}"
            )))
        };
        match self.kind {
            QueryKind::ClosestHit | QueryKind::AnyHit => {
                let want = closest_hits_tree(traversed, &self.rays, driver);
                for (i, w) in want.iter().enumerate() {
                    if self.kind == QueryKind::ClosestHit {
                        let got = Hit::from_best(f32::from_bits(word(8 * i)), word(8 * i + 4));
                        if got.t.to_bits() != w.t.to_bits() || got.prim != w.prim {
                            return differ(i, format!("{got:?}"), format!("{w:?}"));
                        }
                    } else if (word(4 * i) != 0) != w.is_hit() {
                        return differ(i, format!("occluded {}", word(4 * i)), format!("{w:?}"));
                    }
                }
                Ok(format!(
                    "identical to the reference on all {} queries (checksum of its hits {:016x})",
                    self.n,
                    hits_checksum(&want)
                ))
            }
            QueryKind::ClosestPoint => {
                let k = self.n.min(CHECKED_POINTS);
                let mut want = vec![ClosestPoint::start(f32::INFINITY); k];
                let chunks: Vec<std::sync::Mutex<&mut [ClosestPoint]>> = want
                    .chunks_mut(scion_runtime::batch::BLOCK)
                    .map(std::sync::Mutex::new)
                    .collect();
                driver.run(k, |begin, end| {
                    let mut out = chunks[begin / scion_runtime::batch::BLOCK]
                        .lock()
                        .unwrap_or_else(|p| p.into_inner());
                    for (j, i) in (begin..end).enumerate() {
                        out[j] =
                            closest_point_brute(&scene.triangles, self.points[i], f32::INFINITY);
                    }
                });
                drop(chunks);
                for (i, w) in want.iter().enumerate() {
                    let got = closest_point_from(&results[20 * i..20 * i + 20]);
                    if !got.bit_eq(w) {
                        return differ(i, format!("{got:?}"), format!("{w:?}"));
                    }
                }
                Ok(format!(
                    "identical to brute force on {k} of {} queries (the first {k})",
                    self.n
                ))
            }
        }
    }
}

/// The 20-byte record of a closest point: distance, primitive id, point.
fn closest_point_bytes(c: &ClosestPoint) -> Vec<u8> {
    [
        c.distance.to_bits(),
        c.prim,
        c.point.x.to_bits(),
        c.point.y.to_bits(),
        c.point.z.to_bits(),
    ]
    .into_iter()
    .flat_map(u32::to_le_bytes)
    .collect()
}

fn closest_point_from(b: &[u8]) -> ClosestPoint {
    let w = |i: usize| u32::from_le_bytes(b[4 * i..4 * i + 4].try_into().unwrap());
    ClosestPoint {
        distance: f32::from_bits(w(0)),
        prim: w(1),
        point: Vec3::new(
            f32::from_bits(w(2)),
            f32::from_bits(w(3)),
            f32::from_bits(w(4)),
        ),
    }
}

/// A points file: 12-byte records, f32 x, y, z little-endian (docs/formats.md).
fn read_points(path: &std::path::Path) -> Result<Vec<Vec3>, CliError> {
    let bytes = std::fs::read(path)
        .map_err(|e| CliError::new(format!("cannot read {}: {e}", path.display())))?;
    if bytes.len() % 12 != 0 {
        return Err(CliError::new(format!(
            "{}: {} bytes is not a whole number of 12-byte points",
            path.display(),
            bytes.len()
        )));
    }
    let f = |b: &[u8], i: usize| f32::from_le_bytes(b[i..i + 4].try_into().unwrap());
    let points: Vec<Vec3> = bytes
        .chunks_exact(12)
        .map(|b| Vec3::new(f(b, 0), f(b, 4), f(b, 8)))
        .collect();
    if let Some(i) = points.iter().position(|p| !p.is_finite()) {
        return Err(CliError::new(format!(
            "{}: point {i} is not finite: {:?}",
            path.display(),
            points[i]
        )));
    }
    Ok(points)
}

/// `n` points uniform in the box `[low, high]` (xorshift64 seeded by `seed`, 53-bit fractions).
fn uniform_points(low: Vec3, high: Vec3, n: usize, seed: u64) -> Vec<Vec3> {
    let mut x = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    let mut unit = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    let lerp = |a: f32, b: f32, t: f64| (f64::from(a) + (f64::from(b) - f64::from(a)) * t) as f32;
    (0..n)
        .map(|_| {
            Vec3::new(
                lerp(low.x, high.x, unit()),
                lerp(low.y, high.y, unit()),
                lerp(low.z, high.z, unit()),
            )
        })
        .collect()
}
