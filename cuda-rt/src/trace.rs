//! The GPU closest-hit pipeline of docs/design/backends.md §1 and §5: given the PTX of one
//! algorithm `A` specialized to one layout `L` (the kernels `scion_L_sizes_kernel`,
//! `scion_L_build_kernel`, `scion_L_root_kernel` and `scion_A_L_kernel`), pack a logical tree
//! on the device and trace rays. Packing: upload the logical tree and a [`DeviceTreeView`] of
//! it, run the sizes kernel, allocate each buffer (zeroed; `cuMemAlloc` aligns to 256 bytes),
//! upload the table of buffer addresses (`%B`), run the build and root kernels (one thread
//! each, with the stack limit raised for their recursion). Tracing: upload the rays and the
//! results initialized to `(ray.tmax, 0xFFFFFFFF)`, launch the batch kernel with 256 threads
//! per block and `ceil(n / 256)` blocks, download the results and the status word. Output:
//! [`Hit`]s in the runtime's convention and the kernel time.

use crate::args::{DevicePtr, Grid, KernelArg, THREADS_PER_BLOCK};
use crate::device::{Device, DeviceCopy};
use crate::error::CudaError;
use crate::launcher::{CudaLauncher, Launcher};
use scion_runtime::bvh::schema::{LogicalBytes, Schema};
use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::{Hit, Ray};
use scion_runtime::primitive::Primitive;
use std::time::{Duration, Instant};

// The query record of closest hit is a 32-byte `Ray`; its result record is `(f32, u32)`.
const _: () = assert!(std::mem::size_of::<Ray>() == 32);

/// The `ScionTreeView` the packing kernels read (docs/design/specialization.md §3.1), with
/// device addresses: `nodes` @0, `node_count` @8, `root` @12, `prims` @16, `prim_count` @24,
/// 32 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DeviceTreeView {
    /// Device address of the logical nodes (the layout's schema, 8-aligned).
    pub nodes: u64,
    /// Number of nodes.
    pub node_count: u32,
    /// Index of the root node.
    pub root: u32,
    /// Device address of the 40-byte triangles.
    pub prims: u64,
    /// Number of triangles.
    pub prim_count: u32,
    /// Tail padding, zero.
    pub pad: u32,
}

// SAFETY: `#[repr(C)]` with explicit padding: 32 bytes, no implicit padding, every bit pattern
// valid.
#[allow(unsafe_code)]
unsafe impl DeviceCopy for DeviceTreeView {}

const _: () = assert!(std::mem::size_of::<DeviceTreeView>() == 32);

impl DeviceTreeView {
    /// The view of `tree`, its nodes `bytes`, whose arrays were uploaded at `nodes` and
    /// `prims`.
    pub fn new<P: Primitive>(
        tree: &LogicalTree<P>,
        bytes: &LogicalBytes,
        nodes: DevicePtr,
        prims: DevicePtr,
    ) -> Result<Self, CudaError> {
        let count = |n: usize, what: &str| {
            u32::try_from(n).map_err(|_| {
                CudaError::Host(format!(
                    "the logical tree has {n} {what}, more than 2^32 - 1"
                ))
            })
        };
        Ok(DeviceTreeView {
            nodes: nodes.0,
            node_count: count(bytes.node_count, "nodes")?,
            root: bytes.root,
            prims: prims.0,
            prim_count: count(tree.primitives.len(), "primitives")?,
            pad: 0,
        })
    }
}

/// The kernel names of algorithm `A` specialized to layout `L` (source names, e.g.
/// `closest_hit` and `LinearBVH`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct KernelNames {
    /// `scion_L_sizes_kernel`.
    pub sizes: String,
    /// `scion_L_build_kernel`.
    pub build: String,
    /// `scion_L_root_kernel`.
    pub root: String,
    /// `scion_A_L_kernel`.
    pub batch: String,
}

impl KernelNames {
    /// The names for layout `layout` and algorithm `algorithm`.
    pub fn new(layout: &str, algorithm: &str) -> KernelNames {
        KernelNames {
            sizes: format!("scion_{layout}_sizes_kernel"),
            build: format!("scion_{layout}_build_kernel"),
            root: format!("scion_{layout}_root_kernel"),
            batch: format!("scion_{algorithm}_{layout}_kernel"),
        }
    }
}

/// The width of the layout's reference type `R`, read from the batch kernel's `%root`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RootRef {
    /// `u32` (an index).
    U32,
    /// A 64-bit device address.
    U64,
}

/// [`check_kernels`] on PTX text, without a device: the parameter sizes come from the PTX's
/// `.entry` declarations ([`crate::ptx::entries`]).
pub fn check_ptx_kernels(ptx: &str, names: &KernelNames) -> Result<RootRef, CudaError> {
    let entries = crate::ptx::entries(ptx).map_err(CudaError::Host)?;
    check_kernels(names, |k| {
        entries
            .iter()
            .find(|e| e.name == k)
            .map(|e| e.params.iter().map(|p| p.bytes).collect())
            .ok_or_else(|| CudaError::MissingKernel {
                kernel: k.into(),
                available: entries.iter().map(|e| e.name.clone()).collect(),
            })
    })
}

/// Checks the four kernels' parameter sizes against backends.md §1 and returns the reference
/// width. `sizes`: 2 pointers; `build`, `root`: 3 pointers; batch: `(ptr, ptr, ptr, u64, R,
/// ptr)`.
pub fn check_kernels(
    names: &KernelNames,
    params: impl Fn(&str) -> Result<Vec<usize>, CudaError>,
) -> Result<RootRef, CudaError> {
    let expect = |name: &str, want: &[usize]| -> Result<(), CudaError> {
        let got = params(name)?;
        if got != want {
            return Err(CudaError::BadArguments {
                kernel: name.to_string(),
                detail: format!("its parameters have sizes {got:?}, backends.md §1 says {want:?}"),
            });
        }
        Ok(())
    };
    expect(&names.sizes, &[8, 8])?;
    expect(&names.build, &[8, 8, 8])?;
    expect(&names.root, &[8, 8, 8])?;
    let batch = params(&names.batch)?;
    let root = match batch.as_slice() {
        [8, 8, 8, 8, 4, 8] => RootRef::U32,
        [8, 8, 8, 8, 8, 8] => RootRef::U64,
        got => {
            return Err(CudaError::BadArguments {
                kernel: names.batch.clone(),
                detail: format!(
                    "its parameters have sizes {got:?}, backends.md §1 says [8, 8, 8, 8, R, 8] \
                     with R 4 or 8"
                ),
            })
        }
    };
    Ok(root)
}

/// Per-thread stack for the recursive packing kernels: `depth + 4` levels of
/// `per_level` bytes plus 4 KiB for the kernels themselves, rounded up to 16 bytes, at least
/// `current`, at most [`MAX_PACK_STACK`]. `per_level` is the sum of the stack frames of the
/// module's non-kernel functions (one `@L.node` and one build function per level), at least
/// 256 bytes, or 1 KiB when the JIT log does not tell.
pub fn packing_stack(depth: usize, per_level: Option<u64>, current: usize) -> usize {
    let per_level = per_level.map_or(1024, |b| b.max(256)) as usize;
    let want = (depth + 4)
        .saturating_mul(per_level)
        .saturating_add(4096)
        .next_multiple_of(16);
    want.clamp(current, MAX_PACK_STACK.max(current))
}

/// The largest per-thread stack asked for (the driver reserves it for every resident thread:
/// 256 KiB on an H100 is about 70 GB).
pub const MAX_PACK_STACK: usize = 128 << 10;

/// The stack frame of each function in a ptxas info log (`Function properties for f` then
/// `N bytes stack frame, ...`).
pub fn stack_frames(info_log: &str) -> Vec<(String, u64)> {
    let mut out = Vec::new();
    let mut current: Option<String> = None;
    for line in info_log.lines() {
        if let Some((_, name)) = line.split_once("Function properties for ") {
            current = Some(name.trim().trim_matches('\'').to_string());
            continue;
        }
        if let Some(name) = current.take() {
            if let Some(n) = line
                .trim()
                .split_once(" bytes stack frame")
                .and_then(|(n, _)| n.trim().parse::<u64>().ok())
            {
                out.push((name, n));
            }
        }
    }
    out
}

/// The stack bytes one level of the packing recursion may need: the sum of the frames of the
/// module's functions other than `kernels`, each counted once (ptxas repeats a function's
/// properties under every kernel that calls it); `None` when the log names no frame.
pub fn per_level_frame(info_log: &str, kernels: &[&str]) -> Option<u64> {
    let mut seen = std::collections::BTreeMap::new();
    for (f, bytes) in stack_frames(info_log) {
        if !kernels.contains(&f.as_str()) {
            let b = seen.entry(f).or_insert(0);
            *b = bytes.max(*b);
        }
    }
    (!seen.is_empty()).then(|| seen.values().sum())
}

/// The four kernels of one algorithm and layout on a device ([`Launcher`]: CUDA, or the host
/// emulation), ready to pack and trace.
pub struct GpuPipeline<L: Launcher> {
    launcher: L,
    names: KernelNames,
    buffers: Vec<String>,
    logical: Schema,
    root: RootRef,
    /// Summed stack frames of the non-kernel functions, from the JIT log.
    frames: Option<u64>,
}

/// A tree packed on the device.
pub struct PackedTree<B> {
    /// The layout's buffers (empty for the empty tree).
    pub buffers: Vec<B>,
    /// Each buffer's size as `@L.sizes` gave it.
    pub sizes: Vec<u64>,
    table: Option<B>,
    root: u64,
    /// Upload, sizes, allocation, build and root, measured on the host.
    pub pack_time: Duration,
    /// The per-thread stack limit used for the packing kernels.
    pub pack_stack: usize,
    _logical: Vec<B>,
}

/// Rays on the device, uploaded once for several traces.
pub struct DeviceRays<B> {
    rays: Vec<Ray>,
    records: DeviceQueries<B>,
}

/// Queries of any kind on the device, uploaded once for several runs: `n` query records of
/// `query_size` bytes, room for as many result records of `result_size` bytes, the status word.
pub struct DeviceQueries<B> {
    n: usize,
    result_size: usize,
    queries: B,
    results: B,
    status: B,
}

/// The hits of one trace.
#[derive(Clone, Debug)]
pub struct GpuTrace {
    /// One per ray, in the runtime's convention (`Hit::from_best`).
    pub hits: Vec<Hit>,
    /// The batch kernel's time (CUDA events), without the transfers.
    pub kernel_time: Duration,
}

impl<'d> GpuPipeline<CudaLauncher<'d>> {
    /// Loads `ptx` on `device` and checks its kernels for layout `layout` and algorithm
    /// `algorithm`; `buffers` names the layout's buffers in plan order (their count is what
    /// `@L.sizes` writes), `logical` the shape of the logical nodes `@L.build` reads.
    pub fn new(
        device: &'d Device,
        ptx: &str,
        layout: &str,
        algorithm: &str,
        buffers: Vec<String>,
        logical: Schema,
    ) -> Result<GpuPipeline<CudaLauncher<'d>>, CudaError> {
        GpuPipeline::with_launcher(
            CudaLauncher::load(device, ptx)?,
            layout,
            algorithm,
            buffers,
            logical,
        )
    }
}

impl<L: Launcher> GpuPipeline<L> {
    /// Checks the kernels `launcher` has loaded for layout `layout` and algorithm
    /// `algorithm`; `buffers` names the layout's buffers in plan order, `logical` the shape of
    /// the logical nodes.
    pub fn with_launcher(
        launcher: L,
        layout: &str,
        algorithm: &str,
        buffers: Vec<String>,
        logical: Schema,
    ) -> Result<GpuPipeline<L>, CudaError> {
        let names = KernelNames::new(layout, algorithm);
        let root = check_kernels(&names, |k| launcher.params(k))?;
        let kernels = [
            names.sizes.as_str(),
            names.build.as_str(),
            names.root.as_str(),
            names.batch.as_str(),
        ];
        let frames = per_level_frame(launcher.info_log(), &kernels);
        Ok(GpuPipeline {
            launcher,
            names,
            buffers,
            logical,
            root,
            frames,
        })
    }

    /// The kernel names.
    pub fn names(&self) -> &KernelNames {
        &self.names
    }

    /// The reference width of the layout.
    pub fn root_ref(&self) -> RootRef {
        self.root
    }

    /// The JIT's info log (registers and stack frames per function).
    pub fn jit_log(&self) -> &str {
        self.launcher.info_log()
    }

    /// The device the kernels run on.
    pub fn launcher(&self) -> &L {
        &self.launcher
    }

    /// Packs `tree` (of depth `depth`, for the packing kernels' stack) on the device.
    pub fn pack<P: Primitive + DeviceCopy>(
        &self,
        tree: &LogicalTree<P>,
        depth: usize,
    ) -> Result<PackedTree<L::Buffer>, CudaError> {
        let start = Instant::now();
        if tree.is_empty() {
            return Ok(PackedTree {
                buffers: Vec::new(),
                sizes: Vec::new(),
                table: None,
                root: 0,
                pack_time: start.elapsed(),
                pack_stack: 0,
                _logical: Vec::new(),
            });
        }
        let dev = &self.launcher;
        let ptr = |b: &L::Buffer| KernelArg::Ptr(dev.address(b));
        let bytes = LogicalBytes::fill(tree, &self.logical).map_err(CudaError::Host)?;
        let nodes = dev.upload("logical nodes", bytes.nodes())?;
        let prims = dev.upload("logical primitives", &tree.primitives)?;
        let view = DeviceTreeView::new(tree, &bytes, dev.address(&nodes), dev.address(&prims))?;
        let view = dev.upload("logical tree view", &[view])?;
        let count = self.buffers.len();
        let sizes_buf = dev.alloc("buffer sizes", 8 * count as u64)?;
        dev.run(
            &self.names.sizes,
            Grid::SINGLE,
            &[ptr(&view), ptr(&sizes_buf)],
        )?;
        let sizes: Vec<u64> = dev.download(&sizes_buf, count)?;
        let mut buffers = Vec::with_capacity(count);
        for (name, &bytes) in self.buffers.iter().zip(&sizes) {
            buffers.push(dev.alloc(name, bytes)?);
        }
        let addresses: Vec<u64> = buffers.iter().map(|b| dev.address(b).0).collect();
        let table = dev.upload("buffer table", &addresses)?;

        let status = dev.alloc("build status", 4)?;
        let root = dev.alloc("root reference", 8)?;
        let previous = dev.stack_limit()?;
        let stack = packing_stack(depth, self.frames, previous);
        dev.set_stack_limit(stack)?;
        let packed = (|| {
            dev.run(
                &self.names.build,
                Grid::SINGLE,
                &[ptr(&view), ptr(&table), ptr(&status)],
            )?;
            let s: Vec<i32> = dev.download(&status, 1)?;
            if s[0] != 0 {
                return Err(CudaError::BuildStatus {
                    kernel: self.names.build.clone(),
                    status: s[0],
                });
            }
            dev.run(
                &self.names.root,
                Grid::SINGLE,
                &[ptr(&view), ptr(&table), ptr(&root)],
            )?;
            dev.download::<u64>(&root, 1)
        })();
        let restored = dev.set_stack_limit(previous);
        let root = packed?[0];
        restored?;
        let root = match self.root {
            RootRef::U32 => root & 0xFFFF_FFFF,
            RootRef::U64 => root,
        };
        Ok(PackedTree {
            buffers,
            sizes,
            table: Some(table),
            root,
            pack_time: start.elapsed(),
            pack_stack: stack,
            _logical: vec![nodes, prims, view],
        })
    }

    /// Uploads `rays` with room for their results and the status word.
    pub fn upload_rays(&self, rays: &[Ray]) -> Result<DeviceRays<L::Buffer>, CudaError> {
        let bytes = scion_runtime::query::io::rays_to_bytes(rays);
        Ok(DeviceRays {
            rays: rays.to_vec(),
            records: self.upload_queries(&bytes, 32, 8)?,
        })
    }

    /// Uploads query records (`queries`, records of `query_size` bytes, back to back) with room
    /// for their result records of `result_size` bytes and the status word.
    pub fn upload_queries(
        &self,
        queries: &[u8],
        query_size: usize,
        result_size: usize,
    ) -> Result<DeviceQueries<L::Buffer>, CudaError> {
        if query_size == 0 || result_size == 0 || queries.len() % query_size != 0 {
            return Err(CudaError::Host(format!(
                "{} bytes of queries are not whole {query_size}-byte records (results of \
                 {result_size} bytes)",
                queries.len()
            )));
        }
        let dev = &self.launcher;
        let n = queries.len() / query_size;
        Ok(DeviceQueries {
            n,
            result_size,
            queries: dev.upload("queries", queries)?,
            results: dev.alloc("results", (result_size * n.max(1)) as u64)?,
            status: dev.alloc("batch status", 4)?,
        })
    }

    /// Runs the batch kernel over the uploaded queries through the packed tree: results set to
    /// `initial` (one record per query), status zeroed, the kernel over `ceil(n / 256)` blocks
    /// of 256 threads, then the results and status downloaded. An empty tree leaves every
    /// result as it started. Status 1 is a traversal stack overflow.
    pub fn run_queries(
        &self,
        tree: &PackedTree<L::Buffer>,
        q: &DeviceQueries<L::Buffer>,
        initial: &[u8],
    ) -> Result<(Vec<u8>, Duration), CudaError> {
        let dev = &self.launcher;
        let n = q.n;
        if initial.len() != n * q.result_size {
            return Err(CudaError::Host(format!(
                "{} bytes of initial results for {n} records of {} bytes",
                initial.len(),
                q.result_size
            )));
        }
        let Some(table) = &tree.table else {
            return Ok((initial.to_vec(), Duration::ZERO));
        };
        let Some(grid) = Grid::for_queries(n as u64, THREADS_PER_BLOCK)? else {
            return Ok((Vec::new(), Duration::ZERO));
        };
        dev.write(&q.results, initial)?;
        dev.write(&q.status, &[0i32])?;
        let root = match self.root {
            RootRef::U32 => KernelArg::U32(tree.root as u32),
            RootRef::U64 => KernelArg::U64(tree.root),
        };
        let kernel_time = dev.run_timed(
            &self.names.batch,
            grid,
            &[
                KernelArg::Ptr(dev.address(table)),
                KernelArg::Ptr(dev.address(&q.queries)),
                KernelArg::Ptr(dev.address(&q.results)),
                KernelArg::U64(n as u64),
                root,
                KernelArg::Ptr(dev.address(&q.status)),
            ],
        )?;
        let status: Vec<i32> = dev.download(&q.status, 1)?;
        if status[0] != 0 {
            return Err(CudaError::Status {
                kernel: self.names.batch.clone(),
                status: status[0],
            });
        }
        let results: Vec<u8> = dev.download(&q.results, n * q.result_size)?;
        Ok((results, kernel_time))
    }

    /// Traces the uploaded rays through the packed tree ([`GpuPipeline::run_queries`] with
    /// results starting at `(ray.tmax, 0xFFFFFFFF)`).
    pub fn trace(
        &self,
        tree: &PackedTree<L::Buffer>,
        rays: &DeviceRays<L::Buffer>,
    ) -> Result<GpuTrace, CudaError> {
        let initial: Vec<u8> = initial_results(&rays.rays)
            .iter()
            .flatten()
            .flat_map(|w| w.to_le_bytes())
            .collect();
        let (bytes, kernel_time) = self.run_queries(tree, &rays.records, &initial)?;
        let results: Vec<[u32; 2]> = bytes
            .chunks_exact(8)
            .map(|r| {
                let w = |i: usize| u32::from_le_bytes(r[i..i + 4].try_into().expect("4 bytes"));
                [w(0), w(4)]
            })
            .collect();
        Ok(GpuTrace {
            hits: hits_of(&results),
            kernel_time,
        })
    }

    /// Traces once for the hits (a warm-up), then `runs` more times for the kernel times.
    pub fn trace_runs(
        &self,
        tree: &PackedTree<L::Buffer>,
        rays: &DeviceRays<L::Buffer>,
        runs: usize,
    ) -> Result<(Vec<Hit>, Vec<Duration>), CudaError> {
        let first = self.trace(tree, rays)?;
        let mut times = Vec::with_capacity(runs);
        for _ in 0..runs {
            times.push(self.trace(tree, rays)?.kernel_time);
        }
        Ok((first.hits, times))
    }
}

/// The result records before tracing: `(ray.tmax, 0xFFFFFFFF)` as two 32-bit words.
pub fn initial_results(rays: &[Ray]) -> Vec<[u32; 2]> {
    rays.iter().map(|r| [r.tmax.to_bits(), u32::MAX]).collect()
}

/// The hits of downloaded result records.
pub fn hits_of(results: &[[u32; 2]]) -> Vec<Hit> {
    results
        .iter()
        .map(|r| Hit::from_best(f32::from_bits(r[0]), r[1]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use scion_runtime::bvh::build_sah_binned;
    use scion_runtime::bvh::SahOptions;
    use scion_runtime::geom::{Triangle, Vec3};

    #[test]
    fn tree_view_has_the_contract_offsets() {
        let tris: Vec<Triangle> = (0..5)
            .map(|i| {
                let x = i as f32;
                Triangle::new(
                    Vec3::new(x, 0.0, 0.0),
                    Vec3::new(x + 1.0, 0.0, 0.0),
                    Vec3::new(x, 1.0, 0.0),
                    i,
                )
            })
            .collect();
        let tree = build_sah_binned(&tris, &SahOptions::default());
        let lb = LogicalBytes::fill(&tree, &scion_runtime::bvh::schema::binary_bvh()).unwrap();
        let v = DeviceTreeView::new(&tree, &lb, DevicePtr(0x1000), DevicePtr(0x2000)).unwrap();
        let bytes = crate::device::bytes_of(std::slice::from_ref(&v));
        let u64_at = |o: usize| u64::from_le_bytes(bytes[o..o + 8].try_into().unwrap());
        let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
        assert_eq!(bytes.len(), 32);
        assert_eq!(u64_at(0), 0x1000);
        assert_eq!(u32_at(8), tree.nodes.len() as u32);
        assert_eq!(u32_at(12), tree.root);
        assert_eq!(u64_at(16), 0x2000);
        assert_eq!(u32_at(24), 5);
        assert_eq!(u32_at(28), 0);
    }

    #[test]
    fn kernel_names_follow_backends_md() {
        let n = KernelNames::new("LinearBVH", "closest_hit");
        assert_eq!(n.sizes, "scion_LinearBVH_sizes_kernel");
        assert_eq!(n.build, "scion_LinearBVH_build_kernel");
        assert_eq!(n.root, "scion_LinearBVH_root_kernel");
        assert_eq!(n.batch, "scion_closest_hit_LinearBVH_kernel");
    }

    #[test]
    fn kernel_shapes_give_the_reference_width() {
        let n = KernelNames::new("L", "A");
        let shapes = |batch: Vec<usize>| {
            move |k: &str| -> Result<Vec<usize>, CudaError> {
                Ok(match k {
                    "scion_L_sizes_kernel" => vec![8, 8],
                    "scion_A_L_kernel" => batch.clone(),
                    _ => vec![8, 8, 8],
                })
            }
        };
        assert_eq!(
            check_kernels(&n, shapes(vec![8, 8, 8, 8, 4, 8])).unwrap(),
            RootRef::U32
        );
        assert_eq!(
            check_kernels(&n, shapes(vec![8, 8, 8, 8, 8, 8])).unwrap(),
            RootRef::U64
        );
        let e = check_kernels(&n, shapes(vec![8, 8, 8, 4, 4, 8])).unwrap_err();
        assert!(
            e.to_string().starts_with("kernel `scion_A_L_kernel`"),
            "{e}"
        );
        let missing = |k: &str| -> Result<Vec<usize>, CudaError> {
            Err(CudaError::MissingKernel {
                kernel: k.into(),
                available: vec![],
            })
        };
        let e = check_kernels(&n, missing).unwrap_err();
        assert!(e.to_string().contains("scion_L_sizes_kernel"), "{e}");
    }

    #[test]
    fn results_start_at_tmax_and_come_back_as_hits() {
        let mut r = Ray::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0));
        r.tmax = 7.5;
        let init = initial_results(&[r]);
        assert_eq!(init, vec![[7.5f32.to_bits(), u32::MAX]]);
        let hits = hits_of(&[init[0], [2.0f32.to_bits(), 9]]);
        assert_eq!(hits[0], Hit::from_best(7.5, u32::MAX));
        assert!(!hits[0].is_hit());
        assert_eq!(hits[1], Hit::from_best(2.0, 9));
        assert!(hits[1].is_hit());
    }

    #[test]
    fn packing_stack_grows_with_depth_within_bounds() {
        assert_eq!(packing_stack(10, Some(100), 1024), 14 * 256 + 4096);
        assert_eq!(packing_stack(10, None, 1024), 14 * 1024 + 4096);
        assert_eq!(packing_stack(0, Some(0), 1 << 20), 1 << 20);
        assert_eq!(packing_stack(100_000, Some(4096), 1024), MAX_PACK_STACK);
        assert_eq!(packing_stack(3, Some(1000), 0) % 16, 0);
    }

    #[test]
    fn reads_stack_frames_from_the_ptxas_log() {
        let log = "ptxas info    : 0 bytes gmem\n\
                   ptxas info    : Function properties for LinearBVH_node\n\
                   \x20   48 bytes stack frame, 0 bytes spill stores, 0 bytes spill loads\n\
                   ptxas info    : Compiling entry function 'k' for 'sm_90'\n\
                   ptxas info    : Function properties for k\n\
                   \x20   0 bytes stack frame, 0 bytes spill stores, 0 bytes spill loads\n\
                   ptxas info    : Used 12 registers\n";
        assert_eq!(
            stack_frames(log),
            vec![("LinearBVH_node".to_string(), 48), ("k".to_string(), 0)]
        );
        assert!(stack_frames("").is_empty());
    }

    #[test]
    fn per_level_frame_counts_each_function_once() {
        // ptxas lists `node` under both kernels that call it.
        let log = "ptxas info    : Function properties for node\n\
                   \x20   80 bytes stack frame, 80 bytes spill stores, 80 bytes spill loads\n\
                   ptxas info    : Function properties for build_k\n\
                   \x20   8 bytes stack frame, 0 bytes spill stores, 0 bytes spill loads\n\
                   ptxas info    : Function properties for node\n\
                   \x20   80 bytes stack frame, 80 bytes spill stores, 80 bytes spill loads\n\
                   ptxas info    : Function properties for helper\n\
                   \x20   16 bytes stack frame, 0 bytes spill stores, 0 bytes spill loads\n";
        assert_eq!(per_level_frame(log, &["build_k"]), Some(96));
        assert_eq!(per_level_frame(log, &["build_k", "node", "helper"]), None);
        assert_eq!(per_level_frame("", &[]), None);
    }
}
