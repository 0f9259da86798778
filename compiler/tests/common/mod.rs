//! Helpers shared by the compiler's integration tests.
#![allow(dead_code)]

use proptest::prelude::*;
use scion_compiler::syntax::ast::Program;
use scion_compiler::syntax::parse_file;
use scion_ir::diag::{Diagnostics, SourceMap};
use std::path::{Path, PathBuf};

/// The repository's `library/` folder.
pub fn library_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../library")
}

/// `(path, text)` of `library/*.scion` and `library/*/*.scion`, sorted by path.
pub fn library_files() -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut dirs = vec![library_dir()];
    let mut depth = 0;
    while !dirs.is_empty() && depth < 2 {
        let mut next = Vec::new();
        for dir in dirs {
            let Ok(entries) = std::fs::read_dir(&dir) else {
                continue;
            };
            for entry in entries.flatten() {
                let path = entry.path();
                if path.is_dir() {
                    next.push(path);
                } else if path.extension().is_some_and(|e| e == "scion") {
                    let text = std::fs::read_to_string(&path).expect("readable library file");
                    out.push((path.display().to_string(), text));
                }
            }
        }
        dirs = next;
        depth += 1;
    }
    out.sort();
    out
}

/// Parses `text` as one file named `name`.
pub fn parse_str(name: &str, text: &str) -> (Program, Diagnostics, SourceMap) {
    let mut sources = SourceMap::new();
    let file = sources.add(name, text);
    let mut program = Program::default();
    let diags = parse_file(&sources, file, &mut program);
    (program, diags, sources)
}

/// Removes `Span { .. }` and `NodeId(..)` from a Debug rendering, so two trees that differ
/// only in positions and ids compare equal.
pub fn strip_positions(debug: &str) -> String {
    let mut out = String::with_capacity(debug.len());
    let mut rest = debug;
    loop {
        let span = rest.find("Span {");
        let id = rest.find("NodeId(");
        let (at, open, close) = match (span, id) {
            (Some(s), Some(i)) if i < s => (i, '(', ')'),
            (Some(s), _) => (s, '{', '}'),
            (None, Some(i)) => (i, '(', ')'),
            (None, None) => break,
        };
        out.push_str(&rest[..at]);
        let after = &rest[at..];
        let start = after.find(open).expect("opener");
        let mut depth = 0usize;
        let mut end = after.len();
        for (i, c) in after[start..].char_indices() {
            if c == open {
                depth += 1;
            } else if c == close {
                depth -= 1;
                if depth == 0 {
                    end = start + i + 1;
                    break;
                }
            }
        }
        rest = &after[end..];
    }
    out.push_str(rest);
    out
}

/// The `tree` module of `inputs` (name, text), after the library's prelude when `prelude`,
/// unoptimized, printed and parsed back; `Err` holds the rendered diagnostics.
pub fn tree_module_of(inputs: &[(&str, &str)], prelude: bool) -> Result<scion_ir::Module, String> {
    use scion_compiler::driver::cli::Emit;
    use scion_compiler::frontend::{compile, Frontend, PassOptions};
    let mut sources = SourceMap::new();
    let prelude: Vec<_> = if prelude {
        let text = std::fs::read_to_string(library_dir().join("prelude.scion")).expect("prelude");
        vec![sources.add("prelude.scion", text)]
    } else {
        vec![]
    };
    let files: Vec<_> = inputs
        .iter()
        .map(|(name, text)| sources.add(*name, text.to_string()))
        .collect();
    let fe = Frontend {
        sources: &sources,
        prelude: &prelude,
        inputs: &files,
    };
    let out = compile(&fe, Emit::Tree, &[], &PassOptions::default());
    if let Some(ice) = out.internal_error {
        panic!("internal compiler error: {ice}");
    }
    if out.diagnostics.has_errors() {
        return Err(out.diagnostics.render(&sources));
    }
    let text = out.output.expect("tree text");
    let file = sources.add("<tree>", text.clone());
    Ok(scion_ir::parse_module(&text, file).expect("the printed tree parses back"))
}

/// Floats rich in edge cases for differential tests: NaNs with payloads and signs, signed
/// zeros, infinities, subnormals, small values and anything.
pub fn special_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        3 => -8.0f32..8.0,
        1 => Just(0.0f32),
        1 => Just(-0.0f32),
        1 => Just(f32::INFINITY),
        1 => Just(f32::NEG_INFINITY),
        1 => Just(f32::NAN),
        1 => Just(f32::from_bits(0x7fa0_1234)),
        1 => Just(f32::from_bits(0xffc0_0001)),
        1 => Just(f32::from_bits(1)),
        1 => Just(-f32::MIN_POSITIVE / 3.0),
        1 => Just(1.0f32),
        2 => any::<f32>(),
    ]
}

/// How many random cases a differential test runs: `default`, or `PROPTEST_CASES` when set
/// (fuzz harder with e.g. `PROPTEST_CASES=100000`; CI draws new seeds on every run).
pub fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|c| c.parse().ok())
        .unwrap_or(default)
}
