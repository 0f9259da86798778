//! Negative tests of the verifier: each breaks one rule and checks the message and the printed
//! context (errors shown above the offending op).

use expect_test::{expect, Expect};
use scion_ir::diag::FileId;
use scion_ir::module::RegionParent;
use scion_ir::tree::Op;
use scion_ir::verify::dominator_tree;
use scion_ir::{parse_module, verify, Builder, Module, OpSpec};

const TYPES: &str = r#"
tree.type @AABB(low: vector<3xf32>, high: vector<3xf32>)
tree.type @BVH(bounds: !tree.adt<"AABB">) = Interior(left: !tree.adt<"BVH">, right: !tree.adt<"BVH">) | Leaf(n: u16)
"#;

fn check(body: &str, expect: Expect) {
    let text = format!("{TYPES}{body}");
    let m = parse_module(&text, FileId(0)).unwrap_or_else(|d| panic!("{d:?}"));
    let errs = verify(&m).expect_err("the module should be invalid");
    expect.assert_eq(&errs.to_string());
}

#[test]
fn use_before_definition() {
    check(
        r#"
func @f(%a: f32) -> (f32) {
  %b = "tree.add"(%a, %c) : (f32, f32) -> f32
  %c = "tree.neg"(%a) : (f32) -> f32
  "tree.return"(%b) : (f32) -> ()
}"#,
        expect![[r#"
            error: operand #1 does not dominate this use
              in: %1 = "tree.add"(%0, %2) : (f32, f32) -> f32
            func @f(%0: f32) -> (f32) {
              // error: operand #1 does not dominate this use
              %1 = "tree.add"(%0, %2) : (f32, f32) -> f32
              %2 = "tree.neg"(%0) : (f32) -> f32
              "tree.return"(%1) : (f32) -> ()
            }
        "#]],
    );
}

/// The parser already refuses names from a closed region, so build the bad IR directly.
#[test]
fn value_of_a_region_used_outside() {
    let mut m = Module::new();
    let f32t = m.types.f32();
    let i1 = m.types.bool();
    let (_, entry) = m.add_func("f", &[i1, f32t], &[f32t]);
    let (c, a) = (m.blocks[entry].args[0], m.blocks[entry].args[1]);
    let mut b = Builder::at_end(&mut m, entry);
    let mut inner = None;
    let op = b.if_(
        c,
        &[f32t],
        |b| {
            let x = b.unary(Op::Neg, a);
            inner = Some(x);
            b.yield_(&[x]);
        },
        |b| {
            b.yield_(&[a]);
        },
    );
    let _ = b.result(op, 0);
    b.ret(&[inner.unwrap()]);
    expect![[r#"
        error: operand #0 does not dominate this use
          in: "tree.return"(%3) : (f32) -> ()
        func @f(%0: i1, %1: f32) -> (f32) {
          %2 = "tree.if"(%0) ({
          ^bb1:
            %3 = "tree.neg"(%1) : (f32) -> f32
            "tree.yield"(%3) : (f32) -> ()
          }, {
          ^bb2:
            "tree.yield"(%1) : (f32) -> ()
          }) : (i1) -> f32
          // error: operand #0 does not dominate this use
          "tree.return"(%3) : (f32) -> ()
        }
    "#]]
    .assert_eq(&verify(&m).unwrap_err().to_string());
}

#[test]
fn terminators() {
    check(
        r#"
func @f(%a: f32) -> (f32) {
  "tree.return"(%a) : (f32) -> ()
  %b = "tree.neg"(%a) : (f32) -> f32
}
func @g(%a: f32) -> () {
  "tree.yield"() : () -> ()
}"#,
        expect![[r#"
            error: terminator in the middle of a block
              in: "tree.return"(%0) : (f32) -> ()
            error: block does not end with a terminator
              in: %1 = "tree.neg"(%0) : (f32) -> f32
            error: `tree.yield` outside a region of `if`, `match` or `foreach`
              in: "tree.yield"() : () -> ()
            func @f(%0: f32) -> (f32) {
              // error: terminator in the middle of a block
              "tree.return"(%0) : (f32) -> ()
              // error: block does not end with a terminator
              %1 = "tree.neg"(%0) : (f32) -> f32
            }
            func @g(%0: f32) -> () {
              // error: `tree.yield` outside a region of `if`, `match` or `foreach`
              "tree.yield"() : () -> ()
            }
        "#]],
    );
}

#[test]
fn operand_and_result_types() {
    check(
        r#"
func @f(%a: f32, %i: i32, %c: i1) -> (f32) {
  %b = "tree.add"(%a, %i) : (f32, i32) -> f32
  %k = "tree.const"() {value = 0.1} : () -> f32
  %n = "tree.const"() {value = 300} : () -> u8
  %s = "tree.shl"(%a, %i) : (f32, i32) -> f32
  %x = "tree.cmp"(%c, %c) {pred = "lt"} : (i1, i1) -> i1
  %y = "tree.bitcast"(%a) : (f32) -> u16
  %r = "tree.if"(%c) ({
    "tree.yield"() : () -> ()
  }, {
    "tree.yield"(%a) : (f32) -> ()
  }) : (i1) -> f32
  "tree.return"(%i) : (i32) -> ()
}"#,
        expect![[r#"
            error: type mismatch: f32 vs i32
              in: %3 = "tree.add"(%0, %1) : (f32, i32) -> f32
            error: constant 0.1 is not exactly representable as f32
              in: %4 = "tree.const"() {value = 0.1} : () -> f32
            error: constant 300 does not fit in u8
              in: %5 = "tree.const"() {value = 300} : () -> u8
            error: shift of f32 by i32
              in: %6 = "tree.shl"(%0, %1) : (f32, i32) -> f32
            error: `lt` comparison of i1
              in: %7 = "tree.cmp"(%2, %2) {pred = "lt"} : (i1, i1) -> i1
            error: bitcast between f32 and u16 of different widths
              in: %8 = "tree.bitcast"(%0) : (f32) -> u16
            error: region yields 0 values of the wrong types; the op has 1 results
              in: %9 = "tree.if"(%2) ({
            error: returned types do not match the function's results
              in: "tree.return"(%1) : (i32) -> ()
            func @f(%0: f32, %1: i32, %2: i1) -> (f32) {
              // error: type mismatch: f32 vs i32
              %3 = "tree.add"(%0, %1) : (f32, i32) -> f32
              // error: constant 0.1 is not exactly representable as f32
              %4 = "tree.const"() {value = 0.1} : () -> f32
              // error: constant 300 does not fit in u8
              %5 = "tree.const"() {value = 300} : () -> u8
              // error: shift of f32 by i32
              %6 = "tree.shl"(%0, %1) : (f32, i32) -> f32
              // error: `lt` comparison of i1
              %7 = "tree.cmp"(%2, %2) {pred = "lt"} : (i1, i1) -> i1
              // error: bitcast between f32 and u16 of different widths
              %8 = "tree.bitcast"(%0) : (f32) -> u16
              // error: region yields 0 values of the wrong types; the op has 1 results
              %9 = "tree.if"(%2) ({
              ^bb1:
                "tree.yield"() : () -> ()
              }, {
              ^bb2:
                "tree.yield"(%0) : (f32) -> ()
              }) : (i1) -> f32
              // error: returned types do not match the function's results
              "tree.return"(%1) : (i32) -> ()
            }
        "#]],
    );
}

#[test]
fn adt_rules() {
    check(
        r#"
func @f(%n: !tree.adt<"BVH">, %b: !tree.adt<"AABB">) -> () {
  %x = "tree.field"(%b) {index = 1, name = "low"} : (!tree.adt<"AABB">) -> vector<3xf32>
  %y = "tree.ctor"(%b) : (!tree.adt<"AABB">) -> !tree.adt<"BVH">
  "tree.match"(%n) ({
  ^bb1(%bb: !tree.adt<"AABB">, %l: !tree.adt<"BVH">, %r: !tree.adt<"BVH">):
    "tree.yield"() : () -> ()
  }) {arms = ["Interior"]} : (!tree.adt<"BVH">) -> ()
  "tree.match"(%n) ({
  ^bb2(%k: u16):
    "tree.yield"() : () -> ()
  }, {
    "tree.yield"() : () -> ()
  }) {arms = ["Leaf", "_"]} : (!tree.adt<"BVH">) -> ()
  "tree.call"(%b) {callee = @nope} : (!tree.adt<"AABB">) -> ()
  "tree.return"() : () -> ()
}"#,
        expect![[r#"
            error: shared field #1 of `AABB` is `high`, not `low`
              in: %2 = "tree.field"(%1) {index = 1, name = "low"} : (!tree.adt<"AABB">) -> vector<3xf32>
            error: `BVH` is a sum: the constructor needs a `variant`
              in: %3 = "tree.ctor"(%1) : (!tree.adt<"AABB">) -> !tree.adt<"BVH">
            error: match is not exhaustive: variant `Leaf` has no arm
              in: "tree.match"(%0) ({
            error: arm `Leaf`: region block takes 1 arguments of the wrong types or count
              in: "tree.match"(%0) ({
            error: call to unknown function `@nope`
              in: "tree.call"(%1) {callee = @nope} : (!tree.adt<"AABB">) -> ()
            func @f(%0: !tree.adt<"BVH">, %1: !tree.adt<"AABB">) -> () {
              // error: shared field #1 of `AABB` is `high`, not `low`
              %2 = "tree.field"(%1) {index = 1, name = "low"} : (!tree.adt<"AABB">) -> vector<3xf32>
              // error: `BVH` is a sum: the constructor needs a `variant`
              %3 = "tree.ctor"(%1) : (!tree.adt<"AABB">) -> !tree.adt<"BVH">
              // error: match is not exhaustive: variant `Leaf` has no arm
              "tree.match"(%0) ({
              ^bb1(%4: !tree.adt<"AABB">, %5: !tree.adt<"BVH">, %6: !tree.adt<"BVH">):
                "tree.yield"() : () -> ()
              }) {arms = ["Interior"]} : (!tree.adt<"BVH">) -> ()
              // error: arm `Leaf`: region block takes 1 arguments of the wrong types or count
              "tree.match"(%0) ({
              ^bb2(%7: u16):
                "tree.yield"() : () -> ()
              }, {
              ^bb3:
                "tree.yield"() : () -> ()
              }) {arms = ["Leaf", "_"]} : (!tree.adt<"BVH">) -> ()
              // error: call to unknown function `@nope`
              "tree.call"(%1) {callee = @nope} : (!tree.adt<"AABB">) -> ()
              "tree.return"() : () -> ()
            }
        "#]],
    );
}

#[test]
fn undeclared_adt_type() {
    check(
        r#"
func @f(%a: !tree.adt<"Nope">) -> () {
  "tree.return"() : () -> ()
}"#,
        expect![[r#"
            error: signature of `@f` has an ill-formed type
            // error: signature of `@f` has an ill-formed type
            func @f(%0: !tree.adt<"Nope">) -> () {
              "tree.return"() : () -> ()
            }
        "#]],
    );
}

/// A CFG body (blocks linked by successors, as `lo` will have): a value defined in one arm of
/// a diamond does not dominate the join, a value of the entry does.
#[test]
fn dominance_in_cfg_regions() {
    let mut m = Module::new();
    let f32t = m.types.f32();
    let (f, entry) = m.add_func("diamond", &[f32t], &[]);
    let body = m.funcs[f].body;
    let left = m.add_block(body, &[]);
    let right = m.add_block(body, &[]);
    let join = m.add_block(body, &[f32t]);
    let arg = m.blocks[entry].args[0];
    let mut b = Builder::at_end(&mut m, entry);
    let a = b.unary(Op::Neg, arg);
    // `tree.return` stands in for a branch: successors are a structural matter, and the tree
    // dialect's own rule against them is reported separately.
    b.insert(
        OpSpec::new(Op::Return)
            .successor(left, &[])
            .successor(right, &[]),
    );
    b.set_insertion_point_to_end(left);
    let l = b.unary(Op::Neg, a);
    b.insert(OpSpec::new(Op::Return).successor(join, &[l]));
    b.set_insertion_point_to_end(right);
    b.insert(OpSpec::new(Op::Return).successor(join, &[a]));
    b.set_insertion_point_to_end(join);
    b.binary(Op::Add, a, l);
    b.ret(&[]);
    let errs = verify(&m).unwrap_err();
    let msgs: Vec<&str> = errs.errors.iter().map(|e| e.message.as_str()).collect();
    assert_eq!(
        msgs,
        [
            "`tree.return` takes no successors",
            "`tree.return` takes no successors",
            "`tree.return` takes no successors",
            "operand #1 does not dominate this use",
        ]
    );
    let blocks = m.regions[body].blocks.clone();
    let (children, reachable) = dominator_tree(&m, &blocks);
    assert_eq!(children, vec![vec![1, 2, 3], vec![], vec![], vec![]]);
    assert_eq!(reachable, vec![true; 4]);
    assert_eq!(m.regions[body].parent, Some(RegionParent::Func(f)));
    // The text form carries successors and forward block references.
    let text = scion_ir::print_module(&m);
    expect![[r#"
        func @diamond(%0: f32) -> () {
          %1 = "tree.neg"(%0) : (f32) -> f32
          "tree.return"()[^bb1, ^bb2] : () -> ()
        ^bb1:
          %2 = "tree.neg"(%1) : (f32) -> f32
          "tree.return"()[^bb3(%2 : f32)] : () -> ()
        ^bb2:
          "tree.return"()[^bb3(%1 : f32)] : () -> ()
        ^bb3(%3: f32):
          %4 = "tree.add"(%1, %2) : (f32, f32) -> f32
          "tree.return"() : () -> ()
        }
    "#]]
    .assert_eq(&text);
    let back = parse_module(&text, FileId(0)).unwrap();
    assert_eq!(scion_ir::print_module(&back), text);
}

#[test]
fn broken_links_are_reported_not_panics() {
    let mut m = Module::new();
    let f32t = m.types.f32();
    let (_, entry) = m.add_func("f", &[f32t], &[f32t]);
    let arg = m.blocks[entry].args[0];
    let mut b = Builder::at_end(&mut m, entry);
    let n = b.unary(Op::Neg, arg);
    let ret = b.ret(&[n]);
    // List the return twice and point the negation's parent elsewhere.
    m.blocks[entry].ops.push(ret);
    let neg = m.def_op(n).unwrap();
    m.ops[neg].parent = None;
    let errs = verify(&m).unwrap_err();
    let msgs: Vec<&str> = errs.errors.iter().map(|e| e.message.as_str()).collect();
    assert_eq!(
        msgs,
        [
            "op's parent link does not name its block",
            "terminator in the middle of a block",
            "op listed twice"
        ]
    );
}

/// The quantization builtins are defined on `f32` lanes only (`scion_ir::tree::quant`).
#[test]
fn quantization_builtins_take_f32_lanes() {
    check(
        r#"
func @f(%a: vector<3xf64>) -> (vector<3xf64>) {
  %b = "tree.intrinsic"(%a) {name = "frame_origin"} : (vector<3xf64>) -> vector<3xf64>
  "tree.return"(%b) : (vector<3xf64>) -> ()
}"#,
        expect![[r#"
            error: `frame_origin` does not apply to (vector<3xf64>) -> vector<3xf64>
              in: %1 = "tree.intrinsic"(%0) {name = "frame_origin"} : (vector<3xf64>) -> vector<3xf64>
            func @f(%0: vector<3xf64>) -> (vector<3xf64>) {
              // error: `frame_origin` does not apply to (vector<3xf64>) -> vector<3xf64>
              %1 = "tree.intrinsic"(%0) {name = "frame_origin"} : (vector<3xf64>) -> vector<3xf64>
              "tree.return"(%1) : (vector<3xf64>) -> ()
            }
        "#]],
    );
}

/// `tree.intrinsic` names one of `scion_ir::tree::Intrinsic`: names no engine can compute (the
/// transcendentals, options) are refused, not carried to a lowering that cannot take them.
#[test]
fn unknown_intrinsics_are_refused() {
    check(
        r#"
func @f(%a: f32) -> (f32) {
  %b = "tree.intrinsic"(%a) {name = "sin"} : (f32) -> f32
  "tree.return"(%b) : (f32) -> ()
}"#,
        expect![[r#"
            error: unknown intrinsic `sin`
              in: %1 = "tree.intrinsic"(%0) {name = "sin"} : (f32) -> f32
            func @f(%0: f32) -> (f32) {
              // error: unknown intrinsic `sin`
              %1 = "tree.intrinsic"(%0) {name = "sin"} : (f32) -> f32
              "tree.return"(%1) : (f32) -> ()
            }
        "#]],
    );
}
