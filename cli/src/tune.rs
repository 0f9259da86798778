//! `scion tune`: "model only what a scene needs". For one context (a scene, a query kind, a
//! query set and size, a backend) it measures every candidate layout as `scion explore` does
//! (the same rows, in `--results`, so a second call reuses them), finds the Pareto frontier of
//! time per query against bytes per triangle, and picks:
//!
//! * by default, the fastest layout whose answers equal the reference;
//! * with `--max-bytes-per-triangle B`, the fastest within that memory budget;
//! * with `--max-slowdown X`, the smallest within `X` times the fastest's time.
//!
//! It prints the measured points and why the choice won, and with `--emit obj|ptx|header -o
//! FILE` compiles the chosen layout's entries (a host object file, a PTX kit for `scion trace
//! --device gpu --ptx`, or the C header of the entries).

use crate::args_study::ExploreDevice;
use crate::io::outln;
use crate::plot::{contexts, frontier, Point};
use crate::results::read_rows;
use crate::DeviceArg;
use crate::{CliError, ExploreArgs, TuneArgs, TuneEmit};
use scion_host::jit::{program_lo, LoOptions};
use scion_host::library::{resolve_kind, QueryKind};

/// Runs `scion tune`.
pub fn run(args: &TuneArgs) -> Result<(), CliError> {
    let kind = QueryKind::BATCHED
        .into_iter()
        .find(|k| k.name() == args.algorithm)
        .ok_or_else(|| {
            CliError::usage(format!(
                "--algorithm {}: tune chooses among the library's layouts for a query kind: \
                 closest-hit, any-hit or closest-point",
                args.algorithm
            ))
        })?;
    if args.max_bytes_per_triangle.is_some() && args.max_slowdown.is_some() {
        return Err(CliError::usage(
            "give a memory budget (--max-bytes-per-triangle) or a slowdown budget (--max-slowdown), not both",
        ));
    }
    let results = args.results.clone().unwrap_or_else(|| {
        std::env::temp_dir().join(format!(
            "scion-tune-{}-{}.csv",
            args.scene
                .file_name()
                .map_or("scene".into(), |f| f.to_string_lossy().into_owned()),
            kind.name()
        ))
    });
    let queries = match kind {
        QueryKind::ClosestPoint => "points",
        _ => args.rays.name(),
    };
    let sweep = ExploreArgs {
        scenes: Some(vec![args.scene.display().to_string()]),
        layouts: args.layouts.clone(),
        kinds: vec![kind.name().to_string()],
        rays: vec![queries.to_string()],
        sizes: vec![args.n],
        backends: vec![args.backend],
        devices: vec![match args.device {
            DeviceArg::Cpu => ExploreDevice::Cpu,
            DeviceArg::Gpu => ExploreDevice::Gpu,
            DeviceArg::GpuEmulated => ExploreDevice::GpuEmulated,
        }],
        threads: args.threads,
        runs: args.runs,
        builder: crate::BuilderArg::Sah,
        leaf_size: None,
        stack_size: None,
        output: results.clone(),
        plots: None,
        peers: None,
    };
    crate::explore::run(&sweep)?;
    let rows = read_rows(&results)?.unwrap_or_default();
    let scene = args.scene.display().to_string();
    let want = [
        scene.as_str(),
        kind.name(),
        queries,
        &args.n.to_string(),
        crate::explore::backend_column(args.device, args.backend),
        &args.threads.to_string(),
    ];
    let points: Vec<Point> = contexts(&rows)
        .into_iter()
        .filter(|(ctx, _)| ctx.iter().zip(want).all(|(a, b)| a == b))
        .flat_map(|(_, p)| p)
        .filter(|p| args.layouts.as_ref().is_none_or(|l| l.contains(&p.layout)))
        .collect();
    let good: Vec<Point> = points.iter().filter(|p| p.identical).cloned().collect();
    if good.is_empty() {
        return Err(CliError::new(format!(
            "no layout answered {} on {scene} as the reference does; nothing to choose",
            kind.name()
        )));
    }
    let front = frontier(&good);
    let fastest = front.last().expect("a frontier of a nonempty set").clone();
    let (choice, why) = if let Some(b) = args.max_bytes_per_triangle {
        match front
            .iter()
            .filter(|p| p.bytes_per_triangle <= b)
            .min_by(|x, y| x.ns_per_query.total_cmp(&y.ns_per_query))
        {
            Some(p) => (
                p.clone(),
                format!("the fastest within {b} bytes per triangle"),
            ),
            None => {
                return Err(CliError::new(format!(
                "no layout fits in {b} bytes per triangle: the smallest measured, {}, takes {:.1}",
                front[0].layout, front[0].bytes_per_triangle
            )))
            }
        }
    } else if let Some(x) = args.max_slowdown {
        let p = front
            .iter()
            .find(|p| p.ns_per_query <= x * fastest.ns_per_query)
            .expect("the fastest is within any slowdown of at least 1");
        (
            p.clone(),
            format!(
                "the smallest within {x} times the fastest ({}, {:.1} ns per query)",
                fastest.layout, fastest.ns_per_query
            ),
        )
    } else {
        (fastest.clone(), "the fastest".to_string())
    };
    outln!(
        "context      {scene}, {} ({} {queries}), {}, {} thread(s)",
        kind.name(),
        args.n,
        want[4],
        args.threads
    );
    outln!("results      {}", results.display());
    outln!(
        "{:<22} {:>14} {:>12}  Pareto-optimal",
        "layout",
        "bytes/triangle",
        "ns/query"
    );
    let mut sorted = points.clone();
    sorted.sort_by(|a, b| a.ns_per_query.total_cmp(&b.ns_per_query));
    for p in &sorted {
        let on = front.iter().any(|q| q.layout == p.layout);
        outln!(
            "{:<22} {:>14.1} {:>12.1}  {}{}",
            p.layout,
            p.bytes_per_triangle,
            p.ns_per_query,
            if on { "yes" } else { "" },
            if p.identical {
                ""
            } else {
                " (answers differ from the reference: not chosen)"
            }
        );
    }
    outln!(
        "choice       {} ({why}: {:.1} bytes per triangle, {:.1} ns per query)",
        choice.layout,
        choice.bytes_per_triangle,
        choice.ns_per_query
    );
    if let Some(emit) = args.emit {
        let out = args.output.as_ref().ok_or_else(|| {
            CliError::usage("--emit needs -o FILE: where to write the chosen layout's code")
        })?;
        emit_choice(&choice.layout, kind, emit, out)?;
        outln!("output       {}", out.display());
    }
    Ok(())
}

/// Compiles the chosen layout's entries of `kind` to `out`.
fn emit_choice(
    layout: &str,
    kind: QueryKind,
    emit: TuneEmit,
    out: &std::path::Path,
) -> Result<(), CliError> {
    let r = resolve_kind(layout, None, kind).map_err(CliError::new)?;
    crate::trace::over_triangles(&r, layout)?;
    let fail = |e: String| CliError::new(format!("cannot compile for `{layout}`: {e}"));
    let write = |bytes: &[u8]| {
        crate::io::write_whole(out, bytes)
            .map_err(|e| CliError::new(format!("cannot write {}: {e}", out.display())))
    };
    match emit {
        TuneEmit::Ptx => {
            let (kit, _, _) = crate::gpu::compile_program_kit(&r.program, r.boxes, None, None)?;
            crate::gpu::write_kit(&kit, out)
        }
        TuneEmit::Obj | TuneEmit::Header => {
            let lo = program_lo(
                &r.program,
                &LoOptions {
                    stack_size: None,
                    opt_level: 3,
                    dsl_opt: true,
                    target: scion_compiler::abi::EntryTarget::Host,
                },
            )
            .map_err(fail)?;
            if emit == TuneEmit::Header {
                let m = &lo.module;
                let root = m
                    .func_by_name(&lo.entry.layout_fn("root"))
                    .and_then(|f| m.funcs[f].results.first().copied())
                    .map(|t| m.types.get(t).clone())
                    .ok_or_else(|| fail("the entries have no root function".into()))?;
                return write(scion_compiler::abi::header::render(&lo.entry, &root).as_bytes());
            }
            let target = scion_llvm::Target::host()
                .ok_or_else(|| fail("this machine is neither x86-64 nor AArch64".into()))?;
            let opts = scion_llvm::Options {
                target,
                cpu: None,
                opt_level: 3,
            };
            let obj = scion_llvm::emit(&lo.module, &opts, scion_llvm::Output::Object)
                .map_err(|e| fail(e.to_string()))?;
            write(&obj)
        }
    }
}
