//! The physical layout of a tree (paper §4, §6, §7): the model of a `layout` declaration with
//! every byte placed ([`model`]), field resolution from a variant's logical field to its unique
//! physical path ([`resolve`], Algorithm 1 with scopes), the contiguous buffers a constructor
//! allocates ([`plan`], §7.2), and the split-coverage arithmetic ([`domain`]).
//!
//! Input: the AST of a [`Program`](crate::syntax::ast::Program); output: [`LayoutModel`],
//! [`FieldPath`]s and [`BufferPlan`]s for destructor and constructor specialization. The
//! well-formedness checks of layouts and builds (`sema::check_layout`, `sema::check_build`) are
//! declared here for now so this module compiles on its own; they belong to `sema`.

pub mod adt;
pub mod carried;
pub mod domain;
pub mod dump;
pub mod logical;
pub mod model;
mod parents;
mod place;
pub mod plan;
pub mod resolve;
pub mod types;

#[cfg(test)]
pub(crate) mod fixtures;
#[cfg(test)]
mod tests;

#[path = "../sema/check_layout.rs"]
pub mod check_layout;

#[path = "../sema/check_build.rs"]
pub mod check_build;

#[path = "../sema/check_build_root.rs"]
mod check_build_root;

#[cfg(test)]
#[path = "../sema/check_tests.rs"]
mod check_tests;

#[cfg(test)]
#[path = "../sema/check_robustness.rs"]
mod check_robustness;

pub use dump::byte_map;
pub use model::LayoutModel;
pub use plan::BufferPlan;
pub use resolve::{resolve_field, FieldPath, Resolver};
