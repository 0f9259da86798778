//! The JIT of a layout: `closest_hit.scion` specialized to a library layout by the normal
//! pipeline (`destructor-specialize`, `constructor-specialize`, the `-O3` passes, `mem-to-lo`,
//! `recursion-to-stack`, `lo-inline`), compiled by Cranelift (`scion-clif`) or LLVM
//! (`scion-llvm`, [`Codegen`]) and run through the runtime contract of
//! docs/design/specialization.md §3 as a [`LayoutCode`]. Input: a library
//! layout (file stem and layout name) and a stack size; output: native `@L.sizes`, `@L.build`
//! and the batch entry.
//!
//! The batch entry is generated here as `lo` ([`batch_entry`]) and compiled with the rest:
//! `@closest_hit.L.batch(%B, %queries, %results, %begin: u64, %end: u64, %root) -> (i32)` loads
//! query `i` (a 32-byte `Ray`: origin, direction, tmin, tmax), calls `@closest_hit(%B, ray,
//! %root, &results[i])` (the 8-byte result record `(f32, u32)`, in/out) and stops at the first
//! nonzero status. It deviates from design note §3 in one point: the root reference is a
//! parameter, since the host finds it after packing. The host calls the entries through typed
//! `extern "C"` pointers whose signatures are checked against the `lo` functions first. The
//! root reference is what the generated `@L.node` returns for the logical root: after
//! `@L.build`, `@L.node` runs once more with fresh counters (placing every node at the same
//! place again) and its result is kept per packed buffer set (an integer reference as is, a
//! pointer as buffer + offset).

#![allow(unsafe_code)]

use crate::contract::{BufferSpec, LayoutCode, LogicalTreeView, STATUS_OK};
use crate::mem_interp::layout_source;
use crate::oracle::{CLOSEST_HIT, CLOSEST_HIT_NAME};
use scion_compiler::driver::cli::Emit;
use scion_compiler::driver::pipelines::for_level_with;
use scion_compiler::driver::session::{PRELUDE, PRELUDE_NAME};
use scion_compiler::frontend::{self, Frontend, PassOptions};
use scion_ir::diag::SourceMap;
use scion_ir::op::OpKind;
use scion_ir::types::{FloatTy, IntTy, Type};
use scion_ir::Module;
use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::Ray;
use std::collections::HashMap;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Alignment of every buffer: at least any alignment a library layout asks for (the `lo`
/// module does not carry the plan's alignments).
pub const BUFFER_ALIGN: usize = 64;

/// `@L.sizes(%tree, %sizes)`.
type SizesFn = unsafe extern "C" fn(*const LogicalTreeView, *mut u64);
/// `@L.build(%tree, %B) -> i32`.
type BuildFn = unsafe extern "C" fn(*const LogicalTreeView, *const *mut u8) -> i32;
/// `@L.node(%tree, %B, %i, %counter, %cursor, %status) -> R` with `R` a `u32` or a `ptr`.
type NodeIdxFn = unsafe extern "C" fn(
    *const LogicalTreeView,
    *const *mut u8,
    u32,
    *mut u32,
    *mut u32,
    *mut i32,
) -> u32;
type NodePtrFn = unsafe extern "C" fn(
    *const LogicalTreeView,
    *const *mut u8,
    u32,
    *mut u32,
    *mut u32,
    *mut i32,
) -> *const u8;
/// `@closest_hit.L.batch(%B, %queries, %results, %begin, %end, %root) -> i32`, root `u32`.
type BatchIdxFn =
    unsafe extern "C" fn(*const *const u8, *const Ray, *mut [u32; 2], u64, u64, u32) -> i32;
/// The same with a `ptr` root.
type BatchPtrFn =
    unsafe extern "C" fn(*const *const u8, *const Ray, *mut [u32; 2], u64, u64, *const u8) -> i32;

// The query record the batch entry reads: 8 `f32`s, 32 bytes.
const _: () = assert!(std::mem::size_of::<Ray>() == 32);

/// The kind of the layout's reference type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum RefKind {
    /// `u32` (an index).
    Index,
    /// `ptr` (an address).
    Pointer,
}

/// Where a packed tree's root is.
#[derive(Clone, Copy, Debug)]
enum Root {
    Index(u32),
    /// Buffer index and byte offset.
    Pointer(usize, usize),
}

/// The code generator that turns the `lo` module into machine code in this process.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Codegen {
    /// Cranelift (`scion-clif`).
    Cranelift,
    /// LLVM's JIT (`scion-llvm`) at this `-O` level of LLVM's pipeline.
    Llvm(u8),
}

/// The compiled module: keeps the machine code alive.
enum Code {
    Cranelift(Box<scion_clif::JitModule>),
    Llvm(scion_llvm::JitModule),
}

impl Code {
    fn compile(m: &Module, codegen: Codegen) -> Result<Code, String> {
        Ok(match codegen {
            Codegen::Cranelift => {
                let jit = scion_clif::JitModule::compile(m).map_err(|e| e.to_string())?;
                Code::Cranelift(Box::new(jit))
            }
            Codegen::Llvm(level) => {
                Code::Llvm(scion_llvm::JitModule::compile(m, level).map_err(|e| e.to_string())?)
            }
        })
    }

    fn function_ptr(&self, name: &str) -> Option<*const u8> {
        match self {
            Code::Cranelift(j) => j.function_ptr(name),
            Code::Llvm(j) => j.function_ptr(name),
        }
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
    buffers: usize,
    refs: RefKind,
    sizes: SizesFn,
    build: BuildFn,
    node: *const u8,
    trace: *const u8,
    stack_size: u32,
    /// Time of the whole compilation (front end to machine code).
    pub compile_time: Duration,
    /// Root of each packed buffer set, keyed by the buffers' addresses.
    roots: Mutex<HashMap<Vec<usize>, Root>>,
}

// SAFETY: the raw pointers are addresses of finalized machine code owned by `_code`.
unsafe impl Send for JitClosestHit {}
// SAFETY: as above; the only mutable state (`roots`) is behind a mutex.
unsafe impl Sync for JitClosestHit {}

/// The `-O` level [`JitClosestHit::compile`] uses: 3, the full DSL pipeline (`mem-inline`,
/// `const-fold`, `mem-cse`, `dce`) before lowering.
pub const JIT_OPT_LEVEL: u8 = 3;

impl JitClosestHit {
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
        let start = Instant::now();
        let text = layout_source(stem).ok_or_else(|| format!("no library layout `{stem}`"))?;
        let mut sources = SourceMap::new();
        let prelude = [sources.add(PRELUDE_NAME, PRELUDE)];
        let inputs = [
            sources.add(CLOSEST_HIT_NAME, CLOSEST_HIT),
            sources.add(format!("library/layouts/{stem}.scion"), text),
        ];
        let fe = Frontend {
            sources: &sources,
            prelude: &prelude,
            inputs: &inputs,
        };
        let mut pipeline = vec![
            "destructor-specialize".to_string(),
            "constructor-specialize".to_string(),
        ];
        pipeline.extend(for_level_with(opt_level, dsl_opt));
        let popts = PassOptions {
            layout: Some(layout.to_string()),
            stack_size,
            ..PassOptions::default()
        };
        let r = frontend::compile(&fe, Emit::Lo, &pipeline, &popts);
        if let Some(ice) = r.internal_error {
            return Err(format!("internal compiler error: {ice}"));
        }
        if r.diagnostics.has_errors() {
            return Err(r.diagnostics.render(&sources));
        }
        let out = r.output.ok_or("no lo output")?;
        let file = sources.add("<lo IR>", out.clone());
        let m = scion_ir::parse_module(&out, file)
            .map_err(|d| format!("printed lo IR does not parse back: {}", d.render(&sources)))?;
        let refs = check_signatures(&m, layout)?;
        let buffers = buffer_count(&m, &format!("{layout}.sizes"))?;
        let batch_name = format!("closest_hit.{layout}.batch");
        let with_batch = format!("{out}\n{}", batch_entry(&batch_name, refs));
        let file = sources.add("<lo IR with the batch entry>", with_batch.clone());
        let m = scion_ir::parse_module(&with_batch, file).map_err(|d| {
            format!(
                "the generated batch entry does not parse: {}",
                d.render(&sources)
            )
        })?;
        scion_ir::verify(&m).map_err(|e| format!("the generated batch entry: {e:?}"))?;
        let jit = Code::compile(&m, codegen)?;
        let get = |name: &str| {
            jit.function_ptr(name)
                .ok_or_else(|| format!("the JIT has no `@{name}`"))
        };
        let sizes = get(&format!("{layout}.sizes"))?;
        let build = get(&format!("{layout}.build"))?;
        let node = get(&format!("{layout}.node"))?;
        let trace = get(&batch_name)?;
        // SAFETY: `check_signatures` checked that `@L.sizes` is `(ptr, ptr) -> ()` and
        // `@L.build` is `(ptr, ptr) -> (i32)`, which in the host's C calling convention are
        // these function types; the code lives as long as `jit`, kept in `_code`.
        let (sizes, build) = unsafe {
            (
                std::mem::transmute::<*const u8, SizesFn>(sizes),
                std::mem::transmute::<*const u8, BuildFn>(build),
            )
        };
        Ok(JitClosestHit {
            _code: jit,
            layout: layout.to_string(),
            buffers,
            refs,
            sizes,
            build,
            node,
            trace,
            stack_size: stack_size.unwrap_or(64),
            compile_time: start.elapsed(),
            roots: Mutex::new(HashMap::new()),
        })
    }

    /// The root reference of the tree packed into `buffers` by `build`, with a fresh `@L.node`.
    fn find_root(&self, view: &LogicalTreeView, table: &[*mut u8], bufs: &[&mut [u8]]) -> Root {
        let (mut counter, mut cursor, mut status) = (0u32, 0u32, 0i32);
        let args = (
            view as *const LogicalTreeView,
            table.as_ptr(),
            view.root,
            &mut counter as *mut u32,
            &mut cursor as *mut u32,
            &mut status as *mut i32,
        );
        match self.refs {
            RefKind::Index => {
                // SAFETY: `@L.node` was checked to be `(ptr, ptr, u32, ptr, ptr, ptr) -> (u32)`;
                // `view` describes a live tree, `table` holds each buffer's address (each
                // exactly its `@L.sizes` size, just packed by `@L.build`), and the three cells
                // are live locals. It rewrites the same bytes `@L.build` wrote.
                let f = unsafe { std::mem::transmute::<*const u8, NodeIdxFn>(self.node) };
                // SAFETY: see above.
                Root::Index(unsafe { f(args.0, args.1, args.2, args.3, args.4, args.5) })
            }
            RefKind::Pointer => {
                // SAFETY: as for the index case, with a `ptr` result.
                let f = unsafe { std::mem::transmute::<*const u8, NodePtrFn>(self.node) };
                // SAFETY: see above.
                let p = unsafe { f(args.0, args.1, args.2, args.3, args.4, args.5) } as usize;
                bufs.iter()
                    .enumerate()
                    .find_map(|(i, b)| {
                        let base = b.as_ptr() as usize;
                        (p >= base && p < base + b.len()).then(|| Root::Pointer(i, p - base))
                    })
                    .unwrap_or(Root::Pointer(usize::MAX, p))
            }
        }
    }
}

/// Checks the scalarized signatures the host calls and returns the reference kind.
fn check_signatures(m: &Module, layout: &str) -> Result<RefKind, String> {
    let sig = |name: &str| -> Result<(Vec<Type>, Vec<Type>), String> {
        let f = m
            .func_by_name(name)
            .ok_or_else(|| format!("the lo module has no `@{name}`"))?;
        let ty = |t: &scion_ir::TypeId| m.types.get(*t).clone();
        Ok((
            m.funcs[f].params.iter().map(ty).collect(),
            m.funcs[f].results.iter().map(ty).collect(),
        ))
    };
    let f32t = Type::Float(FloatTy::F32);
    let (p, r) = sig("closest_hit")?;
    let refs = match p.get(9) {
        Some(Type::Int(IntTy::U32)) => RefKind::Index,
        Some(Type::Ptr) => RefKind::Pointer,
        other => return Err(format!("@closest_hit: unexpected reference type {other:?}")),
    };
    let ref_ty = p[9].clone();
    let mut want = vec![Type::Ptr];
    want.extend(std::iter::repeat_n(f32t, 8));
    want.push(ref_ty.clone());
    want.push(Type::Ptr);
    if p != want || r != [Type::Int(IntTy::I32)] {
        return Err(format!(
            "@closest_hit has signature {p:?} -> {r:?}, expected {want:?} -> (i32)"
        ));
    }
    let expect = |name: String, params: Vec<Type>, results: Vec<Type>| -> Result<(), String> {
        let (p, r) = sig(&name)?;
        if p != params || r != results {
            return Err(format!(
                "@{name} has signature {p:?} -> {r:?}, expected {params:?} -> {results:?}"
            ));
        }
        Ok(())
    };
    expect(format!("{layout}.sizes"), vec![Type::Ptr; 2], vec![])?;
    expect(
        format!("{layout}.build"),
        vec![Type::Ptr; 2],
        vec![Type::Int(IntTy::I32)],
    )?;
    expect(
        format!("{layout}.node"),
        vec![
            Type::Ptr,
            Type::Ptr,
            Type::Int(IntTy::U32),
            Type::Ptr,
            Type::Ptr,
            Type::Ptr,
        ],
        vec![ref_ty],
    )?;
    Ok(refs)
}

/// The number of buffers: one past the largest `u64` slot `@L.sizes` stores to.
fn buffer_count(m: &Module, sizes: &str) -> Result<usize, String> {
    let f = m
        .func_by_name(sizes)
        .ok_or_else(|| format!("no `@{sizes}`"))?;
    Ok(m.ops
        .iter()
        .filter(|(id, o)| {
            o.kind == OpKind::Lo(scion_ir::lo::Op::Store) && m.func_of_op(*id) == Some(f)
        })
        .filter_map(|(_, o)| o.int_attr("offset"))
        .max()
        .map_or(0, |o| o as usize / 8 + 1))
}

impl LayoutCode for JitClosestHit {
    fn layout(&self) -> String {
        self.layout.clone()
    }
    fn buffers(&self) -> Vec<BufferSpec> {
        (0..self.buffers)
            .map(|i| BufferSpec {
                name: format!("buffer {i}"),
                align: BUFFER_ALIGN,
            })
            .collect()
    }
    fn sizes(&self, tree: &LogicalTree, sizes: &mut [u64]) {
        let Some(view) = LogicalTreeView::new(tree) else {
            sizes.fill(u64::MAX);
            return;
        };
        let mut out = vec![0u64; self.buffers.max(1)];
        // SAFETY: `sizes` has the checked type; `view` points into `tree`, alive for the call;
        // `out` has one slot per buffer (the largest slot the function stores to).
        unsafe { (self.sizes)(&view, out.as_mut_ptr()) };
        for (s, o) in sizes.iter_mut().zip(out) {
            *s = o;
        }
    }
    fn build(&self, tree: &LogicalTree, buffers: &mut [&mut [u8]]) -> i32 {
        let Some(view) = LogicalTreeView::new(tree) else {
            return -1;
        };
        if buffers.len() != self.buffers {
            return -1;
        }
        let table: Vec<*mut u8> = buffers.iter_mut().map(|b| b.as_mut_ptr()).collect();
        // SAFETY: `build` has the checked type; `view` describes the live `tree`; `table` holds
        // one address per buffer, each buffer exactly the size `@L.sizes` asked for (the
        // contract of `LayoutCode::build`), so the generated stores stay inside them.
        let status = unsafe { (self.build)(&view, table.as_ptr()) };
        if status != STATUS_OK || tree.is_empty() {
            return status;
        }
        let root = self.find_root(&view, &table, buffers);
        let key = buffers.iter().map(|b| b.as_ptr() as usize).collect();
        self.roots
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .insert(key, root);
        status
    }
    fn batch(&self, buffers: &[&[u8]], queries: &[Ray], results: &mut [(f32, u32)]) -> i32 {
        let key: Vec<usize> = buffers.iter().map(|b| b.as_ptr() as usize).collect();
        let root = self
            .roots
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .get(&key)
            .copied();
        let Some(root) = root else {
            return -1;
        };
        if queries.len() != results.len() {
            return -1;
        }
        let table: Vec<*const u8> = buffers.iter().map(|b| b.as_ptr()).collect();
        let mut records: Vec<[u32; 2]> = results.iter().map(|r| [r.0.to_bits(), r.1]).collect();
        let (q, r, end) = (queries.as_ptr(), records.as_mut_ptr(), queries.len() as u64);
        let status = match root {
            Root::Index(root) => {
                // SAFETY: the batch entry was generated with this signature (the root a `u32`,
                // checked from `@closest_hit`); `table` holds the packed buffers' addresses
                // (alive for the call), `root` is what `@L.node` returned for them, and it
                // reads `queries[0..end]` (32-byte `Ray`s) and reads and writes
                // `records[0..end]` (8-byte records), both exactly `end` long.
                let f = unsafe { std::mem::transmute::<*const u8, BatchIdxFn>(self.trace) };
                // SAFETY: see above.
                unsafe { f(table.as_ptr(), q, r, 0, end, root) }
            }
            Root::Pointer(i, off) => {
                let Some(buf) = buffers.get(i) else {
                    return -1;
                };
                let root = buf.as_ptr().wrapping_add(off);
                // SAFETY: as for the index case, with the root an address inside the packed
                // buffer `i` (found there after `@L.build`).
                let f = unsafe { std::mem::transmute::<*const u8, BatchPtrFn>(self.trace) };
                // SAFETY: see above.
                unsafe { f(table.as_ptr(), q, r, 0, end, root) }
            }
        };
        for (res, rec) in results.iter_mut().zip(records) {
            *res = (f32::from_bits(rec[0]), rec[1]);
        }
        status
    }
    /// A node at depth `k` (root 1) runs with at most `k - 1` pending entries and pushes two,
    /// so trees of depth up to `stack_size - 1` never overflow.
    fn stack_limit(&self) -> Option<usize> {
        Some(self.stack_size.saturating_sub(1) as usize)
    }
}

/// The `lo` text of the batch entry `@name(%B, %queries, %results, %begin, %end, %root) -> (i32)`
/// over `@closest_hit` (see the module comment).
fn batch_entry(name: &str, refs: RefKind) -> String {
    let r = match refs {
        RefKind::Index => "u32",
        RefKind::Pointer => "ptr",
    };
    let f = "f32, f32, f32, f32, f32, f32, f32, f32";
    let mut t = format!(
        "func @{name}(%0: ptr, %1: ptr, %2: ptr, %3: u64, %4: u64, %5: {r}) -> (i32) {{\n\
         \x20 \"lo.br\"()[^bb1(%3 : u64)] : () -> ()\n\
         ^bb1(%6: u64):\n\
         \x20 %7 = \"lo.cmp\"(%6, %4) {{pred = \"lt\"}} : (u64, u64) -> i1\n\
         \x20 \"lo.cond_br\"(%7)[^bb2, ^bb4] : (i1) -> ()\n\
         ^bb2:\n\
         \x20 %8 = \"lo.const\"() {{value = 32}} : () -> u64\n\
         \x20 %9 = \"lo.mul\"(%6, %8) : (u64, u64) -> u64\n\
         \x20 %10 = \"lo.ptr_add\"(%1, %9) : (ptr, u64) -> ptr\n"
    );
    for k in 0..8 {
        t.push_str(&format!(
            "  %{} = \"lo.load\"(%10) {{offset = {}}} : (ptr) -> f32\n",
            11 + k,
            4 * k
        ));
    }
    t.push_str(&format!(
        "  %19 = \"lo.const\"() {{value = 8}} : () -> u64\n\
         \x20 %20 = \"lo.mul\"(%6, %19) : (u64, u64) -> u64\n\
         \x20 %21 = \"lo.ptr_add\"(%2, %20) : (ptr, u64) -> ptr\n\
         \x20 %22 = \"lo.call\"(%0, %11, %12, %13, %14, %15, %16, %17, %18, %5, %21) \
         {{callee = @closest_hit}} : (ptr, {f}, {r}, ptr) -> i32\n\
         \x20 %23 = \"lo.const\"() {{value = 0}} : () -> i32\n\
         \x20 %24 = \"lo.cmp\"(%22, %23) {{pred = \"ne\"}} : (i32, i32) -> i1\n\
         \x20 \"lo.cond_br\"(%24)[^bb5, ^bb3] : (i1) -> ()\n\
         ^bb3:\n\
         \x20 %25 = \"lo.const\"() {{value = 1}} : () -> u64\n\
         \x20 %26 = \"lo.add\"(%6, %25) : (u64, u64) -> u64\n\
         \x20 \"lo.br\"()[^bb1(%26 : u64)] : () -> ()\n\
         ^bb4:\n\
         \x20 %27 = \"lo.const\"() {{value = 0}} : () -> i32\n\
         \x20 \"lo.return\"(%27) : (i32) -> ()\n\
         ^bb5:\n\
         \x20 \"lo.return\"(%22) : (i32) -> ()\n\
         }}\n"
    ));
    t
}
