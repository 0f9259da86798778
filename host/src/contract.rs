//! The host side of the runtime contract of docs/design/specialization.md §3, for code
//! specialized to a layout (the JIT's, `crate::jit`): ask `@L.sizes` for each buffer's byte size,
//! allocate each buffer once with the layout's alignment, pack with `@L.build`, then run the
//! batch entry over threads in blocks of 64 with each result initialized to
//! `(ray.tmax, 0xFFFFFFFF)`. Input: a [`LayoutCode`] and a logical tree; output: [`Packed`]
//! buffers, then hits or the index of the ray whose traversal failed.
//!
//! [`LayoutCode`] is the safe face of the three entry points; whoever holds native code (the
//! Cranelift JIT) implements it with its calls, and [`LayoutBackend`] makes it one more
//! [`Backend`] of the differential table and of `scion trace`. The empty tree never reaches the
//! code: every ray misses.

use crate::backend::Backend;
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::schema::{LogicalBytes, Schema};
use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::{Hit, Ray, Triangle};
use scion_runtime::primitive::Primitive;
use std::fmt;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Status of the batch entry: success.
pub const STATUS_OK: i32 = 0;
/// Status of the batch entry: the traversal's explicit stack overflowed.
pub const STATUS_STACK_OVERFLOW: i32 = 1;

/// One buffer of a layout's plan.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BufferSpec {
    /// The buffer's name in the layout (for reports).
    pub name: String,
    /// Its alignment in bytes (a power of two).
    pub align: usize,
}

/// The logical tree handed to a layout's code: the runtime's tree and, for code generated
/// from a `build`, its nodes in the schema of the layout's tree type.
#[derive(Clone, Copy)]
pub struct LogicalInput<'a> {
    /// The tree.
    pub tree: &'a LogicalTree,
    /// Its nodes as [`LayoutCode::schema`] describes them (`None` when the code has none).
    pub bytes: Option<&'a LogicalBytes>,
}

/// The entry points of one algorithm specialized to one layout (design note §3).
pub trait LayoutCode: Sync {
    /// The layout's name.
    fn layout(&self) -> String;
    /// The shape of the logical nodes `sizes` and `build` read, for generated code
    /// ([`LogicalInput::bytes`] is then filled in it); `None` for code that reads the tree.
    fn schema(&self) -> Option<&Schema> {
        None
    }
    /// The layout's buffers, in the order `@L.sizes` and `@L.build` use.
    fn buffers(&self) -> Vec<BufferSpec>;
    /// `@L.sizes`: writes each buffer's byte size for `tree` into `sizes`
    /// (`sizes.len() == buffers().len()`).
    fn sizes(&self, tree: &LogicalInput<'_>, sizes: &mut [u64]);
    /// `@L.build`: packs `tree` into the buffers (each exactly its size, aligned); 0 or an
    /// error status.
    fn build(&self, tree: &LogicalInput<'_>, buffers: &mut [&mut [u8]]) -> i32;
    /// The batch entry: traces `queries[i]` into `results[i]` (in/out, initialized by the
    /// caller) for every `i`, in order; 0, or the status of the first failing query, after
    /// which it stops.
    fn batch(&self, buffers: &[&[u8]], queries: &[Ray], results: &mut [Best]) -> i32;
    /// The batch entry bound to `buffers` for many calls (one trace's blocks): what `batch`
    /// does on them, with whatever `batch` looks up per call (the JIT's root) looked up once.
    fn bind<'a>(&'a self, buffers: &'a [&'a [u8]]) -> BoundBatch<'a> {
        Box::new(move |queries, results| self.batch(buffers, queries, results))
    }
    /// The deepest tree the traversal handles without [`STATUS_STACK_OVERFLOW`], when bounded.
    fn stack_limit(&self) -> Option<usize> {
        None
    }
}

/// What a nonzero status of `@L.build` means, for messages: 1 is a value that does not fit the
/// bit range a build stores it in (`this[a:b] = e`), i.e. a tree beyond the layout's limits.
pub fn build_failure(layout: &str, status: i32) -> String {
    match status {
        1 => format!(
            "the tree does not fit layout `{layout}`: a value does not fit the bit range its build \
             stores it in (`this[a:b] = e`), e.g. a leaf with more triangles than the layout's \
             count field holds or an index beyond its index bits; build smaller leaves \
             (scion trace --leaf-size N) or pick a layout with wider fields"
        ),
        s => format!("@{layout}.build failed with status {s}"),
    }
}

/// The header `%tree` points to in `@L.sizes(%tree, %sizes)` and `@L.build(%tree, %B)`
/// (design note §3.1): the logical tree's arrays in C form. Building one is safe; whoever
/// calls native code with its address keeps the tree alive for the call.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct LogicalTreeView {
    /// The nodes in the schema's form ([`LogicalBytes::nodes`]).
    pub nodes: *const u8,
    /// Number of nodes.
    pub node_count: u32,
    /// Index of the root, `u32::MAX` for the empty tree.
    pub root: u32,
    /// `tree.primitives`: records of the prelude type the layout's primitive array holds
    /// (40-byte `Triangle`s, 36-byte `Segment`s).
    pub prims: *const u8,
    /// Number of primitives.
    pub prim_count: u32,
}

impl LogicalTreeView {
    /// The view of `bytes`, the nodes of `tree`; `None` when a count does not fit `u32`.
    pub fn new<P: Primitive>(
        tree: &LogicalTree<P>,
        bytes: &LogicalBytes,
    ) -> Option<LogicalTreeView> {
        Some(LogicalTreeView {
            nodes: bytes.nodes().as_ptr(),
            node_count: u32::try_from(bytes.node_count).ok()?,
            root: bytes.root,
            prims: tree.primitives.as_ptr().cast::<u8>(),
            prim_count: u32::try_from(tree.primitives.len()).ok()?,
        })
    }
}

/// The in/out record of closest hit's batch entry, `best = (t, primitive id)`: the caller
/// sets it to `(ray.tmax, u32::MAX)` ([`Best::start`]) and the entry leaves the nearest hit in
/// it. Laid out as the checked 8-byte result record (`t`'s bits, then the id) and as
/// [`Hit`], so that [`Packed::trace`] lets the generated code write into the hits it returns
/// ([`Best::of_hits`]) instead of copying records in and out for every block.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Best {
    /// The nearest distance found so far (`tmax` to start with).
    pub t: f32,
    /// Its primitive's id (`u32::MAX` until a hit).
    pub id: u32,
}

// `Best::of_hits` reads `Hit`s as `Best`s: the same two 4-byte fields in the same order.
const _: () = {
    assert!(std::mem::size_of::<Best>() == 8 && std::mem::size_of::<Hit>() == 8);
    assert!(std::mem::align_of::<Best>() == std::mem::align_of::<Hit>());
    assert!(std::mem::offset_of!(Best, t) == std::mem::offset_of!(Hit, t));
    assert!(std::mem::offset_of!(Best, id) == std::mem::offset_of!(Hit, prim));
};

impl Best {
    /// The record a query starts with: nothing nearer than the ray's `tmax`.
    pub fn start(ray: &Ray) -> Best {
        Best {
            t: ray.tmax,
            id: u32::MAX,
        }
    }

    /// `hits` as batch records, in place (both `#[repr(C)]` pairs of an `f32` and a `u32`, in
    /// that order, checked above; every bit pattern is valid for both).
    #[allow(unsafe_code)]
    pub fn of_hits(hits: &mut [Hit]) -> &mut [Best] {
        // SAFETY: same size, alignment and field offsets (the assertions above), plain data.
        unsafe { std::slice::from_raw_parts_mut(hits.as_mut_ptr().cast::<Best>(), hits.len()) }
    }
}

/// [`LayoutCode::bind`]'s result: the batch entry over one set of packed buffers.
pub type BoundBatch<'a> = Box<dyn Fn(&[Ray], &mut [Best]) -> i32 + Sync + 'a>;

/// A traversal that failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TraceFailure {
    /// Index of the ray in the batch.
    pub ray: usize,
    /// The batch entry's status.
    pub status: i32,
}

impl fmt::Display for TraceFailure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let what = match self.status {
            STATUS_STACK_OVERFLOW => "traversal stack overflow (the tree is deeper than the \
                                      generated code's stack)"
                .to_string(),
            s => format!("status {s}"),
        };
        write!(f, "ray {}: {what}", self.ray)
    }
}

/// A tree packed into a layout's buffers.
pub struct Packed {
    /// Each buffer's allocation (one per buffer, with room to align).
    storage: Vec<Vec<u8>>,
    /// Where each buffer starts in its allocation, and its size.
    ranges: Vec<(usize, usize)>,
    /// The plan's buffers.
    pub specs: Vec<BufferSpec>,
    /// Time of `@L.sizes`, the allocations and `@L.build`.
    pub pack_time: Duration,
    /// False for the empty tree (nothing was packed; every ray misses).
    pub nonempty: bool,
}

impl Packed {
    /// Packs `tree` for `code`; the error carries `@L.build`'s status.
    pub fn new(code: &dyn LayoutCode, tree: &LogicalTree) -> Result<Packed, String> {
        let start = Instant::now();
        let specs = code.buffers();
        if tree.is_empty() {
            return Ok(Packed {
                storage: Vec::new(),
                ranges: Vec::new(),
                specs,
                pack_time: start.elapsed(),
                nonempty: false,
            });
        }
        let bytes = match code.schema() {
            Some(schema) => Some(
                LogicalBytes::fill(tree, schema)
                    .map_err(|e| format!("the logical tree of `{}`: {e}", code.layout()))?,
            ),
            None => None,
        };
        let input = LogicalInput {
            tree,
            bytes: bytes.as_ref(),
        };
        let mut sizes = vec![0u64; specs.len()];
        code.sizes(&input, &mut sizes);
        let mut storage = Vec::with_capacity(specs.len());
        let mut ranges = Vec::with_capacity(specs.len());
        for (spec, &size) in specs.iter().zip(&sizes) {
            if !spec.align.is_power_of_two() {
                return Err(format!(
                    "buffer `{}`: alignment {} is not a power of two",
                    spec.name, spec.align
                ));
            }
            let size = usize::try_from(size)
                .map_err(|_| format!("buffer `{}`: {size} bytes do not fit", spec.name))?;
            let buf = vec![0u8; size + spec.align];
            let offset = buf.as_ptr().align_offset(spec.align);
            storage.push(buf);
            ranges.push((offset, size));
        }
        let mut views: Vec<&mut [u8]> = storage
            .iter_mut()
            .zip(&ranges)
            .map(|(b, &(o, n))| &mut b[o..o + n])
            .collect();
        let status = code.build(&input, &mut views);
        if status != STATUS_OK {
            return Err(build_failure(&code.layout(), status));
        }
        Ok(Packed {
            storage,
            ranges,
            specs,
            pack_time: start.elapsed(),
            nonempty: true,
        })
    }

    /// The buffers, aligned, each exactly its size.
    pub fn buffers(&self) -> Vec<&[u8]> {
        self.storage
            .iter()
            .zip(&self.ranges)
            .map(|(b, &(o, n))| &b[o..o + n])
            .collect()
    }

    /// Bytes of all buffers (without alignment padding).
    pub fn bytes(&self) -> usize {
        self.ranges.iter().map(|r| r.1).sum()
    }

    /// Closest hits of `rays` by the batch entry over `driver`'s threads, blocks of 64. A
    /// failing block is re-run one query at a time to name the first failing ray.
    pub fn trace(
        &self,
        code: &dyn LayoutCode,
        rays: &[Ray],
        driver: &BatchDriver,
    ) -> Result<Vec<Hit>, TraceFailure> {
        if !self.nonempty {
            return Ok(vec![Hit::MISS; rays.len()]);
        }
        let buffers = self.buffers();
        // Each block writes its own chunk of `hits` (the driver hands them out, no lock), read
        // as `Best`s: the generated code writes the hits in place, and `Hit::from_best` then
        // sets the misses' `t` (left at the ray's `tmax`) to `+inf`. No allocation or copy per
        // block, nothing gathered by the calling thread.
        let bound = code.bind(&buffers);
        let mut hits = vec![Hit::MISS; rays.len()];
        let failed: Mutex<Option<TraceFailure>> = Mutex::new(None);
        driver.run_chunks(&mut hits, 1, |begin, chunk| {
            let end = begin + chunk.len();
            let queries = &rays[begin..end];
            let results = Best::of_hits(chunk);
            for (slot, r) in results.iter_mut().zip(queries) {
                *slot = Best::start(r);
            }
            let status = bound(queries, results);
            if status != STATUS_OK {
                let first = (begin..end)
                    .find_map(|i| {
                        let mut one = [Best::start(&rays[i])];
                        let s = bound(&rays[i..i + 1], &mut one);
                        (s != STATUS_OK).then_some(TraceFailure { ray: i, status: s })
                    })
                    .unwrap_or(TraceFailure { ray: begin, status });
                let mut f = failed.lock().unwrap_or_else(|p| p.into_inner());
                if f.is_none_or(|old| first.ray < old.ray) {
                    *f = Some(first);
                }
                return;
            }
            for h in chunk.iter_mut() {
                *h = Hit::from_best(h.t, h.prim);
            }
        });
        if let Some(f) = failed.into_inner().unwrap_or_else(|p| p.into_inner()) {
            return Err(f);
        }
        Ok(hits)
    }
}

/// A [`LayoutCode`] as a [`Backend`]: packs, then traces (each `trace` packs again, so the
/// differential rows check `@L.build` on every tree).
pub struct LayoutBackend {
    code: Box<dyn LayoutCode>,
    driver: BatchDriver,
}

impl LayoutBackend {
    /// The backend of `code` on `threads` threads (0 = one per core).
    pub fn new(code: Box<dyn LayoutCode>, threads: usize) -> Result<LayoutBackend, String> {
        Ok(LayoutBackend {
            code,
            driver: BatchDriver::new(threads)?,
        })
    }
}

impl Backend for LayoutBackend {
    fn name(&self) -> String {
        format!("layout-{}", self.code.layout())
    }
    fn boxes(&self) -> crate::quantized::Boxes {
        crate::mem_interp::layout_boxes(&self.code.layout())
    }
    fn trace(&self, _: &[Triangle], tree: &LogicalTree, rays: &[Ray]) -> Result<Vec<Hit>, String> {
        let packed = Packed::new(self.code.as_ref(), tree)?;
        packed
            .trace(self.code.as_ref(), rays, &self.driver)
            .map_err(|f| f.to_string())
    }
    fn stack_limit(&self) -> Option<usize> {
        self.code.stack_limit()
    }
}
