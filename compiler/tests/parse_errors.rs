//! Syntax errors: each has its code, a message saying what was expected and found, and a
//! primary span on the right line; several errors in one file are all reported, and the
//! parser keeps the items it could parse.

use crate::common;

use common::parse_str;
use expect_test::{expect, Expect};
use scion_compiler::syntax::ast::Item;

/// `code line:col message` for each diagnostic of `src`, one per line.
fn errors(src: &str) -> (String, Vec<String>) {
    let (program, diags, sources) = parse_str("err.scion", src);
    let mut out = String::new();
    for d in &diags.list {
        let span = d
            .primary_span()
            .expect("every syntax error has a primary span");
        let (line, col) = sources.line_col(span);
        let code = d.code.clone().unwrap_or_default();
        out.push_str(&format!("{code} {line}:{col} {}\n", d.message));
    }
    let names = program
        .items
        .iter()
        .map(|i| i.name().name.clone())
        .collect();
    (out, names)
}

fn check(src: &str, expected: Expect) {
    expected.assert_eq(&errors(src).0);
}

#[test]
fn several_errors_in_one_file_are_all_reported() {
    let src = "\
type A(x: f32, y: );
func f() = {
  let a = 1 +;
  let b: u32 = 2;
  b = = 3;
  return a;
}
func g( = 1;
layout L(I: u32) {
  x u32;
  group g[bogus=1] by I { y: u8; };
  split x { 1 -> A {}; 2 B {}; };
};
build L[order=sideways] { build root {}; build root {}; };
func last() = 1;
";
    let (errs, items) = errors(src);
    expect![[r#"
        E0101 1:19 expected a type, found `)`
        E0101 3:14 expected an expression, found `;`
        E0101 5:7 expected an expression, found `=`
        E0101 8:9 expected a parameter name, found `=`
        E0101 10:5 expected `:` (a stored field) or `=` (a derived field), found name `u32`
        E0111 11:11 unknown group attribute `bogus`
        E0101 12:26 expected `->`, found name `B`
        E0101 14:15 expected `pre` or `post`, found name `sideways`
        E0110 14:42 a build has at most one `build root { ... }`
    "#]]
    .assert_eq(&errs);
    assert_eq!(items, ["A", "f", "L", "L", "last"]);
}

#[test]
fn one_error_per_code() {
    check(
        "func f() = a < b < c;",
        expect![[r#"
        E0107 1:18 comparison operators cannot be chained
    "#]],
    );
    check(
        "func f() = { 1 = 2; g() = 3; }",
        expect![[r#"
        E0108 1:14 invalid left-hand side of `=`
        E0108 1:21 invalid left-hand side of `=`
    "#]],
    );
    check(
        "func f() = (1,); type T(x: (u8,));",
        expect![[r#"
        E0109 1:12 a tuple value needs at least two components
        E0109 1:28 a tuple type needs at least two components
    "#]],
    );
    check(
        "build L { build root {}; build root {}; };",
        expect![[r#"
        E0110 1:26 a build has at most one `build root { ... }`
    "#]],
    );
    check(
        "build L[speed=3] {};",
        expect![[r#"
        E0111 1:9 unknown build attribute `speed`
    "#]],
    );
    check(
        "func f() = (f)(x); func g() = a.b(x);",
        expect![[r#"
        E0112 1:12 only a function, type or variant name can be called
        E0112 1:31 only a function, type or variant name can be called
    "#]],
    );
    check(
        "layout M() { indirect group g by I {}; };",
        expect![[r#"
        E0113 1:31 an indirect group has no `by` index
    "#]],
    );
    check(
        "func f() = 0x + 1e + 0b2 + 12ab;",
        expect![[r#"
        E0102 1:12 malformed numeric literal `0x`
        E0102 1:17 malformed numeric literal `1e`
        E0102 1:22 malformed numeric literal `0b2`
        E0102 1:28 malformed numeric literal `12ab`
    "#]],
    );
    check(
        "func f() = 999999999999999999999999999999999999999999;",
        expect![[r#"
        E0104 1:12 integer literal `999999999999999999999999999999999999999999` is too large
    "#]],
    );
    check(
        "layout M() { 99999999999999999999; };",
        expect![[r#"
        E0104 1:14 padding `99999999999999999999` is too large
    "#]],
    );
    check(
        "type V(a: f32x0);",
        expect![[r#"
        E0105 1:11 invalid vector type `f32x0`
    "#]],
    );
    check(
        "func f() = 1 # 2; @",
        expect![[r#"
            E0101 1:13 expected `;` or the next item, found integer `2`
            E0103 1:14 unknown character `#`
            E0103 1:19 unknown character `@`
        "#]],
    );
}

#[test]
fn unexpected_tokens_say_what_was_expected() {
    check(
        "func f() = { let = 1; }",
        expect![[r#"
        E0101 1:18 expected a name after `let`, found `=`
    "#]],
    );
    check(
        "func f() = { a = 1 b = 2; }",
        expect![[r#"
            E0101 1:19 expected `;` or `}`, found name `b`
        "#]],
    );
    check(
        "func f() = match x { | A => 1 }",
        expect![[r#"
        E0101 1:26 expected `->`, found `=`
    "#]],
    );
    check(
        "func f() = match x { }",
        expect![[r#"
        E0101 1:22 expected a pattern (`Variant(...)` or `_`), found `}`
    "#]],
    );
    check(
        "layout L { split x { 1 -> A {} 2 -> B from g[0] 3 -> C {} }; }",
        expect![[r#"
            E0101 1:48 expected `;` or `}`, found integer `3`
        "#]],
    );
    check(
        "layout L { group g[size] {}; }",
        expect![[r#"
        E0101 1:24 expected `=`, found `]`
    "#]],
    );
    check(
        "42; type",
        expect![[r#"
        E0101 1:1 expected an item (`type`, `func`, `layout` or `build`), found integer `42`
        E0101 1:9 expected the type's name, found end of file
    "#]],
    );
    check(
        "func f() = {",
        expect![[r#"
        E0101 1:13 expected a statement or `}`, found end of file
    "#]],
    );
    check(
        "func f() = { a = 1;\nfunc g() = 1;\nlayout L { x: u8;\ntype T(x: u8",
        expect![[r#"
        E0101 2:1 expected a statement or `}`, found keyword `func`
        E0101 4:1 expected a layout member or `}`, found keyword `type`
        E0101 4:13 expected `,` or `)`, found end of file
    "#]],
    );
    check(
        "func f() = { let type = 1; x; }\nfunc g() = 1;",
        expect![[r#"
            E0101 1:18 expected a name after `let`, found keyword `type`
        "#]],
    );
    check(
        "func f() = { if a { } else if b { } }",
        expect![[r#"
        E0101 1:28 expected `{` (`else if` is written `elif`), found keyword `if`
    "#]],
    );
    check(
        "func f(x: u32 = ) = x;",
        expect![[r#"
        E0101 1:17 expected an expression, found `)`
    "#]],
    );
}

#[test]
fn an_arm_with_a_bare_bar_is_cut_there() {
    // `a | b` in an arm body ends the arm at `|`: `b -> ...` then is the next arm's pattern.
    check(
        "func f() = match x { | A -> a | b | B -> c }",
        expect![[r#"
        E0101 1:35 expected `->`, found `|`
    "#]],
    );
}

#[test]
fn rendered_diagnostic_shows_the_line() {
    let (_, diags, sources) =
        parse_str("err.scion", "func f() = {\n  let x = 1\n  let y = 2;\n}\n");
    expect![[r#"
        error[E0101]: expected `;` or `}`, found keyword `let`
          ┌─ err.scion:2:12
          │
        2 │   let x = 1
          │            ^ expected `;` or `}` here
        3 │   let y = 2;
          │   --- unexpected token

    "#]]
    .assert_eq(&diags.render(&sources));
}

#[test]
fn an_unclosed_body_ends_at_the_next_item() {
    for src in [
        "func f() = match x { | A -> 1 +\nfunc g() = 1;",
        "func f() = match x { | A -> 1\nfunc g() = 1;",
        "func f() = { g(1, 2\nfunc g() = 1;",
        "layout L { group g { split x { 0 -> A { a: u8\nfunc g() = 1;",
        "build L { build A(x: u8) { build x\nfunc g() = 1;",
    ] {
        let (errs, items) = errors(src);
        assert_eq!(errs.lines().count(), 1, "{src}\n{errs}");
        assert_eq!(items.last().map(String::as_str), Some("g"), "{src}\n{errs}");
    }
}

#[test]
fn items_after_errors_are_kept() {
    let (program, diags, _) = parse_str(
        "err.scion",
        "func f( = ;\ntype T(x: u32);\nfunc g() = 1 +;\nfunc h() = 2;",
    );
    assert_eq!(diags.len(), 2);
    let names: Vec<_> = program
        .items
        .iter()
        .map(|i| i.name().name.as_str())
        .collect();
    assert_eq!(names, ["T", "h"]);
    assert!(matches!(program.items[0], Item::Type(_)));
}
