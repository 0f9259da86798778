//! The pass registry: every pass the compiler knows, one line each (name, summary, input and
//! output level, constructor).
//!
//! Generic passes that work on any dialect (`const-fold`, `dce`) come from `scion-ir`; passes
//! that need the compiler's knowledge (layouts, builds) will be registered here next to them.
//! Pass order lives in `driver/pipelines.rs` alone.

pub mod lo_inline;
pub mod mem_to_lo;
#[path = "mem/recursion_to_stack.rs"]
pub mod recursion_to_stack;

use scion_ir::pass::PassRegistry;

/// Every pass `scionc --passes=...` and `--help-passes` know.
pub fn registry() -> PassRegistry {
    let mut reg = PassRegistry::with_builtin();
    lower_passes(&mut reg);
    reg
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
        create: || Box::new(recursion_to_stack::RecursionToStack),
    });
    reg.register(scion_ir::PassInfo {
        name: "lo-inline",
        summary: "inline calls of small leaf functions in lo (option max-ops, default 48)",
        input: scion_ir::pass::Level::Lo,
        output: scion_ir::pass::Level::Lo,
        create: || Box::new(lo_inline::LoInline),
    });
}
