//! `--emit=llvm|asm|obj|ptx`: runs the LLVM backend (`scion-llvm`) on the `lo` module the
//! front end lowered. Input: the module and the command line's `--target`, `--cpu` and `-O`;
//! output: the bytes to write, or a diagnostic for options that do not fit together or a
//! `--cpu` LLVM does not know for the target (E0920, a bad command line) and backend failures
//! (E0921).

use super::cli::{Emit, Options, Target};
use scion_ir::diag::Diagnostic;
use scion_ir::Module;

/// The LLVM target of the command line: `--target`, `nvptx64` for `--emit=ptx`, else this
/// machine. `--emit=ptx` with another target, and `--emit=obj` for nvptx64, are errors.
pub fn select_target(opts: &Options) -> Result<scion_llvm::Target, Diagnostic> {
    let chosen = opts.target.map(|t| match t {
        Target::X86_64 => scion_llvm::Target::X86_64,
        Target::Aarch64 => scion_llvm::Target::Aarch64,
        Target::Nvptx64 => scion_llvm::Target::Nvptx64,
    });
    let target = match (opts.emit, chosen) {
        (Emit::Ptx, Some(t)) if t != scion_llvm::Target::Nvptx64 => {
            return Err(Diagnostic::error(
                "E0920",
                format!(
                    "`--emit=ptx` needs target nvptx64, not `--target={}`",
                    t.name()
                ),
            )
            .with_note("PTX is NVIDIA GPU code: drop --target, or use --emit=asm for a CPU"))
        }
        (Emit::Ptx, _) => scion_llvm::Target::Nvptx64,
        (_, Some(t)) => t,
        (_, None) => scion_llvm::Target::host().ok_or_else(|| {
            Diagnostic::error("E0920", "this machine is not a target scionc knows")
                .with_note("give one with --target=x86_64|aarch64|nvptx64")
        })?,
    };
    if opts.emit == Emit::Obj && target.is_gpu() {
        return Err(Diagnostic::error(
            "E0920",
            "`--emit=obj` has no meaning for nvptx64: GPU code is PTX text",
        )
        .with_note("use --emit=ptx"));
    }
    if let Some(cpu) = &opts.cpu {
        scion_llvm::target::validate_cpu(target, cpu).map_err(|e| {
            Diagnostic::error("E0920", e.0).with_note(format!("target {}", target.triple()))
        })?;
    }
    Ok(target)
}

/// Compiles `m` as the options ask.
pub fn emit(m: &Module, opts: &Options) -> Result<Vec<u8>, Diagnostic> {
    let target = select_target(opts)?;
    let output = match opts.emit {
        Emit::Llvm => scion_llvm::Output::LlvmIr,
        Emit::Obj => scion_llvm::Output::Object,
        _ => scion_llvm::Output::Asm,
    };
    let llvm_opts = scion_llvm::Options {
        target,
        cpu: opts.cpu.clone(),
        opt_level: opts.opt_level,
    };
    scion_llvm::emit(m, &llvm_opts, output).map_err(|e| {
        Diagnostic::error("E0921", e.0).with_note(format!("target {}", target.triple()))
    })
}
