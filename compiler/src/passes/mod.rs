//! The pass registry: every pass the compiler knows, one line each (name, summary, input and
//! output level, constructor).
//!
//! Generic passes that work on any dialect (`const-fold`, `dce`) come from `scion-ir`; passes
//! that need the compiler's knowledge (layouts, builds) will be registered here next to them.
//! Pass order lives in `driver/pipelines.rs` alone.

use scion_ir::pass::PassRegistry;

/// Every pass `scionc --passes=...` and `--help-passes` know.
pub fn registry() -> PassRegistry {
    PassRegistry::with_builtin()
}
