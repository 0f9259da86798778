//! The JIT of a layout: `closest_hit.scion` specialized to a library layout by the normal
//! pipeline (`destructor-specialize`, `constructor-specialize`, the `-O3` passes, `mem-to-lo`,
//! `recursion-to-stack`, `lo-inline`) with the exported C entry points of
//! `scionc --layout L --entry closest_hit` (docs/design/backends.md §1, docs/c-abi.md),
//! compiled by Cranelift (`scion-clif`) or LLVM (`scion-llvm`, [`Codegen`]) and run through the
//! runtime contract of docs/design/specialization.md §3 as a [`LayoutCode`]. Input: a library
//! layout (file stem and layout name) and a stack size; output: native code called only
//! through its exported functions, exactly as a C program (`examples/cpp/`) calls the object
//! file: `@scion_L_sizes`, `@scion_L_build`, `@scion_L_root` and the batch entry
//! `@scion_closest_hit_L`.
//!
//! The front end compiles with the entry option ([`PassOptions::entry`]) through
//! [`scion_compiler::frontend::compile`], the call `scionc` makes, and hands back the entries' C signature
//! ([`EntrySig`]): the layout's buffers (their names, and the header's `SCION_L_BUFFER_ALIGN`,
//! at least [`BUFFER_ALIGN`], for every buffer) and the query and result records, checked to
//! be the 32-byte `Ray` and the 8-byte `(f32, u32)` hit record the host passes. The reference
//! type `R` (`u32` or `ptr`) is the result type of `@scion_L_root`. After `@scion_L_build` the
//! host calls `@scion_L_root` once and keeps the reference per packed buffer set (keyed by the
//! buffers' addresses) for the batch calls.

#![allow(unsafe_code)]

use crate::contract::{
    Best, BoundBatch, BufferSpec, LayoutCode, LogicalInput, LogicalTreeView, STATUS_OK,
};
use crate::mem_interp::{compile_program, Program};
use scion_compiler::abi::EntrySig;
pub use scion_compiler::abi::EntryTarget;
use scion_compiler::driver::cli::Emit;
use scion_compiler::driver::pipelines::for_level_with;
use scion_compiler::frontend::PassOptions;
use scion_ir::backend::{Backend, JitCode};
use scion_ir::types::{FloatTy, IntTy, Type};
use scion_ir::Module;
use scion_runtime::bvh::schema::Schema;
use scion_runtime::geom::Ray;
use std::collections::HashMap;
use std::sync::RwLock;
use std::time::{Duration, Instant};

/// The least alignment of every buffer: a cache line, so that timings do not depend on where
/// the allocator puts the nodes. The plan's own alignment (the header's
/// `SCION_L_BUFFER_ALIGN`) is used when larger.
pub const BUFFER_ALIGN: usize = 64;

/// The algorithm the harness compiles (`--entry closest_hit`).
pub const ALGORITHM: &str = "closest_hit";

/// `@scion_L_sizes(%tree, %sizes)`.
type SizesFn = unsafe extern "C" fn(*const LogicalTreeView, *mut u64);
/// `@scion_L_build(%tree, %B) -> i32`.
type BuildFn = unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> i32;
/// `@scion_L_root(%tree, %B) -> R` with `R` a `u32`.
type RootIdxFn = unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> u32;
/// The same with `R` a `u64` (the eight-wide L64 links).
type RootIdx64Fn = unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> u64;
/// The same with `R` a `ptr`.
type RootPtrFn = unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> *const u8;
/// `@scion_closest_hit_L(%B, %queries, %results, %begin, %end, %root) -> i32`, root `u32`.
type BatchIdxFn =
    unsafe extern "C" fn(*const *const u8, *const Ray, *mut [u32; 2], u64, u64, u32) -> i32;
/// The same with a `u64` root.
type BatchIdx64Fn =
    unsafe extern "C" fn(*const *const u8, *const Ray, *mut [u32; 2], u64, u64, u64) -> i32;
/// The same with a `ptr` root.
type BatchPtrFn =
    unsafe extern "C" fn(*const *const u8, *const Ray, *mut [u32; 2], u64, u64, *const u8) -> i32;

// The query record the batch entry reads: 8 `f32`s, 32 bytes.
const _: () = assert!(std::mem::size_of::<Ray>() == 32);

/// The root reference of a packed tree, as `@scion_L_root` returned it.
#[derive(Clone, Copy, Debug)]
enum Root {
    Index(u32),
    Index64(u64),
    /// An address inside one of the packed buffers (never dereferenced here).
    Pointer(usize),
}

/// The exported functions, typed by the layout's reference type.
#[derive(Clone, Copy)]
enum Refs {
    Index(RootIdxFn, BatchIdxFn),
    Index64(RootIdx64Fn, BatchIdx64Fn),
    Pointer(RootPtrFn, BatchPtrFn),
}

/// The code generator that turns the `lo` module into machine code in this process.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Codegen {
    /// Cranelift (`scion-clif`).
    Cranelift,
    /// LLVM's JIT (`scion-llvm`) at this `-O` level of LLVM's pipeline.
    Llvm(u8),
}

impl Codegen {
    /// The code generator as a [`Backend`].
    pub fn backend(self) -> Box<dyn Backend> {
        match self {
            Codegen::Cranelift => Box::new(scion_clif::Cranelift),
            Codegen::Llvm(opt_level) => Box::new(scion_llvm::Llvm { opt_level }),
        }
    }
}

/// The compiled module: keeps the machine code alive.
pub(crate) struct Code(Box<dyn JitCode>);

impl Code {
    pub(crate) fn compile(m: &Module, codegen: Codegen) -> Result<Code, String> {
        codegen.backend().jit(m).map(Code)
    }

    pub(crate) fn function_ptr(&self, name: &str) -> Option<*const u8> {
        self.0.function_ptr(name)
    }
}

// SAFETY: after `JitModule::compile` returns, the module's code and data are finalized and never
// written again; this wrapper only keeps them mapped (it is never used to define or call
// through `JitModule`'s `&mut` API), and the function pointers taken from it are plain
// re-entrant machine code whose only state is its arguments and its own stack frame.
unsafe impl Send for Code {}
// SAFETY: as above: shared access is only to immutable, finalized code.
unsafe impl Sync for Code {}

/// Closest hit specialized to one library layout and compiled to machine code.
pub struct JitClosestHit {
    _code: Code,
    layout: String,
    buffers: Vec<BufferSpec>,
    schema: Schema,
    sizes: SizesFn,
    build: BuildFn,
    refs: Refs,
    stack_size: u32,
    /// Whether `recursion-to-stack` deferred the traversal's calls (attribute
    /// `deferred_calls`).
    deferred: bool,
    /// Time of the whole compilation (front end to machine code).
    pub compile_time: Duration,
    /// Root of each packed buffer set, keyed by the buffers' addresses.
    roots: RwLock<HashMap<Vec<usize>, Root>>,
}

// SAFETY: the function pointers are addresses of finalized machine code owned by `_code`.
unsafe impl Send for JitClosestHit {}
// SAFETY: as above; the only mutable state (`roots`) is behind a lock.
unsafe impl Sync for JitClosestHit {}

/// The `-O` level [`JitClosestHit::compile`] uses: 3, the full DSL pipeline (`mem-inline`,
/// `const-fold`, `mem-cse`, `dce`) before lowering.
pub const JIT_OPT_LEVEL: u8 = 3;

/// How [`library_lo`] compiles.
#[derive(Clone, Copy, Debug)]
pub struct LoOptions {
    /// Traversal stack entries (`None`: the default, 64, or 512 where visits push all calls).
    pub stack_size: Option<u32>,
    /// The tree/mem `-O` level.
    pub opt_level: u8,
    /// False leaves out the DSL optimizations of that level (`--no-dsl-opt`).
    pub dsl_opt: bool,
    /// Host entries, or also the GPU kernels (`--target nvptx64`).
    pub target: EntryTarget,
}

/// Closest hit specialized to a library layout, lowered to `lo` with its exported entry points.
pub struct LibraryLo {
    /// The verified `lo` module.
    pub module: Module,
    /// The C signature of the entries (records, buffers).
    pub entry: EntrySig,
}

/// Compiles `closest_hit.scion` for the library layout in file `stem` named `layout`, as
/// `scionc --layout L --entry closest_hit --emit=lo` does (the one front-end path of the CPU
/// JITs and of the GPU's PTX). Errors are rendered diagnostics.
pub fn library_lo(stem: &str, layout: &str, o: &LoOptions) -> Result<LibraryLo, String> {
    program_lo(&Program::library(stem, layout)?, o)
}

/// [`library_lo`] for any program: its layout and algorithm as `--layout` and `--entry`.
pub fn program_lo(program: &Program, o: &LoOptions) -> Result<LibraryLo, String> {
    let mut pipeline = vec![
        "destructor-specialize".to_string(),
        "constructor-specialize".to_string(),
    ];
    pipeline.extend(for_level_with(o.opt_level, o.dsl_opt));
    let popts = PassOptions {
        layout: Some(program.layout.clone()),
        stack_size: o.stack_size,
        entry: Some(program.algorithm.clone()),
        entry_target: o.target,
        ..PassOptions::default()
    };
    let (module, entry, _) = compile_program(program, Emit::Lo, &pipeline, &popts)?;
    let entry = entry.ok_or("no entry signature")?;
    Ok(LibraryLo { module, entry })
}

impl JitClosestHit {
    /// The root `build` found for the buffers at the addresses `table`, if it packed them.
    fn root_of(&self, table: &[usize]) -> Option<Root> {
        self.roots
            .read()
            .unwrap_or_else(|p| p.into_inner())
            .get(table)
            .copied()
    }

    /// The batch entry over the buffers at the addresses `table`, whose root is `root`.
    fn run(&self, table: &[usize], root: Root, queries: &[Ray], results: &mut [Best]) -> i32 {
        if queries.len() != results.len() {
            return -1;
        }
        let table = table.as_ptr().cast::<*const u8>();
        // `Best` is the checked result record (`t`'s bits, then the id; `#[repr(C)]`).
        let (q, r, end) = (
            queries.as_ptr(),
            results.as_mut_ptr().cast::<[u32; 2]>(),
            queries.len() as u64,
        );
        // SAFETY: the batch entry has the checked type for the layout's reference kind;
        // `table` holds the addresses of the buffers `build` packed (alive for the call: the
        // caller's buffers, whose addresses found `root` in `roots`; `usize` and `*const u8`
        // have one layout), `root` is what `@scion_L_root` returned for them, and it reads
        // `queries[0..end]` (32-byte `Ray`s, the checked query record) and reads and writes
        // `results[0..end]` (the checked 8-byte result record), both exactly `end` long.
        unsafe {
            match (self.refs, root) {
                (Refs::Index(_, batch), Root::Index(root)) => batch(table, q, r, 0, end, root),
                (Refs::Index64(_, batch), Root::Index64(root)) => batch(table, q, r, 0, end, root),
                (Refs::Pointer(_, batch), Root::Pointer(root)) => {
                    batch(table, q, r, 0, end, root as *const u8)
                }
                _ => -1,
            }
        }
    }

    /// Compiles closest hit for the library layout in file `stem` (`pbrt`, `ptr`, ...) named
    /// `layout`, with a traversal stack of `stack_size` entries (`None`: the default, 64), at
    /// [`JIT_OPT_LEVEL`].
    pub fn compile(
        stem: &str,
        layout: &str,
        stack_size: Option<u32>,
    ) -> Result<JitClosestHit, String> {
        JitClosestHit::compile_at(stem, layout, stack_size, JIT_OPT_LEVEL)
    }

    /// As [`JitClosestHit::compile`], with the tree/mem passes of `-O{opt_level}` after the
    /// specializations.
    pub fn compile_at(
        stem: &str,
        layout: &str,
        stack_size: Option<u32>,
        opt_level: u8,
    ) -> Result<JitClosestHit, String> {
        JitClosestHit::compile_with(stem, layout, stack_size, opt_level, Codegen::Cranelift)
    }

    /// As [`JitClosestHit::compile_at`], with the machine code from `codegen`.
    pub fn compile_with(
        stem: &str,
        layout: &str,
        stack_size: Option<u32>,
        opt_level: u8,
        codegen: Codegen,
    ) -> Result<JitClosestHit, String> {
        JitClosestHit::compile_full(stem, layout, stack_size, opt_level, true, codegen)
    }

    /// As [`JitClosestHit::compile_with`]; `dsl_opt: false` leaves out the DSL optimizations of
    /// the level (`scionc --no-dsl-opt`), the baseline of `scripts/bench-dslopt.sh`.
    pub fn compile_full(
        stem: &str,
        layout: &str,
        stack_size: Option<u32>,
        opt_level: u8,
        dsl_opt: bool,
        codegen: Codegen,
    ) -> Result<JitClosestHit, String> {
        let program = Program::library(stem, layout)?;
        JitClosestHit::compile_program(&program, stack_size, opt_level, dsl_opt, codegen)
    }

    /// As [`JitClosestHit::compile_full`] for any program whose algorithm is a closest hit
    /// (`(ray: Ray, tree, best: mut (f32, u32))`) over its layout.
    pub fn compile_program(
        program: &Program,
        stack_size: Option<u32>,
        opt_level: u8,
        dsl_opt: bool,
        codegen: Codegen,
    ) -> Result<JitClosestHit, String> {
        let start = Instant::now();
        let layout = program.layout.as_str();
        let LibraryLo {
            module: m,
            entry: sig,
        } = program_lo(
            program,
            &LoOptions {
                stack_size,
                opt_level,
                dsl_opt,
                target: EntryTarget::Host,
            },
        )?;
        let ref_ty = check_entries(&m, &sig)?;
        let deferred = m
            .func_order
            .iter()
            .any(|&f| m.funcs[f].attrs.get("deferred_calls").is_some());
        let jit = Code::compile(&m, codegen)?;
        let get = |name: &str| {
            jit.function_ptr(name)
                .ok_or_else(|| format!("the JIT has no `@{name}`"))
        };
        let sizes = get(&sig.layout_fn("sizes"))?;
        let build = get(&sig.layout_fn("build"))?;
        let root = get(&sig.layout_fn("root"))?;
        let batch = get(&sig.batch_fn())?;
        // SAFETY: `check_entries` checked the `lo` signatures of the four exported functions
        // (backends.md §1, with the reference type `R` it returned), which in the host's C
        // calling convention are these function types; the code lives as long as `jit`, kept
        // in `_code`.
        let (sizes, build, refs) = unsafe {
            (
                std::mem::transmute::<*const u8, SizesFn>(sizes),
                std::mem::transmute::<*const u8, BuildFn>(build),
                match ref_ty {
                    Type::Ptr => Refs::Pointer(
                        std::mem::transmute::<*const u8, RootPtrFn>(root),
                        std::mem::transmute::<*const u8, BatchPtrFn>(batch),
                    ),
                    Type::Int(IntTy::U64) => Refs::Index64(
                        std::mem::transmute::<*const u8, RootIdx64Fn>(root),
                        std::mem::transmute::<*const u8, BatchIdx64Fn>(batch),
                    ),
                    _ => Refs::Index(
                        std::mem::transmute::<*const u8, RootIdxFn>(root),
                        std::mem::transmute::<*const u8, BatchIdxFn>(batch),
                    ),
                },
            )
        };
        let align = (sig.buffer_align() as usize).max(BUFFER_ALIGN);
        let buffers = sig
            .buffers
            .iter()
            .map(|b| BufferSpec {
                name: b.name.clone(),
                align,
            })
            .collect();
        Ok(JitClosestHit {
            _code: jit,
            layout: layout.to_string(),
            buffers,
            schema: sig.logical.clone(),
            sizes,
            build,
            refs,
            stack_size: stack_size.unwrap_or(64),
            deferred,
            compile_time: start.elapsed(),
            roots: RwLock::new(HashMap::new()),
        })
    }
}

/// Checks what the host's calls rely on: the query record is a `Ray` (eight `f32`s, 32 bytes),
/// the result record the `(f32, u32)` hit record (8 bytes), and the four exported functions of
/// `sig` have the `lo` signatures of backends.md §1. Returns the reference type `R`: `ptr`,
/// `u32` or `u64`.
fn check_entries(m: &Module, sig: &EntrySig) -> Result<Type, String> {
    let f32t = Type::Float(FloatTy::F32);
    let (u32t, u64t, i32t) = (
        Type::Int(IntTy::U32),
        Type::Int(IntTy::U64),
        Type::Int(IntTy::I32),
    );
    let types = |fields: &[scion_compiler::abi::record::Field]| -> Vec<Type> {
        fields.iter().map(|f| f.ty.clone()).collect()
    };
    if sig.query.size != 32 || types(&sig.query.fields) != vec![f32t.clone(); 8] {
        return Err(format!(
            "`{}`'s query record is not a 32-byte `Ray`: {:?}",
            sig.algorithm, sig.query
        ));
    }
    if sig.result.size != 8 || types(&sig.result.fields) != [f32t, u32t] {
        return Err(format!(
            "`{}`'s result record is not the 8-byte `(f32, u32)` hit: {:?}",
            sig.algorithm, sig.result
        ));
    }
    let signature = |name: &str| -> Result<(Vec<Type>, Vec<Type>), String> {
        let f = m
            .func_by_name(name)
            .filter(|&f| m.funcs[f].attrs.get("export").is_some())
            .ok_or_else(|| format!("the lo module exports no `@{name}`"))?;
        let ty = |t: &scion_ir::TypeId| m.types.get(*t).clone();
        Ok((
            m.funcs[f].params.iter().map(ty).collect(),
            m.funcs[f].results.iter().map(ty).collect(),
        ))
    };
    let (_, root_results) = signature(&sig.layout_fn("root"))?;
    let r = match root_results.as_slice() {
        [t @ (Type::Ptr | Type::Int(IntTy::U32 | IntTy::U64))] => t.clone(),
        other => {
            return Err(format!(
                "`@{}` returns {other:?}, not one `u32` or `ptr` reference",
                sig.layout_fn("root")
            ))
        }
    };
    let want = [
        (sig.layout_fn("sizes"), vec![Type::Ptr; 2], vec![]),
        (
            sig.layout_fn("build"),
            vec![Type::Ptr; 2],
            vec![i32t.clone()],
        ),
        (sig.layout_fn("root"), vec![Type::Ptr; 2], vec![r.clone()]),
        (
            sig.batch_fn(),
            vec![
                Type::Ptr,
                Type::Ptr,
                Type::Ptr,
                u64t.clone(),
                u64t,
                r.clone(),
            ],
            vec![i32t],
        ),
    ];
    for (name, params, results) in want {
        let (p, res) = signature(&name)?;
        if p != params || res != results {
            return Err(format!(
                "`@{name}` has signature {p:?} -> {res:?}, expected {params:?} -> {results:?}"
            ));
        }
    }
    Ok(r)
}

impl LayoutCode for JitClosestHit {
    fn layout(&self) -> String {
        self.layout.clone()
    }
    fn buffers(&self) -> Vec<BufferSpec> {
        self.buffers.clone()
    }
    fn schema(&self) -> Option<&Schema> {
        Some(&self.schema)
    }
    fn sizes(&self, tree: &LogicalInput<'_>, sizes: &mut [u64]) {
        let Some(view) = tree.bytes.and_then(|b| LogicalTreeView::new(tree.tree, b)) else {
            sizes.fill(u64::MAX);
            return;
        };
        let mut out = vec![0u64; self.buffers.len().max(1)];
        // SAFETY: `@scion_L_sizes` has the checked type; `view` points into `tree`, alive for
        // the call; `out` has one slot per buffer of the plan.
        unsafe { (self.sizes)(&view, out.as_mut_ptr()) };
        for (s, o) in sizes.iter_mut().zip(out) {
            *s = o;
        }
    }
    fn build(&self, tree: &LogicalInput<'_>, buffers: &mut [&mut [u8]]) -> i32 {
        let Some(view) = tree.bytes.and_then(|b| LogicalTreeView::new(tree.tree, b)) else {
            return -1;
        };
        if buffers.len() != self.buffers.len() {
            return -1;
        }
        let table: Vec<*mut u8> = buffers.iter_mut().map(|b| b.as_mut_ptr()).collect();
        // SAFETY: `@scion_L_build` has the checked type; `view` describes the live `tree`;
        // `table` holds one address per buffer, each buffer exactly the size `@scion_L_sizes`
        // asked for (the contract of `LayoutCode::build`), so the generated stores stay inside
        // them.
        let status = unsafe { (self.build)(&view, table.as_ptr()) };
        if status != STATUS_OK {
            return status;
        }
        // SAFETY: `@scion_L_root` has the checked type; it reads `view` (live) and re-places
        // the nodes into the buffers `@scion_L_build` just packed, writing the same bytes.
        let root = unsafe {
            match self.refs {
                Refs::Index(root, _) => Root::Index(root(&view, table.as_ptr())),
                Refs::Index64(root, _) => Root::Index64(root(&view, table.as_ptr())),
                Refs::Pointer(root, _) => Root::Pointer(root(&view, table.as_ptr()) as usize),
            }
        };
        let key = buffers.iter().map(|b| b.as_ptr() as usize).collect();
        self.roots
            .write()
            .unwrap_or_else(|p| p.into_inner())
            .insert(key, root);
        status
    }
    fn batch(&self, buffers: &[&[u8]], queries: &[Ray], results: &mut [Best]) -> i32 {
        let table: Vec<usize> = buffers.iter().map(|b| b.as_ptr() as usize).collect();
        match self.root_of(&table) {
            Some(root) => self.run(&table, root, queries, results),
            None => -1,
        }
    }
    fn bind<'a>(&'a self, buffers: &'a [&'a [u8]]) -> BoundBatch<'a> {
        // The root is looked up once for the whole trace, not under the shared lock once per
        // block: with several threads, the lock's counter went from core to core every block.
        let table: Vec<usize> = buffers.iter().map(|b| b.as_ptr() as usize).collect();
        let root = self.root_of(&table);
        Box::new(move |queries, results| match root {
            Some(root) => self.run(&table, root, queries, results),
            None => -1,
        })
    }
    /// A node at depth `k` (root 1) runs with at most `k - 1` pending entries and pushes one
    /// (`recursion-to-stack` visits the first of its two children at once), so trees of depth
    /// up to `stack_size + 1` never overflow. A traversal whose calls are deferred pushes all
    /// of a node's children: no depth bound then (an overflow is still reported).
    fn stack_limit(&self) -> Option<usize> {
        (!self.deferred).then_some(self.stack_size as usize + 1)
    }
}
