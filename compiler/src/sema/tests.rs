//! Tests of semantic analysis: each rule and each error code, positive and negative, on source
//! text parsed by `syntax`, and the library files.

mod builds;
mod dump;
mod hand_built;
mod layouts;
mod library;
mod robustness;
mod traversal;

use super::{check_program, TypedProgram};
use crate::syntax::ast::Program;
use crate::syntax::parse_program;
use scion_ir::diag::{Diagnostics, SourceMap};

pub(super) const PRELUDE: &str = include_str!("../../../library/prelude.scion");

/// Parses `files` (name, text) in order and checks the program.
pub(super) fn check_files(
    files: &[(&str, &str)],
) -> (Program, TypedProgram, Diagnostics, SourceMap) {
    let mut sm = SourceMap::new();
    let ids: Vec<_> = files.iter().map(|(n, t)| sm.add(*n, *t)).collect();
    let (program, pdiags) = parse_program(&sm, &ids);
    assert!(
        !pdiags.has_errors(),
        "test input does not parse:\n{}",
        pdiags.render(&sm)
    );
    let (typed, diags) = check_program(&program);
    (program, typed, diags, sm)
}

/// Checks `src` alone.
pub(super) fn check(src: &str) -> (Program, TypedProgram, Diagnostics, SourceMap) {
    check_files(&[("test.scion", src)])
}

/// Checks `src` after the prelude.
pub(super) fn check_with_prelude(src: &str) -> (Program, TypedProgram, Diagnostics, SourceMap) {
    check_files(&[("prelude.scion", PRELUDE), ("test.scion", src)])
}

/// `src` (after the prelude) type-checks without any diagnostic.
pub(super) fn ok(src: &str) -> TypedProgram {
    let (_, typed, diags, sm) = check_with_prelude(src);
    assert!(
        diags.is_empty(),
        "unexpected diagnostics:\n{}",
        diags.render(&sm)
    );
    typed
}

/// `src` (after the prelude) reports an error with `code`; returns the rendered diagnostics.
pub(super) fn err(src: &str, code: &str) -> String {
    let (_, _, diags, sm) = check_with_prelude(src);
    let text = diags.render(&sm);
    assert!(
        diags.list.iter().any(|d| d.code.as_deref() == Some(code)),
        "expected {code}, got:\n{text}"
    );
    for d in &diags.list {
        assert!(
            d.primary_span().is_some(),
            "diagnostic without a primary span: {d}"
        );
    }
    text
}

/// A structural mistake in a layout or build: `check_layout` / `check_build` report `code`, and
/// semantic analysis stays silent so that the mistake is reported once.
pub(super) fn structural(src: &str, code: &str) {
    let (program, _, diags, sm) = check_with_prelude(src);
    assert!(
        diags.is_empty(),
        "sema should leave this to the structural checks:\n{}",
        diags.render(&sm)
    );
    let mut all = Diagnostics::new();
    let models = crate::layout::model::Models::inferred(&program);
    all.extend(crate::layout::check_layout::check_layouts(
        &program, &models,
    ));
    all.extend(crate::layout::check_build::check_builds(&program, &models));
    assert!(
        all.list.iter().any(|d| d.code.as_deref() == Some(code)),
        "expected {code}, got:\n{}",
        all.render(&sm)
    );
}
