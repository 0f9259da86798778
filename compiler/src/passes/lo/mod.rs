//! Passes on the `lo` CFG: [`recursion_to_stack`] (recursive traversals to a loop over an
//! explicit stack), [`inline`] (`lo-inline`), [`entries`] (`add-entries`, the exported C entry
//! points) and [`host_kernels`] (GPU kernels as host functions, for running them on the CPU).

pub mod best_first;
pub mod deferred_calls;
pub mod entries;
pub mod host_kernels;
pub mod inline;
pub mod recursion_to_stack;
