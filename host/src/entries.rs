//! Any algorithm's exported C entries (docs/c-abi.md), called as a C host calls them:
//! `scion_L_sizes`, one 64-byte aligned buffer per entry of the plan, `scion_L_build`,
//! `scion_L_root`, then the batch entry `scion_A_L` over blocks of queries on a
//! [`BatchDriver`]'s threads.
//!
//! Queries and results are records of the sizes the compiler's ABI computed for the algorithm
//! ([`scion_compiler::abi::EntrySig`]: the query record holds its non-tree, non-`mut`
//! parameters, the result record its `mut` ones), handed over as bytes: the runner knows no
//! algorithm. What a record means (how to make queries, how to start a result, what the right
//! answer is) is the caller's (`scion run`'s table of query kinds, the tests).

// Calling generated machine code through function pointers needs unsafe; each call says why
// it is sound.
#![allow(unsafe_code)]

use crate::contract::LogicalTreeView;
use crate::jit::{program_lo, Codegen, LibraryLo, LoOptions};
use crate::mem_interp::Program;
use scion_compiler::abi::{EntrySig, EntryTarget};
use scion_ir::backend::JitCode;
use scion_ir::types::Type;
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::oriented::OrientedOptions;
use scion_runtime::bvh::schema::LogicalBytes;
use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::{Hit, Ray};
use scion_runtime::primitive::Primitive;
use std::sync::Mutex;
use std::time::{Duration, Instant};

type SizesFn = unsafe extern "C" fn(*const LogicalTreeView, *mut u64);
type BuildFn = unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> i32;

/// An algorithm compiled for a layout, with its entries' addresses.
pub struct Entries {
    lo: LibraryLo,
    code: Box<dyn JitCode>,
    /// Time of the whole compilation (front end to machine code).
    pub compile_time: Duration,
}

/// The root reference's C type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum RootTy {
    Ptr,
    U64,
    U32,
}

/// A tree packed by the generated `scion_L_build`: the buffers and the root reference.
pub struct PackedEntries {
    buffers: Vec<(Vec<u8>, usize, usize)>,
    pub(crate) root: u64,
    pub(crate) root_ty: RootTy,
    /// Time of `sizes`, the allocations and `build`.
    pub pack_time: Duration,
    /// False for the empty tree (nothing to traverse: every query keeps its initial result).
    pub nonempty: bool,
}

impl PackedEntries {
    /// Bytes of all buffers (without alignment padding).
    pub fn bytes(&self) -> usize {
        self.buffers.iter().map(|b| b.2).sum()
    }

    pub(crate) fn table(&self) -> Vec<*const u8> {
        self.buffers
            .iter()
            .map(|(b, off, _)| b[*off..].as_ptr())
            .collect()
    }
}

/// The batch entry's address and the packed buffers' table, read by every thread.
struct Shared {
    batch: *const u8,
    table: Vec<*const u8>,
}

impl Shared {
    /// Runs the batch entry over the queries `q` (records of `qs` bytes) into `r`.
    fn call(&self, packed: &PackedEntries, qs: usize, q: &[u8], r: &mut [u8]) -> i32 {
        let count = (q.len() / qs) as u64;
        let (batch, t) = (self.batch, self.table.as_ptr());
        // SAFETY: `batch` is the exported `scion_A_L` with the C signature of docs/c-abi.md
        // for the root reference type read from `scion_L_root`; `table` holds the buffers
        // `build` filled, alive in `packed`; `q` and `r` hold `count` records of the sizes the
        // entry's signature gives (checked by the caller); the batch reads `q[0..count]` and
        // updates `r[0..count]` only.
        unsafe {
            match packed.root_ty {
                RootTy::Ptr => std::mem::transmute::<
                    *const u8,
                    unsafe extern "C" fn(
                        *const *const u8,
                        *const u8,
                        *mut u8,
                        u64,
                        u64,
                        *const u8,
                    ) -> i32,
                >(batch)(
                    t,
                    q.as_ptr(),
                    r.as_mut_ptr(),
                    0,
                    count,
                    packed.root as *const u8,
                ),
                RootTy::U64 => std::mem::transmute::<
                    *const u8,
                    unsafe extern "C" fn(
                        *const *const u8,
                        *const u8,
                        *mut u8,
                        u64,
                        u64,
                        u64,
                    ) -> i32,
                >(batch)(
                    t, q.as_ptr(), r.as_mut_ptr(), 0, count, packed.root
                ),
                RootTy::U32 => std::mem::transmute::<
                    *const u8,
                    unsafe extern "C" fn(
                        *const *const u8,
                        *const u8,
                        *mut u8,
                        u64,
                        u64,
                        u32,
                    ) -> i32,
                >(batch)(
                    t, q.as_ptr(), r.as_mut_ptr(), 0, count, packed.root as u32
                ),
            }
        }
    }
}

// SAFETY: both are addresses of immutable data for the duration of a run: finalized machine
// code (owned by `Entries`) and the packed buffers (owned by `PackedEntries`, borrowed by the
// run); the batch entry only reads the buffers, so concurrent calls share them safely.
unsafe impl Sync for Shared {}

/// Why a run did not complete.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RunError {
    /// The records or the compiled code do not fit the run (before any query ran).
    Setup(String),
    /// A query failed: the first one, with the entry's status.
    Query(BatchFailure),
}

impl std::fmt::Display for RunError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RunError::Setup(e) => f.write_str(e),
            RunError::Query(b) => write!(
                f,
                "query {}: the batch entry returned status {}{}",
                b.query,
                b.status,
                if b.status == 1 {
                    " (the traversal's stack overflowed: try a larger --stack-size)"
                } else {
                    ""
                }
            ),
        }
    }
}

/// Where a batch stopped: the first failing query and the entry's status.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BatchFailure {
    /// The query's index.
    pub query: usize,
    /// The entry's status (1: the traversal's stack overflowed).
    pub status: i32,
}

impl Entries {
    /// Compiles `program` (its layout and algorithm) to `lo` with the host entries, as `scionc
    /// -O3 --entry` does, with a traversal stack of `stack_size` entries, and to machine code
    /// by `codegen`.
    pub fn compile(
        program: &Program,
        codegen: Codegen,
        stack_size: Option<u32>,
    ) -> Result<Entries, String> {
        let start = Instant::now();
        let lo = program_lo(
            program,
            &LoOptions {
                stack_size,
                opt_level: 3,
                dsl_opt: true,
                target: EntryTarget::Host,
            },
        )?;
        let code = codegen.backend().jit(&lo.module)?;
        Ok(Entries {
            lo,
            code,
            compile_time: start.elapsed(),
        })
    }

    /// The entries' C signature (records, buffers, logical tree).
    pub fn sig(&self) -> &EntrySig {
        &self.lo.entry
    }

    /// The address of the exported function `name`.
    pub(crate) fn function(&self, name: &str) -> Result<*const u8, String> {
        function(self.code.as_ref(), name)
    }

    /// Packs `tree` (its logical nodes filled in the entry's schema) with the generated
    /// `sizes` and `build`.
    pub fn pack<P: Primitive>(&self, tree: &LogicalTree<P>) -> Result<PackedEntries, String> {
        self.pack_oriented(tree, &OrientedOptions::default())
    }

    /// [`Entries::pack`] with the rule for orienting nodes of a tree type with an oriented
    /// interior variant (the hair BVH's `OBBNode`; `scion_runtime::bvh::oriented::fit`).
    pub fn pack_oriented<P: Primitive>(
        &self,
        tree: &LogicalTree<P>,
        oriented: &OrientedOptions,
    ) -> Result<PackedEntries, String> {
        let bytes = LogicalBytes::fill_oriented(tree, &self.lo.entry.logical, oriented)?;
        pack(&self.lo, self.code.as_ref(), tree, &bytes)
    }

    /// The closest hits of `rays` by a closest-hit entry (result records `(t, id)` starting
    /// at `(ray.tmax, u32::MAX)`), on `driver`'s threads.
    pub fn closest_hits(
        &self,
        packed: &PackedEntries,
        rays: &[Ray],
        driver: &BatchDriver,
    ) -> Result<Vec<Hit>, RunError> {
        let queries = scion_runtime::query::io::rays_to_bytes(rays);
        let mut results: Vec<u8> = rays
            .iter()
            .flat_map(|r| {
                let mut b = [0u8; 8];
                b[..4].copy_from_slice(&r.tmax.to_le_bytes());
                b[4..].copy_from_slice(&u32::MAX.to_le_bytes());
                b
            })
            .collect();
        self.run(packed, &queries, &mut results, driver)?;
        Ok(results
            .chunks_exact(8)
            .map(|c| {
                let t = f32::from_le_bytes([c[0], c[1], c[2], c[3]]);
                let p = u32::from_le_bytes([c[4], c[5], c[6], c[7]]);
                Hit::from_best(t, p)
            })
            .collect())
    }

    /// Runs the batch entry over `queries` into `results` on `driver`'s threads ([`run`]).
    pub fn run(
        &self,
        packed: &PackedEntries,
        queries: &[u8],
        results: &mut [u8],
        driver: &BatchDriver,
    ) -> Result<(), RunError> {
        run(
            &self.lo,
            self.code.as_ref(),
            packed,
            queries,
            results,
            driver,
        )
    }
}

fn function(code: &dyn JitCode, name: &str) -> Result<*const u8, String> {
    code.function_ptr(name)
        .ok_or_else(|| format!("the compiled code has no `{name}`"))
}

/// Packs `tree`, whose logical nodes the caller filled in `bytes` (in the schema of the
/// entry's `logical`, e.g. `LogicalBytes::fill_oriented`), with the generated `sizes` and
/// `build` of `lo` compiled to `code`.
pub fn pack<P: Primitive>(
    lo: &LibraryLo,
    code: &dyn JitCode,
    tree: &LogicalTree<P>,
    bytes: &LogicalBytes,
) -> Result<PackedEntries, String> {
    let sig = &lo.entry;
    let start = Instant::now();
    let view = LogicalTreeView::new(tree, bytes)
        .ok_or("the tree has more nodes or primitives than a u32 counts")?;
    let root_name = sig.layout_fn("root");
    let root_ty = match lo
        .module
        .func_by_name(&root_name)
        .map(|r| lo.module.types.get(lo.module.funcs[r].results[0]).clone())
    {
        Some(Type::Ptr) => RootTy::Ptr,
        Some(Type::Int(t)) if t.bits() == 64 => RootTy::U64,
        _ => RootTy::U32,
    };
    let sizes = function(code, &sig.layout_fn("sizes"))?;
    let build = function(code, &sig.layout_fn("build"))?;
    let root = function(code, &root_name)?;
    // SAFETY: `sizes`, `build` and `root` are the layout's exported entries with the C
    // signatures of docs/c-abi.md (the root's result type read from its `lo` signature
    // above); the view describes the live tree and its filled nodes; `sizes` writes one
    // u64 per buffer of the plan into a vector of that length; each buffer handed to
    // `build` and `root` has at least the size `sizes` gave, 64-byte aligned.
    unsafe {
        let sizes = std::mem::transmute::<*const u8, SizesFn>(sizes);
        let build = std::mem::transmute::<*const u8, BuildFn>(build);
        let mut sz = vec![0u64; sig.buffers.len()];
        sizes(&view, sz.as_mut_ptr());
        let mut buffers: Vec<(Vec<u8>, usize, usize)> = sz
            .iter()
            .map(|&s| {
                let v = vec![0u8; s as usize + 128];
                let off = v.as_ptr().align_offset(64);
                (v, off, s as usize)
            })
            .collect();
        let table: Vec<*mut u8> = buffers
            .iter_mut()
            .map(|(b, off, _)| b.as_mut_ptr().add(*off))
            .collect();
        let nonempty = !tree.is_empty();
        if nonempty {
            let status = build(&view, table.as_ptr());
            if status != 0 {
                return Err(crate::contract::build_failure(&sig.layout, status));
            }
        }
        let root = match (nonempty, root_ty) {
            (false, _) => 0,
            (true, RootTy::Ptr) => std::mem::transmute::<
                *const u8,
                unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> *const u8,
            >(root)(&view, table.as_ptr()) as u64,
            (true, RootTy::U64) => std::mem::transmute::<
                *const u8,
                unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> u64,
            >(root)(&view, table.as_ptr()),
            (true, RootTy::U32) => u64::from(std::mem::transmute::<
                *const u8,
                unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> u32,
            >(root)(&view, table.as_ptr())),
        };
        Ok(PackedEntries {
            buffers,
            root,
            root_ty,
            pack_time: start.elapsed(),
            nonempty,
        })
    }
}

/// Runs the batch entry of `lo` compiled to `code` over `queries` (records of the query size,
/// back to back) into `results` (records of the result size, initialized by the caller, updated
/// in place) on `driver`'s threads, in blocks. A failing block is re-run one query at a time
/// to name the first failing query.
pub fn run(
    lo: &LibraryLo,
    code: &dyn JitCode,
    packed: &PackedEntries,
    queries: &[u8],
    results: &mut [u8],
    driver: &BatchDriver,
) -> Result<(), RunError> {
    let sig = &lo.entry;
    let (qs, rs) = (sig.query.size as usize, sig.result.size as usize);
    if qs == 0 || rs == 0 {
        return Err(RunError::Setup(format!(
            "`{}` has an empty query or result record ({qs} and {rs} bytes)",
            sig.algorithm
        )));
    }
    if queries.len() / qs * qs != queries.len()
        || results.len() / rs * rs != results.len()
        || queries.len() / qs != results.len() / rs
    {
        return Err(RunError::Setup(format!(
            "{} bytes of queries and {} bytes of results are not the same number of {qs}- \
             and {rs}-byte records",
            queries.len(),
            results.len()
        )));
    }
    if !packed.nonempty {
        return Ok(());
    }
    let shared = Shared {
        batch: function(code, &sig.batch_fn()).map_err(RunError::Setup)?,
        table: packed.table(),
    };
    let call = |q: &[u8], r: &mut [u8]| shared.call(packed, qs, q, r);
    let failed: Mutex<Option<BatchFailure>> = Mutex::new(None);
    // Each block of the driver's queries writes its own chunk of `results`.
    driver.run_chunks(results, rs, |begin, r| {
        let end = begin + r.len() / rs;
        let q = &queries[begin * qs..end * qs];
        let before = r.to_vec();
        let status = call(q, r);
        if status == 0 {
            return;
        }
        r.copy_from_slice(&before);
        let first = (0..end - begin)
            .find_map(|i| {
                let s = call(&q[i * qs..(i + 1) * qs], &mut r[i * rs..(i + 1) * rs]);
                (s != 0).then_some(BatchFailure {
                    query: begin + i,
                    status: s,
                })
            })
            .unwrap_or(BatchFailure {
                query: begin,
                status,
            });
        let mut f = failed.lock().unwrap_or_else(|p| p.into_inner());
        if f.is_none_or(|old| first.query < old.query) {
            *f = Some(first);
        }
    });
    match failed.into_inner().unwrap_or_else(|p| p.into_inner()) {
        None => Ok(()),
        Some(f) => Err(RunError::Query(f)),
    }
}
