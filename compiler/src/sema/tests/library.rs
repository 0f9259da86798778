//! The library's programs type-check with zero diagnostics: the prelude, then every other
//! `library/*.scion` and `library/*/*.scion` file (each after the prelude, an algorithm with the
//! algorithm files declaring the tree types it names, a layout also after the algorithm files, which declare the tree types beyond the prelude's that layouts realize;
//! and the prelude with all the algorithm files together, as the registry compiles them with
//! each layout), and the `lit-tests` inputs that are meant to compile. Layout files are
//! alternatives to one another and are never compiled together: each may name its helpers as
//! it likes (the eight-wide quantized layouts each have their own `Frame` and `dequant`).

use super::{check_files, PRELUDE};
use std::path::{Path, PathBuf};

fn scion_files(dir: &Path, depth: usize, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() && depth > 0 {
            scion_files(&p, depth - 1, out);
        } else if p.extension().is_some_and(|e| e == "scion") && !p.ends_with("prelude.scion") {
            out.push(p);
        }
    }
}

/// The types `text` declares (`type NAME`).
fn declared_types(text: &str) -> Vec<String> {
    text.lines()
        .filter_map(|l| l.trim_start().strip_prefix("type "))
        .filter_map(|rest| {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            (!name.is_empty()).then_some(name)
        })
        .collect()
}

/// Whether `text` names type `ty` without declaring it.
fn names_type(text: &str, ty: &str) -> bool {
    let word = |c: char| c.is_alphanumeric() || c == '_';
    !declared_types(text).iter().any(|t| t == ty)
        && text.match_indices(ty).any(|(i, _)| {
            let before = text[..i].chars().next_back().is_none_or(|c| !word(c));
            let after = text[i + ty.len()..].chars().next().is_none_or(|c| !word(c));
            before && after
        })
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

#[test]
fn library_files_type_check() {
    let mut files = Vec::new();
    scion_files(&root().join("library"), 1, &mut files);
    assert!(files.len() >= 3, "library files not found: {files:?}");
    let texts: Vec<(String, String)> = files
        .iter()
        .map(|p| {
            (
                p.display().to_string(),
                std::fs::read_to_string(p).expect("readable library file"),
            )
        })
        .collect();
    let mut all: Vec<(&str, &str)> = vec![("prelude.scion", PRELUDE)];
    let algorithms: Vec<(&str, &str)> = texts
        .iter()
        .filter(|(n, _)| n.contains("/algorithms/"))
        .map(|(n, t)| (n.as_str(), t.as_str()))
        .collect();
    for (name, text) in &texts {
        let mut inputs = vec![("prelude.scion", PRELUDE)];
        if name.contains("/layouts/") {
            inputs.extend(algorithms.iter().copied());
        } else {
            // An algorithm over another file's tree type comes with that file, as the registry
            // compiles it (`closest_point8.scion` with `closest_hit8.scion`'s `BVH8`).
            inputs.extend(algorithms.iter().copied().filter(|(other, t)| {
                other != name && declared_types(t).iter().any(|ty| names_type(text, ty))
            }));
        }
        inputs.push((name, text));
        let (_, typed, diags, sm) = check_files(&inputs);
        assert!(diags.is_empty(), "{name}:\n{}", diags.render(&sm));
        assert!(
            typed
                .expr_types
                .values()
                .all(|t| !t.has_vars() && !t.has_error()),
            "{name}"
        );
        if !name.contains("/layouts/") {
            all.push((name, text));
        }
    }
    let (_, _, diags, sm) = check_files(&all);
    assert!(diags.is_empty(), "{}", diags.render(&sm));
}

#[test]
fn lit_inputs_that_compile_type_check() {
    let mut files = Vec::new();
    scion_files(&root().join("lit-tests"), 1, &mut files);
    for p in files {
        let text = std::fs::read_to_string(&p).expect("readable lit test");
        // Negative tests expect errors (`RUN: not scionc`); the others must type-check.
        if text.contains("not scionc") || text.contains("not %scionc") {
            continue;
        }
        let name = p.display().to_string();
        let (_, _, diags, sm) = check_files(&[("prelude.scion", PRELUDE), (&name, &text)]);
        assert!(!diags.has_errors(), "{name}:\n{}", diags.render(&sm));
    }
}
