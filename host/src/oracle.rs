//! The layout-free oracle (issue 3 item 6): `library/algorithms/closest_hit.scion` compiled to
//! the `tree` dialect and run by the `tree` interpreter over a runtime [`LogicalTree`], with no
//! layout in between. Input: a logical tree and rays; output: one [`Hit`] per ray.
//!
//! The tree is never materialized as interpreter values: [`Val::Extern`] handles stand for
//! nodes, and the provider destructures a node when the program matches on it (paper §3, the
//! traversal written against the algebraic data type `BVH`). An interior node is
//! `Interior(bounds, left, right)` with handles as children; a leaf is
//! `Leaf(bounds, nprims, data)` with `data` the leaf's triangles as `Triangle` values carrying
//! their original `id`. Each ray runs `closest_hit(ray, root, best)` with
//! `best = (ray.tmax, 0xFFFFFFFF)`; the result is normalized by [`Hit::from_best`].

use scion_compiler::driver::cli::Emit;
use scion_compiler::driver::pipelines;
use scion_compiler::driver::session::{PRELUDE, PRELUDE_NAME};
use scion_compiler::frontend::{self, Frontend, PassOptions};
use scion_ir::diag::SourceMap;
use scion_ir::interp::{AdtVal, Interp, Val};
use scion_ir::types::IntTy;
use scion_ir::Module;
use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::{Aabb, Hit, Ray, Triangle, Vec3};
use std::rc::Rc;

/// The closest-hit algorithm of the library.
pub const CLOSEST_HIT: &str = include_str!("../../library/algorithms/closest_hit.scion");
/// Its name in diagnostics.
pub const CLOSEST_HIT_NAME: &str = "library/algorithms/closest_hit.scion";

/// Native stack of one interpreter thread: a recursion level of the interpreted traversal
/// costs up to about 32 KiB in debug builds (dialects/src/interp/mod.rs, `max_depth`).
const STACK_PER_LEVEL: usize = 64 << 10;

/// A closest-hit program in the `tree` dialect, ready to interpret.
pub struct ClosestHit {
    module: Module,
    interior: usize,
    leaf: usize,
}

impl ClosestHit {
    /// Compiles the library's `closest_hit.scion` with the prelude through the front end and
    /// the pass pipeline of `-O{opt_level}`.
    pub fn compile(opt_level: u8) -> Result<ClosestHit, String> {
        ClosestHit::compile_source(CLOSEST_HIT_NAME, CLOSEST_HIT, opt_level)
    }

    /// Compiles an algorithm's source text (with the prelude) that defines
    /// `closest_hit(ray: Ray, bvh: BVH, best: mut (f32, u32))`.
    pub fn compile_source(name: &str, text: &str, opt_level: u8) -> Result<ClosestHit, String> {
        let mut sources = SourceMap::new();
        let prelude = [sources.add(PRELUDE_NAME, PRELUDE)];
        let inputs = [sources.add(name, text)];
        let fe = Frontend {
            sources: &sources,
            prelude: &prelude,
            inputs: &inputs,
        };
        let pipeline = pipelines::for_level(opt_level);
        let r = frontend::compile(&fe, Emit::Tree, &pipeline, &PassOptions::default());
        if let Some(ice) = r.internal_error {
            return Err(format!("internal compiler error: {ice}"));
        }
        if r.diagnostics.has_errors() {
            return Err(r.diagnostics.render(&sources));
        }
        let text = r.output.ok_or("the front end produced no tree IR")?;
        let file = sources.add("<tree IR>", text.clone());
        let module = scion_ir::parse_module(&text, file).map_err(|d| {
            format!(
                "printed tree IR does not parse back: {}",
                d.render(&sources)
            )
        })?;
        scion_ir::verify(&module).map_err(|e| format!("tree IR does not verify: {e:?}"))?;
        ClosestHit::from_module(module)
    }

    /// Wraps a verified `tree` module holding `@closest_hit` and the prelude's `BVH`.
    pub fn from_module(module: Module) -> Result<ClosestHit, String> {
        if module.func_by_name("closest_hit").is_none() {
            return Err("the module has no function `@closest_hit`".into());
        }
        let bvh = module
            .adt("BVH")
            .ok_or("the module declares no ADT `BVH`")?;
        let interior = bvh
            .variant("Interior")
            .ok_or("`BVH` has no variant `Interior`")?
            .0;
        let leaf = bvh.variant("Leaf").ok_or("`BVH` has no variant `Leaf`")?.0;
        Ok(ClosestHit {
            module,
            interior,
            leaf,
        })
    }

    /// The program's `tree` module.
    pub fn module(&self) -> &Module {
        &self.module
    }

    /// Closest hits of `rays` against `tree` on the calling thread. The calling thread's stack
    /// must hold the tree's depth (see [`ClosestHit::trace_all`], which makes sure it does).
    pub fn trace(&self, tree: &LogicalTree, rays: &[Ray]) -> Result<Vec<Hit>, String> {
        self.trace_from(tree, rays, 0)
    }

    /// [`ClosestHit::trace`] with errors naming ray `first + i` for `rays[i]`.
    fn trace_from(
        &self,
        tree: &LogicalTree,
        rays: &[Ray],
        first: usize,
    ) -> Result<Vec<Hit>, String> {
        if tree.is_empty() {
            return Ok(vec![Hit::MISS; rays.len()]);
        }
        let mut it = Interp::new(&self.module);
        // closest_hit -> distmin -> slab_interval below the deepest leaf.
        it.max_depth = tree_depth(tree) + 4;
        it.max_steps = u64::MAX;
        let mut nodes = NodeProvider::new(tree, self.interior, self.leaf);
        it.set_adt_provider(Box::new(move |h| nodes.node(h)));
        let root = Val::Extern(u64::from(tree.root));
        closest_hits_in(&mut it, &[], rays, &root, first)
    }

    /// Closest hits of `rays` on `threads` threads (at least one), each with a stack sized for
    /// the tree's depth; the rays are split into contiguous chunks.
    pub fn trace_all(
        &self,
        tree: &LogicalTree,
        rays: &[Ray],
        threads: usize,
    ) -> Result<Vec<Hit>, String> {
        in_threads(tree, rays, threads, |part, first| {
            self.trace_from(tree, part, first)
        })
    }
}

/// The native stack of a thread that interprets a recursion as deep as `tree`: twice the depth,
/// since packing at the mem level recurses through two functions per level.
fn interp_stack(tree: &LogicalTree) -> usize {
    (8 << 20) + 2 * tree_depth(tree) * STACK_PER_LEVEL
}

/// Runs `f` on a thread with [`in_threads`]' native stack for `tree`.
pub fn on_interp_stack<T: Send>(
    tree: &LogicalTree,
    f: impl FnOnce() -> Result<T, String> + Send,
) -> Result<T, String> {
    std::thread::scope(|s| {
        std::thread::Builder::new()
            .name("scion-interp".into())
            .stack_size(interp_stack(tree))
            .spawn_scoped(s, f)
            .map_err(|e| format!("cannot start an interpreter thread: {e}"))?
            .join()
            .map_err(|_| "an interpreter thread panicked".to_string())?
    })
}

/// Runs `f(chunk, first index)` on contiguous chunks of `rays` on `threads` threads (at least
/// one), each with a native stack sized for interpreting a recursion as deep as `tree`, and
/// concatenates the hits; the first error (in ray order) wins.
pub fn in_threads(
    tree: &LogicalTree,
    rays: &[Ray],
    threads: usize,
    f: impl Fn(&[Ray], usize) -> Result<Vec<Hit>, String> + Sync,
) -> Result<Vec<Hit>, String> {
    let threads = threads.max(1);
    let stack = interp_stack(tree);
    let chunk = rays.len().div_ceil(threads).max(1);
    let f = &f;
    std::thread::scope(|s| {
        let handles: Vec<_> = rays
            .chunks(chunk)
            .enumerate()
            .map(|(k, part)| {
                std::thread::Builder::new()
                    .name(format!("scion-interp-{k}"))
                    .stack_size(stack)
                    .spawn_scoped(s, move || f(part, k * chunk))
                    .map_err(|e| format!("cannot start an interpreter thread: {e}"))
            })
            .collect();
        let mut hits = Vec::with_capacity(rays.len());
        for h in handles {
            let part = h?
                .join()
                .map_err(|_| "an interpreter thread panicked".to_string())??;
            hits.extend(part);
        }
        Ok(hits)
    })
}

/// Nodes on the longest root-to-leaf path (0 for the empty tree), without recursion.
pub fn tree_depth(tree: &LogicalTree) -> usize {
    if tree.is_empty() {
        return 0;
    }
    let mut deepest = 0;
    let mut stack = vec![(tree.root, 1usize)];
    while let Some((i, d)) = stack.pop() {
        deepest = deepest.max(d);
        let n = &tree.nodes[i as usize];
        if !n.is_leaf() {
            stack.push((n.child[0], d + 1));
            stack.push((n.child[1], d + 1));
        }
    }
    deepest
}

/// Resolves node handles (indices into `tree.nodes`) to `BVH` values, caching each node once
/// it has been asked for.
struct NodeProvider<'t> {
    tree: &'t LogicalTree,
    interior: usize,
    leaf: usize,
    cache: Vec<Option<Rc<AdtVal>>>,
}

impl<'t> NodeProvider<'t> {
    fn new(tree: &'t LogicalTree, interior: usize, leaf: usize) -> NodeProvider<'t> {
        NodeProvider {
            tree,
            interior,
            leaf,
            cache: Vec::new(),
        }
    }

    fn node(&mut self, h: u64) -> Result<Rc<AdtVal>, String> {
        let i = usize::try_from(h).map_err(|_| format!("node handle {h} out of range"))?;
        let n =
            self.tree.nodes.get(i).ok_or_else(|| {
                format!("node {i} out of range ({} nodes)", self.tree.nodes.len())
            })?;
        if self.cache.is_empty() {
            self.cache = vec![None; self.tree.nodes.len()];
        }
        if let Some(v) = &self.cache[i] {
            return Ok(v.clone());
        }
        let bounds = aabb_val(&n.aabb());
        let v = Rc::new(if n.is_leaf() {
            let tris = self.tree.leaf_primitives(n);
            AdtVal {
                ty: "BVH".into(),
                variant: Some(self.leaf),
                fields: vec![
                    bounds,
                    Val::Int(tris.len() as i128, IntTy::U16),
                    Val::Array(Rc::new(tris.iter().map(triangle_val).collect())),
                ],
            }
        } else {
            AdtVal {
                ty: "BVH".into(),
                variant: Some(self.interior),
                fields: vec![
                    bounds,
                    Val::Extern(u64::from(n.child[0])),
                    Val::Extern(u64::from(n.child[1])),
                ],
            }
        });
        self.cache[i] = Some(v.clone());
        Ok(v)
    }
}

/// `f32x3` as the interpreter's vector of three `f32` lanes.
pub fn vec3_val(v: Vec3) -> Val {
    Val::Vector(vec![Val::F32(v.x), Val::F32(v.y), Val::F32(v.z)])
}

/// The prelude's `AABB(low, high)`.
pub fn aabb_val(b: &Aabb) -> Val {
    Val::Adt(Rc::new(AdtVal {
        ty: "AABB".into(),
        variant: None,
        fields: vec![vec3_val(b.low), vec3_val(b.high)],
    }))
}

/// The prelude's `Triangle(p0, p1, p2, id)`.
pub fn triangle_val(t: &Triangle) -> Val {
    Val::Adt(Rc::new(AdtVal {
        ty: "Triangle".into(),
        variant: None,
        fields: vec![
            vec3_val(t.p0),
            vec3_val(t.p1),
            vec3_val(t.p2),
            Val::Int(i128::from(t.id), IntTy::U32),
        ],
    }))
}

/// Runs the interpreter's `closest_hit(before.., ray, root, best)` for one ray with `best`
/// starting at `(ray.tmax, u32::MAX)`, and reads `best` back as a [`Hit`]. `before` are the
/// arguments ahead of the ray (the buffer table at the mem level, none over the logical tree).
pub fn closest_hit_in(
    it: &mut Interp<'_>,
    before: Vec<Val>,
    ray: &Ray,
    root: Val,
) -> Result<Hit, String> {
    let best = it.alloc(Val::Tuple(vec![
        Val::F32(ray.tmax),
        Val::Int(i128::from(u32::MAX), IntTy::U32),
    ]));
    let mut args = before;
    args.extend([ray_val(ray), root, best.clone()]);
    it.call("closest_hit", args).map_err(|e| e.to_string())?;
    match it.read(&best) {
        Some(Val::Tuple(p)) => match &p[..] {
            [Val::F32(t), Val::Int(id, _)] => Ok(Hit::from_best(*t, *id as u32)),
            _ => Err(format!("`best` holds {}", Val::Tuple(p.clone()))),
        },
        other => Err(format!("`best` is not a pair: {other:?}")),
    }
}

/// [`closest_hit_in`] for each of `rays`; an error names ray `first + i` for `rays[i]`.
pub fn closest_hits_in(
    it: &mut Interp<'_>,
    before: &[Val],
    rays: &[Ray],
    root: &Val,
    first: usize,
) -> Result<Vec<Hit>, String> {
    rays.iter()
        .enumerate()
        .map(|(k, ray)| {
            let hit = closest_hit_in(it, before.to_vec(), ray, root.clone())
                .map_err(|e| format!("ray {}: {e}", first + k));
            crate::progress::add(1);
            hit
        })
        .collect()
}

/// The prelude's `Ray(origin, direction, tmin, tmax)`.
pub fn ray_val(r: &Ray) -> Val {
    Val::Adt(Rc::new(AdtVal {
        ty: "Ray".into(),
        variant: None,
        fields: vec![
            vec3_val(r.origin),
            vec3_val(r.dir),
            Val::F32(r.tmin),
            Val::F32(r.tmax),
        ],
    }))
}
