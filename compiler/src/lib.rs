//! The Scion compiler.
//!
//! Pipeline: `syntax` (source → AST) → `sema` (names, types, well-formedness) → `irgen`
//! (typed AST → `tree` dialect) → passes → backends. Each stage lives in its own module and
//! sees only the stage before it.

pub mod abi;
pub mod driver;
pub mod frontend;
pub mod fuzz;
pub mod irgen;
pub mod layout;
pub mod mlir;
pub mod passes;
pub mod sema;
pub mod syntax;
