//! Generic passes shipped with the IR crate, usable at any level: they exercise the pass
//! manager end to end and clean up after the compiler's own passes. The compiler's registry
//! (`compiler/src/passes/mod.rs`) lists them next to its own.

pub mod const_fold;
pub mod dce;

use crate::pass::{Level, PassInfo};

/// Registry entries of this crate's passes.
pub fn builtin_passes() -> Vec<PassInfo> {
    vec![
        PassInfo {
            name: "const-fold",
            summary: "Evaluate tree arithmetic, comparisons and casts on scalar constants (exact IEEE semantics)",
            input: Level::Any,
            output: Level::Any,
            create: || Box::new(const_fold::ConstFold),
        },
        PassInfo {
            name: "dce",
            summary: "Remove operations without side effects whose results are unused",
            input: Level::Any,
            output: Level::Any,
            create: || Box::new(dce::Dce),
        },
    ]
}
