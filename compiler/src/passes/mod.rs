//! The pass registry: every pass the compiler knows, one line each (name, summary, input and
//! output level, constructor).
//!
//! Generic passes that work on any dialect (`const-fold`, `dce`) come from `scion-ir`; the
//! compiler's own passes sit under the level they transform or between the two they connect:
//! [`tree_to_mem`] (the specializations, `tree` to `mem`), [`mem`] (`mem-inline`, `mem-cse`),
//! [`mem_to_lo`] (`mem` to `lo`) and [`lo`] (`recursion-to-stack`, `lo-inline`,
//! `lo-host-kernels`). Pass order lives in `driver/pipelines.rs` alone.

pub mod lo;
pub mod mem;
pub mod mem_to_lo;
pub mod prune;
pub mod tree_to_mem;

use scion_ir::pass::{Level, PassInfo, PassRegistry};

/// Every pass `scionc --passes=...` and `--help-passes` know.
pub fn registry() -> PassRegistry {
    let mut r = PassRegistry::with_builtin();
    r.register(PassInfo {
        name: "destructor-specialize",
        summary: "rewrite traversals of the layout's tree type into reads of the layout (needs --layout)",
        input: Level::Tree,
        output: Level::Mem,
        create: || Box::new(tree_to_mem::destructor::DestructorSpecialize),
    });
    r.register(PassInfo {
        name: "constructor-specialize",
        summary: "generate @L.sizes and @L.build, the packer of the layout, from its build (needs --layout)",
        input: Level::Mem,
        output: Level::Mem,
        create: || Box::new(tree_to_mem::constructor::ConstructorSpecialize),
    });
    r.register(PassInfo {
        name: "mem-inline",
        summary:
            "inline calls of small non-recursive tree/mem functions (option max-ops, default 32)",
        input: Level::Any,
        output: Level::Any,
        create: || Box::new(mem::inline::MemInline),
    });
    r.register(PassInfo {
        name: "mem-sink",
        summary: "move pure ops and layout loads into the one conditional region that uses them",
        input: Level::Any,
        output: Level::Any,
        create: || Box::new(mem::sink::MemSink),
    });
    r.register(PassInfo {
        name: "mem-split-loads",
        summary: "read an indexed layout array one element at a time instead of whole",
        input: Level::Any,
        output: Level::Any,
        create: || Box::new(mem::split_loads::MemSplitLoads),
    });
    r.register(PassInfo {
        name: "mem-cse",
        summary: "reuse dominating equivalent pure tree/mem ops: layout and cell loads, pure calls",
        input: Level::Any,
        output: Level::Any,
        create: || Box::new(mem::cse::MemCse),
    });
    r.register(PassInfo {
        name: "prune-functions",
        summary: "drop functions that no function of the user's files reaches (scionc adds it before the lowering)",
        input: Level::Any,
        output: Level::Any,
        create: || Box::new(prune::PruneFunctions),
    });
    lower_passes(&mut r);
    r
}

/// The passes from `tree`/`mem` down to `lo`.
fn lower_passes(reg: &mut PassRegistry) {
    reg.register(scion_ir::PassInfo {
        name: "mem-to-lo",
        summary: "structured tree/mem functions to the lo CFG (scalarized)",
        input: scion_ir::pass::Level::Any,
        output: scion_ir::pass::Level::Lo,
        create: || Box::new(mem_to_lo::MemToLo),
    });
    reg.register(scion_ir::PassInfo {
        name: "recursion-to-stack",
        summary: "recursive traversals to a loop over a fixed stack (status 1 on overflow)",
        input: scion_ir::pass::Level::Lo,
        output: scion_ir::pass::Level::Lo,
        create: || Box::new(lo::recursion_to_stack::RecursionToStack),
    });
    reg.register(scion_ir::PassInfo {
        name: "lo-inline",
        summary: "inline calls of small leaf functions in lo (option max-ops, default 48)",
        input: scion_ir::pass::Level::Lo,
        output: scion_ir::pass::Level::Lo,
        create: || Box::new(lo::inline::LoInline),
    });
    reg.register(scion_ir::PassInfo {
        name: "add-entries",
        summary: "add the exported C entry points of --entry (needs --entry and --layout; last)",
        input: scion_ir::pass::Level::Lo,
        output: scion_ir::pass::Level::Lo,
        create: || Box::new(lo::entries::AddEntries),
    });
    reg.register(scion_ir::PassInfo {
        name: "lo-host-kernels",
        summary: "GPU kernels to host functions taking the thread index as a last u64 parameter (host emulation of a launch)",
        input: scion_ir::pass::Level::Lo,
        output: scion_ir::pass::Level::Lo,
        create: || Box::new(lo::host_kernels::LoHostKernels),
    });
}
