//! Passes on structured `tree`/`mem` functions, after the specializations: [`inline`]
//! (`mem-inline`), [`cse`] (`mem-cse`) and [`sink`] (`mem-sink`).

pub mod cse;
pub mod inline;
pub mod sink;
