//! The runtime's tests, one test binary (one link, the files' tests side by side on every core).

mod common;

mod hard_cases;
mod load_errors;
mod query_files;
mod real_scenes;
mod transforms;
