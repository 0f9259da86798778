//! The compiler's tests that need no code generator, one test binary: they build and pass with `--no-default-features` too (no LLVM, no Cranelift).

mod common;

mod abi_header;
mod bare_variants;
mod data_layout_agrees;
mod doc_examples;
mod driver_io;
mod dsl_opt_diff;
mod frontend_robustness;
mod library_layouts;
mod lower_robustness;
mod parse_constructs;
mod parse_errors;
mod parse_library;
mod parse_print_roundtrip;
mod parse_robustness;
mod prelude_triangle4;
mod without_backends;
