//! The back half of a compilation, as passes of the one pipeline (design note §5, paper §7.3):
//! `prune-functions` (the user's code and what it reaches), then, for an output made from `lo`,
//! `mem-to-lo` (partial: functions that still need a layout, such as traversals of a sum ADT
//! without `--layout`, are left out with a warning), `recursion-to-stack` with `--stack-size`,
//! `lo-inline`, and with `--entry` the exported entry points (`add-entries`) last. So
//! `--print-pipeline`, `--print-after-all`, `--stop-after` and `--time-passes` see every pass.
//! After the pipeline, [`render_low`] prints the `lo` module, its Cranelift IR or (for
//! `--emit=header`) the C header of the entries; `--emit=llvm|asm|obj|ptx` hand the module to
//! the LLVM backend (`driver::codegen`).

use super::cli::Emit;
use crate::abi::{self, EntrySig};
use scion_ir::diag::{Diagnostic, InternalError};
use scion_ir::pass::{PassCx, PassError};
use scion_ir::Module;

/// The passes from `tree`/`mem` to `lo`, in order.
pub const LOWER_PIPELINE: &[&str] = &["mem-to-lo", "recursion-to-stack", "lo-inline"];

/// Whether `emit` is made from the `lo` module (`lo`, `clif`, `header` and LLVM's outputs).
pub fn needs_lo(emit: Emit) -> bool {
    emit.lowers_to_lo() || emit == Emit::Header
}

/// `names` completed for `emit`: `prune-functions` unless the list has it or lowers by itself
/// (names `mem-to-lo`); then, when `emit` is made from `lo` and the list does not lower, the
/// lowering ([`LOWER_PIPELINE`]); with `entry`, `add-entries` last.
pub fn complete(mut names: Vec<String>, emit: Emit, entry: bool) -> Vec<String> {
    let has = |names: &[String], n: &str| names.iter().any(|x| x == n);
    let lowers = has(&names, "mem-to-lo");
    if !lowers && !has(&names, "prune-functions") {
        names.push("prune-functions".to_string());
    }
    if needs_lo(emit) {
        if !lowers {
            names.extend(LOWER_PIPELINE.iter().map(|s| s.to_string()));
        }
        if entry && !has(&names, "add-entries") {
            names.push("add-entries".to_string());
        }
    }
    names
}

/// Puts the lowering's options in `cx`: `mem-to-lo` in partial mode and the traversal stack of
/// `--stack-size` entries (E0909 for 0 when `pipeline` has `recursion-to-stack`).
pub fn lowering_options(
    cx: &mut PassCx,
    pipeline: &[String],
    stack_size: Option<u32>,
) -> Result<(), Diagnostic> {
    if stack_size == Some(0) && pipeline.iter().any(|n| n == "recursion-to-stack") {
        return Err(Diagnostic::error(
            "E0909",
            "--stack-size=0: a traversal stack needs at least one entry",
        )
        .with_note("the default is 64 entries"));
    }
    cx.set_option("mem-to-lo", "partial", "true");
    if let Some(n) = stack_size {
        cx.set_option("recursion-to-stack", "stack-size", &n.to_string());
    }
    Ok(())
}

/// The text `--emit=lo`, `--emit=clif` or `--emit=header` prints for the lowered module `m`.
/// `--emit=header` needs `entry`.
pub fn render_low(m: &Module, emit: Emit, entry: Option<&EntrySig>) -> Result<String, PassError> {
    Ok(match emit {
        Emit::Header => {
            let Some(sig) = entry else {
                return Err(PassError::Internal(InternalError::new(
                    "--emit=header without an entry signature",
                )));
            };
            let root = m
                .func_by_name(&sig.layout_fn("root"))
                .and_then(|f| m.funcs[f].results.first().copied())
                .map(|t| m.types.get(t).clone())
                .ok_or_else(|| {
                    PassError::Internal(InternalError::new("the entries have no root function"))
                })?;
            abi::header::render(sig, &root)
        }
        Emit::Mlir => crate::mlir::print_mlir(m).map_err(|d| PassError::Diagnostics(d.into()))?,
        #[cfg(feature = "backends")]
        Emit::Clif => scion_clif::print_clif(m)
            .map_err(|e| PassError::Internal(InternalError::new(e.to_string())))?,
        #[cfg(not(feature = "backends"))]
        Emit::Clif => {
            return Err(PassError::Diagnostics(
                super::codegen::missing(Emit::Clif).into(),
            ))
        }
        _ => scion_ir::print::print_module(m),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn the_pipeline_is_completed_for_the_output() {
        let o3 = names(&["mem-inline", "const-fold", "mem-cse", "dce"]);
        assert_eq!(
            complete(o3.clone(), Emit::Tree, false).join(","),
            "mem-inline,const-fold,mem-cse,dce,prune-functions"
        );
        assert_eq!(
            complete(o3, Emit::Asm, true).join(","),
            "mem-inline,const-fold,mem-cse,dce,prune-functions,mem-to-lo,recursion-to-stack,lo-inline,add-entries"
        );
        // A list that lowers by itself is taken as it is (entries still come last).
        let own = names(&["mem-to-lo", "lo-inline"]);
        assert_eq!(complete(own.clone(), Emit::Lo, false), own);
        assert_eq!(
            complete(own, Emit::Lo, true).join(","),
            "mem-to-lo,lo-inline,add-entries"
        );
        // Completing twice changes nothing.
        let once = complete(Vec::new(), Emit::Header, true);
        assert_eq!(complete(once.clone(), Emit::Header, true), once);
    }
}
