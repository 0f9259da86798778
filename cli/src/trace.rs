//! `scion trace`: scene -> logical tree -> rays -> hits, with the numbers the paper reports
//! (§9: build and pack time, trace time by the trimmed mean of 9 runs, Mrays/s, bytes of the
//! structure and per node).
//!
//! The layout-free backends (reference, interp, brute) trace the logical tree itself: their
//! structure is the tree's node array plus its reordered triangles, and there is nothing to
//! pack. `--backend jit` follows the runtime contract of docs/design/specialization.md §3
//! through `scion_host::contract` (`@L.sizes`, one aligned allocation per buffer, `@L.build`
//! timed as the pack time, the batch entry over blocks of 64, a nonzero status reported with
//! the failing ray), with the code of `scion_host::jit` (closest hit specialized to the
//! layout, lowered to `lo` at `-O2` and compiled by Cranelift; the compile time is printed).
//! `--backend llvm` is the same with the machine code from LLVM's JIT at `-O3` (`scion-llvm`).

use crate::io::outln;
use crate::{BackendArg, BuilderArg, CliError, DeviceArg, RaysArg, TraceArgs};
use scion_host::backend::{Backend, BackendKind};
use scion_host::contract::{LayoutCode, Packed};
use scion_host::entries::Entries;
use scion_host::hit_reference::{check_hits, Traversed};
use scion_host::jit::{Codegen, JitClosestHit};
use scion_host::mem_interp::{layout_boxes, library_layouts, MemInterpBackend};
use scion_host::quantized::{Boxes, DecodedTree};
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::wide::collapse;
use scion_runtime::bvh::{
    build_fcpw, build_median, build_sah_binned, FcpwOptions, LogicalNode, LogicalTree, SahOptions,
};
use scion_runtime::geom::{Ray, Triangle};
use scion_runtime::query::{
    axis_rays, hits_checksum, primary_rays_n, read_rays, secondary_rays, write_hits,
};
use scion_runtime::reference::{closest_hits_tree_stats, closest_hits_wide_stats};
use scion_runtime::scene::{load_obj, Scene};
use scion_runtime::timing::{measure_with, Timing, TimingPlan};
use std::time::{Duration, Instant};

/// The library's closest-hit layouts by the names `--layout` takes (`pbrt-q16`), for messages.
pub fn closest_hit_layout_names() -> String {
    library_layouts()
        .iter()
        .map(|l| scion_host::library::layout_name(l.0))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Runs `scion trace`.
pub fn run(args: &TraceArgs) -> Result<(), CliError> {
    if args.device != DeviceArg::Cpu {
        return crate::gpu::run_trace(args);
    }
    for (flag, given) in [
        ("--ptx", args.ptx.is_some()),
        ("--emit-ptx", args.emit_ptx.is_some()),
        ("--cpu", args.cpu.is_some()),
    ] {
        if given {
            eprintln!("scion: note: {flag} is used by --device gpu only");
        }
    }
    // Decide the backend before the (possibly long) load, so that a backend that cannot run
    // fails at once.
    let layout = args.layout.as_deref().unwrap_or("pbrt");
    let compiled = matches!(args.backend, BackendArg::Jit | BackendArg::Llvm);
    let uses_layout = compiled || args.backend == BackendArg::MemInterp;
    if args.stack_size.is_some() && !compiled {
        eprintln!("scion: note: --stack-size is used by --backend jit|llvm only");
    }
    if (args.no_dsl_opt || args.opt_level != 3) && !compiled {
        eprintln!("scion: note: --opt-level and --no-dsl-opt are used by --backend jit|llvm only");
    }
    if args.layout.is_some() && !uses_layout {
        eprintln!("scion: note: --layout is used by --backend jit|llvm|mem-interp only; this backend traces the logical tree");
    }
    if args.algorithm.is_some() && !compiled {
        eprintln!("scion: note: --algorithm is used by --backend jit|llvm only");
    }
    let mut peaks = crate::memory::Peaks::start();
    // What --layout and --algorithm name (a library name or a file), for the compiled backends.
    let resolved = match compiled {
        true => Some(
            scion_host::library::resolve(layout, args.algorithm.as_deref())
                .map_err(|e| CliError::usage(e).note("scion trace --help says what they take"))?,
        ),
        false => None,
    };
    // A layout over blocks of four triangles (`bvh8-tri4`) packs a tree over blocks
    // (crate::trace_blocks); every other compiled layout holds triangles.
    let blocks = resolved
        .as_ref()
        .is_some_and(|r| r.primitive == crate::trace_blocks::PRIMITIVE);
    if let Some(r) = resolved.as_ref().filter(|_| !blocks) {
        over_triangles(r, layout)?;
    }
    let boxes = match (&resolved, args.backend) {
        (Some(r), _) => r.boxes,
        (None, BackendArg::MemInterp) => layout_boxes(&layout.replace('-', "_")),
        _ => Boxes::Exact,
    };
    let engine = match args.backend {
        BackendArg::Reference => Engine::Free(instantiate(BackendKind::Reference, args)?),
        BackendArg::Brute => Engine::Free(instantiate(BackendKind::Brute, args)?),
        BackendArg::Interp => Engine::Free(instantiate(BackendKind::Interp(1), args)?),
        BackendArg::MemInterp => Engine::Mem(Box::new(mem_backend(layout, args.threads)?)),
        BackendArg::Jit | BackendArg::Llvm if blocks => {
            let (codegen, engine) = match args.backend {
                BackendArg::Jit => (Codegen::Cranelift, "jit"),
                _ => (Codegen::Llvm(3), "llvm -O3"),
            };
            let r = resolved.as_ref().expect("resolved for jit and llvm");
            Engine::Blocks {
                entries: Box::new(crate::trace_blocks::compile(r, args, codegen)?),
                layout: r.program.layout.clone(),
                driver: BatchDriver::new(args.threads).map_err(CliError::new)?,
                engine,
            }
        }
        BackendArg::Jit => Engine::Layout {
            code: jit_code(
                resolved.as_ref().expect("resolved for jit"),
                args,
                Codegen::Cranelift,
            )?,
            driver: BatchDriver::new(args.threads).map_err(CliError::new)?,
            engine: "jit",
        },
        BackendArg::Llvm => Engine::Layout {
            code: jit_code(
                resolved.as_ref().expect("resolved for llvm"),
                args,
                Codegen::Llvm(3),
            )?,
            driver: BatchDriver::new(args.threads).map_err(CliError::new)?,
            engine: "llvm -O3",
        },
    };

    peaks.mark("compile");
    progress(&format!("loading {}", args.scene.display()));
    let t = Instant::now();
    let file = args.scene.to_string_lossy();
    if file.ends_with(".hair") || file.ends_with(".hair.gz") {
        return Err(CliError::usage(format!(
            "{file} is a strand scene; `scion trace` traces triangle meshes"
        ))
        .note("`scion strands trace --scene FILE.hair` traces strands (layout hair-bvh-strands)"));
    }
    let scene = load_obj(&args.scene).map_err(|e| {
        let err = CliError::new(format!("cannot load the scene: {e}"));
        match e.line() {
            Some(_) => err.note("scenes are Wavefront OBJ files (docs/formats.md)"),
            None => err,
        }
    })?;
    let load_time = t.elapsed();
    peaks.mark("load");

    let t = Instant::now();
    let tree = match blocks {
        true => crate::trace_blocks::build(&scene, args),
        false => build(&scene, args),
    };
    let build_time = t.elapsed();
    peaks.mark("build");
    // FCPW's builder makes a larger leaf at its depth limit only.
    let cap = match args.builder {
        BuilderArg::Fcpw if tree.stats().depth > FcpwOptions::default().max_depth => {
            u16::MAX as usize
        }
        BuilderArg::Sah if blocks => crate::trace_blocks::leaf_size(args),
        b => b.leaf_size(args.leaf_size),
    };
    tree.validate_with_cap(cap)
        .map_err(|e| CliError::new(format!("the builder made an invalid tree: {e}")))?;

    let rays = rays(&scene, args)?;
    let threads = match args.threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        t => t,
    };
    let tracing = || {
        progress(&format!(
            "tracing {} rays with {} on {threads} thread{}",
            rays.len(),
            engine.name(),
            if threads == 1 { "" } else { "s" }
        ))
    };
    // The interpreters get a progress bar over every trace (the checked one and the timed runs).
    let traces = 1 + if args.runs > 1 { args.runs as u64 } else { 0 };
    let bar = || crate::bar::Bar::new("rays", rays.len() as u64 * traces);
    // The tree over blocks a `Triangle4` layout traced (for the check and --stats).
    let mut block_tree = None;
    let (hits, timing, packed) = match &engine {
        Engine::Free(b) => {
            tracing();
            let _bar = (args.backend == BackendArg::Interp).then(bar);
            let (hits, timing) = timed(args.runs, || {
                b.trace(&scene.triangles, &tree, &rays)
                    .map_err(|e| CliError::new(format!("{} failed: {e}", b.name())))
            })?;
            (hits, timing, None)
        }
        Engine::Mem(b) => {
            progress(&format!(
                "packing the tree into layout `{layout}` in the interpreter"
            ));
            let (sizes, time) = b.program().pack_report(&tree).map_err(CliError::new)?;
            tracing();
            let _bar = bar();
            let (hits, timing) = timed(args.runs, || {
                b.trace(&scene.triangles, &tree, &rays)
                    .map_err(|e| CliError::new(format!("{} failed: {e}", b.name())))
            })?;
            let buffers = sizes
                .iter()
                .enumerate()
                .map(|(i, &n)| (format!("buffer {i}"), n as usize, None))
                .collect();
            let note = " (sizes + build, interpreted)";
            (
                hits,
                timing,
                Some(PackInfo {
                    time,
                    buffers,
                    note,
                }),
            )
        }
        Engine::Layout { code, driver, .. } => {
            progress(&format!("packing the tree into layout `{}`", code.layout()));
            let packed = Packed::new(code.as_ref(), &tree).map_err(CliError::new)?;
            peaks.mark("pack");
            tracing();
            let (hits, timing) = timed(args.runs, || {
                packed.trace(code.as_ref(), &rays, driver).map_err(|f| {
                    CliError::new(format!("layout `{}`: {f}", code.layout())).note(
                        "trees deeper than the generated traversal's stack cannot be traced \
                         with this layout; try --builder sah with a larger --leaf-size",
                    )
                })
            })?;
            let buffers = packed
                .specs
                .iter()
                .zip(packed.buffers())
                .map(|(spec, b)| (spec.name.clone(), b.len(), Some(spec.align)))
                .collect();
            let info = PackInfo {
                time: packed.pack_time,
                buffers,
                note: "",
            };
            (hits, timing, Some(info))
        }
        Engine::Blocks {
            entries,
            layout,
            driver,
            ..
        } => {
            progress(&format!(
                "packing the tree into layout `{layout}` (blocks of four triangles)"
            ));
            let (blocks, packed) = crate::trace_blocks::pack(entries, &tree, layout)?;
            peaks.mark("pack");
            tracing();
            let (hits, timing) = timed(args.runs, || {
                crate::trace_blocks::trace(entries, &packed, &rays, driver, layout)
            })?;
            let info = PackInfo {
                time: packed.pack_time,
                buffers: vec![("buffers".into(), packed.bytes(), Some(64))],
                note: "",
            };
            block_tree = Some(blocks);
            (hits, timing, Some(info))
        }
    };

    peaks.mark("trace");
    let stats = tree.stats();
    let node_bytes = tree.nodes.len() * std::mem::size_of::<LogicalNode>();
    let prim_bytes = tree.primitives.len() * std::mem::size_of::<Triangle>();
    let (pack_line, layout_line, bytes) = match &packed {
        None => (
            "0 s (layout-free backend: it reads the logical tree)".to_string(),
            format!("none (logical tree: {node_bytes} B of nodes + {prim_bytes} B of triangles)"),
            node_bytes + prim_bytes,
        ),
        Some(p) => {
            let parts: Vec<String> = p
                .buffers
                .iter()
                .map(|(name, n, align)| {
                    let per_node = *n as f64 / stats.nodes.max(1) as f64;
                    match align {
                        Some(a) => format!("{name} {n} B (align {a}, {per_node:.1} B/node)"),
                        None => format!("{name} {n} B ({per_node:.1} B/node)"),
                    }
                })
                .collect();
            (
                format!("{}{}", secs(p.time), p.note),
                format!("{layout}: {}", parts.join(", ")),
                p.buffers.iter().map(|b| b.1).sum(),
            )
        }
    };
    let hit_count = hits.iter().filter(|h| h.is_hit()).count();
    let builder = match blocks && args.builder == BuilderArg::Sah {
        true => format!(
            "binned SAH + reinsertion + leaves collapsed for blocks of four, leaves <= {}",
            crate::trace_blocks::leaf_size(args)
        ),
        false => args.builder.describe(args.leaf_size),
    };
    let source = match &args.rays_file {
        Some(p) => format!("from {}", p.display()),
        None => format!("{:?} (seed {})", args.rays, args.seed).to_lowercase(),
    };
    outln!("scene        {}", args.scene.display());
    outln!("triangles    {}", scene.len());
    outln!(
        "nodes        {} ({} interior, {} leaves, depth {}, SAH cost {:.2})",
        stats.nodes,
        stats.interior,
        stats.leaves,
        stats.depth,
        stats.sah_cost
    );
    outln!("builder      {builder}");
    outln!("load time    {}", secs(load_time));
    outln!("build time   {}", secs(build_time));
    outln!("pack time    {pack_line}");
    outln!("layout       {layout_line}");
    outln!(
        "structure    {bytes} bytes, {:.1} bytes/node",
        bytes as f64 / stats.nodes.max(1) as f64
    );
    if let Some(m) = peaks.report() {
        outln!("memory       peak resident per phase: {m}");
    }
    outln!("rays         {} {source}", rays.len());
    outln!("backend      {} on {threads} threads", engine.name());
    outln!(
        "trace time   {} ({})",
        secs(timing.mean),
        plan_text(args.runs)
    );
    outln!(
        "throughput   {} Mrays/s ({:.1} ns/ray)",
        significant(timing.queries_per_second(rays.len()) / 1e6),
        timing.ns_per_query(rays.len())
    );
    outln!("hits         {hit_count} of {} rays", rays.len());
    if let Some(r) = resolved.as_ref().filter(|_| !args.no_check) {
        progress("checking every hit against the reference");
        let (want, which) = match &block_tree {
            Some(b) => (
                crate::trace_blocks::reference(b, &rays),
                "eight-wide reference over the same blocks",
            ),
            None => {
                let traversed = Traversed::of(r, &tree);
                let driver = BatchDriver::new(threads).map_err(CliError::new)?;
                let want = traversed.hits(&rays, &driver).map_err(|e| {
                    CliError::new(format!("cannot check the hits: {e}"))
                        .note("--no-check traces without the check")
                })?;
                (want, traversed.name())
            }
        };
        let agreement = check_hits(&hits, &want, &rays, &scene.triangles, which, "ray")
            .map_err(|e| CliError::new(e).note("--no-check traces without this comparison"))?;
        outln!("check        {}", agreement.describe(which, "rays"));
    }
    if args.stats {
        if let Some(b) = &block_tree {
            let driver = BatchDriver::new(threads).map_err(CliError::new)?;
            crate::trace_blocks::stats(b, &rays, &driver);
        }
        let traversed = boxes.decoded_tree(&tree);
        // Quantized boxes of the binary tree (not per wide node, reported below).
        let binary_quantized = !matches!(boxes, Boxes::Exact) && boxes.node_codes().is_none();
        let driver = BatchDriver::new(threads).map_err(CliError::new)?;
        let s = closest_hits_tree_stats(&traversed, &rays, &driver);
        let per = |x: u64| x as f64 / rays.len().max(1) as f64;
        outln!(
            "work/ray     {:.2} box tests, {:.2} nodes visited, {:.2} skipped, {:.2} triangle tests in {:.2} runs of up to four; deepest stack {} (reference traversal{})",
            per(s.boxes_tested),
            per(s.nodes_visited),
            per(s.nodes_pruned),
            per(s.triangles_tested),
            per(s.leaf_runs),
            s.max_pending,
            if binary_quantized { " of the decoded boxes" } else { "" }
        );
        if binary_quantized {
            // What the quantized boxes cost: inflation and extra work against the exact tree.
            let exact = closest_hits_tree_stats(&tree, &rays, &driver);
            let i = crate::quant_error::inflation(&tree, &traversed);
            for line in crate::quant_error::report(&i, &s, &exact) {
                outln!("{line}");
            }
        }
        // The same tree collapsed to 4 and 8 children per node: the work a wide layout's
        // traversal would do (nearest first, scion_runtime::reference::closest_hit_wide).
        let w4 = collapse::<4>(&traversed);
        let w8 = collapse::<8>(&traversed);
        if boxes.node_codes().is_some() {
            // An eight-wide layout quantizing each node's children in the node's frame: its
            // decoded child boxes against the exact ones, and the wide traversal's extra work.
            let decoded = scion_host::quantized::decoded_wide(boxes, &w8);
            let exact = closest_hits_wide_stats(&w8, &traversed.primitives, &rays, &driver);
            let s = closest_hits_wide_stats(&decoded, &traversed.primitives, &rays, &driver);
            let i = crate::quant_error::inflation_wide(&w8, &decoded);
            for line in crate::quant_error::report(&i, &s, &exact) {
                outln!("{line}");
            }
        }
        let s4 = closest_hits_wide_stats(&w4, &traversed.primitives, &rays, &driver);
        let s8 = closest_hits_wide_stats(&w8, &traversed.primitives, &rays, &driver);
        for (w, n, s) in [(4, w4.nodes.len(), s4), (8, w8.nodes.len(), s8)] {
            outln!(
                "{w}-wide       {:.2} box tests, {:.2} nodes visited, {:.2} triangle tests per ray; {n} nodes (the tree collapsed, reference traversal)",
                per(s.boxes_tested),
                per(s.nodes_visited),
                per(s.triangles_tested),
            );
        }
    }
    // The same number as the C library's `scion_hits_checksum` (examples/cpp prints it too).
    outln!("checksum: {:016x}", hits_checksum(&hits));
    if let Some(path) = &args.output {
        write_hits(path, &hits)
            .map_err(|e| CliError::new(format!("cannot write the hits: {e}")))?;
        outln!("output       {} ({} bytes)", path.display(), hits.len() * 8);
    }
    Ok(())
}

/// How `scion trace` traces: a layout-free backend, or code specialized to a layout driven
/// through the runtime contract.
enum Engine {
    Free(Box<dyn Backend>),
    Mem(Box<MemInterpBackend>),
    Layout {
        code: Box<dyn LayoutCode>,
        driver: BatchDriver,
        /// `jit` (Cranelift) or `llvm -O3`.
        engine: &'static str,
    },
    /// A layout over blocks of four triangles, through its C entries (crate::trace_blocks).
    Blocks {
        entries: Box<Entries>,
        layout: String,
        driver: BatchDriver,
        /// `jit` (Cranelift) or `llvm -O3`.
        engine: &'static str,
    },
}

impl Engine {
    fn name(&self) -> String {
        match self {
            Engine::Free(b) => b.name(),
            Engine::Mem(b) => b.name(),
            Engine::Layout { code, engine, .. } => format!("{engine} ({})", code.layout()),
            Engine::Blocks { layout, engine, .. } => format!("{engine} ({layout})"),
        }
    }
}

/// What packing into a layout produced: its time and each buffer (name, bytes, alignment).
struct PackInfo {
    time: Duration,
    buffers: Vec<(String, usize, Option<usize>)>,
    note: &'static str,
}

/// Closest hit specialized to the library layout `layout` (a `--layout` name), interpreted
/// at the mem level.
fn mem_backend(layout: &str, threads: usize) -> Result<MemInterpBackend, CliError> {
    let stem = layout.replace('-', "_");
    let Some(&(stem, name, _)) = library_layouts().iter().find(|l| l.0 == stem) else {
        return Err(CliError::usage(format!(
            "unknown layout `{layout}` for --backend mem-interp"
        ))
        .note(format!(
            "it runs the library's closest-hit layouts: {}",
            closest_hit_layout_names()
        )));
    };
    let threads = match threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        t => t,
    };
    MemInterpBackend::new(stem, name, threads)
        .map_err(|e| CliError::new(format!("cannot specialize closest hit to `{layout}`: {e}")))
}

fn instantiate(kind: BackendKind, args: &TraceArgs) -> Result<Box<dyn Backend>, CliError> {
    kind.instantiate(args.threads).map_err(CliError::new)
}

/// The closest-hit program `resolved` (`--layout`, `--algorithm`) compiled by `codegen`, after
/// the tree/mem passes of `args.opt_level` (without the DSL optimizations with `--no-dsl-opt`),
/// with a traversal stack of `args.stack_size` entries.
fn jit_code(
    resolved: &scion_host::library::Resolved,
    args: &TraceArgs,
    codegen: Codegen,
) -> Result<Box<dyn LayoutCode>, CliError> {
    let p = &resolved.program;
    progress(&format!(
        "compiling {} for layout `{}`",
        p.algorithm, p.layout
    ));
    let code = JitClosestHit::compile_program(
        p,
        args.stack_size,
        args.opt_level,
        !args.no_dsl_opt,
        codegen,
    )
    .map_err(|e| {
        CliError::new(format!(
            "cannot compile {} for `{}`: {e}",
            p.algorithm, p.layout
        ))
    })?;
    eprintln!(
        "scion: compiled in {:.3} s",
        code.compile_time.as_secs_f64()
    );
    Ok(Box::new(code))
}

/// Any program's C entries (`scion_host::entries`, as `scionc -O3 --entry` compiles them) by
/// `codegen`, with a traversal stack of `stack_size` entries; says what it compiles.
pub(crate) fn compile_entries(
    p: &scion_host::mem_interp::Program,
    codegen: Codegen,
    stack_size: Option<u32>,
) -> Result<Entries, CliError> {
    progress(&format!(
        "compiling {} for layout `{}`",
        p.algorithm, p.layout
    ));
    Entries::compile(p, codegen, stack_size).map_err(|e| {
        CliError::new(format!(
            "cannot compile {} for `{}`: {e}",
            p.algorithm, p.layout
        ))
    })
}

pub(crate) fn build(scene: &Scene, args: &TraceArgs) -> LogicalTree {
    build_with(scene, args.builder, args.leaf_size)
}

/// The logical tree of `scene` by `builder` (leaves of at most `builder.leaf_size(leaf_size)`
/// triangles).
pub(crate) fn build_with(
    scene: &Scene,
    builder: BuilderArg,
    leaf_size: Option<u32>,
) -> LogicalTree {
    build_for_runs(scene, builder, leaf_size, SahOptions::default().block)
}

/// [`build_with`] for an algorithm that tests a leaf's primitives in runs of `runs` (the
/// library's closest hit: four, the runtime's default; closest point, any hit and collision
/// test them one at a time: 1, no leaf collapse). Only the SAH builder uses it.
pub(crate) fn build_for_runs(
    scene: &Scene,
    builder: BuilderArg,
    leaf_size: Option<u32>,
    runs: usize,
) -> LogicalTree {
    let max_leaf = builder.leaf_size(leaf_size);
    progress(&format!(
        "building the logical tree of {} triangles",
        scene.len()
    ));
    match builder {
        BuilderArg::Sah => build_sah_binned(
            &scene.triangles,
            &SahOptions {
                max_leaf,
                block: runs,
                ..SahOptions::default()
            },
        ),
        BuilderArg::Median => build_median(&scene.triangles),
        BuilderArg::Fcpw => build_fcpw(
            &scene.triangles,
            &FcpwOptions {
                leaf_size: max_leaf,
                ..FcpwOptions::default()
            },
        ),
    }
}

pub(crate) fn rays(scene: &Scene, args: &TraceArgs) -> Result<Vec<Ray>, CliError> {
    if let Some(path) = &args.rays_file {
        progress(&format!("reading rays from {}", path.display()));
        return read_rays(path).map_err(|e| CliError::new(format!("cannot read the rays: {e}")));
    }
    let b = scene.bounds();
    if scene.is_empty() {
        return Err(CliError::new(format!(
            "{}: the scene has no triangles, so there is no box to aim generated rays at",
            args.scene.display()
        ))
        .note("give rays with --rays-file"));
    }
    let n = usize::try_from(args.n).map_err(|_| CliError::new("--n: too many rays"))?;
    Ok(match args.rays {
        RaysArg::Primary => primary_rays_n(b, n as u64, args.seed)
            .ok_or_else(|| CliError::new(format!("--n: {n} is not a valid ray count")))?,
        RaysArg::Secondary => secondary_rays(b, n, args.seed),
        RaysArg::Axis => axis_rays(b, n, args.seed),
    })
}

/// Traces once for the hits, then times by the plan of `runs` (the first trace is the
/// warm-up; with `runs == 1` it is also the one timed run).
pub(crate) fn timed<T>(
    runs: u32,
    mut trace: impl FnMut() -> Result<T, CliError>,
) -> Result<(T, Timing), CliError> {
    // A bar over the runs, unless an interpreter's bar over the queries is up.
    let bar = (!crate::bar::queries_bar_up())
        .then(|| crate::bar::RunsBar::new(1 + if runs > 1 { u64::from(runs) } else { 0 }));
    let tick = || {
        if let Some(b) = &bar {
            b.tick();
        }
    };
    let mut trace = move || {
        let r = trace();
        tick();
        r
    };
    let t = Instant::now();
    let hits = trace()?;
    let first = t.elapsed();
    if runs == 1 {
        return Ok((
            hits,
            Timing {
                raw: vec![first],
                mean: first,
            },
        ));
    }
    let drop = ((runs - 1) / 4) as usize;
    let plan = TimingPlan {
        warmup: 0,
        runs: runs as usize,
        drop_low: drop,
        drop_high: drop,
    };
    let mut failed = None;
    let timing = measure_with(&plan, || {
        if let Err(e) = trace() {
            failed = Some(e);
        }
    });
    match failed {
        Some(e) => Err(e),
        None => Ok((hits, timing)),
    }
}

fn plan_text(runs: u32) -> String {
    if runs == 1 {
        return "1 run, no warm-up".into();
    }
    let drop = (runs - 1) / 4;
    format!(
        "mean of {} of {runs} runs after 1 warm-up, dropping the {drop} fastest and {drop} slowest",
        runs - 2 * drop
    )
}

/// `x` with four significant digits (throughputs span 0.001 to 1000 Mrays/s).
pub(crate) fn significant(x: f64) -> String {
    let digits = if x > 0.0 && x.is_finite() {
        (3 - x.log10().floor() as i32).clamp(0, 9) as usize
    } else {
        3
    };
    format!("{x:.digits$}")
}

pub(crate) fn secs(d: Duration) -> String {
    format!("{:.6} s", d.as_secs_f64())
}

/// A usage error unless the layout `name` resolved to holds triangles (the scenes of `scion
/// trace`, `run`, `render` and `tune` are triangle meshes).
pub(crate) fn over_triangles(
    r: &scion_host::library::Resolved,
    name: &str,
) -> Result<(), CliError> {
    if r.primitive == "Triangle" {
        return Ok(());
    }
    let e = CliError::usage(format!(
        "--layout {name}: its leaves hold `{}`s, and this command's scenes are triangle meshes",
        r.primitive
    ));
    Err(match r.primitive == crate::trace_blocks::PRIMITIVE {
        true => e.note(format!(
            "`scion trace --backend llvm --layout {name}` traces a mesh's triangles in blocks of four"
        )),
        false => e.note("`scion strands trace --scene FILE.hair --layout NAME` traces strand scenes"),
    })
}

pub(crate) fn progress(what: &str) {
    eprintln!("scion: {what}...");
}
