//! Syntax of the three Scion languages: tokens, lexer, parser and the AST.
//!
//! `syntax` knows nothing of `sema` or of the IR. The parser recovers from errors and returns
//! the AST together with every diagnostic it found (codes `E01xx`).

pub mod ast;
