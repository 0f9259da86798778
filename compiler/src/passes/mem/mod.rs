//! Passes on structured `tree`/`mem` functions, after the specializations: [`inline`]
//! (`mem-inline`), [`cse`] (`mem-cse`), [`split_loads`] (`mem-split-loads`) and [`sink`]
//! (`mem-sink`).

pub mod cse;
pub mod inline;
pub mod sink;
pub mod split_loads;
