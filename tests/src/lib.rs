//! `scion-tests`: the layout-free oracle and the differential harness (issue 3, items 6 and
//! the test plan of docs/design/specialization.md).
//!
//! - [`oracle`]: `closest_hit.scion` compiled to the `tree` dialect and interpreted over a
//!   runtime logical tree, lazily (no layout).
//! - [`backend`]: the [`backend::Backend`] trait every way of tracing rays implements
//!   (reference traversal, brute force, the interpreter; the JIT per layout later), so that a
//!   new backend is one more row of the differential table.
//! - [`cases`]: the scenes (real and generated hard cases), trees and ray sets the rows use,
//!   and [`cases::compare`], the bit-for-bit comparison with its one documented exception.
//! - [`contract`]: the host side of the runtime contract (`@L.sizes`, aligned buffers,
//!   `@L.build`, batch entries over blocks of 64, statuses with the failing ray's index) for
//!   code specialized to a layout.
//! - [`mem_interp`]: closest hit specialized to each library layout (`tree`+`mem` level) and
//!   run by the interpreter over its byte memory through that contract: the layout rows of
//!   the differential table without the JIT.
//! - [`jit`]: closest hit specialized to each library layout, lowered to `lo` and compiled by
//!   Cranelift, as a [`contract::LayoutCode`].

pub mod backend;
pub mod cases;
pub mod contract;
pub mod jit;
pub mod mem_interp;
pub mod oracle;
pub mod quantized;
