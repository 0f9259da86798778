//! The LLVM backend's tests, one test binary (one link, the files' tests side by side on every core).

mod emit;
mod nvptx_rounding;
mod ops;
