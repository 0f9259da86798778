//! `scion trace --device gpu` and `scion ptx`: closest hit specialized to a library layout,
//! compiled in-process to PTX (front end with the layout and `--entry closest_hit` for
//! `nvptx64`, then `scion-llvm` at `-O3`, `sm_90` by default) and run on an NVIDIA GPU through
//! `scion-cuda` (docs/gpu.md): the tree is packed on the device by the generated kernels, the
//! rays traced with one thread per ray, and every hit compared bit for bit with the runtime's
//! reference traversal of the same logical tree (for a quantized layout such as `pbrt-q16`,
//! with the boxes it decodes, which the kit names: `PtxKit::reference_tree`). Input: the trace arguments; output: the
//! report of `scion trace` with the kernel's Mrays/s and a `check` line, or the PTX kit
//! (`scion_cuda::kit`) that `scion-gpu` runs on machines without LLVM.

use crate::io::outln;
use crate::trace::{build, closest_hit_layout_names, progress, rays, secs, significant};
use crate::{BackendArg, CliError, DeviceArg, PtxArgs, TraceArgs};
use scion_compiler::abi::EntryTarget;
use scion_cuda::kit::PtxKit;
use scion_cuda::trace::GpuPipeline;
use scion_cuda::{Device, Launcher};
use scion_host::gpu_emu::EmulatedGpu;
use scion_host::hit_reference::{check_hits, Traversed};
use scion_host::jit::{program_lo, Codegen, LoOptions, ALGORITHM};
use scion_host::mem_interp::Program;
use scion_host::quantized::Boxes;
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::Ray;
use scion_runtime::scene::{load_obj, Scene};
use scion_runtime::timing::trimmed_mean;
use scion_runtime::triangle4::{block_tree, Triangle4};
use std::path::Path;
use std::time::{Duration, Instant};

/// The `-O` level of the tree/mem passes and of LLVM for PTX.
const OPT_LEVEL: u8 = 3;

/// Compiles closest hit for the library layout `layout` (a `--layout` name) to a PTX kit for
/// `cpu` (`sm_XX`; `None`: scion-llvm's default, sm_90).
pub fn compile_kit(
    layout: &str,
    stack_size: Option<u32>,
    cpu: Option<&str>,
) -> Result<(PtxKit, Duration), CliError> {
    let (program, boxes, _) = gpu_program(layout, Target::Kit)?;
    let (kit, _, time) = compile_program_kit(&program, boxes, stack_size, cpu)?;
    Ok((kit, time))
}

/// Compiles any program (a layout and an algorithm over one tree) to a PTX kit for `cpu`, with
/// the entries' C signature (its record sizes).
pub fn compile_program_kit(
    program: &Program,
    boxes: Boxes,
    stack_size: Option<u32>,
    cpu: Option<&str>,
) -> Result<(PtxKit, scion_compiler::abi::EntrySig, Duration), CliError> {
    let start = Instant::now();
    let name = program.layout.as_str();
    let fail = |what: &str, detail: String| {
        CliError::new(format!(
            "cannot compile {} for `{name}` ({what}): {detail}",
            program.algorithm
        ))
    };
    let lo = program_lo(
        program,
        &LoOptions {
            stack_size,
            opt_level: OPT_LEVEL,
            dsl_opt: true,
            target: EntryTarget::Gpu,
        },
    )
    .map_err(|e| fail("front end", e))?;
    let m = lo.module;
    let buffers: Vec<String> = lo.entry.buffers.iter().map(|b| b.name.clone()).collect();
    let logical = lo.entry.logical.clone();
    let opts = scion_llvm::Options {
        target: scion_llvm::Target::Nvptx64,
        cpu: cpu.map(String::from),
        opt_level: OPT_LEVEL,
    };
    let ptx = scion_llvm::emit(&m, &opts, scion_llvm::Output::Asm)
        .map_err(|e| fail("LLVM", e.to_string()))?;
    let ptx = String::from_utf8(ptx).map_err(|_| fail("LLVM", "PTX is not UTF-8".into()))?;
    Ok((
        PtxKit::new(name, &program.algorithm, buffers, boxes, logical, &ptx),
        lo.entry,
        start.elapsed(),
    ))
}

/// `scion ptx`: writes the PTX kit of `--layout`.
pub fn run_ptx(args: &PtxArgs) -> Result<(), CliError> {
    progress(&format!(
        "compiling closest hit for layout `{}` to PTX",
        args.layout
    ));
    let (kit, time) = compile_kit(&args.layout, args.stack_size, args.cpu.as_deref())?;
    write_kit(&kit, &args.output)?;
    eprintln!("scion: compiled in {:.3} s", time.as_secs_f64());
    Ok(())
}

pub(crate) fn write_kit(kit: &PtxKit, path: &Path) -> Result<(), CliError> {
    crate::io::write_whole(path, kit.ptx.as_bytes())
        .map_err(|e| CliError::new(format!("cannot write {}: {e}", path.display())))?;
    outln!(
        "ptx          {} ({} bytes, {} {}, buffers {})",
        path.display(),
        kit.ptx.len(),
        kit.algorithm,
        kit.layout,
        kit.buffers.join(", ")
    );
    Ok(())
}

/// `scion trace --device gpu|gpu-emulated`.
pub fn run_trace(args: &TraceArgs) -> Result<(), CliError> {
    if args.device == DeviceArg::GpuEmulated {
        return run_emulated(args);
    }
    // The device first: without one there is nothing to compile for.
    let device = open_device(args.gpu)?;
    let layout = args.layout.as_deref().unwrap_or("pbrt");
    if args.backend != BackendArg::Reference {
        eprintln!(
            "scion: note: --backend is not used with --device gpu (the GPU runs closest hit \
             for --layout, checked against the reference)"
        );
    }
    if args.ptx.is_some() && args.layout.is_some() {
        eprintln!("scion: note: --layout is not used with --ptx (the kit names its layout)");
    }
    let (kit, compile_time, blocks) = match &args.ptx {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| CliError::new(format!("cannot read {}: {e}", path.display())))?;
            let kit = PtxKit::parse(&text)
                .map_err(|e| CliError::new(format!("{}: {e}", path.display())))?;
            (kit, None, false)
        }
        None => {
            progress(&format!(
                "compiling closest hit for layout `{layout}` to PTX"
            ));
            // Without --cpu, the device's own architecture when LLVM knows it.
            let own = own_cpu(&device);
            let cpu = args.cpu.as_deref().or(own.as_deref());
            // A kit written out (--emit-ptx) is for scion-gpu, whose check is the binary
            // reference's; without one, any closest hit over triangles.
            let target = match args.emit_ptx {
                Some(_) => Target::Kit,
                None => Target::Run,
            };
            let (program, boxes, blocks) = gpu_program(layout, target)?;
            let (kit, _, t) = compile_program_kit(&program, boxes, args.stack_size, cpu)?;
            (kit, Some(t), blocks)
        }
    };
    if let Some(path) = &args.emit_ptx {
        write_kit(&kit, path)?;
    }
    let input = load(args, blocks)?;

    progress(&format!("loading the PTX on {}", device.name));
    let t = Instant::now();
    let pipeline = GpuPipeline::new(
        &device,
        &kit.ptx,
        &kit.layout,
        &kit.algorithm,
        kit.buffers.clone(),
        kit.logical.clone(),
    )
    .map_err(gpu_err)?;
    let module_time = t.elapsed();
    let target = scion_cuda::ptx::directive(&kit.ptx, ".target").unwrap_or("?");
    let report = Report {
        device: format!(
            "{} (sm_{}{}, driver CUDA {})",
            device.name,
            device.compute_capability.0,
            device.compute_capability.1,
            scion_cuda::error::version_text(device.driver.version)
        ),
        compile: match compile_time {
            Some(t) => format!("{} (front end + LLVM -O3 to PTX for {target})", secs(t)),
            None => format!("none (PTX kit for {target} read from a file)"),
        },
        load: Some(format!("{} (PTX JIT by the driver)", secs(module_time))),
        place: "on the GPU",
        timing: "batch kernel, CUDA events",
        backend: format!("gpu ({} {})", kit.algorithm, kit.layout),
        layout: kit.layout.clone(),
        boxes: kit.boxes,
        arity: kit.logical.arity,
        buffers: kit.buffers.clone(),
    };
    trace_and_report(&pipeline, args, &input, &report)
}

/// Opens GPU `ordinal`, or says why not and what to do instead.
pub(crate) fn open_device(ordinal: i32) -> Result<Device, CliError> {
    Device::open(ordinal).map_err(|e| {
        CliError::new(e.to_string())
            .note("--device gpu needs an NVIDIA GPU and its driver")
            .note("--device gpu-emulated runs the same kernels on this CPU")
    })
}

/// The device's own architecture (`sm_90`) when LLVM knows it.
pub(crate) fn own_cpu(device: &Device) -> Option<String> {
    let (major, minor) = device.compute_capability;
    let own = format!("sm_{major}{minor}");
    scion_llvm::target::cpus::NVPTX64_CPUS
        .contains(&own.as_str())
        .then_some(own)
}

/// `scion trace --device gpu-emulated`: the kernels of `--device gpu` compiled for this CPU
/// (`scion_host::gpu_emu`), packed and traced by the same pipeline.
fn run_emulated(args: &TraceArgs) -> Result<(), CliError> {
    for (flag, given) in [
        ("--ptx", args.ptx.is_some()),
        ("--emit-ptx", args.emit_ptx.is_some()),
        ("--cpu", args.cpu.is_some()),
        ("--gpu", args.gpu != 0),
    ] {
        if given {
            eprintln!("scion: note: {flag} is not used with --device gpu-emulated");
        }
    }
    if args.backend != BackendArg::Reference {
        eprintln!(
            "scion: note: --backend is not used with --device gpu-emulated (the GPU kernels \
             of --layout run on the CPU, checked against the reference)"
        );
    }
    let layout = args.layout.as_deref().unwrap_or("pbrt");
    let (program, boxes, blocks) = gpu_program(layout, Target::Run)?;
    let name = program.layout.clone();
    progress(&format!(
        "compiling the GPU kernels of closest hit for layout `{layout}` for this CPU"
    ));
    let gpu = EmulatedGpu::compile_program(
        &program,
        &LoOptions {
            stack_size: args.stack_size,
            opt_level: OPT_LEVEL,
            dsl_opt: true,
            target: EntryTarget::Gpu,
        },
        Codegen::Llvm(OPT_LEVEL),
        args.threads,
    )
    .map_err(|e| {
        CliError::new(format!(
            "cannot compile the GPU kernels of closest hit for `{layout}`: {e}"
        ))
    })?;
    let compile_time = gpu.compile_time;
    let arity = gpu.entry().map_or(2, |e| e.logical.arity);
    let buffers = gpu.buffers().to_vec();
    let input = load(args, blocks)?;
    let pipeline = gpu.into_pipeline().map_err(CliError::new)?;
    let workers = if args.threads == 0 {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    } else {
        args.threads
    };
    let report = Report {
        device: format!(
            "emulated on the CPU ({workers} host thread{}, one kernel call per GPU thread)",
            if workers == 1 { "" } else { "s" }
        ),
        compile: format!(
            "{} (front end, lo-host-kernels, LLVM -O3 for this CPU)",
            secs(compile_time)
        ),
        load: None,
        place: "on the emulated GPU",
        timing: "batch kernel on host threads, wall clock",
        backend: format!("gpu-emulated ({} {name})", program.algorithm),
        layout: name.to_string(),
        boxes,
        arity,
        buffers,
    };
    trace_and_report(&pipeline, args, &input, &report)
}

/// What a GPU program is compiled for.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Target {
    /// A PTX kit (`scion ptx`, `--emit-ptx`): `scion-gpu` checks its hits against the binary
    /// reference, so kits hold the binary `closest_hit`.
    Kit,
    /// A trace in this process, checked against the reference of the tree the layout
    /// traverses (`scion_host::hit_reference`): any library closest hit over triangles.
    Run,
}

/// The closest-hit program of the layout `--layout` names (a library name or a layout file,
/// `scion_host::library::resolve`), how it stores boxes, and whether its leaves hold blocks of
/// four triangles (`Triangle4`, traced over the block tree as on the CPU): the GPU kernels are
/// closest hit's.
fn gpu_program(layout: &str, target: Target) -> Result<(Program, Boxes, bool), CliError> {
    let unknown = |why: String| {
        let e = CliError::usage(format!("unknown layout `{layout}` for the GPU: {why}"));
        match target {
            Target::Kit => e.note(format!(
                "layouts a kit holds: {}",
                closest_hit_layout_names()
            )),
            Target::Run => e.note("`scion layouts --primitive Triangle` lists the layouts it runs"),
        }
    };
    let r = scion_host::library::resolve(layout, None).map_err(unknown)?;
    if target == Target::Kit && r.program.algorithm != ALGORITHM {
        return Err(unknown(format!(
            "it is traversed by `{}`, and a PTX kit holds `{ALGORITHM}` (scion-gpu checks it \
             against the binary reference)",
            r.program.algorithm
        ))
        .note(format!(
            "`scion trace --device gpu --layout {layout}` without --emit-ptx runs it"
        )));
    }
    let blocks = r.primitive == crate::trace_blocks::PRIMITIVE;
    if r.primitive != "Triangle" && !blocks {
        return Err(unknown(format!(
            "its leaves hold `{}`s, and the GPU path traces triangle meshes",
            r.primitive
        )));
    }
    Ok((r.program, r.boxes, blocks))
}

pub(crate) fn gpu_err(e: scion_cuda::CudaError) -> CliError {
    CliError::new(format!("GPU: {e}"))
}

/// The scene, its logical tree and the rays of a trace.
struct Input {
    scene: Scene,
    tree: LogicalTree,
    /// The tree over blocks of four triangles a `Triangle4` layout packs (crate::trace_blocks).
    blocks: Option<LogicalTree<Triangle4>>,
    rays: Vec<Ray>,
}

fn load(args: &TraceArgs, blocks: bool) -> Result<Input, CliError> {
    progress(&format!("loading {}", args.scene.display()));
    let scene =
        load_obj(&args.scene).map_err(|e| CliError::new(format!("cannot load the scene: {e}")))?;
    let (tree, blocks) = match blocks {
        true => {
            let tree = crate::trace_blocks::build(&scene, args);
            let blocks =
                block_tree(&tree).map_err(|e| CliError::new(format!("the block tree: {e}")))?;
            (tree, Some(blocks))
        }
        false => (build(&scene, args), None),
    };
    let rays = rays(&scene, args)?;
    Ok(Input {
        scene,
        tree,
        blocks,
        rays,
    })
}

/// What the report says about where the kernels ran.
struct Report {
    device: String,
    compile: String,
    load: Option<String>,
    place: &'static str,
    timing: &'static str,
    backend: String,
    layout: String,
    boxes: Boxes,
    /// Children per node of the tree the kernels traverse (which reference checks them).
    arity: u32,
    buffers: Vec<String>,
}

/// Packs, traces `args.runs` times after a warm-up, checks every hit against the reference of
/// the boxes the layout traverses, and prints the report of `scion trace`.
fn trace_and_report<L: Launcher>(
    pipeline: &GpuPipeline<L>,
    args: &TraceArgs,
    input: &Input,
    r: &Report,
) -> Result<(), CliError> {
    let Input {
        scene,
        tree,
        blocks,
        rays,
    } = input;
    let stats = tree.stats();
    progress(&format!(
        "packing the tree into layout `{}` {}",
        r.layout, r.place
    ));
    let packed = match blocks {
        Some(b) => pipeline.pack(b, stats.depth),
        None => pipeline.pack(tree, stats.depth),
    }
    .map_err(gpu_err)?;
    let on_device = pipeline.upload_rays(rays).map_err(gpu_err)?;
    progress(&format!("tracing {} rays {}", rays.len(), r.place));
    let runs = args.runs as usize;
    let (hits, times) = pipeline
        .trace_runs(&packed, &on_device, runs)
        .map_err(|e| {
            gpu_err(e).note(
                "trees deeper than the generated traversal's stack cannot be traced with this \
                 layout; try a larger --stack-size",
            )
        })?;
    progress("tracing the same rays with the reference for the check");
    let driver = BatchDriver::new(args.threads).map_err(CliError::new)?;
    // The reference of the tree the kernels traverse: its decoded boxes when quantized, the
    // tree collapsed to the layout's children per node when wide (scion_host::hit_reference).
    // Blocks: the eight-wide reference over the same blocks (as on the CPU).
    let traversed = Traversed {
        tree,
        boxes: r.boxes,
        arity: r.arity,
    };
    let (reference, which) = match blocks {
        Some(b) => (
            crate::trace_blocks::reference(b, rays),
            "eight-wide reference over the same blocks",
        ),
        None => (
            traversed.hits(rays, &driver).map_err(CliError::new)?,
            traversed.name(),
        ),
    };
    let check = check_hits(&hits, &reference, rays, &scene.triangles, which, "ray");

    let drop = (runs - 1) / 4;
    let kernel = trimmed_mean(&times, drop, drop);
    let bytes: u64 = packed.sizes.iter().sum();
    let parts: Vec<String> = r
        .buffers
        .iter()
        .zip(&packed.sizes)
        .map(|(n, s)| format!("{n} {s} B"))
        .collect();
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
    outln!("device       {}", r.device);
    outln!("compile time {}", r.compile);
    if let Some(load) = &r.load {
        outln!("module load  {load}");
    }
    outln!(
        "pack time    {} ({}: upload, sizes, allocation, build, root)",
        secs(packed.pack_time),
        r.place
    );
    outln!("layout       {}: {}", r.layout, parts.join(", "));
    outln!(
        "structure    {bytes} bytes, {:.1} bytes/node",
        bytes as f64 / stats.nodes.max(1) as f64
    );
    outln!("rays         {}", rays.len());
    outln!("backend      {}", r.backend);
    outln!(
        "trace time   {} ({}; mean of the middle {} of {} runs after 1 warm-up)",
        secs(kernel),
        r.timing,
        times.len() - 2 * drop,
        times.len()
    );
    let mrays = if kernel.is_zero() {
        0.0
    } else {
        rays.len() as f64 / kernel.as_secs_f64() / 1e6
    };
    outln!("throughput   {} Mrays/s", significant(mrays));
    outln!(
        "hits         {} of {} rays",
        hits.iter().filter(|h| h.is_hit()).count(),
        rays.len()
    );
    // The same number as `scion trace` on the CPU and the C library print.
    outln!(
        "checksum: {:016x}",
        scion_runtime::query::hits_checksum(&hits)
    );
    let verdict = check.as_ref().map(|a| a.describe(which, "rays"));
    match &verdict {
        Ok(v) => outln!("check        {v}"),
        Err(e) => outln!("check        not identical: {e}"),
    }
    if let Some(path) = &args.output {
        scion_runtime::query::write_hits(path, &hits)
            .map_err(|e| CliError::new(format!("cannot write the hits: {e}")))?;
        outln!("output       {} ({} bytes)", path.display(), hits.len() * 8);
    }
    if let Err(e) = verdict {
        return Err(CliError::new(format!(
            "{} hits differ from the {}: {e}",
            if r.place == "on the GPU" {
                "GPU"
            } else {
                "emulated GPU"
            },
            which
        )));
    }
    Ok(())
}
