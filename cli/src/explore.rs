//! `scion explore`: the design space swept (paper §9.2): every scene × query kind × query set
//! (primary or secondary rays, points) × size × target (this CPU through each backend; an
//! NVIDIA GPU, or its kernels emulated on this CPU: `--devices`) × layout that has an entry of
//! the kind, timed by the paper's method on the same queries (on the CPU the layouts of a
//! context interleaved round by round: one warm-up round, then `--runs` rounds, the middle ones
//! averaged; on a GPU each layout's kernels timed by the device after a warm-up, as `scion run
//! --device` does) and checked against the reference, one CSV row per measurement
//! (`ROW_FIELDS`), appended and flushed as each context ends. A rerun with the same output
//! skips the rows already there (the key: scene, kind, queries, size, backend, threads,
//! builder, layout), so a sweep stopped halfway resumes; rows of an earlier commit count as
//! measured (delete the file, or give another, to measure again). Every row carries the
//! machine, the commit and the toolchain.
//!
//! Per row: the packed bytes and bytes per triangle, the mean time of the middle runs, the
//! time per query and the throughput, whether the answers equal the reference, and for a
//! quantized layout its speed against error: the decoded boxes' surface area over the exact
//! ones', and the extra box tests and node visits of the reference traversal over them
//! (`crate::quant_error`). Trees are built once per scene, entries compiled once per layout,
//! kind and backend. `--plots DIR` then draws the results (`crate::plot`).

use crate::args_study::ExploreDevice;
use crate::io::outln;
use crate::results::{csv_field, key, now_utc, provenance, read_csv, read_rows, ROW_FIELDS};
use crate::trace::build_with;
use crate::{CliError, DeviceArg, ExploreArgs, RunBackend};
use scion_host::entries::Entries;
use scion_host::hit_reference::Traversed;
use scion_host::jit::Codegen;
use scion_host::library::{self, resolve_kind, QueryKind, Resolved};
use scion_host::queries::{uniform_points, Queries};
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::LogicalTree;
use scion_runtime::query::{primary_rays_n, secondary_rays};
use scion_runtime::scene::{load_obj, Scene};
use std::collections::{BTreeMap, BTreeSet};
use std::io::Write;
use std::path::Path;

/// What a set of queries is made from: scene, kind, query set, size.
type QueryKey = (String, &'static str, &'static str, usize);

/// Closest points checked against brute force per context (the first ones).
const CHECKED_POINTS: usize = 1024;

/// Where a measurement runs: this CPU through one of the code generators, or a GPU (an NVIDIA
/// one through CUDA, or the same kernels emulated on this CPU).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Target {
    Cpu(RunBackend),
    Gpu { emulated: bool },
}

impl Target {
    /// The `backend` column.
    fn name(self) -> &'static str {
        match self {
            Target::Cpu(RunBackend::Jit) => "cranelift",
            Target::Cpu(RunBackend::Llvm) => "llvm-O3",
            Target::Gpu { emulated: false } => "ptx",
            Target::Gpu { emulated: true } => "gpu-emulated",
        }
    }
}

/// The `backend` column of the rows measured on `device` (with `backend` on the CPU).
pub fn backend_column(device: DeviceArg, backend: RunBackend) -> &'static str {
    match device {
        DeviceArg::Cpu => Target::Cpu(backend),
        DeviceArg::Gpu => Target::Gpu { emulated: false },
        DeviceArg::GpuEmulated => Target::Gpu { emulated: true },
    }
    .name()
}

/// The targets of `--devices` and `--backends`: every backend on the CPU, and a GPU when named
/// (or, for `auto`, when one opens).
fn targets(args: &ExploreArgs) -> Vec<Target> {
    let mut out = Vec::new();
    for d in &args.devices {
        match d {
            ExploreDevice::Cpu | ExploreDevice::Auto => {
                out.extend(args.backends.iter().map(|&b| Target::Cpu(b)));
                if *d == ExploreDevice::Auto && crate::gpu::open_device(0).is_ok() {
                    out.push(Target::Gpu { emulated: false });
                }
            }
            ExploreDevice::Gpu => out.push(Target::Gpu { emulated: false }),
            ExploreDevice::GpuEmulated => out.push(Target::Gpu { emulated: true }),
        }
    }
    let mut unique = Vec::new();
    for t in out {
        if !unique.contains(&t) {
            unique.push(t);
        }
    }
    unique
}

/// A sweep's plan: what to measure, in order.
struct Job {
    scene: String,
    kind: QueryKind,
    queries: &'static str,
    n: usize,
    target: Target,
    layout: String,
}

/// The query sets of a kind: rays for hits, points for closest points.
fn query_sets(kind: QueryKind, rays: &[String]) -> Vec<&'static str> {
    match kind {
        QueryKind::ClosestPoint => vec!["points"],
        _ => rays
            .iter()
            .filter_map(|r| match r.as_str() {
                "primary" => Some("primary"),
                "secondary" => Some("secondary"),
                _ => None,
            })
            .collect(),
    }
}

fn make_queries(kind: QueryKind, set: &str, scene: &Scene, n: usize) -> Result<Queries, String> {
    let b = scene.bounds();
    Ok(match set {
        "points" => Queries::points(uniform_points(b.low, b.high, n, 1)),
        "primary" => Queries::rays(
            kind,
            primary_rays_n(b, n as u64, 1).ok_or("no rays for that many queries")?,
        ),
        _ => Queries::rays(kind, secondary_rays(b, n, 1)),
    })
}

/// The library layouts with an entry of `kind` over their type, by command-line name.
fn layouts_of(kind: QueryKind, names: &[String]) -> Vec<String> {
    names
        .iter()
        .filter(|n| resolve_kind(n, None, kind).is_ok())
        .cloned()
        .collect()
}

/// Runs `scion explore`.
pub fn run(args: &ExploreArgs) -> Result<(), CliError> {
    let kinds: Vec<QueryKind> = args
        .kinds
        .iter()
        .map(|k| {
            QueryKind::BATCHED
                .into_iter()
                .find(|q| q.name() == k)
                .ok_or_else(|| {
                    CliError::usage(format!(
                        "--kinds: `{k}` is not a batched query kind (closest-hit, any-hit, closest-point)"
                    ))
                })
        })
        .collect::<Result<_, _>>()?;
    // The sweep's scenes are triangle meshes: the layouts over triangles.
    let primitive = |name: &str| library::resolve(name, None).map(|r| r.primitive).ok();
    let over_triangles = |name: &str| primitive(name).is_none_or(|p| p == "Triangle");
    let all_layouts: Vec<String> = library::layout_names();
    let layout_names: Vec<String> = match &args.layouts {
        Some(l) => {
            for name in l {
                if !all_layouts.contains(name) && !name.ends_with(".scion") {
                    return Err(CliError::usage(format!(
                        "--layouts: unknown layout `{name}`: the library's are {}",
                        all_layouts.join(", ")
                    )));
                }
                if all_layouts.contains(name) && !over_triangles(name) {
                    let p = primitive(name).unwrap_or_default();
                    let e = CliError::usage(format!(
                        "--layouts: `{name}`'s leaves hold `{p}`s, and the sweep measures layouts \
                         over triangles"
                    ));
                    return Err(match p == crate::trace_blocks::PRIMITIVE {
                        true => e.note(format!(
                            "`scion trace --backend llvm --layout {name} --scene S` measures it"
                        )),
                        false => {
                            e.note("`scion strands trace --scene F.hair` traces strand scenes")
                        }
                    });
                }
            }
            l.clone()
        }
        None => all_layouts
            .into_iter()
            .filter(|n| over_triangles(n))
            .collect(),
    };
    let scenes: Vec<String> = match &args.scenes {
        Some(s) => s.clone(),
        None => scion_runtime::scene::manifest::REAL_SCENES
            .iter()
            .map(|s| s.name.to_string())
            .collect(),
    };
    let existing = read_rows(&args.output)?;
    let done: BTreeSet<Vec<String>> = existing.iter().flatten().map(key).collect();
    let threads = args.threads.to_string();
    let builder = args.builder.describe(args.leaf_size);

    let all_targets = targets(args);
    if args.devices.contains(&ExploreDevice::Gpu) {
        // Fail now rather than on every measurement.
        crate::gpu::open_device(0)?;
    }
    // The plan, in the order it runs (scene by scene, so each tree is built once).
    let mut jobs = Vec::new();
    let mut layouts_by_kind = BTreeMap::new();
    for kind in &kinds {
        layouts_by_kind.insert(kind.name(), layouts_of(*kind, &layout_names));
    }
    for scene in &scenes {
        for kind in &kinds {
            for set in query_sets(*kind, &args.rays) {
                for &n in &args.sizes {
                    for &target in &all_targets {
                        for layout in &layouts_by_kind[kind.name()] {
                            let job = Job {
                                scene: scene.clone(),
                                kind: *kind,
                                queries: set,
                                n,
                                target,
                                layout: layout.clone(),
                            };
                            let k = vec![
                                job.scene.clone(),
                                kind.name().to_string(),
                                set.to_string(),
                                n.to_string(),
                                target.name().to_string(),
                                threads.clone(),
                                builder.clone(),
                                layout.clone(),
                            ];
                            if !done.contains(&k) {
                                jobs.push(job);
                            }
                        }
                    }
                }
            }
        }
    }
    let total = jobs.len();
    outln!(
        "explore      {total} measurements to make ({} already in {})",
        done.len(),
        args.output.display()
    );
    let failed = if total > 0 {
        sweep(args, jobs, existing.is_none(), &threads, &builder)?
    } else {
        0
    };
    if let Some(dir) = &args.plots {
        let rows = read_rows(&args.output)?.unwrap_or_default();
        let peers = match &args.peers {
            Some(path) => {
                read_csv(path, &crate::plot::PEER_FIELDS, "a peers file")?.ok_or_else(|| {
                    CliError::usage(format!("--peers: there is no file {}", path.display()))
                })?
            }
            None => Vec::new(),
        };
        let written = crate::plot::write_all(&rows, &peers, dir)?;
        outln!("plots        {} files in {}", written, dir.display());
    }
    if failed > 0 {
        return Err(CliError::new(format!(
            "{failed} measurements failed (the warnings above say why); a rerun tries them again"
        )));
    }
    Ok(())
}

fn sweep(
    args: &ExploreArgs,
    jobs: Vec<Job>,
    new_file: bool,
    threads: &str,
    builder: &str,
) -> Result<usize, CliError> {
    let prov = provenance();
    let open = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&args.output);
    let mut out =
        open.map_err(|e| CliError::new(format!("cannot write {}: {e}", args.output.display())))?;
    let write_err =
        |e: std::io::Error| CliError::new(format!("cannot write {}: {e}", args.output.display()));
    if new_file {
        writeln!(out, "{}", ROW_FIELDS.join(",")).map_err(write_err)?;
    }
    let bar = indicatif::ProgressBar::new(jobs.len() as u64);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "scion: {bar:40} {pos}/{len} measurements ({elapsed} elapsed, about {eta} left) {msg}",
    ) {
        bar.set_style(style);
    }
    let driver = BatchDriver::new(args.threads).map_err(CliError::new)?;
    let mut compiled: BTreeMap<(String, &'static str, &'static str), (Entries, Resolved)> =
        BTreeMap::new();
    let mut scene_cache: Option<(String, Scene, LogicalTree)> = None;
    let mut queries_cache: Option<(QueryKey, Queries)> = None;
    let mut measured = 0usize;
    // The layouts of one context (scene, kind, queries, size, backend) are timed together, round
    // by round as the paper's method does for contenders (one warm-up round, then `runs`
    // rounds, each timing every layout once), so drifts of this shared machine fall on all of
    // them alike; then each gets its CSV fields (an error skips a layout, with a warning).
    let mut measure_group = |group: &[Job]| -> Vec<Result<Vec<String>, CliError>> {
        let job0 = &group[0];
        if scene_cache.as_ref().is_none_or(|c| c.0 != job0.scene) {
            let loaded = scion_runtime::scene::manifest::resolve(Path::new(&job0.scene))
                .map_err(|e| format!("--scenes {}: {e}", job0.scene))
                .and_then(|path| {
                    load_obj(&path).map_err(|e| format!("cannot load {}: {e}", job0.scene))
                });
            match loaded {
                Ok(scene) => {
                    let tree = build_with(&scene, args.builder, args.leaf_size);
                    scene_cache = Some((job0.scene.clone(), scene, tree));
                }
                Err(e) => {
                    return group
                        .iter()
                        .map(|_| Err(CliError::new(e.clone())))
                        .collect()
                }
            }
        }
        let (_, scene, tree) = scene_cache.as_ref().expect("loaded above");
        let qkey = (job0.scene.clone(), job0.kind.name(), job0.queries, job0.n);
        if queries_cache.as_ref().is_none_or(|c| c.0 != qkey) {
            match make_queries(job0.kind, job0.queries, scene, job0.n) {
                Ok(q) => queries_cache = Some((qkey, q)),
                Err(e) => {
                    return group
                        .iter()
                        .map(|_| Err(CliError::new(e.clone())))
                        .collect()
                }
            }
        }
        let (_, queries) = queries_cache.as_ref().expect("made above");
        let init = queries.initial_results();
        let points_want = std::cell::OnceCell::new();
        // A measured layout's row: its answers checked, its error measured when quantized.
        let finish = |job: &Job,
                      resolved: &Resolved,
                      bytes: u64,
                      results: &[u8],
                      timing: scion_runtime::timing::Timing|
         -> Vec<String> {
            // Hits against the reference of the tree the layout traverses (binary or wide,
            // decoded boxes; scion_host::hit_reference), closest points against brute force.
            let traversed = Traversed::of(resolved, tree);
            let checked = if job.kind == QueryKind::ClosestPoint {
                // Brute force's answers, computed once for every layout of the context.
                let want = points_want.get_or_init(|| {
                    queries.expected(&scene.triangles, traversed, CHECKED_POINTS, &driver)
                });
                want.as_ref()
                    .map_err(Clone::clone)
                    .and_then(|w| queries.compare(w, results, &scene.triangles))
            } else {
                queries.check(
                    &scene.triangles,
                    traversed,
                    results,
                    CHECKED_POINTS,
                    &driver,
                )
            };
            let check = match checked {
                Ok(_) => "identical".to_string(),
                Err(e) => {
                    say(
                        &bar,
                        format!(
                            "scion: warning: {} {} {} {} {}: {e}",
                            job.scene,
                            job.kind.name(),
                            job.queries,
                            job.target.name(),
                            job.layout
                        ),
                    );
                    "differs".to_string()
                }
            };
            let err = match job.kind {
                QueryKind::ClosestPoint => None,
                _ => crate::quant_error::measure(resolved.boxes, tree, &queries.rays, &driver),
            };
            let n = queries.len();
            let f = |x: f64| format!("{x:.6}");
            vec![
                prov.commit.clone(),
                prov.machine.clone(),
                prov.cpus.clone(),
                prov.toolchain.clone(),
                now_utc(),
                job.scene.clone(),
                scene.len().to_string(),
                job.kind.name().to_string(),
                job.queries.to_string(),
                job.n.to_string(),
                job.target.name().to_string(),
                threads.to_string(),
                builder.to_string(),
                job.layout.clone(),
                bytes.to_string(),
                f(bytes as f64 / scene.len().max(1) as f64),
                format!("{:.9}", timing.mean.as_secs_f64()),
                f(timing.ns_per_query(n)),
                f(timing.queries_per_second(n) / 1e6),
                check,
                err.as_ref().map_or(String::new(), |e| f(e.inflation.area)),
                err.as_ref().map_or(String::new(), |e| f(e.extra()[0])),
                err.as_ref().map_or(String::new(), |e| f(e.extra()[1])),
                args.runs.to_string(),
            ]
        };
        let backend = match job0.target {
            Target::Cpu(b) => b,
            // On a GPU each layout runs alone (its kernels timed by the device: CUDA events, or
            // the emulated launch's wall clock), one warm-up and `--runs` runs, as `scion run
            // --device` does.
            Target::Gpu { emulated } => {
                let options = crate::run_gpu::GpuOptions {
                    device: if emulated {
                        DeviceArg::GpuEmulated
                    } else {
                        DeviceArg::Gpu
                    },
                    threads: args.threads,
                    runs: args.runs,
                    quiet: true,
                };
                return group
                    .iter()
                    .map(|job| {
                        let resolved =
                            resolve_kind(&job.layout, None, job.kind).map_err(CliError::new)?;
                        let g = crate::run_gpu::run(
                            &options,
                            &resolved,
                            args.stack_size,
                            tree,
                            (&queries.bytes, &init),
                            queries.record_sizes(),
                        )?;
                        Ok(finish(job, &resolved, g.bytes, &g.results, g.timing))
                    })
                    .collect();
            }
        };
        let ckey = |job: &Job| (job.layout.clone(), job.kind.name(), job.target.name());
        let mut compile_errors: BTreeMap<String, String> = BTreeMap::new();
        for job in group {
            if compiled.contains_key(&ckey(job)) {
                continue;
            }
            let made = resolve_kind(&job.layout, None, job.kind).and_then(|resolved| {
                let codegen = match backend {
                    RunBackend::Jit => Codegen::Cranelift,
                    RunBackend::Llvm => Codegen::Llvm(3),
                };
                Entries::compile(&resolved.program, codegen, args.stack_size)
                    .map(|entries| (entries, resolved))
                    .map_err(|e| format!("cannot compile for {}: {e}", job.layout))
            });
            match made {
                Ok(m) => {
                    compiled.insert(ckey(job), m);
                }
                Err(e) => {
                    compile_errors.insert(job.layout.clone(), e);
                }
            }
        }
        // Pack every layout of the context.
        let mut ready = Vec::new();
        let mut out: Vec<Result<Vec<String>, CliError>> = Vec::new();
        for job in group {
            if let Some(e) = compile_errors.get(&job.layout) {
                ready.push(None);
                out.push(Err(CliError::new(e.clone())));
                continue;
            }
            let (entries, resolved) = &compiled[&ckey(job)];
            match entries.pack(tree) {
                Ok(packed) => {
                    ready.push(Some((entries, resolved, packed, init.clone(), Vec::new())));
                    out.push(Ok(Vec::new()));
                }
                Err(e) => {
                    ready.push(None);
                    out.push(Err(CliError::new(e)));
                }
            }
        }
        // The rounds: a warm-up, then the timed ones.
        let runs = args.runs as usize;
        let rounds = if runs > 1 { 1 + runs } else { 1 };
        for round in 0..rounds {
            for (k, slot) in ready.iter_mut().enumerate() {
                let Some((entries, _, packed, results, times)) = slot else {
                    continue;
                };
                results.copy_from_slice(&init);
                let t = std::time::Instant::now();
                let ran = entries.run(packed, &queries.bytes, results, &driver);
                let took = t.elapsed();
                if let Err(e) = ran {
                    out[k] = Err(CliError::new(format!(
                        "{} on {}: {e}",
                        group[k].layout, group[k].scene
                    )));
                    *slot = None;
                    continue;
                }
                if round > 0 || rounds == 1 {
                    times.push(took);
                }
            }
        }
        for (k, slot) in ready.into_iter().enumerate() {
            let Some((_, resolved, packed, results, times)) = slot else {
                continue;
            };
            let drop = (runs.saturating_sub(1)) / 4;
            let mean = scion_runtime::timing::trimmed_mean(&times, drop, drop);
            let timing = scion_runtime::timing::Timing { raw: times, mean };
            let bytes = packed.bytes() as u64;
            out[k] = Ok(finish(&group[k], resolved, bytes, &results, timing));
        }
        out
    };
    let mut failed = 0usize;
    let context = |j: &Job| {
        (
            j.scene.clone(),
            j.kind.name(),
            j.queries,
            j.n,
            j.target.name(),
        )
    };
    let mut start = 0;
    while start < jobs.len() {
        let mut end = start + 1;
        while end < jobs.len() && context(&jobs[end]) == context(&jobs[start]) {
            end += 1;
        }
        let group = &jobs[start..end];
        bar.set_message(format!(
            "{} {} {}",
            group[0].scene,
            group[0].kind.name(),
            group[0].queries
        ));
        for (job, row) in group.iter().zip(measure_group(group)) {
            match row {
                Ok(row) => {
                    let line: Vec<String> = row.iter().map(|c| csv_field(c)).collect();
                    writeln!(out, "{}", line.join(",")).map_err(write_err)?;
                    out.flush().map_err(write_err)?;
                    measured += 1;
                }
                Err(e) => {
                    say(
                        &bar,
                        format!(
                            "scion: warning: {} {} {} {}: not measured: {}",
                            job.scene,
                            job.kind.name(),
                            job.queries,
                            job.layout,
                            e.message
                        ),
                    );
                    failed += 1;
                }
            }
            bar.inc(1);
        }
        start = end;
    }
    bar.finish_and_clear();
    outln!(
        "results      {measured} rows appended to {}",
        args.output.display()
    );
    Ok(failed)
}

/// A warning above the bar, or on standard error when the bar is hidden (not a terminal).
fn say(bar: &indicatif::ProgressBar, line: String) {
    if bar.is_hidden() {
        eprintln!("{line}");
    } else {
        bar.println(line);
    }
}
