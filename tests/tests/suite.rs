//! Scion's differential and end-to-end tests, one test binary (each file below was its own; one binary links the stack once and runs the files' tests side by side on every core).

mod c_entries;
mod common;
mod tools;

mod aarch64_qemu;
mod abi_entries;
mod closest_point;
mod collide;
mod contract;
mod cpp_example;
mod differential;
mod dop14;
mod gpu_emu;
mod gpu_emu_layouts;
mod hair;
mod jit;
mod mlir;
mod occluded;
mod query_kinds;
mod shared_slab;
mod strands;
mod triangle4;
mod wide;
mod work_counts;
