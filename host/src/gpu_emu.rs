//! The GPU pipeline emulated on the CPU (docs/gpu.md, "Checking the GPU pipeline without a
//! GPU"): the `lo` module whose PTX `scion trace --device gpu` runs (closest hit specialized
//! to a library layout with the GPU entries: `scion_L_sizes_kernel`, `scion_L_build_kernel`,
//! `scion_L_root_kernel`, `scion_A_L_kernel`) goes through `lo-host-kernels` (each kernel
//! takes its thread index as a last `u64` parameter in place of `lo.global_id`) and is
//! compiled for this CPU by LLVM or Cranelift. [`EmulatedGpu`] is a
//! [`scion_cuda::Launcher`]: its buffers are zeroed host allocations aligned to 256 bytes
//! like `cuMemAlloc`'s, whose addresses the kernels receive; a launch calls the kernel once
//! per thread index of the grid, on a pool of host threads taking one block at a time.
//! Driven by `scion_cuda`'s own [`GpuPipeline`], it checks everything of the GPU path but
//! NVPTX code generation and the CUDA driver: the kernels' code, their parameters, and the
//! pipeline's protocol (sizes, buffer table, build status, root, result records, status word).

#![allow(unsafe_code)]

use crate::backend::Backend;
use crate::jit::{Code, Codegen, LoOptions, ALGORITHM};
use crate::quantized::Boxes;
use scion_compiler::abi::EntryTarget;
use scion_cuda::args::PackedArgs;
use scion_cuda::device::{bytes_of, check_copy_len, DeviceCopy};
use scion_cuda::ptx::PtxParam;
use scion_cuda::trace::GpuPipeline;
use scion_cuda::{CudaError, DevicePtr, Grid, KernelArg, Launcher};
use scion_ir::types::Type;
use scion_ir::Module;
use scion_runtime::bvh::schema::Schema;
use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::{Hit, Ray, Triangle};
use std::alloc::Layout;
use std::collections::BTreeMap;
use std::ptr::NonNull;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// The alignment of every buffer: `cuMemAlloc`'s.
pub const BUFFER_ALIGN: usize = 256;

/// The host stack of a thread running a one-thread launch (the recursive packing kernels):
/// reserved, not committed, so it costs address space only.
const SINGLE_THREAD_STACK: usize = 256 << 20;

/// The host stack of each thread of a wider launch (the batch kernel keeps its traversal
/// stack in a fixed slot of its frame).
const GRID_THREAD_STACK: usize = 16 << 20;

/// A kernel compiled for the host.
struct HostKernel {
    /// Its parameters as the PTX would declare them (without the thread index).
    params: Vec<PtxParam>,
    /// The machine code, taking the parameters and then the thread index.
    code: usize,
}

/// The four kernels of one layout compiled for the host, with the memory of an emulated device.
pub struct EmulatedGpu {
    _code: Code,
    kernels: BTreeMap<String, HostKernel>,
    stack_limit: AtomicUsize,
    workers: usize,
    layout: String,
    /// The algorithm whose batch kernel this is (closest hit for a bare module).
    algorithm: String,
    /// The entries' C signature, when compiled from a program.
    entry: Option<scion_compiler::abi::EntrySig>,
    buffers: Vec<String>,
    logical: Schema,
    codegen: Codegen,
    /// Front end, `lo-host-kernels` and machine code.
    pub compile_time: Duration,
}

// SAFETY: the machine code is finalized and re-entrant (see `jit::Code`); the kernel table
// holds its addresses and is never written after `compile`; the stack limit is atomic.
unsafe impl Send for EmulatedGpu {}
// SAFETY: as above.
unsafe impl Sync for EmulatedGpu {}

impl EmulatedGpu {
    /// Compiles closest hit for the library layout in file `stem` named `layout` with the GPU
    /// entries (`opts.target` is taken to be [`EntryTarget::Gpu`]), then its kernels for the
    /// host with `codegen`; launches use `workers` threads (0: one per core).
    pub fn compile(
        stem: &str,
        layout: &str,
        opts: &LoOptions,
        codegen: Codegen,
        workers: usize,
    ) -> Result<EmulatedGpu, String> {
        let program = crate::mem_interp::Program::library(stem, layout)?;
        EmulatedGpu::compile_program(&program, opts, codegen, workers)
    }

    /// [`EmulatedGpu::compile`] for any program: a layout file's closest hit, or any
    /// algorithm whose entry answers a batch of queries over one tree.
    pub fn compile_program(
        program: &crate::mem_interp::Program,
        opts: &LoOptions,
        codegen: Codegen,
        workers: usize,
    ) -> Result<EmulatedGpu, String> {
        let start = Instant::now();
        let lo = crate::jit::program_lo(
            program,
            &LoOptions {
                target: EntryTarget::Gpu,
                ..*opts
            },
        )?;
        let buffers = lo.entry.buffers.iter().map(|b| b.name.clone()).collect();
        let mut gpu = EmulatedGpu::from_module(lo.module, codegen, workers)?;
        gpu.layout = lo.entry.layout.clone();
        gpu.algorithm = lo.entry.algorithm.clone();
        gpu.entry = Some(lo.entry.clone());
        gpu.buffers = buffers;
        gpu.logical = lo.entry.logical.clone();
        gpu.compile_time = start.elapsed();
        Ok(gpu)
    }

    /// Compiles the kernels of the `lo` module `m` (functions with the attribute `kernel`) for
    /// the host.
    pub fn from_module(
        mut m: Module,
        codegen: Codegen,
        workers: usize,
    ) -> Result<EmulatedGpu, String> {
        let start = Instant::now();
        let mut shapes = Vec::new();
        for &f in &m.func_order {
            let func = &m.funcs[f];
            if func.attrs.get("kernel").is_none() {
                continue;
            }
            let params = func
                .params
                .iter()
                .enumerate()
                .map(|(i, &t)| PtxParam {
                    name: format!("{}_param_{i}", func.name),
                    bytes: match m.types.get(t) {
                        Type::Ptr => 8,
                        _ => m.types.bit_width(t).map_or(0, |b| b.div_ceil(8)) as usize,
                    },
                    is_float: matches!(m.types.get(t), Type::Float(_)),
                    array: false,
                })
                .collect::<Vec<_>>();
            shapes.push((func.name.clone(), params));
        }
        scion_compiler::passes::lo::host_kernels::run(&mut m).map_err(|d| d.to_string())?;
        let code = Code::compile(&m, codegen)?;
        let mut kernels = BTreeMap::new();
        for (name, params) in shapes {
            let ptr = code
                .function_ptr(&name)
                .ok_or_else(|| format!("the host code has no kernel `@{name}`"))?;
            kernels.insert(
                name,
                HostKernel {
                    params,
                    code: ptr as usize,
                },
            );
        }
        let workers = if workers == 0 {
            std::thread::available_parallelism().map_or(1, |n| n.get())
        } else {
            workers
        };
        Ok(EmulatedGpu {
            _code: code,
            kernels,
            // CUDA's default per-thread stack.
            stack_limit: AtomicUsize::new(1024),
            workers,
            layout: String::new(),
            algorithm: ALGORITHM.to_string(),
            entry: None,
            buffers: Vec::new(),
            logical: scion_runtime::bvh::schema::binary_bvh(),
            codegen,
            compile_time: start.elapsed(),
        })
    }

    /// The layout's source name (`LinearBVH`), which names its kernels.
    pub fn layout(&self) -> &str {
        &self.layout
    }

    /// The entries' C signature (records, buffers), when compiled from a program.
    pub fn entry(&self) -> Option<&scion_compiler::abi::EntrySig> {
        self.entry.as_ref()
    }

    /// The layout's buffers in plan order.
    pub fn buffers(&self) -> &[String] {
        &self.buffers
    }

    /// The kernels, by name.
    pub fn kernel_names(&self) -> Vec<&str> {
        self.kernels.keys().map(String::as_str).collect()
    }

    /// The pipeline over these kernels (`scion_cuda::trace`).
    pub fn into_pipeline(self) -> Result<GpuPipeline<EmulatedGpu>, String> {
        let (layout, buffers) = (self.layout.clone(), self.buffers.clone());
        let (logical, algorithm) = (self.logical.clone(), self.algorithm.clone());
        GpuPipeline::with_launcher(self, &layout, &algorithm, buffers, logical)
            .map_err(|e| e.to_string())
    }

    fn kernel(&self, name: &str) -> Result<&HostKernel, CudaError> {
        self.kernels
            .get(name)
            .ok_or_else(|| CudaError::MissingKernel {
                kernel: name.to_string(),
                available: self.kernels.keys().cloned().collect(),
            })
    }
}

type P2Fn = unsafe extern "C" fn(u64, u64, u64);
type P3Fn = unsafe extern "C" fn(u64, u64, u64, u64);
type BatchU32Fn = unsafe extern "C" fn(u64, u64, u64, u64, u32, u64, u64);
type BatchU64Fn = unsafe extern "C" fn(u64, u64, u64, u64, u64, u64, u64);

/// A kernel's machine code by the sizes of its parameters (backends.md §1), each followed by
/// the thread index.
#[derive(Clone, Copy)]
enum Shape {
    /// `sizes`: two pointers.
    P2(P2Fn),
    /// `build`, `root`: three pointers.
    P3(P3Fn),
    /// The batch kernel with a `u32` reference.
    BatchU32(BatchU32Fn),
    /// The batch kernel with a 64-bit reference.
    BatchU64(BatchU64Fn),
}

impl Shape {
    /// # Safety
    /// `code` must be the address of a host function whose parameters have the C types the
    /// sizes say (integers and pointers), then a `u64`.
    unsafe fn of(kernel: &str, params: &[PtxParam], code: usize) -> Result<Shape, CudaError> {
        let sizes: Vec<usize> = params.iter().map(|p| p.bytes).collect();
        let p = code as *const u8;
        // SAFETY: by the caller's contract, the function has exactly these parameters.
        unsafe {
            Ok(match sizes.as_slice() {
                [8, 8] => Shape::P2(std::mem::transmute::<*const u8, P2Fn>(p)),
                [8, 8, 8] => Shape::P3(std::mem::transmute::<*const u8, P3Fn>(p)),
                [8, 8, 8, 8, 4, 8] => {
                    Shape::BatchU32(std::mem::transmute::<*const u8, BatchU32Fn>(p))
                }
                [8, 8, 8, 8, 8, 8] => {
                    Shape::BatchU64(std::mem::transmute::<*const u8, BatchU64Fn>(p))
                }
                got => {
                    return Err(CudaError::Host(format!(
                        "kernel `{kernel}`: the host emulation launches the kernel shapes of \
                         backends.md §1 only, not parameters of sizes {got:?}"
                    )))
                }
            })
        }
    }

    /// Runs thread `id` with the packed arguments `a`.
    ///
    /// # Safety
    /// The arguments must be what the kernel reads: addresses of live host buffers large
    /// enough for it.
    unsafe fn call(self, a: &[u64], id: u64) {
        // SAFETY: by the caller's contract.
        unsafe {
            match self {
                Shape::P2(f) => f(a[0], a[1], id),
                Shape::P3(f) => f(a[0], a[1], a[2], id),
                Shape::BatchU32(f) => f(a[0], a[1], a[2], a[3], a[4] as u32, a[5], id),
                Shape::BatchU64(f) => f(a[0], a[1], a[2], a[3], a[4], a[5], id),
            }
        }
    }
}

/// Memory of the emulated device: a zeroed host allocation aligned to [`BUFFER_ALIGN`], named,
/// freed on drop.
pub struct HostBuffer {
    ptr: NonNull<u8>,
    bytes: u64,
    layout: Layout,
    name: String,
}

// SAFETY: the buffer owns its allocation; access goes through `&self` copies (the emulator's
// `write`/`download`) or through kernels, which the pipeline runs one launch at a time.
unsafe impl Send for HostBuffer {}
// SAFETY: as above.
unsafe impl Sync for HostBuffer {}

impl HostBuffer {
    fn check_len(&self, bytes: usize, what: &str) -> Result<(), CudaError> {
        check_copy_len(&self.name, self.bytes, bytes, what)
    }
}

impl Drop for HostBuffer {
    fn drop(&mut self) {
        // SAFETY: allocated in `alloc` with exactly this layout, freed once.
        unsafe { std::alloc::dealloc(self.ptr.as_ptr(), self.layout) }
    }
}

impl Launcher for EmulatedGpu {
    type Buffer = HostBuffer;

    fn alloc(&self, name: &str, bytes: u64) -> Result<HostBuffer, CudaError> {
        let oom = || CudaError::OutOfMemory {
            buffer: name.to_string(),
            bytes,
            free_total: None,
        };
        let len = usize::try_from(bytes.max(1)).map_err(|_| oom())?;
        let layout = Layout::from_size_align(len, BUFFER_ALIGN).map_err(|_| oom())?;
        // SAFETY: `layout` has a nonzero size.
        let ptr = NonNull::new(unsafe { std::alloc::alloc_zeroed(layout) }).ok_or_else(oom)?;
        Ok(HostBuffer {
            ptr,
            bytes,
            layout,
            name: name.to_string(),
        })
    }

    fn upload<T: DeviceCopy>(&self, name: &str, data: &[T]) -> Result<HostBuffer, CudaError> {
        let b = self.alloc(name, std::mem::size_of_val(data) as u64)?;
        self.write(&b, data)?;
        Ok(b)
    }

    fn address(&self, buffer: &HostBuffer) -> DevicePtr {
        DevicePtr(buffer.ptr.as_ptr() as u64)
    }

    fn write<T: DeviceCopy>(&self, buffer: &HostBuffer, data: &[T]) -> Result<(), CudaError> {
        let bytes = bytes_of(data);
        buffer.check_len(bytes.len(), "writing")?;
        // SAFETY: at most the allocation's size (checked), from a live slice that cannot
        // overlap the buffer (the buffer is only reachable through raw addresses).
        unsafe {
            std::ptr::copy_nonoverlapping(bytes.as_ptr(), buffer.ptr.as_ptr(), bytes.len());
        }
        Ok(())
    }

    fn download<T: DeviceCopy>(&self, buffer: &HostBuffer, n: usize) -> Result<Vec<T>, CudaError> {
        let len = n
            .checked_mul(std::mem::size_of::<T>())
            .ok_or_else(|| CudaError::Host(format!("reading {n} elements overflows")))?;
        buffer.check_len(len, "reading")?;
        let mut out: Vec<T> = Vec::with_capacity(n);
        // SAFETY: copies `len` bytes (within the allocation, checked) into the vector's spare
        // capacity; every bit pattern is a valid `T` (`DeviceCopy`), so the `n` elements are
        // initialized afterwards.
        unsafe {
            std::ptr::copy_nonoverlapping(buffer.ptr.as_ptr(), out.as_mut_ptr().cast::<u8>(), len);
            out.set_len(n);
        }
        Ok(out)
    }

    fn params(&self, kernel: &str) -> Result<Vec<usize>, CudaError> {
        Ok(self
            .kernel(kernel)?
            .params
            .iter()
            .map(|p| p.bytes)
            .collect())
    }

    fn run(&self, kernel: &str, grid: Grid, args: &[KernelArg]) -> Result<(), CudaError> {
        let k = self.kernel(kernel)?;
        let packed = PackedArgs::new(kernel, &k.params, args)?;
        let slots: Vec<u64> = (0..packed.len())
            .map(|i| {
                let mut b = [0u8; 8];
                let v = packed.bytes(i);
                b[..v.len()].copy_from_slice(&v);
                u64::from_le_bytes(b)
            })
            .collect();
        // SAFETY: the kernel's `lo` parameters are integers and pointers of these sizes, then
        // the `u64` that `lo-host-kernels` added.
        let shape = unsafe { Shape::of(kernel, &k.params, k.code)? };
        let threads = u64::from(grid.blocks) * u64::from(grid.threads);
        let block = u64::from(grid.threads.max(1));
        let next = AtomicU64::new(0);
        let slots = &slots;
        let work = || loop {
            let first = next.fetch_add(block, Ordering::Relaxed);
            if first >= threads {
                break;
            }
            for id in first..(first + block).min(threads) {
                // SAFETY: the pipeline passes the addresses of live buffers of the sizes the
                // kernels were generated for, as a CUDA launch would.
                unsafe { shape.call(slots, id) };
            }
        };
        let (workers, stack) = if threads <= 1 {
            (1, SINGLE_THREAD_STACK)
        } else {
            let blocks = threads.div_ceil(block);
            (
                (self.workers as u64).min(blocks) as usize,
                GRID_THREAD_STACK,
            )
        };
        let stack = stack.max(self.stack_limit.load(Ordering::Relaxed));
        std::thread::scope(|s| -> Result<(), CudaError> {
            let handles = (0..workers)
                .map(|_| {
                    std::thread::Builder::new()
                        .name(format!("emulated {kernel}"))
                        .stack_size(stack)
                        .spawn_scoped(s, work)
                        .map_err(|e| {
                            CudaError::Host(format!(
                                "kernel `{kernel}`: cannot start a host thread: {e}"
                            ))
                        })
                })
                .collect::<Vec<_>>();
            for h in handles {
                h?.join().map_err(|_| {
                    CudaError::Host(format!("kernel `{kernel}`: a host thread panicked"))
                })?;
            }
            Ok(())
        })
    }

    fn run_timed(
        &self,
        kernel: &str,
        grid: Grid,
        args: &[KernelArg],
    ) -> Result<Duration, CudaError> {
        let t = Instant::now();
        self.run(kernel, grid, args)?;
        Ok(t.elapsed())
    }

    fn stack_limit(&self) -> Result<usize, CudaError> {
        Ok(self.stack_limit.load(Ordering::Relaxed))
    }

    fn set_stack_limit(&self, bytes: usize) -> Result<(), CudaError> {
        self.stack_limit.store(bytes, Ordering::Relaxed);
        Ok(())
    }

    fn info_log(&self) -> &str {
        ""
    }
}

/// [`crate::backend::BackendKind::GpuEmulated`]: the emulated GPU pipeline as a backend.
pub struct EmulatedBackend {
    pipeline: GpuPipeline<EmulatedGpu>,
    boxes: Boxes,
    stack: u32,
}

impl EmulatedBackend {
    /// Closest hit for the library layout `stem` named `layout` (boxes stored as `boxes`) with
    /// a traversal stack of `stack` entries, its kernels compiled by LLVM -O3 for the host.
    pub fn new(
        stem: &str,
        layout: &str,
        boxes: Boxes,
        stack: u32,
        workers: usize,
    ) -> Result<EmulatedBackend, String> {
        let gpu = EmulatedGpu::compile(
            stem,
            layout,
            &LoOptions {
                stack_size: Some(stack),
                opt_level: crate::jit::JIT_OPT_LEVEL,
                dsl_opt: true,
                target: EntryTarget::Gpu,
            },
            Codegen::Llvm(3),
            workers,
        )?;
        Ok(EmulatedBackend {
            pipeline: gpu.into_pipeline()?,
            boxes,
            stack,
        })
    }
}

impl Backend for EmulatedBackend {
    fn name(&self) -> String {
        let gpu = self.pipeline.launcher();
        let by = match gpu.codegen {
            Codegen::Llvm(l) => format!("llvm-O{l}"),
            Codegen::Cranelift => "cranelift".into(),
        };
        format!("gpu-emulated-{by}-{}", gpu.layout)
    }

    fn trace(&self, _: &[Triangle], tree: &LogicalTree, rays: &[Ray]) -> Result<Vec<Hit>, String> {
        let p = &self.pipeline;
        let packed = p
            .pack(tree, tree.stats().depth)
            .map_err(|e| e.to_string())?;
        let on_device = p.upload_rays(rays).map_err(|e| e.to_string())?;
        Ok(p.trace(&packed, &on_device)
            .map_err(|e| e.to_string())?
            .hits)
    }

    fn stack_limit(&self) -> Option<usize> {
        Some(self.stack as usize)
    }

    fn boxes(&self) -> Boxes {
        self.boxes
    }
}
