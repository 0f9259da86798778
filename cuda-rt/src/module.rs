//! PTX modules and kernel launches: load PTX text through the driver's JIT (with its error and
//! info logs), look kernels up by name with their parameters read from the PTX, and launch
//! them with a typed argument list checked against those parameters. Input: PTX text and
//! [`KernelArg`]s; output: launches, their errors naming the kernel, and kernel times (CUDA
//! events, or the host clock around a synchronize when the driver lacks event timing).

#![allow(unsafe_code)]

use crate::args::{Grid, KernelArg, PackedArgs};
use crate::device::Device;
use crate::driver::{check, check_what, ElapsedFn};
use crate::error::CudaError;
use crate::ptx::{self, PtxEntry, PtxParam};
use cudarc::driver::sys;
use std::ffi::{c_uint, c_void, CString};
use std::time::{Duration, Instant};

/// Bytes of each JIT log buffer.
const LOG_BYTES: usize = 1 << 16;

/// A PTX module loaded on a device.
pub struct Module<'d> {
    device: &'d Device,
    module: sys::CUmodule,
    entries: Vec<PtxEntry>,
    /// The JIT's info log (with `CU_JIT_LOG_VERBOSE`: registers and stack frame per function).
    pub info_log: String,
}

impl<'d> Module<'d> {
    /// JIT-compiles `ptx` for `device`. A rejected module is [`CudaError::ModuleLoad`] with the
    /// JIT's error log.
    pub fn load(device: &'d Device, ptx: &str) -> Result<Module<'d>, CudaError> {
        let entries = ptx::entries(ptx)
            .map_err(|e| CudaError::Host(format!("cannot read the PTX's kernels: {e}")))?;
        if let Some(target) = ptx::directive(ptx, ".target") {
            ptx::target_runs_on(target, device.compute_capability)
                .map_err(|why| CudaError::Host(format!("{}: {why}", device.name)))?;
        }
        let image = CString::new(ptx)
            .map_err(|_| CudaError::Host("the PTX text contains a NUL byte".into()))?;
        device.bind()?;
        let mut error_log = vec![0u8; LOG_BYTES];
        let mut info_log = vec![0u8; LOG_BYTES];
        let mut options = [
            sys::CUjit_option::CU_JIT_ERROR_LOG_BUFFER,
            sys::CUjit_option::CU_JIT_ERROR_LOG_BUFFER_SIZE_BYTES,
            sys::CUjit_option::CU_JIT_INFO_LOG_BUFFER,
            sys::CUjit_option::CU_JIT_INFO_LOG_BUFFER_SIZE_BYTES,
            sys::CUjit_option::CU_JIT_LOG_VERBOSE,
        ];
        // The driver reads scalar option values from the pointer slots themselves.
        let mut values: [*mut c_void; 5] = [
            error_log.as_mut_ptr().cast(),
            std::ptr::without_provenance_mut(LOG_BYTES),
            info_log.as_mut_ptr().cast(),
            std::ptr::without_provenance_mut(LOG_BYTES),
            std::ptr::without_provenance_mut(1),
        ];
        let mut module: sys::CUmodule = std::ptr::null_mut();
        // SAFETY: `image` is NUL-terminated PTX; the options and values arrays have the same
        // length; the log buffers are `LOG_BYTES` long as the size options say and outlive the
        // call.
        let r = unsafe {
            sys::cuModuleLoadDataEx(
                &mut module,
                image.as_ptr().cast::<c_void>(),
                options.len() as c_uint,
                options.as_mut_ptr(),
                values.as_mut_ptr(),
            )
        };
        let text = |b: &[u8]| {
            let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
            String::from_utf8_lossy(&b[..end]).into_owned()
        };
        if let Err(code) = check(r) {
            return Err(CudaError::ModuleLoad {
                code,
                log: text(&error_log),
            });
        }
        Ok(Module {
            device,
            module,
            entries,
            info_log: text(&info_log),
        })
    }

    /// The kernels the PTX declares.
    pub fn entries(&self) -> &[PtxEntry] {
        &self.entries
    }

    /// The kernel `name`.
    pub fn kernel(&self, name: &str) -> Result<Kernel<'_>, CudaError> {
        let missing = || CudaError::MissingKernel {
            kernel: name.to_string(),
            available: self.entries.iter().map(|e| e.name.clone()).collect(),
        };
        let entry = self
            .entries
            .iter()
            .find(|e| e.name == name)
            .ok_or_else(missing)?;
        let cname = CString::new(name).map_err(|_| missing())?;
        self.device.bind()?;
        let mut func: sys::CUfunction = std::ptr::null_mut();
        // SAFETY: looks a function up in this live module by a NUL-terminated name.
        let r = unsafe { sys::cuModuleGetFunction(&mut func, self.module, cname.as_ptr()) };
        match check(r) {
            Ok(()) => Ok(Kernel {
                device: self.device,
                func,
                name: name.to_string(),
                params: entry.params.clone(),
            }),
            Err(code) if code.code == 500 => Err(missing()),
            Err(code) => Err(CudaError::Driver {
                what: format!("looking up kernel `{name}`"),
                code,
            }),
        }
    }
}

impl Drop for Module<'_> {
    fn drop(&mut self) {
        if self.device.bind().is_ok() {
            // SAFETY: unloads this module once; kernels borrow it, so none is left.
            let _ = unsafe { sys::cuModuleUnload(self.module) };
        }
    }
}

/// A kernel of a loaded module.
pub struct Kernel<'m> {
    device: &'m Device,
    func: sys::CUfunction,
    name: String,
    params: Vec<PtxParam>,
}

impl Kernel<'_> {
    /// Its name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Its parameters as the PTX declares them.
    pub fn params(&self) -> &[PtxParam] {
        &self.params
    }

    /// Launches on the default stream without waiting. Errors the driver reports at launch
    /// (bad shape, too many resources) are [`CudaError::Launch`]; faults during execution
    /// surface at the next [`Device::synchronize`].
    pub fn launch(&self, grid: Grid, args: &[KernelArg]) -> Result<(), CudaError> {
        let mut packed = PackedArgs::new(&self.name, &self.params, args)?;
        let mut pointers = packed.pointers();
        self.device.bind()?;
        // SAFETY: `func` belongs to a live module of the current context; `pointers` holds one
        // pointer per kernel parameter (count and sizes checked against the PTX by
        // `PackedArgs::new`), each to a live 8-byte slot of `packed`, which outlives the call
        // (the driver copies the values at launch).
        let r = unsafe {
            sys::cuLaunchKernel(
                self.func,
                grid.blocks,
                1,
                1,
                grid.threads,
                1,
                1,
                0,
                std::ptr::null_mut(),
                pointers.as_mut_ptr(),
                std::ptr::null_mut(),
            )
        };
        check(r).map_err(|code| CudaError::Launch {
            kernel: self.name.clone(),
            code,
        })
    }

    /// Launches and waits; faults during execution are [`CudaError::Launch`] naming this
    /// kernel.
    pub fn run(&self, grid: Grid, args: &[KernelArg]) -> Result<(), CudaError> {
        self.launch(grid, args)?;
        self.device.synchronize(&self.name)
    }

    /// Launches, waits and returns the kernel's time: CUDA events recorded on the default
    /// stream around the launch, or the host clock around launch and synchronize.
    pub fn run_timed(&self, grid: Grid, args: &[KernelArg]) -> Result<Duration, CudaError> {
        let Some(elapsed) = self.device.driver.elapsed else {
            let t = Instant::now();
            self.run(grid, args)?;
            return Ok(t.elapsed());
        };
        self.device.bind()?;
        let start = Event::new(self.device)?;
        let end = Event::new(self.device)?;
        start.record()?;
        self.launch(grid, args)?;
        end.record()?;
        self.device.synchronize(&self.name)?;
        end.wait(&self.name)?;
        let mut ms = 0f32;
        // SAFETY: both events were recorded on the default stream and `end` has completed.
        let r = unsafe {
            match elapsed {
                ElapsedFn::V2 => sys::cuEventElapsedTime_v2(&mut ms, start.0, end.0),
                ElapsedFn::V1 => sys::cuEventElapsedTime(&mut ms, start.0, end.0),
            }
        };
        check_what(r, || format!("timing kernel `{}`", self.name))?;
        Ok(Duration::from_secs_f64(f64::from(ms.max(0.0)) / 1e3))
    }
}

/// A CUDA event (default flags: timing enabled), destroyed on drop.
struct Event(sys::CUevent);

impl Event {
    fn new(device: &Device) -> Result<Event, CudaError> {
        device.bind()?;
        let mut e: sys::CUevent = std::ptr::null_mut();
        // SAFETY: creates an event in the current context.
        let r = unsafe { sys::cuEventCreate(&mut e, 0) };
        check_what(r, || "creating a CUDA event".into())?;
        Ok(Event(e))
    }

    fn record(&self) -> Result<(), CudaError> {
        // SAFETY: records a live event on the default stream.
        let r = unsafe { sys::cuEventRecord(self.0, std::ptr::null_mut()) };
        check_what(r, || "recording a CUDA event".into())
    }

    fn wait(&self, kernel: &str) -> Result<(), CudaError> {
        // SAFETY: waits for a live, recorded event.
        let r = unsafe { sys::cuEventSynchronize(self.0) };
        check(r).map_err(|code| CudaError::Launch {
            kernel: kernel.to_string(),
            code,
        })
    }
}

impl Drop for Event {
    fn drop(&mut self) {
        // SAFETY: destroys this live event once.
        let _ = unsafe { sys::cuEventDestroy_v2(self.0) };
    }
}
