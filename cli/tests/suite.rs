//! The `scion` command's tests, one test binary (one link, the files' tests side by side on every core).

mod common;

mod blocks;
mod cli;
mod explore;
mod gpu;
mod render;
mod run;
mod strands;
