//! The compiler's tests that run generated code through Cranelift or LLVM (or `scion-opt`), one test binary.

mod common;

mod best_first;
mod lower_diff;
mod lower_random;
mod pbrt_jit;
mod quant_diff;
mod recursion_stack;
mod specialize_text_ir;
