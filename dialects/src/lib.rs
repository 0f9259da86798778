//! `scion-ir`: the intermediate representation shared by every level of the Scion compiler.
//!
//! This crate depends on nothing else of Scion's and on neither LLVM nor Cranelift. It holds
//! source positions and diagnostics ([`diag`]), and the IR core with its dialects.

#![warn(missing_docs)]

pub mod diag;
