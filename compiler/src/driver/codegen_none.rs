//! `--emit=llvm|asm|obj|ptx` in a `scionc` built without the `backends` feature (which links
//! LLVM and Cranelift): an error that says so (E0922), instead of machine code. The front end,
//! the IR, every pass and `--emit=ast|check|tree|mem|lo|header` work without it.

use super::cli::{Emit, Options};
use scion_ir::diag::Diagnostic;
use scion_ir::Module;

/// The LLVM target of the command line: none without the backend.
pub fn select_target(opts: &Options) -> Result<(), Diagnostic> {
    Err(missing(opts.emit))
}

/// Compiles `m` as the options ask: an error without the backend.
pub fn emit(_m: &Module, opts: &Options) -> Result<Vec<u8>, Diagnostic> {
    Err(missing(opts.emit))
}

/// E0922: `emit` needs a code generator this build does not have.
pub fn missing(emit: Emit) -> Diagnostic {
    Diagnostic::error(
        "E0922",
        format!(
            "`--emit={}` needs a code generator, and this scionc was built without them",
            emit.as_str()
        ),
    )
    .with_note("build scion-compiler with its default feature `backends` (LLVM and Cranelift)")
}
