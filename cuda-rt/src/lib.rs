//! `scion-cuda`: the CUDA runtime of Scion (docs/design/backends.md §5, docs/gpu.md). It runs
//! the PTX that `scion-llvm` emits for `--target nvptx64` on an NVIDIA GPU through the CUDA
//! driver API (cudarc, the driver loaded at run time, so nothing CUDA is needed to build or to
//! test on a machine without a GPU).
//!
//! * [`driver`]: find and check the driver library ([`CudaError::NoDriver`],
//!   [`CudaError::DriverTooOld`]) before cudarc could panic;
//! * [`device`]: [`Device::open`], named [`DeviceBuffer`]s, the stack limit;
//! * [`module`]: PTX modules (with the JIT log) and kernel launches;
//! * [`args`], [`ptx`]: typed kernel arguments checked against the PTX's `.entry`
//!   parameters, launch grids;
//! * [`launcher`]: what the pipeline needs of a device ([`Launcher`]), done by CUDA
//!   ([`CudaLauncher`]) or by `scion-host`'s emulation on the CPU;
//! * [`trace`]: the pipeline (pack the logical tree on the device, run the batch kernel over
//!   query records of any kind; closest hit's rays and hits);
//! * [`kit`]: self-describing PTX for machines without the compiler (`scion-gpu`);
//! * [`compare`]: GPU hits against the CPU reference, bit for bit;
//! * [`ptxas`]: NVIDIA's offline assembler, to check PTX where there is no GPU.

pub mod args;
pub mod compare;
pub mod device;
pub mod driver;
pub mod error;
pub mod kit;
pub mod launcher;
pub mod module;
pub mod ptx;
pub mod ptxas;
pub mod trace;

pub use args::{DevicePtr, Grid, KernelArg};
pub use device::{Device, DeviceBuffer};
pub use error::CudaError;
pub use launcher::{CudaLauncher, Launcher};
pub use module::{Kernel, Module};
pub use trace::{DeviceQueries, GpuPipeline, GpuTrace, PackedTree};

/// Opens device 0, or says why not: the reason a GPU test skips. `Err` carries the one-line
/// reason (`no CUDA driver: ...`).
pub fn open_for_tests() -> Result<Device, String> {
    let ordinal = std::env::var("SCION_CUDA_DEVICE")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    Device::open(ordinal).map_err(|e| e.to_string())
}
