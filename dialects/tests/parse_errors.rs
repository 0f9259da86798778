//! The parser's diagnostics: code, message, and the position rendered against a source map.

use expect_test::{expect, Expect};
use scion_ir::diag::SourceMap;
use scion_ir::parse_module;

fn check(text: &str, expect: Expect) {
    let mut sm = SourceMap::new();
    let file = sm.add("input.tree", text);
    let diags = parse_module(text, file).expect_err("the text should not parse");
    expect.assert_eq(&diags.render(&sm));
}

#[test]
fn unknown_op() {
    check(
        "func @f() -> () {\n  \"tree.frobnicate\"() : () -> ()\n}\n",
        expect![[r#"
            error[E0952]: unknown op `tree.frobnicate`
              ┌─ input.tree:2:3
              │
            2 │   "tree.frobnicate"() : () -> ()
              │   ^^^^^^^^^^^^^^^^^
              │
              = at 2:3

        "#]],
    );
}

#[test]
fn undefined_value() {
    check(
        "func @f() -> (f32) {\n  \"tree.return\"(%x) : (f32) -> ()\n}\n",
        expect![[r#"
            error[E0953]: use of undefined value `%x`
              ┌─ input.tree:2:17
              │
            2 │   "tree.return"(%x) : (f32) -> ()
              │                 ^^
              │
              = at 2:17

        "#]],
    );
}

#[test]
fn type_of_use_differs_from_definition() {
    check(
        "func @f(%a: f32) -> (f32) {\n  \"tree.return\"(%a) : (i32) -> ()\n}\n",
        expect![[r#"
            error[E0955]: `%a` has type f32 but is used as i32
              ┌─ input.tree:2:17
              │
            2 │   "tree.return"(%a) : (i32) -> ()
              │                 ^^
              │
              = at 2:17

        "#]],
    );
}

#[test]
fn missing_parenthesis() {
    check(
        "func @f(%a: f32) -> (f32) {\n  %b = \"tree.neg\"(%a : (f32) -> f32\n}\n",
        expect![[r#"
            error[E0951]: expected `)`, found `:`
              ┌─ input.tree:2:22
              │
            2 │   %b = "tree.neg"(%a : (f32) -> f32
              │                      ^
              │
              = near `%b = "tree.neg"(%a : (f32) -> f32`
              = at 2:22

        "#]],
    );
}

#[test]
fn redefinitions() {
    check(
        "func @f(%a: f32) -> () {\n  %a = \"tree.neg\"(%a) : (f32) -> f32\n  \"tree.return\"() : () -> ()\n}\n",
        expect![[r#"
            error[E0954]: value `%a` defined twice
              ┌─ input.tree:2:3
              │
            2 │   %a = "tree.neg"(%a) : (f32) -> f32
              │   ^^
              │
              = at 2:3

        "#]],
    );
    check(
        "tree.type @A(x: f32)\ntree.type @A(y: f32)\n",
        expect![[r#"
            error[E0954]: type `A` declared twice
              ┌─ input.tree:2:1
              │
            2 │ tree.type @A(y: f32)
              │ ^^^^^^^^^
              │
              = at 2:1

        "#]],
    );
}

#[test]
fn lexical_errors() {
    check(
        "func @f() -> () {\n  \"tree.return\n}\n",
        expect![[r#"
            error[E0950]: unterminated string
              ┌─ input.tree:2:3
              │
            2 │   "tree.return
              │   ^
              │
              = at 2:3

        "#]],
    );
    check(
        "func @f() -> (f32 {\n}\n# \n",
        expect![[r#"
            error[E0950]: unexpected character `#`
              ┌─ input.tree:3:1
              │
            3 │ # 
              │ ^
              │
              = at 3:1

        "#]],
    );
}

#[test]
fn bad_types_and_attributes() {
    check(
        "func @f(%a: vector<0xf32>) -> () {\n}\n",
        expect![[r#"
            error[E0951]: expected `x` and an element type, found `>`
              ┌─ input.tree:1:25
              │
            1 │ func @f(%a: vector<0xf32>) -> () {
              │                         ^
              │
              = near `func @f(%a: vector<0xf32>) -> () {`
              = at 1:25

        "#]],
    );
    check(
        "func @f() -> () {\n  \"tree.return\"() {x = nan(0x1)} : () -> ()\n}\n",
        expect![[r#"
            error[E0957]: `nan(...)` needs the bits of an f64 NaN
              ┌─ input.tree:2:24
              │
            2 │   "tree.return"() {x = nan(0x1)} : () -> ()
              │                        ^^^
              │
              = at 2:24

        "#]],
    );
}

#[test]
fn deep_nesting_is_an_error_not_a_stack_overflow() {
    let mut text = String::from("func @f(%a: ");
    for _ in 0..5000 {
        text.push_str("tuple<");
    }
    let mut sm = SourceMap::new();
    let file = sm.add("deep.tree", text.as_str());
    let diags = parse_module(&text, file).unwrap_err();
    assert_eq!(diags.list[0].code.as_deref(), Some("E0958"));
}

#[test]
fn deep_regions_are_an_error_not_a_stack_overflow() {
    let mut text = String::from("func @f(%c: i1) -> () {\n");
    for _ in 0..3000 {
        text.push_str("\"tree.if\"(%c) ({\n");
    }
    let mut sm = SourceMap::new();
    let file = sm.add("deep.tree", text.as_str());
    let diags = parse_module(&text, file).unwrap_err();
    assert_eq!(diags.list[0].code.as_deref(), Some("E0958"));
}

#[test]
fn block_names_are_local_to_their_region() {
    // Sibling regions may reuse `^bb0` and value names, as in MLIR.
    let text = r#"
func @f(%c: i1, %a: f32) -> (f32) {
  %r = "tree.if"(%c) ({
  ^bb0:
    %x = "tree.neg"(%a) : (f32) -> f32
    "tree.yield"(%x) : (f32) -> ()
  }, {
  ^bb0:
    %x = "tree.add"(%a, %a) : (f32, f32) -> f32
    "tree.yield"(%x) : (f32) -> ()
  }) : (i1) -> f32
  "tree.return"(%r) : (f32) -> ()
}
"#;
    let m = parse_module(text, scion_ir::diag::FileId(0)).unwrap();
    scion_ir::verify(&m).unwrap();
    check(
        "func @f(%c: i1) -> () {\n  \"tree.if\"(%c) ({\n    \"tree.yield\"()[^nowhere] : () -> ()\n  }, {\n    \"tree.yield\"() : () -> ()\n  }) : (i1) -> ()\n  \"tree.return\"() : () -> ()\n}\n",
        expect![[r#"
            error[E0953]: reference to undefined block `^nowhere`
              ┌─ input.tree:3:20
              │
            3 │     "tree.yield"()[^nowhere] : () -> ()
              │                    ^^^^^^^^
              │
              = at 3:20

        "#]],
    );
}
