//! `scion run`: any algorithm of a known query kind, compiled for any layout, on a scene.
//!
//! The algorithm and layout are resolved by the registry (`scion_host::library::resolve_kind`:
//! a kind name such as `closest-point` takes the library's entry of that kind over the type the
//! layout realizes; a function name or `PATH.scion[:FUNCTION]` names one), compiled to the
//! layout's C entries (`scion_host::entries`), packed by the generated `build` and run over
//! blocks of queries on the batch driver's threads, timed by the paper's method. The table of
//! query kinds (`scion_host::queries`) says how a result starts and what the reference answer
//! is; every answer is compared with it (all of them, or for closest point the first
//! `CHECKED_POINTS` against brute force) and a difference is an error.

use crate::io::outln;
use crate::trace::{build_for_runs, progress, secs, significant, timed};
use crate::{CliError, DeviceArg, RunArgs};
use scion_host::entries::Entries;
use scion_host::hit_reference::Traversed;
use scion_host::jit::Codegen;
use scion_host::library::{resolve_kind, QueryKind, Resolved};
use scion_host::queries::{points_from_bytes, uniform_points, Expected, Queries};
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::SahOptions;
use scion_runtime::query::{axis_rays, primary_rays_n, read_rays, secondary_rays};
use scion_runtime::scene::{load_obj, Scene};
use scion_runtime::timing::Timing;
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
    let layout = args.layout.as_deref().unwrap_or("pbrt");
    // A layout over blocks of four triangles (`bvh8-tri4`) runs over the block tree of the
    // scene's triangles (crate::trace_blocks), on the CPU.
    let blocks = resolved.primitive == crate::trace_blocks::PRIMITIVE;
    if !blocks {
        crate::trace::over_triangles(&resolved, layout)?;
    } else if args.device != DeviceArg::Cpu {
        return Err(CliError::usage(format!(
            "--layout {layout} holds blocks of four triangles, which `scion run` runs on the CPU"
        ))
        .note(format!(
            "`scion trace --device gpu-emulated --layout {layout}` runs its GPU kernels"
        )));
    }
    let p = &resolved.program;
    let codegen = match args.backend {
        crate::RunBackend::Jit => Codegen::Cranelift,
        crate::RunBackend::Llvm => Codegen::Llvm(3),
    };
    // A collision's stack holds pairs of subtrees: deeper than one tree's.
    let stack_size = match kind {
        QueryKind::Collide => Some(args.stack_size.unwrap_or(1024)),
        _ => args.stack_size,
    };
    if kind == QueryKind::Collide && args.device != DeviceArg::Cpu {
        return Err(CliError::usage(
            "--algorithm collide runs on the CPU: the GPU path runs batches of queries over one tree",
        ));
    }
    // On the CPU, the entries compiled for this machine; on a GPU, run_gpu compiles its own.
    let entries = if args.device == DeviceArg::Cpu {
        progress(&format!(
            "compiling {} ({}) for layout `{}`",
            p.algorithm,
            kind.name(),
            p.layout
        ));
        Some(Entries::compile(p, codegen, stack_size).map_err(|e| {
            CliError::new(format!(
                "cannot compile {} for `{}`: {e}",
                p.algorithm, p.layout
            ))
        })?)
    } else {
        None
    };
    progress(&format!("loading {}", args.scene.display()));
    let t = Instant::now();
    let scene =
        load_obj(&args.scene).map_err(|e| CliError::new(format!("cannot load the scene: {e}")))?;
    let load_time = t.elapsed();
    if kind == QueryKind::Collide {
        let entries = entries.as_ref().expect("collision runs on the CPU");
        return crate::collide::run(args, &resolved, entries, &scene, load_time);
    }
    let (tree, block_tree) = match blocks {
        true => {
            let tree = crate::trace_blocks::build_with(&scene, args.builder, args.leaf_size);
            let b = scion_runtime::triangle4::block_tree(&tree)
                .map_err(|e| CliError::new(format!("the block tree: {e}")))?;
            (tree, Some(b))
        }
        false => {
            // Closest hit tests a leaf in runs of four; the other queries one at a time.
            let runs = match kind {
                QueryKind::ClosestHit => SahOptions::default().block,
                _ => 1,
            };
            (
                build_for_runs(&scene, args.builder, args.leaf_size, runs),
                None,
            )
        }
    };
    let driver = BatchDriver::new(args.threads).map_err(CliError::new)?;
    let (queries, source) = make_queries(kind, &scene, args)?;
    let n = queries.len();
    let init = queries.initial_results();
    let (results, timing, ran) = match &entries {
        Some(entries) => {
            progress(&format!("packing the tree into layout `{}`", p.layout));
            let packed = match &block_tree {
                Some(b) => entries.pack(b),
                None => entries.pack(&tree),
            };
            run_cpu(entries, &queries, &init, packed, &driver, args, kind)?
        }
        None => {
            let options = crate::run_gpu::GpuOptions {
                device: args.device,
                threads: args.threads,
                runs: args.runs,
                quiet: false,
            };
            let g = crate::run_gpu::run(
                &options,
                &resolved,
                stack_size,
                &tree,
                (&queries.bytes, &init),
                queries.record_sizes(),
            )?;
            let ran = Ran {
                compile_time: g.compile_time,
                pack_time: g.pack_time,
                bytes: g.bytes as usize,
                device: g.device,
            };
            (g.results, g.timing, ran)
        }
    };
    progress("checking the answers against the reference");
    let check = match &block_tree {
        Some(b) => {
            let want = Expected::Hits(
                crate::trace_blocks::reference(b, &queries.rays),
                "eight-wide reference over the same blocks",
            );
            queries.compare(&want, &results, &scene.triangles)
        }
        None => queries.check(
            &scene.triangles,
            Traversed::of(&resolved, &tree),
            &results,
            CHECKED_POINTS,
            &driver,
        ),
    }
    .map_err(CliError::new)?;

    outln!("scene        {}", args.scene.display());
    outln!("triangles    {}", scene.len());
    outln!(
        "algorithm    {} ({}, {})",
        p.algorithm,
        kind.name(),
        resolved.tree_type
    );
    outln!("layout       {} ({} bytes packed)", p.layout, ran.bytes);
    outln!("device       {}", ran.device);
    outln!("load time    {}", secs(load_time));
    outln!("compile time {}", secs(ran.compile_time));
    outln!("pack time    {}", secs(ran.pack_time));
    outln!("queries      {n} {source}");
    outln!(
        "time         {} (mean of the middle runs, paper method)",
        secs(timing.mean)
    );
    outln!(
        "throughput   {} Mqueries/s ({:.1} ns/query)",
        significant(timing.queries_per_second(n) / 1e6),
        timing.ns_per_query(n)
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

/// Where and how a run went, for the report.
struct Ran {
    compile_time: std::time::Duration,
    pack_time: std::time::Duration,
    bytes: usize,
    device: String,
}

/// The CPU path: the entries' records checked against the kind's, the tree packed by the
/// generated builder, the batch entry run on the driver's threads by the paper's method.
fn run_cpu(
    entries: &Entries,
    queries: &Queries,
    init: &[u8],
    packed: Result<scion_host::entries::PackedEntries, String>,
    driver: &BatchDriver,
    args: &RunArgs,
    kind: QueryKind,
) -> Result<(Vec<u8>, Timing, Ran), CliError> {
    let sig = entries.sig();
    let p = (&sig.algorithm, &sig.layout);
    if queries.record_sizes() != (sig.query.size, sig.result.size) || sig.trees() != 1 {
        return Err(CliError::new(format!(
            "`{}`'s records are {} and {} bytes over {} trees, not those of a {} query",
            p.0,
            sig.query.size,
            sig.result.size,
            sig.trees(),
            kind.name()
        )));
    }
    let packed = packed.map_err(CliError::new)?;
    progress(&format!("running {} queries", queries.len()));
    let (results, timing) = timed(args.runs, || {
        let mut r = init.to_vec();
        entries
            .run(&packed, &queries.bytes, &mut r, driver)
            .map_err(|e| CliError::new(format!("{}: {e}", p.0)))?;
        Ok(r)
    })?;
    let ran = Ran {
        compile_time: entries.compile_time,
        pack_time: packed.pack_time,
        bytes: packed.bytes(),
        device: format!("this CPU ({} thread(s))", driver.threads()),
    };
    Ok((results, timing, ran))
}

/// 64-bit FNV-1a of `bytes` (the hits checksum's hash, over any result records).
pub(crate) fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// Generated or read queries of `kind` (rays for hits, points for closest points), and what
/// the report says of where they came from.
fn make_queries(
    kind: QueryKind,
    scene: &Scene,
    args: &RunArgs,
) -> Result<(Queries, String), CliError> {
    let b = scene.bounds();
    let n = usize::try_from(args.n).map_err(|_| CliError::usage("--n: too many queries"))?;
    if args.queries_file.is_none() && scene.is_empty() {
        return Err(CliError::new(
            "the scene has no triangles, so there is no box to place generated queries in",
        )
        .note("give them with --queries-file"));
    }
    Ok(match (kind, &args.queries_file) {
        (QueryKind::ClosestPoint, Some(path)) => {
            let bytes = std::fs::read(path)
                .map_err(|e| CliError::new(format!("cannot read {}: {e}", path.display())))?;
            let points = points_from_bytes(&bytes)
                .map_err(|e| CliError::new(format!("{}: {e}", path.display())))?;
            (
                Queries::points(points),
                format!("(points from {})", path.display()),
            )
        }
        (QueryKind::ClosestPoint, None) => (
            Queries::points(uniform_points(b.low, b.high, n, args.seed)),
            format!("(points uniform in the scene's box, seed {})", args.seed),
        ),
        (_, Some(path)) => {
            let rays =
                read_rays(path).map_err(|e| CliError::new(format!("cannot read the rays: {e}")))?;
            (
                Queries::rays(kind, rays),
                format!("(rays from {})", path.display()),
            )
        }
        (_, None) => {
            let rays = match args.rays {
                crate::RaysArg::Primary => primary_rays_n(b, n as u64, args.seed)
                    .ok_or_else(|| CliError::usage(format!("--n {n}: not a ray count")))?,
                crate::RaysArg::Secondary => secondary_rays(b, n, args.seed),
                crate::RaysArg::Axis => axis_rays(b, n, args.seed),
            };
            (
                Queries::rays(kind, rays),
                format!("({} rays, seed {})", args.rays.name(), args.seed),
            )
        }
    })
}
