//! The `scion` code blocks of docs/language.md, README.md and the how-tos compile (to the tree
//! dialect) without diagnostics, so the documentation cannot drift from the compiler; the
//! blocks of docs/howto-add-a-layout.md are also pieces of the file the tests trace.
//!
//! A block whose first line is `// no-prelude` compiles without the prelude; one whose first
//! line is `// continued` is appended to the block before it.

use scion_compiler::driver::cli::Emit;
use scion_compiler::driver::session::{PRELUDE, PRELUDE_NAME};
use scion_compiler::frontend::{compile, Frontend, PassOptions};
use scion_ir::diag::SourceMap;
use std::path::PathBuf;

fn blocks(markdown: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut current: Option<(usize, String)> = None;
    for (i, line) in markdown.lines().enumerate() {
        match (&mut current, line.trim_start()) {
            (None, l) if l.starts_with("```scion") => current = Some((i + 1, String::new())),
            (Some(_), l) if l.starts_with("```") => out.extend(current.take()),
            (Some((_, text)), _) => {
                text.push_str(line);
                text.push('\n');
            }
            _ => {}
        }
    }
    out
}

fn check_file(rel: &str) -> usize {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(rel);
    let md = std::fs::read_to_string(&path).expect("reading the document");
    let mut previous = String::new();
    let mut checked = 0;
    for (line, block) in blocks(&md) {
        let text = if block.starts_with("// continued") {
            format!("{previous}\n{block}")
        } else {
            block.clone()
        };
        previous = text.clone();
        let mut sources = SourceMap::new();
        let prelude = if text.starts_with("// no-prelude") {
            vec![]
        } else {
            vec![sources.add(PRELUDE_NAME, PRELUDE)]
        };
        let input = sources.add(format!("{rel}:{line}"), text);
        let fe = Frontend {
            sources: &sources,
            prelude: &prelude,
            inputs: &[input],
        };
        let r = compile(&fe, Emit::Tree, &[], &PassOptions::default());
        assert!(
            r.internal_error.is_none(),
            "{rel}:{line}: {:?}",
            r.internal_error
        );
        assert!(
            r.diagnostics.is_empty(),
            "the example at {rel}:{line} does not compile:\n{}",
            r.diagnostics.render(&sources)
        );
        checked += 1;
    }
    checked
}

#[test]
fn language_reference_examples_compile() {
    assert!(check_file("docs/language.md") >= 3);
}

#[test]
fn readme_examples_compile() {
    assert!(check_file("README.md") >= 1);
}

/// Every `scion` block of the how-to `doc` is a verbatim piece of one of `files`, the files the
/// tests trace.
fn blocks_are_pieces_of(doc: &str, files: &[&str]) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let md = std::fs::read_to_string(root.join(doc)).unwrap();
    let texts: Vec<String> = files
        .iter()
        .map(|f| std::fs::read_to_string(root.join(f)).unwrap())
        .collect();
    for (line, block) in blocks(&md) {
        let piece = block.strip_prefix("// continued\n").unwrap_or(&block);
        assert!(
            texts.iter().any(|t| t.contains(piece)),
            "{doc}:{line}: the block is not in {files:?}"
        );
    }
}

#[test]
fn howto_add_a_layout_examples_compile_and_are_the_traced_file() {
    assert!(check_file("docs/howto-add-a-layout.md") >= 5);
    blocks_are_pieces_of(
        "docs/howto-add-a-layout.md",
        &[
            "library/algorithms/closest_hit8.scion",
            "library/layouts/bvh8.scion",
        ],
    );
}

#[test]
fn howto_add_an_algorithm_examples_compile_and_are_the_library_file() {
    assert!(check_file("docs/howto-add-an-algorithm.md") >= 3);
    blocks_are_pieces_of(
        "docs/howto-add-an-algorithm.md",
        &[
            "library/algorithms/occluded.scion",
            "library/algorithms/closest_point.scion",
        ],
    );
}
