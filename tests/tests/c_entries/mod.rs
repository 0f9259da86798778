//! Calling a layout's generated C entry points as a C host does (docs/c-abi.md):
//! `scion_L_sizes`, then 64-byte aligned buffers of those sizes, `scion_L_build`, `scion_L_root`
//! and a batch entry `scion_A_L` over all queries. Shared by the tests of the algorithms and
//! case studies that run through the C ABI (occluded, closest point, DOP-14, shared slab).

#![allow(dead_code)]
// Calling the generated entries needs unsafe (each call carries its SAFETY note).
#![allow(unsafe_code)]

use scion_compiler::abi::EntryTarget;
use scion_host::contract::LogicalTreeView;
use scion_host::jit::{program_lo, LibraryLo, LoOptions};
use scion_host::mem_interp::Program;
use scion_ir::backend::JitCode;
use scion_ir::types::Type;
use scion_runtime::bvh::schema::LogicalBytes;
use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::{Hit, Ray};

type SizesFn = unsafe extern "C" fn(*const LogicalTreeView, *mut u64);
type BuildFn = unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> i32;

/// The program of `files` (paths from the repository root) with `layout` and `algorithm`.
pub fn program(files: &[&str], layout: &str, algorithm: &str) -> Program {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let read = |rel: &str| std::fs::read_to_string(root.join(rel)).expect(rel);
    Program {
        files: files
            .iter()
            .map(|f| (f.rsplit('/').next().unwrap().to_string(), read(f)))
            .collect(),
        layout: layout.to_string(),
        algorithm: algorithm.to_string(),
    }
}

/// `program` compiled to `lo` with its C entries for the host, as `scionc -O3` does, with a
/// stack of 4096 entries (the hard cases include a chain a thousand nodes deep).
pub fn host_lo(program: &Program) -> LibraryLo {
    host_lo_stack(program, 4096)
}

/// [`host_lo`] with a stack of `entries` (a wide reference takes more of the thread's stack
/// per entry).
pub fn host_lo_stack(program: &Program, entries: u32) -> LibraryLo {
    program_lo(
        program,
        &LoOptions {
            stack_size: Some(entries),
            opt_level: 3,
            dsl_opt: true,
            target: EntryTarget::Host,
        },
    )
    .unwrap_or_else(|e| panic!("{}: {e}", program.layout))
}

/// 64-byte aligned zeroed bytes (at least one block, so every buffer has a real address).
fn aligned(size: usize) -> (Vec<u8>, usize) {
    let bytes = vec![0u8; size + 128];
    let off = bytes.as_ptr().align_offset(64);
    (bytes, off)
}

/// Packs `tree` with the layout's entries in `code` (compiled from `lo`) and runs the batch
/// entry of algorithm `algorithm` over `queries`, updating `results` (which the caller
/// initialized); returns the batch's status. `Q` and `R` are the `#[repr(C)]` query and result
/// records, checked against the entry's sizes.
pub fn run_batch<Q, R>(
    lo: &LibraryLo,
    code: &dyn JitCode,
    tree: &LogicalTree,
    algorithm: &str,
    queries: &[Q],
    results: &mut [R],
) -> i32 {
    let bytes = LogicalBytes::fill(tree, &lo.entry.logical).unwrap();
    run_batch_bytes(lo, code, tree, &bytes, algorithm, queries, results)
}

/// [`run_batch`] over logical nodes filled by the caller (`LogicalBytes::fill_oriented`).
pub fn run_batch_bytes<Q, R>(
    lo: &LibraryLo,
    code: &dyn JitCode,
    tree: &LogicalTree,
    bytes: &LogicalBytes,
    algorithm: &str,
    queries: &[Q],
    results: &mut [R],
) -> i32 {
    assert_eq!(
        std::mem::size_of::<Q>() as u64,
        lo.entry.query.size,
        "query record"
    );
    assert_eq!(
        std::mem::size_of::<R>() as u64,
        lo.entry.result.size,
        "result record"
    );
    assert_eq!(queries.len(), results.len());
    let layout = &lo.entry.layout;
    let f = |name: String| {
        code.function_ptr(&name)
            .unwrap_or_else(|| panic!("no `@{name}`"))
    };
    let root_name = format!("scion_{layout}_root");
    // The root reference's C type: a pointer, a 64-bit or a 32-bit integer.
    let root_ty = lo
        .module
        .func_by_name(&root_name)
        .map(|r| lo.module.types.get(lo.module.funcs[r].results[0]).clone());
    let view = LogicalTreeView::new(tree, bytes).unwrap();
    let n = queries.len() as u64;
    // SAFETY: the entries have the signatures of docs/c-abi.md for this layout's reference type
    // (the root reference's type is what `scion_L_root` returns); the view describes the live
    // tree; every buffer has the size `sizes` gave and is 64-byte aligned; `queries` and
    // `results` have `n` elements of the record sizes the entry was checked to have above.
    unsafe {
        let sizes = std::mem::transmute::<*const u8, SizesFn>(f(format!("scion_{layout}_sizes")));
        let build = std::mem::transmute::<*const u8, BuildFn>(f(format!("scion_{layout}_build")));
        let mut sz = vec![0u64; lo.entry.buffers.len()];
        sizes(&view, sz.as_mut_ptr());
        let mut bufs: Vec<(Vec<u8>, usize)> = sz.iter().map(|&s| aligned(s as usize)).collect();
        let table: Vec<*mut u8> = bufs
            .iter_mut()
            .map(|(b, o)| b.as_mut_ptr().add(*o))
            .collect();
        assert_eq!(build(&view, table.as_ptr()), 0, "{layout}: build");
        let batch = f(format!("scion_{algorithm}_{layout}"));
        let root = f(root_name);
        let (q, r) = (queries.as_ptr(), results.as_mut_ptr());
        match root_ty {
            Some(Type::Ptr) => batch_from::<*const u8, Q, R>(root, batch, &view, &table, q, r, n),
            Some(Type::Int(t)) if t.bits() == 64 => {
                batch_from::<u64, Q, R>(root, batch, &view, &table, q, r, n)
            }
            _ => batch_from::<u32, Q, R>(root, batch, &view, &table, q, r, n),
        }
    }
}

/// Runs batch entry `batch` from the root reference (of C type `Rt`) that `root` gives.
///
/// # Safety
/// `root` and `batch` are a layout's `scion_L_root` and `scion_A_L` with reference type `Rt`;
/// `table` holds the built buffers; `q` and `r` have `n` records of the entry's sizes.
unsafe fn batch_from<Rt, Q, R>(
    root: *const u8,
    batch: *const u8,
    view: &LogicalTreeView,
    table: &[*mut u8],
    q: *const Q,
    r: *mut R,
    n: u64,
) -> i32 {
    let root = std::mem::transmute::<
        *const u8,
        unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> Rt,
    >(root);
    let batch = std::mem::transmute::<
        *const u8,
        unsafe extern "C" fn(*const *const u8, *const Q, *mut R, u64, u64, Rt) -> i32,
    >(batch);
    let ctable: Vec<*const u8> = table.iter().map(|&p| p as *const u8).collect();
    let start = root(view, table.as_ptr());
    batch(ctable.as_ptr(), q, r, 0, n, start)
}

/// The closest hits of `rays` by a closest-hit algorithm's batch entry (`best` starting at
/// `(ray.tmax, u32::MAX)`); panics on a status other than 0.
pub fn closest_hits(
    lo: &LibraryLo,
    code: &dyn JitCode,
    tree: &LogicalTree,
    algorithm: &str,
    rays: &[Ray],
) -> Vec<Hit> {
    let bytes = LogicalBytes::fill(tree, &lo.entry.logical).unwrap();
    closest_hits_bytes(lo, code, tree, &bytes, algorithm, rays)
}

/// [`closest_hits`] over logical nodes filled by the caller.
pub fn closest_hits_bytes(
    lo: &LibraryLo,
    code: &dyn JitCode,
    tree: &LogicalTree,
    bytes: &LogicalBytes,
    algorithm: &str,
    rays: &[Ray],
) -> Vec<Hit> {
    let mut best: Vec<(f32, u32)> = rays.iter().map(|r| (r.tmax, u32::MAX)).collect();
    let status = run_batch_bytes(lo, code, tree, bytes, algorithm, rays, &mut best);
    assert_eq!(status, 0, "{algorithm}: batch status");
    best.into_iter()
        .map(|(t, p)| Hit::from_best(t, p))
        .collect()
}
