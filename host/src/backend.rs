//! Backends: ways to trace closest-hit rays through a scene's logical tree. Input: the scene's
//! triangles, its logical tree, rays; output: one [`Hit`] per ray in the hits-file convention
//! (a miss is [`Hit::MISS`]).
//!
//! The differential tests and the `scion` command pick backends by [`BackendKind`]; adding a
//! backend (the JIT of one layout) is one more variant and one more arm of
//! [`BackendKind::instantiate`].

use crate::contract::LayoutBackend;
use crate::gpu_emu::EmulatedBackend;
use crate::jit::{Codegen, JitClosestHit, JIT_OPT_LEVEL};
use crate::mem_interp::library_layouts;
use crate::oracle::ClosestHit;
use crate::quantized::Boxes;
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::{Hit, Ray, Triangle};
use scion_runtime::reference::{closest_hits_brute, closest_hits_tree};

/// A way to trace rays.
pub trait Backend: Sync {
    /// A short name for reports (`reference`, `interp-O1`, ...).
    fn name(&self) -> String;
    /// Closest hits of `rays` in `tree` (built over `triangles`).
    fn trace(
        &self,
        triangles: &[Triangle],
        tree: &LogicalTree,
        rays: &[Ray],
    ) -> Result<Vec<Hit>, String>;
    /// The deepest tree the backend traverses without a stack overflow, when bounded
    /// (generated code keeps a fixed-size stack); on deeper trees an error saying
    /// "stack overflow" is a correct answer.
    fn stack_limit(&self) -> Option<usize> {
        None
    }
    /// How the boxes the backend traverses relate to the logical tree's: its hits equal the
    /// reference traversal of `boxes().decoded_tree(tree)` bit for bit.
    fn boxes(&self) -> Boxes {
        Boxes::Exact
    }
    /// The largest scene worth giving this backend in tests (a slow one packs every tree
    /// again in an interpreter); `None` for any.
    fn max_triangles(&self) -> Option<usize> {
        None
    }
    /// The most rays of one test row worth giving this backend (an interpreter runs every
    /// ray's traversal op by op); `None` for all of them.
    fn max_rays(&self) -> Option<usize> {
        None
    }
}

/// The backends the harness knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BackendKind {
    /// The runtime's Rust traversal with the prelude's arithmetic.
    Reference,
    /// Every triangle, no tree.
    Brute,
    /// The `tree` interpreter running `closest_hit.scion` compiled at this `-O` level.
    Interp(u8),
    /// Closest hit specialized to the library layout in file `stem` (`pbrt`, `ptr`, ...),
    /// lowered to `lo` and compiled by LLVM's JIT at `-O3` (`scion-llvm`), with a traversal
    /// stack of `stack` entries, run through the runtime contract.
    Llvm {
        /// The layout's file stem in `library/layouts`.
        stem: &'static str,
        /// Entries of the traversal stack.
        stack: u32,
    },
    /// The GPU pipeline of `scion trace --device gpu` emulated on the CPU
    /// ([`crate::gpu_emu`]): closest hit for the library layout `stem` with the GPU kernels,
    /// compiled for the host by LLVM -O3, packed and traced by `scion_cuda`'s pipeline with a
    /// traversal stack of `stack` entries.
    GpuEmulated {
        /// The layout's file stem in `library/layouts`.
        stem: &'static str,
        /// Entries of the traversal stack.
        stack: u32,
    },
}

impl BackendKind {
    /// The backend, ready to trace on `threads` threads (0 = one per core).
    pub fn instantiate(self, threads: usize) -> Result<Box<dyn Backend>, String> {
        Ok(match self {
            BackendKind::Reference => Box::new(Reference {
                driver: BatchDriver::new(threads)?,
            }),
            BackendKind::Brute => Box::new(Brute {
                driver: BatchDriver::new(threads)?,
            }),
            BackendKind::Interp(level) => Box::new(Interpreter {
                program: ClosestHit::compile(level)?,
                level,
                threads: if threads == 0 {
                    std::thread::available_parallelism().map_or(1, |n| n.get())
                } else {
                    threads
                },
            }),
            BackendKind::Llvm { stem, stack } => {
                let &(_, layout, _) = library_layouts()
                    .iter()
                    .find(|l| l.0 == stem)
                    .ok_or_else(|| format!("no library layout `{stem}`"))?;
                let code = JitClosestHit::compile_with(
                    stem,
                    layout,
                    Some(stack),
                    JIT_OPT_LEVEL,
                    Codegen::Llvm(3),
                )?;
                Box::new(Compiled {
                    name: format!("llvm-O3-{layout}"),
                    inner: LayoutBackend::new(Box::new(code), threads)?,
                })
            }
            BackendKind::GpuEmulated { stem, stack } => {
                let &(_, layout, boxes) = library_layouts()
                    .iter()
                    .find(|l| l.0 == stem)
                    .ok_or_else(|| format!("no library layout `{stem}`"))?;
                Box::new(EmulatedBackend::new(stem, layout, boxes, stack, threads)?)
            }
        })
    }
}

/// [`BackendKind::Llvm`]: a layout's compiled code under the name of its code generator.
pub struct Compiled {
    name: String,
    inner: LayoutBackend,
}

impl Backend for Compiled {
    fn name(&self) -> String {
        self.name.clone()
    }
    fn trace(
        &self,
        tris: &[Triangle],
        tree: &LogicalTree,
        rays: &[Ray],
    ) -> Result<Vec<Hit>, String> {
        self.inner.trace(tris, tree, rays)
    }
    fn stack_limit(&self) -> Option<usize> {
        self.inner.stack_limit()
    }
    fn boxes(&self) -> Boxes {
        self.inner.boxes()
    }
    fn max_triangles(&self) -> Option<usize> {
        self.inner.max_triangles()
    }
}

/// [`BackendKind::Reference`].
pub struct Reference {
    driver: BatchDriver,
}

impl Backend for Reference {
    fn name(&self) -> String {
        "reference".into()
    }
    fn trace(&self, _: &[Triangle], tree: &LogicalTree, rays: &[Ray]) -> Result<Vec<Hit>, String> {
        Ok(closest_hits_tree(tree, rays, &self.driver))
    }
}

/// [`BackendKind::Brute`].
pub struct Brute {
    driver: BatchDriver,
}

impl Backend for Brute {
    fn name(&self) -> String {
        "brute".into()
    }
    fn trace(&self, tris: &[Triangle], _: &LogicalTree, rays: &[Ray]) -> Result<Vec<Hit>, String> {
        Ok(closest_hits_brute(tris, rays, &self.driver))
    }
}

/// [`BackendKind::Interp`].
pub struct Interpreter {
    program: ClosestHit,
    level: u8,
    threads: usize,
}

impl Backend for Interpreter {
    fn name(&self) -> String {
        format!("interp-O{}", self.level)
    }
    fn trace(&self, _: &[Triangle], tree: &LogicalTree, rays: &[Ray]) -> Result<Vec<Hit>, String> {
        self.program.trace_all(tree, rays, self.threads)
    }
    fn max_rays(&self) -> Option<usize> {
        Some(64)
    }
}
