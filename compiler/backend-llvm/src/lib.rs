//! `scion-llvm`: Scion's LLVM backend (LLVM 22 through inkwell). Input: a verified module of
//! the `lo` dialect; output: LLVM IR text, assembly (PTX on NVPTX) or an ELF object for
//! x86-64, AArch64 or NVPTX ([`emit`]), or machine code in this process ([`JitModule`]).
//!
//! The translation ([`translate`]) is one-to-one and has exactly the float semantics of
//! `scion-clif` and the interpreters of `scion-ir` (NaN canonicalization, minNum/maxNum,
//! ulp steps, saturating casts); the differential tests check the JIT against both on random
//! inputs with NaNs, signed zeros, infinities and subnormals. `-O0`..`-O3` run LLVM's
//! `default<O0>`..`default<O3>` pipelines and code generation at the same level.
//!
//! Linkage follows `docs/design/backends.md` §1: when a function carries the `export`
//! attribute, every other defined function is internal, so an object exports only the C entry
//! points; otherwise every function is external under its `lo` name. On NVPTX, `kernel`
//! functions get the `ptx_kernel` calling convention and `lo.global_id` reads the special
//! registers `%ctaid.x * %ntid.x + %tid.x`.
//!
//! ```
//! use scion_ir::interp::Val;
//! let m = scion_ir::parse_module(r#"
//! func @twice(%x: f32) -> (f32) {
//!   %y = "lo.add"(%x, %x) : (f32, f32) -> f32
//!   "lo.return"(%y) : (f32) -> ()
//! }
//! "#, scion_ir::diag::FileId(0)).unwrap();
//! let jit = scion_llvm::JitModule::compile(&m, 2).unwrap();
//! let out = jit.call("twice", &[Val::F32(1.5)]).unwrap();
//! assert!(matches!(out[0], Val::F32(x) if x == 3.0));
//! let opts = scion_llvm::Options::new(scion_llvm::Target::Aarch64);
//! let asm = scion_llvm::emit(&m, &opts, scion_llvm::Output::Asm).unwrap();
//! assert!(String::from_utf8(asm).unwrap().contains("fadd"));
//! ```

mod clamps;
pub mod jit;
mod mask_counts;
pub mod target;
pub mod translate;

pub use jit::{JitModule, Llvm};

/// The version of the LLVM library linked in (`major.minor.patch`).
pub fn llvm_version() -> String {
    let (a, b, c) = inkwell::support::get_llvm_version();
    format!("{a}.{b}.{c}")
}
pub use target::Target;

use inkwell::context::Context;
use inkwell::targets::FileType;
use std::fmt;

/// A backend failure: unsupported IR for the target, a bad option, or an LLVM error.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LlvmError(pub String);

impl fmt::Display for LlvmError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "llvm backend: {}", self.0)
    }
}

impl std::error::Error for LlvmError {}

/// What [`emit`] produces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Output {
    /// The optimized LLVM IR, as text.
    LlvmIr,
    /// Assembly text (PTX on [`Target::Nvptx64`]).
    Asm,
    /// A relocatable ELF object (not for NVPTX).
    Object,
}

/// Code generation options.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Options {
    /// The target architecture.
    pub target: Target,
    /// The CPU: `None` for the target's default (`x86-64`, `generic`, `sm_90`), `native` for
    /// this machine's CPU and features, or an LLVM CPU name (`znver4`, `neoverse-v2`, `sm_80`).
    pub cpu: Option<String>,
    /// `-O0`..`-O3`.
    pub opt_level: u8,
}

impl Options {
    /// `target` with its default CPU at `-O2`.
    pub fn new(target: Target) -> Options {
        Options {
            target,
            cpu: None,
            opt_level: 2,
        }
    }
}

/// Translates, verifies, optimizes and compiles the verified `lo` module `m`.
pub fn emit(m: &scion_ir::Module, opts: &Options, out: Output) -> Result<Vec<u8>, LlvmError> {
    let tm = target::target_machine(opts.target, opts.cpu.as_deref(), opts.opt_level)?;
    let cx = Context::create();
    let (lm, _) = translate::translate(&cx, m, "scion", opts.target, true).map_err(LlvmError)?;
    lm.set_triple(&tm.get_triple());
    lm.set_data_layout(&tm.get_target_data().get_data_layout());
    lm.verify()
        .map_err(|e| LlvmError(format!("invalid LLVM module (a backend bug): {e}")))?;
    target::optimize(&lm, &tm, opts.opt_level, opts.target.is_gpu())?;
    match out {
        Output::LlvmIr => Ok(lm.print_to_string().to_bytes().to_vec()),
        Output::Asm => target::codegen(&lm, &tm, FileType::Assembly),
        Output::Object if opts.target.is_gpu() => Err(LlvmError(
            "NVPTX has no object files: emit PTX (assembly) instead".into(),
        )),
        Output::Object => target::codegen(&lm, &tm, FileType::Object),
    }
}

/// The LLVM IR of `m` for `target` as translated, before any optimization (for tests and
/// debugging), after LLVM's verifier accepted it.
pub fn translate_to_ir(m: &scion_ir::Module, target: Target) -> Result<String, LlvmError> {
    let cx = Context::create();
    let (lm, _) = translate::translate(&cx, m, "scion", target, true).map_err(LlvmError)?;
    lm.verify()
        .map_err(|e| LlvmError(format!("invalid LLVM module (a backend bug): {e}")))?;
    Ok(lm.print_to_string().to_string())
}
