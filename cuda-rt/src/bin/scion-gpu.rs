//! `scion-gpu`: runs a PTX kit (closest hit specialized to a layout, written by `scion trace
//! --device gpu --emit-ptx`) on a scene and compares every hit with the CPU reference. For
//! machines with a GPU but without the compiler's LLVM: it links only the runtime and the CUDA
//! driver (loaded at run time). Prints the same kind of report as `scion trace` and a final
//! `check` line; exit status 0 when the hits are identical, 1 on a difference or an error.
//!
//! `scion-gpu --info` opens the device and describes it (or says why it cannot).
//!
//! ```text
//! scion-gpu --info [--device 0]
//! scion-gpu --ptx pbrt.ptx --scene scenes/bunny.obj.gz [--rays primary|secondary]
//!           [--n 65536] [--seed 1] [--runs 9] [--device 0]
//! ```

use scion_cuda::compare::Comparison;
use scion_cuda::kit::PtxKit;
use scion_cuda::trace::GpuPipeline;
use scion_cuda::Device;
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::{build_sah_binned, SahOptions};
use scion_runtime::query::{hits_checksum, primary_rays_n, secondary_rays};
use scion_runtime::reference::closest_hit::closest_hits_tree;
use scion_runtime::scene::load_obj;
use scion_runtime::timing::trimmed_mean;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

/// What `--help` prints: what the command does, then the usage.
const HELP: &str = "scion-gpu: run a PTX kit (closest hit compiled for a layout by `scion ptx` or \
`scion trace --device gpu --emit-ptx`) on an NVIDIA GPU over a scene's rays, and compare every \
hit with the CPU reference. Needs the CUDA driver, not the compiler's LLVM. Exit status: 0 when \
every hit is identical, 1 on a difference or an error, 2 for a bad command line. docs/gpu.md.\n";

const USAGE: &str = "usage: scion-gpu --ptx KIT.ptx --scene SCENE.obj [--rays primary|secondary] \
                     [--n N] [--seed S] [--runs R] [--device D]\n       scion-gpu --info [--device D]";

struct Args {
    info: bool,
    ptx: PathBuf,
    scene: PathBuf,
    secondary: bool,
    n: usize,
    seed: u64,
    runs: usize,
    device: i32,
}

fn parse_args() -> Result<Args, String> {
    let mut ptx = None;
    let mut scene = None;
    let mut a = Args {
        info: false,
        ptx: PathBuf::new(),
        scene: PathBuf::new(),
        secondary: false,
        n: 1 << 16,
        seed: 1,
        runs: 9,
        device: 0,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        if flag == "--help" || flag == "-h" {
            print!("{HELP}\n{USAGE}\n");
            std::process::exit(0);
        }
        if flag == "--info" {
            a.info = true;
            continue;
        }
        let value = it
            .next()
            .ok_or_else(|| format!("{flag} needs a value\n{USAGE}"))?;
        let num = |v: &str| {
            v.parse::<u64>()
                .map_err(|_| format!("{flag}: `{v}` is not a number"))
        };
        match flag.as_str() {
            "--ptx" => ptx = Some(PathBuf::from(value)),
            "--scene" => scene = Some(PathBuf::from(value)),
            "--rays" => {
                a.secondary = match value.as_str() {
                    "primary" => false,
                    "secondary" => true,
                    v => return Err(format!("--rays: `{v}` is not primary or secondary")),
                }
            }
            "--n" => a.n = num(&value)? as usize,
            "--seed" => a.seed = num(&value)?,
            "--runs" => a.runs = num(&value)? as usize,
            "--device" => a.device = num(&value)? as i32,
            f => return Err(format!("unknown flag `{f}`\n{USAGE}")),
        }
    }
    if a.info {
        return Ok(a);
    }
    a.ptx = ptx.ok_or_else(|| format!("--ptx is required\n{USAGE}"))?;
    a.scene = scene.ok_or_else(|| format!("--scene is required\n{USAGE}"))?;
    if a.n == 0 {
        return Err("--n: at least one ray".into());
    }
    Ok(a)
}

/// `--info`: the device, its driver and memory.
fn info(ordinal: i32) -> Result<bool, String> {
    let d = Device::open(ordinal).map_err(|e| e.to_string())?;
    let (free, total) = d.memory().map_err(|e| e.to_string())?;
    let stack = d.stack_limit().map_err(|e| e.to_string())?;
    println!(
        "device {ordinal}: {} (sm_{}{}), driver CUDA {}, {} of {} MiB free, stack limit {stack} \
         bytes per thread",
        d.name,
        d.compute_capability.0,
        d.compute_capability.1,
        scion_cuda::error::version_text(d.driver.version),
        free >> 20,
        total >> 20
    );
    Ok(true)
}

fn run(a: &Args) -> Result<bool, String> {
    if a.info {
        return info(a.device);
    }
    let text = std::fs::read_to_string(&a.ptx)
        .map_err(|e| format!("cannot read {}: {e}", a.ptx.display()))?;
    let kit = PtxKit::parse(&text).map_err(|e| format!("{}: {e}", a.ptx.display()))?;
    let device = Device::open(a.device).map_err(|e| e.to_string())?;
    let scene = load_obj(&a.scene).map_err(|e| format!("cannot load the scene: {e}"))?;
    if scene.is_empty() {
        return Err(format!("{}: the scene has no triangles", a.scene.display()));
    }
    let tree = build_sah_binned(&scene.triangles, &SahOptions::default());
    let stats = tree.stats();
    let b = scene.bounds();
    let rays = if a.secondary {
        secondary_rays(b, a.n, a.seed)
    } else {
        primary_rays_n(b, a.n as u64, a.seed)
            .ok_or_else(|| format!("--n: {} is not a valid ray count", a.n))?
    };
    let t = Instant::now();
    let p = GpuPipeline::new(
        &device,
        &kit.ptx,
        &kit.layout,
        &kit.algorithm,
        kit.buffers.clone(),
        kit.logical.clone(),
    )
    .map_err(|e| e.to_string())?;
    let load = t.elapsed();
    let packed = p.pack(&tree, stats.depth).map_err(|e| e.to_string())?;
    let on_device = p.upload_rays(&rays).map_err(|e| e.to_string())?;
    let (hits, times) = p
        .trace_runs(&packed, &on_device, a.runs)
        .map_err(|e| e.to_string())?;
    // A quantized layout traverses its decoded (conservative) boxes: that tree is its reference.
    let reference = closest_hits_tree(&kit.reference_tree(&tree), &rays, &BatchDriver::new(0)?);
    let cmp = Comparison::of(&hits, &reference);
    let drop = a.runs.saturating_sub(1) / 4;
    let kernel = trimmed_mean(&times, drop, drop);
    println!("device       {device:?}");
    println!(
        "ptx          {} ({} {})",
        a.ptx.display(),
        kit.algorithm,
        kit.layout
    );
    println!("module load  {:.6} s (PTX JIT)", load.as_secs_f64());
    println!(
        "scene        {} ({} triangles)",
        a.scene.display(),
        scene.len()
    );
    println!("nodes        {} (depth {})", stats.nodes, stats.depth);
    println!(
        "pack time    {:.6} s (on the device, stack {} bytes)",
        packed.pack_time.as_secs_f64(),
        packed.pack_stack
    );
    println!(
        "rays         {} {}",
        rays.len(),
        if a.secondary { "secondary" } else { "primary" }
    );
    let secs = kernel.as_secs_f64();
    println!(
        "kernel time  {secs:.6} s (mean of the middle {} of {} runs)",
        a.runs - 2 * drop,
        a.runs
    );
    if secs > 0.0 {
        println!("throughput   {:.1} Mrays/s", rays.len() as f64 / secs / 1e6);
    }
    println!(
        "hits         {} of {} rays",
        hits.iter().filter(|h| h.is_hit()).count(),
        rays.len()
    );
    println!("checksum: {:016x}", hits_checksum(&hits));
    println!("check        {cmp}");
    Ok(cmp.identical())
}

fn main() -> ExitCode {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    match run(&args) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}
