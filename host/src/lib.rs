//! `scion-host`: the host side of code Scion compiles for the closest-hit algorithm, shared by
//! the `scion` command, the benchmarks and the differential tests (`scion-tests`). Input: a
//! scene's logical tree and rays; output: hits, through one of the [`backend::Backend`]s.
//!
//! - [`oracle`]: `closest_hit.scion` compiled to the `tree` dialect and interpreted over a
//!   runtime logical tree, lazily (no layout): the layout-free oracle and the `interp` backend.
//! - [`backend`]: the [`backend::Backend`] trait every way of tracing rays implements
//!   (reference traversal, brute force, the interpreter, the JIT of each library layout) and
//!   [`backend::BackendKind`], the backends `scion trace` offers.
//! - [`contract`]: the host side of the runtime contract (`@L.sizes`, aligned buffers,
//!   `@L.build`, batch entries over blocks of 64, statuses with the failing ray's index) for
//!   code specialized to a layout.
//! - [`mem_interp`]: the library layouts' sources ([`mem_interp::library_layouts`]) and closest
//!   hit specialized to each of them (`tree`+`mem` level), run by the interpreter over its byte
//!   memory through that contract.
//! - [`library`]: the library's layouts and algorithms as a registry (found by `build.rs`,
//!   described by the front end), and what `--layout` / `--algorithm` name: a library name or
//!   any `.scion` file.
//! - [`jit`]: closest hit specialized to each library layout, lowered to `lo` and compiled by
//!   Cranelift or LLVM, as a [`contract::LayoutCode`].
//! - [`entries`]: any algorithm's exported C entries called as a C host calls them, over
//!   query and result records of the sizes the compiler's ABI computed (`scion run`).
//! - [`collide`]: a collision entry over two packed trees, its pairs through a sink.
//! - [`gpu_emu`]: the GPU pipeline of `scion-cuda` emulated on the CPU: the GPU kernels
//!   compiled for the host (`lo-host-kernels`), launched as grids of host threads.
//! - [`progress`]: how many queries the interpreters have answered, for progress bars.
//! - [`queries`]: the table of query kinds: queries, initial results, reference answers.
//! - [`hit_reference`]: which reference traversal a layout's hits are compared with (binary,
//!   or wide over the tree collapsed to its children per node) and the rule every check of
//!   hits follows (equal to it, or brute force's where its rounding pruned that hit).
//! - [`quantized`]: how a layout stores its boxes, and the decoded tree a quantized layout
//!   really traverses (its bit-for-bit reference).
pub mod backend;
pub mod collide;
pub mod contract;
pub mod entries;
pub mod gpu_emu;
pub mod hit_reference;
pub mod jit;
pub mod library;
pub mod mem_interp;
pub mod oracle;
pub mod progress;
pub mod quantized;
pub mod queries;
