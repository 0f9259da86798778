//! Calling a layout's generated C entry points as a C host does (docs/c-abi.md):
//! `scion_L_sizes`, then 64-byte aligned buffers of those sizes, `scion_L_build`, `scion_L_root`
//! and a batch entry `scion_A_L` over all queries. Shared by the tests of the algorithms and
//! case studies that run through the C ABI (occluded, closest point, DOP-14, shared slab).

#![allow(dead_code)]
// Calling the generated entries needs unsafe (each call carries its SAFETY note).
#![allow(unsafe_code)]

use scion_compiler::abi::EntryTarget;
use scion_host::entries;
use scion_host::jit::{program_lo, LibraryLo, LoOptions};
use scion_host::mem_interp::Program;
use scion_ir::backend::JitCode;
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::schema::LogicalBytes;
use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::{Hit, Ray};
use scion_runtime::primitive::Primitive;

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

/// Packs `tree` with the layout's entries in `code` (compiled from `lo`) and runs the batch
/// entry of algorithm `algorithm` over `queries`, updating `results` (which the caller
/// initialized); returns the batch's status. `Q` and `R` are the `#[repr(C)]` query and result
/// records, checked against the entry's sizes.
pub fn run_batch<Q: Copy, R: Copy, P: Primitive>(
    lo: &LibraryLo,
    code: &dyn JitCode,
    tree: &LogicalTree<P>,
    algorithm: &str,
    queries: &[Q],
    results: &mut [R],
) -> i32 {
    let bytes = LogicalBytes::fill(tree, &lo.entry.logical).unwrap();
    run_batch_bytes(lo, code, tree, &bytes, algorithm, queries, results)
}

/// [`run_batch`] over logical nodes filled by the caller (`LogicalBytes::fill_oriented`),
/// through the host's runner (`scion_host::entries`: the entries called as a C host calls
/// them) on the calling thread; 0, or the status of the first failing query.
pub fn run_batch_bytes<Q: Copy, R: Copy, P: Primitive>(
    lo: &LibraryLo,
    code: &dyn JitCode,
    tree: &LogicalTree<P>,
    bytes: &LogicalBytes,
    algorithm: &str,
    queries: &[Q],
    results: &mut [R],
) -> i32 {
    assert_eq!(lo.entry.algorithm, algorithm, "the entry's algorithm");
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
    let packed = entries::pack(lo, code, tree, bytes).unwrap_or_else(|e| panic!("{e}"));
    // SAFETY: `Q` and `R` are plain `#[repr(C)]` records of scalars (`Copy`, no padding the
    // entry reads: their sizes are the entry's record sizes, checked above); viewing them as
    // bytes and writing back bytes the entry produced for the same record type is sound.
    let (q, r) = unsafe {
        (
            std::slice::from_raw_parts(
                queries.as_ptr().cast::<u8>(),
                std::mem::size_of_val(queries),
            ),
            std::slice::from_raw_parts_mut(
                results.as_mut_ptr().cast::<u8>(),
                std::mem::size_of_val(results),
            ),
        )
    };
    match entries::run(lo, code, &packed, q, r, &BatchDriver::sequential()) {
        Ok(()) => 0,
        Err(entries::RunError::Query(f)) => f.status,
        Err(e) => panic!("{e}"),
    }
}

/// The closest hits of `rays` by a closest-hit algorithm's batch entry (`best` starting at
/// `(ray.tmax, u32::MAX)`); panics on a status other than 0.
pub fn closest_hits<P: Primitive>(
    lo: &LibraryLo,
    code: &dyn JitCode,
    tree: &LogicalTree<P>,
    algorithm: &str,
    rays: &[Ray],
) -> Vec<Hit> {
    let bytes = LogicalBytes::fill(tree, &lo.entry.logical).unwrap();
    closest_hits_bytes(lo, code, tree, &bytes, algorithm, rays)
}

/// [`closest_hits`] over logical nodes filled by the caller.
pub fn closest_hits_bytes<P: Primitive>(
    lo: &LibraryLo,
    code: &dyn JitCode,
    tree: &LogicalTree<P>,
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
