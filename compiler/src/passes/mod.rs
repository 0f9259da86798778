//! The pass registry: every pass the compiler knows, one line each (name, summary, input and
//! output level, constructor).
//!
//! Generic passes that work on any dialect (`const-fold`, `dce`) come from `scion-ir`; passes
//! that need the compiler's knowledge of layouts are registered here next to them
//! ([`tree_to_mem`]). Pass order lives in `driver/pipelines.rs` alone.

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
    r
}
