//! A layout backend without the JIT: `closest_hit.scion` specialized to a library layout
//! (`destructor-specialize`, `constructor-specialize`: the `tree`+`mem` level) and run by the
//! interpreter over its byte memory, through the runtime contract of
//! docs/design/specialization.md §3.1. Input: a logical tree and rays; output: hits.
//!
//! Per interpreter: the logical tree's C-ABI bytes (`LogicalTreeView`, 44-byte nodes, 40-byte
//! triangles) go into the interpreter's memory; `@L.sizes` gives each buffer's size; each
//! buffer is allocated once (64-byte aligned) and `@L.build` packs; then every ray runs
//! `closest_hit(%B, ray, root, best)` with `best = (ray.tmax, 0xFFFFFFFF)`. The root's
//! reference is what `@L.node` returns for the root: calling it once more on the packed
//! buffers (fresh counters) places every node at the same place again and returns it (index 0
//! for `by I` layouts in pre-order, an address for `ptr` layouts).
//!
//! It also gives the library's closest-hit layouts ([`library_layouts`], [`layout_source`],
//! [`layout_boxes`], derived from `library/layouts` by [`crate::library`]), which the JIT
//! ([`crate::jit`]) and the GPU path of `scion trace` compile too.

use crate::backend::Backend;
use crate::oracle::{
    closest_hits_in, in_threads, on_interp_stack, tree_depth, CLOSEST_HIT, CLOSEST_HIT_NAME,
};
use crate::quantized::Boxes;
use scion_compiler::abi::EntrySig;
use scion_compiler::driver::cli::Emit;
use scion_compiler::driver::session::{PRELUDE, PRELUDE_NAME};
use scion_compiler::frontend::{self, Frontend, PassOptions};
use scion_ir::diag::SourceMap;
use scion_ir::interp::{Interp, Val};
use scion_ir::op::OpKind;
use scion_ir::types::IntTy;
use scion_ir::Module;
use scion_runtime::bvh::schema::{LogicalBytes, Schema};
use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::{Hit, Ray, Triangle};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// The library's layouts that the prelude's `closest_hit` traverses (those realizing `BVH`):
/// file stem, layout name, and how the layout stores boxes (a quantized layout's bit-for-bit
/// reference is the traversal of [`DecodedTree::decoded_tree`](crate::quantized::DecodedTree::decoded_tree)).
/// Derived from `library/layouts` by [`crate::library`], sorted by stem; a new file there is a
/// new entry.
pub fn library_layouts() -> &'static [(&'static str, &'static str, Boxes)] {
    static LAYOUTS: std::sync::OnceLock<Vec<(&'static str, &'static str, Boxes)>> =
        std::sync::OnceLock::new();
    LAYOUTS.get_or_init(|| {
        crate::library::LAYOUT_FILES
            .iter()
            .filter_map(|&(stem, _)| {
                let r = crate::library::resolve(stem, None).ok()?;
                (r.program.algorithm == crate::jit::ALGORITHM).then(|| {
                    let name: &'static str = Box::leak(r.program.layout.into_boxed_str());
                    (stem, name, r.boxes)
                })
            })
            .collect()
    })
}

/// How the library layout named `layout` (or with file stem `layout`) stores boxes;
/// [`Boxes::Exact`] for any other layout.
pub fn layout_boxes(layout: &str) -> Boxes {
    library_layouts()
        .iter()
        .find(|l| l.0 == layout || l.1 == layout)
        .map_or(Boxes::Exact, |l| l.2)
}

/// The source of a library layout by file stem.
pub fn layout_source(stem: &str) -> Option<&'static str> {
    crate::library::layout_file(stem).map(|(_, text)| text)
}

/// Closest hit specialized to one layout, at the `mem` level.
pub struct MemClosestHit {
    module: Module,
    layout: String,
    buffers: usize,
    schema: Schema,
    /// The last tree packed for tracing, kept for the next traces of the same tree: packing
    /// runs the generated builder op by op, and in the differential test it took more time than
    /// the traversals (every ray kind of a scene traces one tree, in two threads).
    packed: Mutex<Option<Packed>>,
}

/// A tree packed in an interpreter's memory, as plain data that other threads can copy.
struct Packed {
    /// [`fingerprint`] of the tree.
    key: u64,
    /// The interpreter's byte memory after packing.
    memory: Vec<u8>,
    /// The buffer table `%B`.
    b: u64,
    /// The root's reference.
    root: Plain,
}

/// A value without shared parts ([`Val`] holds `Rc`s, which stay in one thread): what a
/// layout's reference is made of.
enum Plain {
    Bool(bool),
    Int(i128, IntTy),
    F32(f32),
    F64(f64),
    Vector(Vec<Plain>),
    Tuple(Vec<Plain>),
}

impl Plain {
    /// `v` as plain data; `None` when it has shared parts (arrays, ADT values, references).
    fn of(v: &Val) -> Option<Plain> {
        let all = |xs: &[Val]| xs.iter().map(Plain::of).collect::<Option<Vec<_>>>();
        Some(match v {
            Val::Bool(b) => Plain::Bool(*b),
            Val::Int(i, t) => Plain::Int(*i, *t),
            Val::F32(x) => Plain::F32(*x),
            Val::F64(x) => Plain::F64(*x),
            Val::Vector(xs) => Plain::Vector(all(xs)?),
            Val::Tuple(xs) => Plain::Tuple(all(xs)?),
            _ => return None,
        })
    }

    fn val(&self) -> Val {
        match self {
            Plain::Bool(b) => Val::Bool(*b),
            Plain::Int(i, t) => Val::Int(*i, *t),
            Plain::F32(x) => Val::F32(*x),
            Plain::F64(x) => Val::F64(*x),
            Plain::Vector(xs) => Val::Vector(xs.iter().map(Plain::val).collect()),
            Plain::Tuple(xs) => Val::Tuple(xs.iter().map(Plain::val).collect()),
        }
    }
}

/// A hash of everything packing reads of `tree` (its nodes' fields and bits, its root, its
/// primitives' corners' bits and ids).
fn fingerprint(tree: &LogicalTree) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    tree.root.hash(&mut h);
    for n in &tree.nodes {
        (n.kind, n.child, n.prim_offset, n.prim_count).hash(&mut h);
        n.bounds.map(f32::to_bits).hash(&mut h);
    }
    for t in &tree.primitives {
        for p in [t.p0, t.p1, t.p2] {
            [p.x, p.y, p.z].map(f32::to_bits).hash(&mut h);
        }
        t.id.hash(&mut h);
    }
    h.finish()
}

/// What the host compiles: Scion files after the prelude (name, text), one of their layouts and
/// the algorithm whose entry points it calls (a closest hit: `(ray, tree, best: mut (f32, u32))`).
#[derive(Clone, Debug)]
pub struct Program {
    /// The files, in order.
    pub files: Vec<(String, String)>,
    /// The layout's name (`--layout`).
    pub layout: String,
    /// The algorithm's name (`--entry`).
    pub algorithm: String,
}

impl Program {
    /// `closest_hit.scion` and the library layout in file `stem` named `layout`.
    pub fn library(stem: &str, layout: &str) -> Result<Program, String> {
        let text = layout_source(stem).ok_or_else(|| format!("no library layout `{stem}`"))?;
        Ok(Program {
            files: vec![
                (CLOSEST_HIT_NAME.to_string(), CLOSEST_HIT.to_string()),
                (format!("library/layouts/{stem}.scion"), text.to_string()),
            ],
            layout: layout.to_string(),
            algorithm: crate::jit::ALGORITHM.to_string(),
        })
    }
}

/// Compiles `closest_hit.scion` with the prelude and the library layout in file `stem` through
/// the front end; see [`compile_program`].
pub fn compile_library(
    stem: &str,
    emit: Emit,
    pipeline: &[String],
    popts: &PassOptions,
) -> Result<(Module, Option<EntrySig>, Option<Schema>), String> {
    let layout = popts.layout.clone().unwrap_or_default();
    compile_program(&Program::library(stem, &layout)?, emit, pipeline, popts)
}

/// Compiles `program`'s files with the prelude through the front end (`frontend::compile`, as
/// scionc does) to `emit` with `pipeline` and `popts`, and parses the printed module back.
/// Output: the module, with `popts.entry` the entries' C signature, and with `popts.layout` the
/// schema of the logical tree its constructor reads; errors are rendered diagnostics.
pub fn compile_program(
    program: &Program,
    emit: Emit,
    pipeline: &[String],
    popts: &PassOptions,
) -> Result<(Module, Option<EntrySig>, Option<Schema>), String> {
    let mut sources = SourceMap::new();
    let prelude = [sources.add(PRELUDE_NAME, PRELUDE)];
    let inputs: Vec<_> = program
        .files
        .iter()
        .map(|(name, text)| sources.add(name.clone(), text.clone()))
        .collect();
    let fe = Frontend {
        sources: &sources,
        prelude: &prelude,
        inputs: &inputs,
    };
    let r = frontend::compile(&fe, emit, pipeline, popts);
    if let Some(ice) = r.internal_error {
        return Err(format!("internal compiler error: {ice}"));
    }
    if r.diagnostics.has_errors() {
        return Err(r.diagnostics.render(&sources));
    }
    let level = emit.as_str();
    let out = r.output.ok_or_else(|| format!("no {level} output"))?;
    let file = sources.add(format!("<{level} IR>"), out.clone());
    let module = scion_ir::parse_module(&out, file).map_err(|d| {
        format!(
            "printed {level} IR does not parse back: {}",
            d.render(&sources)
        )
    })?;
    Ok((module, r.entry, r.logical))
}

impl MemClosestHit {
    /// Compiles closest hit for the library layout in file `stem` named `layout`.
    pub fn compile(stem: &str, layout: &str) -> Result<MemClosestHit, String> {
        let popts = PassOptions {
            layout: Some(layout.to_string()),
            ..PassOptions::default()
        };
        let pipeline = ["destructor-specialize", "constructor-specialize"].map(String::from);
        let (module, _, schema) = compile_library(stem, Emit::Mem, &pipeline, &popts)?;
        let schema = schema.ok_or_else(|| format!("layout `{layout}` has no logical tree"))?;
        for f in ["closest_hit", "sizes", "build", "node"] {
            let name = if f == "closest_hit" {
                f.to_string()
            } else {
                format!("{layout}.{f}")
            };
            if module.func_by_name(&name).is_none() {
                return Err(format!("the specialized module has no `@{name}`"));
            }
        }
        // Buffers: one past the largest `mem.buffer` index.
        let buffers = module
            .ops
            .iter()
            .filter(|(_, o)| matches!(o.kind, OpKind::Mem(scion_ir::mem::Op::Buffer)))
            .filter_map(|(_, o)| o.int_attr("index"))
            .max()
            .map_or(0, |i| i as usize + 1);
        Ok(MemClosestHit {
            module,
            layout: layout.to_string(),
            buffers,
            schema,
            packed: Mutex::new(None),
        })
    }

    /// The byte size of each buffer for `tree` and the time `@L.sizes` plus `@L.build` take
    /// in the interpreter (the pack time of this backend).
    pub fn pack_report(&self, tree: &LogicalTree) -> Result<(Vec<u64>, Duration), String> {
        if tree.is_empty() {
            return Ok((vec![0; self.buffers], Duration::ZERO));
        }
        let mut it = self.interp(tree);
        let p = self.pack(&mut it, tree)?;
        Ok((p.sizes, p.time))
    }

    fn interp(&self, tree: &LogicalTree) -> Interp<'_> {
        let mut it = Interp::new(&self.module);
        // Packing recurses through `@L.node` and a build function per tree level.
        it.max_depth = 2 * tree_depth(tree) + 8;
        it.max_steps = u64::MAX;
        it
    }

    /// Puts the logical tree in `it`'s memory, sizes, allocates and builds the buffers, and
    /// finds the root's reference.
    fn pack(&self, it: &mut Interp<'_>, tree: &LogicalTree) -> Result<Packing, String> {
        let l = &self.layout;
        let (view, root_index) = put_tree(it, tree, &self.schema)?;
        let start = Instant::now();
        let ptr = |a: u64| Val::Int(i128::from(a), IntTy::U64);
        let sizes_at = it.alloc_bytes(&vec![0u8; 8 * self.buffers.max(1)], 8);
        it.call(&format!("{l}.sizes"), vec![ptr(view), ptr(sizes_at)])
            .map_err(|e| format!("@{l}.sizes: {e}"))?;
        let mut table = Vec::new();
        let mut sizes = Vec::new();
        for i in 0..self.buffers {
            let at = sizes_at + 8 * i as u64;
            let n = it
                .bytes(at, 8)
                .and_then(|b| b.try_into().ok())
                .map(u64::from_le_bytes)
                .ok_or("sizes table outside memory")?;
            sizes.push(n);
            let n = usize::try_from(n).map_err(|_| format!("buffer {i}: {n} bytes"))?;
            table.extend(it.alloc_bytes(&vec![0u8; n], 64).to_le_bytes());
        }
        let b = it.alloc_bytes(&table, 8);
        let status = it
            .call(&format!("{l}.build"), vec![ptr(view), ptr(b)])
            .map_err(|e| format!("@{l}.build: {e}"))?;
        match status.first() {
            Some(Val::Int(0, _)) => {}
            other => return Err(format!("@{l}.build returned status {other:?}")),
        }
        let time = start.elapsed();
        let cell = |it: &mut Interp<'_>| it.alloc(Val::Int(0, IntTy::U32));
        let (c, k, s) = (cell(it), cell(it), it.alloc(Val::Int(0, IntTy::I32)));
        let root = it
            .call(
                &format!("{l}.node"),
                vec![
                    ptr(view),
                    ptr(b),
                    Val::Int(i128::from(root_index), IntTy::U32),
                    c,
                    k,
                    s,
                ],
            )
            .map_err(|e| format!("@{l}.node: {e}"))?
            .into_iter()
            .next()
            .ok_or("@node returned nothing")?;
        Ok(Packing {
            b,
            root,
            sizes,
            time,
        })
    }

    /// The work profile of the specialized program: how often each function was called while
    /// tracing `rays` through `tree` (packing not counted), by function name. For closest hit,
    /// the calls of `closest_hit_node` are the nodes reached, of `distmin` over `SlabLanes`
    /// (`distmin.2`) the root's box tests and of `distmin_pair` two box tests each (a node's
    /// children), of `hit_lanes` the runs of up to four triangles.
    pub fn call_profile(
        &self,
        tree: &LogicalTree,
        rays: &[Ray],
    ) -> Result<Vec<(String, u64)>, String> {
        if tree.is_empty() {
            return Ok(Vec::new());
        }
        let mut it = self.interp(tree);
        let Packing { b, root, .. } = self.pack(&mut it, tree)?;
        let table = Val::Int(i128::from(b), IntTy::U64);
        it.count_calls();
        closest_hits_in(&mut it, &[table], rays, &root, 0)?;
        Ok(it.call_counts())
    }

    /// Packs `tree` in a fresh interpreter and traces `rays` (errors name ray `first + i`).
    fn trace_from(
        &self,
        tree: &LogicalTree,
        rays: &[Ray],
        first: usize,
    ) -> Result<Vec<Hit>, String> {
        if tree.is_empty() {
            return Ok(vec![Hit::MISS; rays.len()]);
        }
        let mut it = self.interp(tree);
        let (b, root) = self.packed_in(&mut it, tree)?;
        let table = Val::Int(i128::from(b), IntTy::U64);
        closest_hits_in(&mut it, &[table], rays, &root, first)
    }

    /// `tree` packed in `it`'s memory: a copy of the packing kept from an earlier trace of the
    /// same tree, or packed now (and kept, when its root is plain data). Returns the buffer
    /// table and the root.
    fn packed_in(&self, it: &mut Interp<'_>, tree: &LogicalTree) -> Result<(u64, Val), String> {
        let key = fingerprint(tree);
        let lock = || self.packed.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = lock().as_ref().filter(|p| p.key == key) {
            it.set_memory(p.memory.clone());
            return Ok((p.b, p.root.val()));
        }
        let Packing { b, root, .. } = self.pack(it, tree)?;
        if let Some(plain) = Plain::of(&root) {
            *lock() = Some(Packed {
                key,
                memory: it.memory().to_vec(),
                b,
                root: plain,
            });
        }
        Ok((b, root))
    }

    /// Packs `tree` for the traces that follow ([`Self::packed_in`]), once for all threads.
    fn prepare(&self, tree: &LogicalTree) -> Result<(), String> {
        if tree.is_empty() {
            return Ok(());
        }
        on_interp_stack(tree, || {
            let mut it = self.interp(tree);
            self.packed_in(&mut it, tree).map(|_| ())
        })
    }
}

/// A tree packed in an interpreter's memory.
struct Packing {
    /// The buffer table `%B`.
    b: u64,
    /// The root's reference.
    root: Val,
    /// Each buffer's byte size.
    sizes: Vec<u64>,
    /// Time of `@L.sizes`, the allocations and `@L.build`.
    time: Duration,
}

/// The logical tree's C-ABI bytes in `it`'s memory (its nodes in `schema`'s form, 40-byte
/// triangles); returns the `LogicalTreeView` address and the root's index.
fn put_tree(
    it: &mut Interp<'_>,
    tree: &LogicalTree,
    schema: &Schema,
) -> Result<(u64, u32), String> {
    let lb = LogicalBytes::fill(tree, schema)?;
    let mut pb = Vec::with_capacity(40 * tree.primitives.len());
    for t in &tree.primitives {
        for p in [t.p0, t.p1, t.p2] {
            for x in p.to_array() {
                pb.extend(x.to_le_bytes());
            }
        }
        pb.extend(t.id.to_le_bytes());
    }
    let count = |n: usize| u32::try_from(n).map_err(|_| format!("{n} does not fit u32"));
    let na = it.alloc_bytes(lb.nodes(), 8);
    let pa = it.alloc_bytes(&pb, 4);
    let mut h = Vec::with_capacity(32);
    h.extend(na.to_le_bytes());
    h.extend(count(lb.node_count)?.to_le_bytes());
    h.extend(lb.root.to_le_bytes());
    h.extend(pa.to_le_bytes());
    h.extend(count(tree.primitives.len())?.to_le_bytes());
    h.extend(0u32.to_le_bytes());
    Ok((it.alloc_bytes(&h, 8), lb.root))
}

/// [`MemClosestHit`] as a [`Backend`] on `threads` threads (each packs its own copy).
pub struct MemInterpBackend {
    program: MemClosestHit,
    stem: String,
    threads: usize,
}

impl MemInterpBackend {
    /// The backend for library layout `stem` (`pbrt`, `ptr`, ...) named `layout`.
    pub fn new(stem: &str, layout: &str, threads: usize) -> Result<MemInterpBackend, String> {
        Ok(MemInterpBackend {
            program: MemClosestHit::compile(stem, layout)?,
            stem: stem.to_string(),
            threads: threads.max(1),
        })
    }
}

impl MemInterpBackend {
    /// The compiled program.
    pub fn program(&self) -> &MemClosestHit {
        &self.program
    }
}

impl Backend for MemInterpBackend {
    fn name(&self) -> String {
        format!("mem-interp-{}", self.stem)
    }
    fn boxes(&self) -> Boxes {
        layout_boxes(&self.stem)
    }
    fn trace(&self, _: &[Triangle], tree: &LogicalTree, rays: &[Ray]) -> Result<Vec<Hit>, String> {
        self.program.prepare(tree)?;
        in_threads(tree, rays, self.threads, |part, first| {
            self.program.trace_from(tree, part, first)
        })
    }
    fn max_triangles(&self) -> Option<usize> {
        Some(2_000)
    }
    fn max_rays(&self) -> Option<usize> {
        Some(32)
    }
}
