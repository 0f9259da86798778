//! The IR crate's tests, one test binary (one link, the files' tests side by side on every core).

mod common;

mod builder;
mod interp;
mod interp_lazy;
mod lo;
mod parse_errors;
mod passes;
mod rewrite;
mod roundtrip;
mod text_form;
mod verifier;
