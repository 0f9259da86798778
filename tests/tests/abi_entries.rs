//! The exported entry points of `scionc --layout L --entry closest_hit` (docs/design/
//! backends.md §1), JIT-compiled by Cranelift and called exactly as a C program calls them:
//! `scion_L_sizes`, one aligned allocation per buffer, `scion_L_build`, `scion_L_root`, then
//! `scion_closest_hit_L` over a few ranges of the rays. The hits must equal the runtime's
//! reference bit for bit, for pbrt (`u32` references) and ptr (`ptr` references), on a real
//! scene (`teapot` from the repository's `scenes/`).

#![allow(unsafe_code)]

use scion_clif::JitModule;
use scion_compiler::driver::cli::Emit;
use scion_compiler::driver::pipelines::for_level;
use scion_compiler::frontend::PassOptions;
use scion_host::contract::LogicalTreeView;
use scion_host::mem_interp::compile_library;
use scion_ir::diag::SourceMap;
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::schema::{LogicalBytes, Schema};
use scion_runtime::bvh::{build_sah_binned, LogicalTree, SahOptions};
use scion_runtime::geom::{Hit, Ray};
use scion_runtime::query::{hits_checksum, primary_rays_n, secondary_rays};
use scion_runtime::reference::closest_hits_tree;
use scion_runtime::scene::{gen, Scene};
use scion_tests::cases::real_scene;

type SizesFn = unsafe extern "C" fn(*const LogicalTreeView, *mut u64);
type BuildFn = unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> i32;
type RootIdxFn = unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> u32;
type RootPtrFn = unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> *const u8;
type BatchIdxFn =
    unsafe extern "C" fn(*const *mut u8, *const Ray, *mut [u32; 2], u64, u64, u32) -> i32;
type BatchPtrFn =
    unsafe extern "C" fn(*const *mut u8, *const Ray, *mut [u32; 2], u64, u64, *const u8) -> i32;

/// The `lo` text of `scionc -O2 --emit=lo --layout NAME --entry closest_hit`.
fn entries_lo(stem: &str, layout: &str) -> (String, Schema) {
    let mut pipeline = vec![
        "destructor-specialize".to_string(),
        "constructor-specialize".to_string(),
    ];
    pipeline.extend(for_level(2));
    let popts = PassOptions {
        layout: Some(layout.to_string()),
        entry: Some("closest_hit".to_string()),
        ..PassOptions::default()
    };
    let (m, entry, schema) =
        compile_library(stem, Emit::Lo, &pipeline, &popts).unwrap_or_else(|e| panic!("{e}"));
    let entry = entry.expect("--entry gives the entries' signature");
    assert_eq!(
        Some(&entry.logical),
        schema.as_ref(),
        "one logical tree per layout"
    );
    (scion_ir::print_module(&m), entry.logical)
}

fn jit(lo: &str) -> JitModule {
    let mut sources = SourceMap::new();
    let file = sources.add("<lo>", lo.to_string());
    let m = scion_ir::parse_module(lo, file).expect("the printed lo parses back");
    scion_ir::verify(&m).expect("the entries verify");
    JitModule::compile(&m).expect("Cranelift compiles the module")
}

/// An allocation of `size` bytes aligned to `align` (at least one byte so the address is real).
struct Aligned {
    bytes: Vec<u8>,
    offset: usize,
}

impl Aligned {
    fn new(size: usize, align: usize) -> Aligned {
        let mut bytes = vec![0u8; size + align];
        let offset = bytes.as_mut_ptr().align_offset(align);
        Aligned { bytes, offset }
    }
    fn ptr(&mut self) -> *mut u8 {
        self.bytes[self.offset..].as_mut_ptr()
    }
}

/// Runs the four entries of `layout` on `tree` and `rays` the way a C host does.
fn trace_with_entries(stem: &str, layout: &str, tree: &LogicalTree, rays: &[Ray]) -> Vec<Hit> {
    let (lo, schema) = entries_lo(stem, layout);
    let code = jit(&lo);
    let f = |name: &str| {
        code.function_ptr(name)
            .unwrap_or_else(|| panic!("no `@{name}` in the JIT"))
    };
    let bytes = LogicalBytes::fill(tree, &schema).expect("the runtime fills the schema");
    let view = LogicalTreeView::new(tree, &bytes).expect("a tree the view can describe");
    let pointer_refs = lo.contains(&format!(
        "func @scion_{layout}_root(%0: ptr, %1: ptr) -> (ptr)"
    ));
    // SAFETY: the signatures are those of docs/design/backends.md §1, which the lo text shows
    // (`@scion_L_sizes(ptr, ptr)`, `@scion_L_build(ptr, ptr) -> (i32)`, the root and batch
    // entries with the reference type checked just above).
    let (sizes, build) = unsafe {
        (
            std::mem::transmute::<*const u8, SizesFn>(f(&format!("scion_{layout}_sizes"))),
            std::mem::transmute::<*const u8, BuildFn>(f(&format!("scion_{layout}_build"))),
        )
    };
    // The buffer count is the header's SCION_L_BUFFER_COUNT; 16 slots is more than any layout.
    let mut sz = [u64::MAX; 16];
    // SAFETY: `view` describes the live tree; `sz` has room for every buffer.
    unsafe { sizes(&view, sz.as_mut_ptr()) };
    let count = sz.iter().take_while(|&&s| s != u64::MAX).count();
    assert!(count > 0, "{layout}: no buffer sizes");
    let mut bufs: Vec<Aligned> = sz[..count]
        .iter()
        .map(|&s| Aligned::new(s as usize, 64))
        .collect();
    let table: Vec<*mut u8> = bufs.iter_mut().map(Aligned::ptr).collect();
    // SAFETY: each buffer has the size `scion_L_sizes` asked for and is 64-byte aligned.
    let status = unsafe { build(&view, table.as_ptr()) };
    assert_eq!(status, 0, "{layout}: build status");
    let mut records: Vec<[u32; 2]> = rays.iter().map(|r| [r.tmax.to_bits(), u32::MAX]).collect();
    let n = rays.len() as u64;
    let ranges = [(0, n / 3), (n / 3, n / 2), (n / 2, n)];
    if pointer_refs {
        // SAFETY: as above, with a `ptr` reference.
        let root = unsafe {
            std::mem::transmute::<*const u8, RootPtrFn>(f(&format!("scion_{layout}_root")))
        };
        // SAFETY: the tree was packed into `table` by `build`.
        let r = unsafe { root(&view, table.as_ptr()) };
        let inside = bufs.iter().zip(&sz).any(|(b, &s)| {
            (r as usize) >= b.bytes.as_ptr() as usize + b.offset
                && (r as usize) < b.bytes.as_ptr() as usize + b.offset + s as usize
        });
        assert!(inside, "{layout}: the root address is not in a buffer");
        // SAFETY: the batch entry's signature with a `ptr` root (checked above).
        let batch = unsafe {
            std::mem::transmute::<*const u8, BatchPtrFn>(f(&format!("scion_closest_hit_{layout}")))
        };
        for (b, e) in ranges {
            // SAFETY: `rays` and `records` have `n` elements; the buffers hold the packed tree.
            let s = unsafe { batch(table.as_ptr(), rays.as_ptr(), records.as_mut_ptr(), b, e, r) };
            assert_eq!(s, 0, "{layout}: batch status");
        }
    } else {
        // SAFETY: as above, with a `u32` reference.
        let root = unsafe {
            std::mem::transmute::<*const u8, RootIdxFn>(f(&format!("scion_{layout}_root")))
        };
        // SAFETY: the tree was packed into `table` by `build`.
        let r = unsafe { root(&view, table.as_ptr()) };
        // SAFETY: the batch entry's signature with a `u32` root.
        let batch = unsafe {
            std::mem::transmute::<*const u8, BatchIdxFn>(f(&format!("scion_closest_hit_{layout}")))
        };
        for (b, e) in ranges {
            // SAFETY: as for the pointer case.
            let s = unsafe { batch(table.as_ptr(), rays.as_ptr(), records.as_mut_ptr(), b, e, r) };
            assert_eq!(s, 0, "{layout}: batch status");
        }
    }
    records
        .iter()
        .map(|r| Hit::from_best(f32::from_bits(r[0]), r[1]))
        .collect()
}

fn scene() -> Scene {
    real_scene("teapot").unwrap_or_else(|e| panic!("the real scene teapot: {e}"))
}

#[test]
fn exported_entries_trace_like_the_reference() {
    let scene = scene();
    let tree = build_sah_binned(&scene.triangles, &SahOptions::default());
    let mut rays = primary_rays_n(scene.bounds(), 5000, 1).unwrap();
    rays.extend(secondary_rays(scene.bounds(), 3000, 2));
    let want = closest_hits_tree(&tree, &rays, &BatchDriver::new(2).unwrap());
    assert!(want.iter().any(|h| h.is_hit()));
    for (stem, layout) in [("pbrt", "LinearBVH"), ("ptr", "PtrBVH")] {
        let got = trace_with_entries(stem, layout, &tree, &rays);
        let differ = got.iter().zip(&want).position(|(g, w)| !g.bit_eq(w));
        assert_eq!(differ, None, "{layout}: first differing ray");
        assert_eq!(hits_checksum(&got), hits_checksum(&want));
    }
}

#[test]
fn non_exported_functions_are_local_but_the_entries_are_callable() {
    // The module has export functions, so the backend keeps the rest local; the JIT still
    // finds the entries by name.
    let (lo, _) = entries_lo("pbrt", "LinearBVH");
    assert!(
        lo.contains("func @scion_LinearBVH_root(%0: ptr, %1: ptr) -> (u32) attributes {export}")
    );
    let code = jit(&lo);
    for name in [
        "scion_LinearBVH_sizes",
        "scion_LinearBVH_build",
        "scion_closest_hit_LinearBVH",
    ] {
        assert!(code.function_ptr(name).is_some(), "{name}");
    }
}

#[test]
fn the_root_of_an_empty_tree_is_zero() {
    use scion_ir::interp::Val;
    use scion_ir::types::IntTy;
    let tree = build_sah_binned(&gen::empty().triangles, &SahOptions::default());
    assert!(tree.is_empty());
    let addr = |p: *const u8| Val::Int(p as usize as i128, IntTy::U64);
    for (stem, layout) in [("pbrt", "LinearBVH"), ("ptr", "PtrBVH")] {
        let (lo, schema) = entries_lo(stem, layout);
        let code = jit(&lo);
        let bytes = LogicalBytes::fill(&tree, &schema).unwrap();
        let view = LogicalTreeView::new(&tree, &bytes).unwrap();
        let mut sizes = [0u64; 16];
        let sizes_ptr = sizes.as_mut_ptr() as *const u8;
        let view_ptr = &view as *const LogicalTreeView as *const u8;
        code.call(
            &format!("scion_{layout}_sizes"),
            &[addr(view_ptr), addr(sizes_ptr)],
        )
        .unwrap();
        let mut bufs: Vec<Aligned> = sizes
            .iter()
            .map(|&s| Aligned::new(s as usize, 64))
            .collect();
        let table: Vec<*mut u8> = bufs.iter_mut().map(Aligned::ptr).collect();
        let table_ptr = table.as_ptr() as *const u8;
        let build = code
            .call(
                &format!("scion_{layout}_build"),
                &[addr(view_ptr), addr(table_ptr)],
            )
            .unwrap();
        assert!(
            matches!(build.as_slice(), [Val::Int(0, IntTy::I32)]),
            "{layout}: build status {build:?}"
        );
        let root = code
            .call(
                &format!("scion_{layout}_root"),
                &[addr(view_ptr), addr(table_ptr)],
            )
            .unwrap();
        let zero = match root.first() {
            Some(Val::Int(v, _)) => *v == 0,
            other => panic!("{layout}: root {other:?}"),
        };
        assert!(zero, "{layout}: the empty tree's root is {root:?}, not 0");
    }
}
