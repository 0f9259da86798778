//! Syntax of the three Scion languages: tokens, lexer, parser, the AST and its printer.
//!
//! `syntax` knows nothing of `sema` or of the IR. The parser recovers from errors and returns
//! the AST together with every diagnostic it found (codes `E01xx`, listed in `errors.rs`).
//! Entry points: [`parse_file`], [`parse_program`] and [`print::print_program`]
//! (`scionc --emit=ast`).

pub mod ast;
pub mod errors;
pub mod lexer;
pub mod parser;
pub mod print;
pub mod token;

pub use parser::{parse_file, parse_program};
