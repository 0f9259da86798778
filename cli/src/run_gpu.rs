//! `scion run --device gpu|gpu-emulated`: any algorithm over one tree (closest hit, any hit,
//! closest point) with the GPU entries: compiled to PTX and run through CUDA on an NVIDIA GPU,
//! or its kernels compiled for this CPU and launched as grids of host threads
//! (`scion_host::gpu_emu`). The tree is packed on the device by the generated kernels, the
//! query records uploaded once, and the batch kernel (one thread per query) run once to warm up
//! and `--runs` more times, timed by the kernel (CUDA events, or the wall clock of the emulated
//! launch). The caller checks the answers as on the CPU.

use crate::gpu::{compile_program_kit, gpu_err, open_device, own_cpu};
use crate::trace::progress;
use crate::{CliError, DeviceArg};
use scion_compiler::abi::{EntrySig, EntryTarget};
use scion_cuda::trace::GpuPipeline;
use scion_cuda::Launcher;
use scion_host::gpu_emu::EmulatedGpu;
use scion_host::jit::{Codegen, LoOptions};
use scion_host::library::Resolved;
use scion_runtime::bvh::LogicalTree;
use scion_runtime::timing::{trimmed_mean, Timing};
use std::time::Duration;

/// What a run on a (real or emulated) GPU gives back.
pub struct GpuRun {
    /// The result records, in query order.
    pub results: Vec<u8>,
    /// The batch kernel's times: the paper's trimmed mean of `--runs` runs after the warm-up.
    pub timing: Timing,
    /// Packing on the device.
    pub pack_time: Duration,
    /// Bytes of the packed buffers.
    pub bytes: u64,
    /// Front end and code generation.
    pub compile_time: Duration,
    /// Where it ran, for the report.
    pub device: String,
}

/// Where and how often a GPU run goes (`scion run`'s and `scion explore`'s flags).
#[derive(Clone, Copy, Debug)]
pub struct GpuOptions {
    /// A real or an emulated GPU (not the CPU).
    pub device: DeviceArg,
    /// Host threads of the emulated GPU's grid.
    pub threads: usize,
    /// Timed runs after the warm-up (the paper's method: 9).
    pub runs: u32,
    /// No progress lines (a caller with its own progress bar).
    pub quiet: bool,
}

fn step(args: &GpuOptions, what: &str) {
    if !args.quiet {
        progress(what);
    }
}

/// Compiles `resolved`'s program for the device `args.device` names and runs `queries` (records
/// of the algorithm's query size) from the result records `initial` over `tree`; `expected`
/// are the query kind's record sizes, which the entry's must be.
pub fn run(
    args: &GpuOptions,
    resolved: &Resolved,
    stack_size: Option<u32>,
    tree: &LogicalTree,
    (queries, initial): (&[u8], &[u8]),
    expected: (u64, u64),
) -> Result<GpuRun, CliError> {
    let p = &resolved.program;
    let check = |sig: &EntrySig| -> Result<(usize, usize), CliError> {
        let (qs, rs) = (sig.query.size as usize, sig.result.size as usize);
        if sig.trees() != 1 || (qs, rs) != (expected.0 as usize, expected.1 as usize) {
            return Err(CliError::new(format!(
                "`{}`'s records are {qs} and {rs} bytes over {} trees, not those of the query \
                 kind ({} and {} bytes over one tree)",
                p.algorithm,
                sig.trees(),
                expected.0,
                expected.1
            )));
        }
        Ok((qs, rs))
    };
    match args.device {
        DeviceArg::Cpu => unreachable!("the CPU path is `scion run`'s own"),
        DeviceArg::GpuEmulated => {
            step(
                args,
                &format!(
                    "compiling the GPU kernels of {} for layout `{}` for this CPU",
                    p.algorithm, p.layout
                ),
            );
            let gpu = EmulatedGpu::compile_program(
                p,
                &LoOptions {
                    stack_size,
                    opt_level: 3,
                    dsl_opt: true,
                    target: EntryTarget::Gpu,
                },
                Codegen::Llvm(3),
                args.threads,
            )
            .map_err(|e| {
                CliError::new(format!(
                    "cannot compile the GPU kernels of {}: {e}",
                    p.algorithm
                ))
            })?;
            let sizes = check(gpu.entry().expect("compiled from a program"))?;
            let compile_time = gpu.compile_time;
            let pipeline = gpu.into_pipeline().map_err(CliError::new)?;
            let device = "emulated on the CPU (kernels compiled for this CPU by LLVM -O3, one \
                          call per GPU thread on host threads)"
                .to_string();
            launch(
                &pipeline,
                args,
                tree,
                queries,
                initial,
                sizes,
                compile_time,
                device,
            )
        }
        DeviceArg::Gpu => {
            let device = open_device(0)?;
            step(
                args,
                &format!("compiling {} for layout `{}` to PTX", p.algorithm, p.layout),
            );
            let own = own_cpu(&device);
            let (kit, sig, compile_time) =
                compile_program_kit(p, resolved.boxes, stack_size, own.as_deref())?;
            let sizes = check(&sig)?;
            let pipeline = GpuPipeline::new(
                &device,
                &kit.ptx,
                &kit.layout,
                &kit.algorithm,
                kit.buffers.clone(),
                kit.logical.clone(),
            )
            .map_err(gpu_err)?;
            let (major, minor) = device.compute_capability;
            let name = format!("{} (sm_{major}{minor}, CUDA events)", device.name);
            launch(
                &pipeline,
                args,
                tree,
                queries,
                initial,
                sizes,
                compile_time,
                name,
            )
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn launch<L: Launcher>(
    pipeline: &GpuPipeline<L>,
    args: &GpuOptions,
    tree: &LogicalTree,
    queries: &[u8],
    initial: &[u8],
    (qs, rs): (usize, usize),
    compile_time: Duration,
    device: String,
) -> Result<GpuRun, CliError> {
    step(args, "packing the tree on the device");
    let packed = pipeline.pack(tree, tree.stats().depth).map_err(gpu_err)?;
    let on_device = pipeline.upload_queries(queries, qs, rs).map_err(gpu_err)?;
    step(
        args,
        &format!("running {} queries on the device", queries.len() / qs),
    );
    let stack_note = |e: scion_cuda::CudaError| {
        gpu_err(e).note(
            "a traversal deeper than its stack stops with status 1: try a larger --stack-size",
        )
    };
    // The first run is the warm-up (and the answers); with --runs 1 it is the one timed.
    let (results, first) = pipeline
        .run_queries(&packed, &on_device, initial)
        .map_err(stack_note)?;
    let mut raw = Vec::new();
    if args.runs > 1 {
        for _ in 0..args.runs {
            let (_, t) = pipeline
                .run_queries(&packed, &on_device, initial)
                .map_err(stack_note)?;
            raw.push(t);
        }
    } else {
        raw.push(first);
    }
    let drop = (args.runs.saturating_sub(1) / 4) as usize;
    let mean = trimmed_mean(&raw, drop, drop);
    Ok(GpuRun {
        results,
        timing: Timing { raw, mean },
        pack_time: packed.pack_time,
        bytes: packed.sizes.iter().sum(),
        compile_time,
        device,
    })
}
