//! The back half of `scionc`: from the `tree` module the front end produced to `--emit=lo` or
//! `--emit=clif` text (design note §5, paper §7.3).
//!
//! Runs `mem-to-lo` (partial: functions that still need a layout, such as traversals of a sum
//! ADT before destructor specialization exists for the input, are left out) and then
//! `recursion-to-stack` with `--stack-size`, then `lo-inline`, and prints the `lo` module or its Cranelift IR.
//! `--emit=llvm|asm|obj|ptx` use [`lower_to_lo`] the same way and hand the module to the LLVM
//! backend (`driver::codegen`).

use super::cli::Emit;
use crate::passes;
use scion_ir::diag::{Diagnostics, InternalError};
use scion_ir::pass::{PassCx, PassError, PassManager};
use scion_ir::Module;

/// The passes from `tree`/`mem` to `lo`, in order.
pub const LOWER_PIPELINE: &[&str] = &["mem-to-lo", "recursion-to-stack", "lo-inline"];

/// Lowers `m` to `lo` in place (partial mode) with the given traversal stack size; returns the
/// warnings (functions left out).
pub fn lower_to_lo(m: &mut Module, stack_size: Option<u32>) -> Result<Diagnostics, PassError> {
    if stack_size == Some(0) {
        let d = scion_ir::diag::Diagnostic::error(
            "E0909",
            "--stack-size=0: a traversal stack needs at least one entry",
        )
        .with_note("the default is 64 entries");
        return Err(PassError::Diagnostics(d.into()));
    }
    let registry = passes::registry();
    let names: Vec<String> = LOWER_PIPELINE.iter().map(|s| s.to_string()).collect();
    let mut pm =
        PassManager::from_names(&registry, &names).map_err(|d| PassError::Diagnostics(d.into()))?;
    let mut cx = PassCx::new();
    cx.set_option("mem-to-lo", "partial", "true");
    if let Some(n) = stack_size {
        cx.set_option("recursion-to-stack", "stack-size", &n.to_string());
    }
    let mut dumps = String::new();
    pm.run(m, &mut cx, &mut dumps)?;
    Ok(std::mem::take(&mut cx.diagnostics))
}

/// The text `--emit=lo` or `--emit=clif` prints for the `tree` module `m`, and the warnings.
pub fn emit_low(
    m: &mut Module,
    emit: Emit,
    stack_size: Option<u32>,
) -> Result<(String, Diagnostics), PassError> {
    let warnings = lower_to_lo(m, stack_size)?;
    let text = match emit {
        Emit::Clif => scion_clif::print_clif(m)
            .map_err(|e| PassError::Internal(InternalError::new(e.to_string())))?,
        _ => scion_ir::print::print_module(m),
    };
    Ok((text, warnings))
}
