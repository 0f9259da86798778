//! The `scionc` driver: command line, compilation session, pass pipelines and output.
//!
//! [`run`] takes parsed [`Options`] and returns the process exit status: 0 on success, 1 when
//! the input has errors (diagnostics were printed), 101 on an internal compiler error. Nothing
//! here panics on user input.

pub mod cli;
#[cfg(feature = "backends")]
pub mod codegen;
/// Without the `backends` feature: the LLVM outputs are an error (E0922).
#[cfg(not(feature = "backends"))]
#[path = "codegen_none.rs"]
pub mod codegen;
pub mod lower;
pub mod pipelines;
pub mod session;

pub use cli::Options;
pub use session::run;
