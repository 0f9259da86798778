//! What the closest-hit pipeline ([`crate::trace`]) asks of a GPU: named buffers (allocated
//! zeroed, written, read back), the parameter sizes of a kernel, launches of a grid, and the
//! per-thread stack limit. [`CudaLauncher`] does it with the CUDA driver and a loaded PTX
//! module; `scion-host`'s emulator does it on the CPU with the same kernels compiled for the
//! host (docs/gpu.md), so the pipeline's protocol (argument order, buffer sizes, status words,
//! result records) is checked on machines without a GPU by the very code that drives one.

use crate::args::{DevicePtr, Grid, KernelArg};
use crate::device::{Device, DeviceBuffer, DeviceCopy};
use crate::error::CudaError;
use crate::module::Module;
use std::time::Duration;

/// A device (real or emulated) with the four kernels of one algorithm and layout loaded.
pub trait Launcher {
    /// A buffer in the device's memory, freed on drop.
    type Buffer;

    /// `bytes` (at least 1 allocated) of zeroed memory named `name`, aligned to 256 bytes.
    fn alloc(&self, name: &str, bytes: u64) -> Result<Self::Buffer, CudaError>;

    /// A new buffer named `name` holding `data`.
    fn upload<T: DeviceCopy>(&self, name: &str, data: &[T]) -> Result<Self::Buffer, CudaError>;

    /// The buffer's device address, as kernels receive it.
    fn address(&self, buffer: &Self::Buffer) -> DevicePtr;

    /// Copies `data` to the start of `buffer`.
    fn write<T: DeviceCopy>(&self, buffer: &Self::Buffer, data: &[T]) -> Result<(), CudaError>;

    /// The first `n` elements of `T` in `buffer`.
    fn download<T: DeviceCopy>(&self, buffer: &Self::Buffer, n: usize)
        -> Result<Vec<T>, CudaError>;

    /// The byte sizes of kernel `kernel`'s parameters ([`CudaError::MissingKernel`] when there
    /// is no such kernel).
    fn params(&self, kernel: &str) -> Result<Vec<usize>, CudaError>;

    /// Runs `kernel` over `grid` with `args` (checked against its parameters) and waits.
    fn run(&self, kernel: &str, grid: Grid, args: &[KernelArg]) -> Result<(), CudaError>;

    /// As [`Launcher::run`], returning the kernel's time.
    fn run_timed(
        &self,
        kernel: &str,
        grid: Grid,
        args: &[KernelArg],
    ) -> Result<Duration, CudaError>;

    /// The per-thread stack limit in bytes.
    fn stack_limit(&self) -> Result<usize, CudaError>;

    /// Sets the per-thread stack limit.
    fn set_stack_limit(&self, bytes: usize) -> Result<(), CudaError>;

    /// The compiler's log of the loaded code: per function, registers and stack frame (empty
    /// where there is none).
    fn info_log(&self) -> &str;
}

/// A CUDA device with a PTX module loaded on it.
pub struct CudaLauncher<'d> {
    /// The device.
    pub device: &'d Device,
    /// The loaded module.
    pub module: Module<'d>,
}

impl<'d> CudaLauncher<'d> {
    /// Loads `ptx` on `device` ([`Module::load`]).
    pub fn load(device: &'d Device, ptx: &str) -> Result<CudaLauncher<'d>, CudaError> {
        Ok(CudaLauncher {
            device,
            module: Module::load(device, ptx)?,
        })
    }
}

impl<'d> Launcher for CudaLauncher<'d> {
    type Buffer = DeviceBuffer<'d>;

    fn alloc(&self, name: &str, bytes: u64) -> Result<DeviceBuffer<'d>, CudaError> {
        self.device.alloc(name, bytes)
    }

    fn upload<T: DeviceCopy>(&self, name: &str, data: &[T]) -> Result<DeviceBuffer<'d>, CudaError> {
        self.device.upload(name, data)
    }

    fn address(&self, buffer: &DeviceBuffer<'d>) -> DevicePtr {
        buffer.ptr()
    }

    fn write<T: DeviceCopy>(&self, buffer: &DeviceBuffer<'d>, data: &[T]) -> Result<(), CudaError> {
        buffer.write(data)
    }

    fn download<T: DeviceCopy>(
        &self,
        buffer: &DeviceBuffer<'d>,
        n: usize,
    ) -> Result<Vec<T>, CudaError> {
        buffer.download(n)
    }

    fn params(&self, kernel: &str) -> Result<Vec<usize>, CudaError> {
        Ok(self
            .module
            .kernel(kernel)?
            .params()
            .iter()
            .map(|p| p.bytes)
            .collect())
    }

    fn run(&self, kernel: &str, grid: Grid, args: &[KernelArg]) -> Result<(), CudaError> {
        self.module.kernel(kernel)?.run(grid, args)
    }

    fn run_timed(
        &self,
        kernel: &str,
        grid: Grid,
        args: &[KernelArg],
    ) -> Result<Duration, CudaError> {
        self.module.kernel(kernel)?.run_timed(grid, args)
    }

    fn stack_limit(&self) -> Result<usize, CudaError> {
        self.device.stack_limit()
    }

    fn set_stack_limit(&self, bytes: usize) -> Result<(), CudaError> {
        self.device.set_stack_limit(bytes)
    }

    fn info_log(&self) -> &str {
        &self.module.info_log
    }
}
