//! What a code generator offers the rest of Scion: JIT compilation of a verified `lo` module to
//! machine code in this process, and calls into it. Cranelift (`scion_clif::Cranelift`) and
//! LLVM (`scion_llvm::Llvm`) implement [`Backend`], their compiled modules [`JitCode`], so the
//! host's engines and the differential tests treat them alike and a new code generator plugs in
//! by implementing the two traits (docs/backends.md).

use crate::interp::Val;
use crate::module::Module;

/// Machine code of a `lo` module, in executable memory for as long as the value lives.
pub trait JitCode {
    /// The machine-code address of `@name` (the host's C calling convention), if defined.
    fn function_ptr(&self, name: &str) -> Option<*const u8>;

    /// Calls `@name` on scalar arguments (`ptr` as a `u64` integer) and returns its results;
    /// the arguments' types must match the parameters (checked).
    fn call(&self, name: &str, args: &[Val]) -> Result<Vec<Val>, String>;
}

/// A code generator that JIT-compiles `lo` modules.
pub trait Backend {
    /// A short name for reports and test messages (`cranelift`, `llvm -O3`).
    fn name(&self) -> String;

    /// Compiles every function of the verified `lo` module `m`.
    fn jit(&self, m: &Module) -> Result<Box<dyn JitCode>, String>;
}
