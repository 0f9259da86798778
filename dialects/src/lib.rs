//! `scion-ir`: the intermediate representation shared by every level of the Scion compiler.

#![warn(missing_docs)]

pub mod attr;
pub mod builder;
pub mod diag;
pub mod entity;
pub mod module;
pub mod op;
pub mod parse;
pub mod print;
pub mod rewrite;
pub mod tree;
pub mod types;
pub mod verify;
pub mod walk;

pub use builder::{Builder, InsertPoint, OpSpec};
pub use module::Module;
