//! Passes on structured `tree`/`mem` functions, after the specializations: [`inline`]
//! (`mem-inline`) and [`cse`] (`mem-cse`).

pub mod cse;
pub mod inline;
