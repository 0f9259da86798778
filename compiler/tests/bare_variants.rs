//! A bare field-less variant used as an expression (`Em` for `Em()`) is its constructor, in
//! sema and in irgen: as a call argument, a `let` initializer and a function result, also when
//! variants of two types share the name (the expected type decides). The programs run in the
//! `tree` interpreter and give the same values as the spelled-out `Em()` forms; a bare variant
//! with fields is E0234 with a span, never an internal error.

use crate::common;

use scion_ir::interp::{Interp, Val};
use scion_ir::Module;

const PROGRAM: &str = r#"
type E = Em | Full(x: f32);
type F = Em | Other;

func area(e: E, k: f32) -> f32 =
  match e {
    | Em -> 0.0
    | Full(x) -> x * k
  }

func tag(f: F) -> u32 = match f { | Em -> 1 | Other -> 2 }

func bare(k: f32) -> f32 = {
  let e: E = Em;
  area(Em, k) + area(e, k) + area(Full(k), 2.0)
}

func called(k: f32) -> f32 = {
  let e: E = Em();
  area(Em(), k) + area(e, k) + area(Full(k), 2.0)
}

func make_bare() -> E = Em
func make_called() -> E = Em()
func tag_bare() -> u32 = tag(Em) + tag(Other)
func tag_called() -> u32 = tag(Em()) + tag(Other())
"#;

/// Compiles `text` (no prelude) to the `tree` module, or its rendered diagnostics.
fn tree_module(text: &str) -> Result<Module, String> {
    common::tree_module_of(&[("bare.scion", text)], false)
}

fn run(m: &Module, name: &str, args: Vec<Val>) -> Vec<Val> {
    Interp::new(m)
        .call(name, args)
        .unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn bare_fieldless_variants_are_constructors() {
    let m = tree_module(PROGRAM).unwrap_or_else(|d| panic!("{d}"));
    for k in [0.0f32, 1.5, -3.25, f32::INFINITY] {
        let got = run(&m, "bare", vec![Val::F32(k)]);
        let want = run(&m, "called", vec![Val::F32(k)]);
        assert_eq!(format!("{got:?}"), format!("{want:?}"), "k = {k}");
        match got.as_slice() {
            [Val::F32(v)] => assert_eq!(v.to_bits(), (0.0 + 0.0 + k * 2.0f32).to_bits()),
            other => panic!("bare({k}) = {other:?}"),
        }
    }
    let (made, spelled) = (run(&m, "make_bare", vec![]), run(&m, "make_called", vec![]));
    assert_eq!(format!("{made:?}"), format!("{spelled:?}"));
    match made.as_slice() {
        [Val::Adt(a)] => {
            assert_eq!((a.ty.as_str(), a.variant), ("E", Some(0)));
            assert!(a.fields.is_empty());
        }
        other => panic!("make_bare() = {other:?}"),
    }
    let (tags, spelled) = (run(&m, "tag_bare", vec![]), run(&m, "tag_called", vec![]));
    assert_eq!(format!("{tags:?}"), format!("{spelled:?}"));
}

#[test]
fn a_bare_variant_with_fields_is_a_diagnostic() {
    let text = "type E = Em | Full(x: f32);\n\
                func area(e: E) -> f32 = match e { | Em -> 0.0 | Full(x) -> x }\n\
                func f() -> f32 = area(Full)\n";
    let err = tree_module(text).expect_err("a bare `Full` needs its fields");
    assert!(err.contains("error[E0234]"), "{err}");
    assert!(err.contains("variant `Full` has fields"), "{err}");
    assert!(err.contains("bare.scion:3:24"), "{err}");
}
