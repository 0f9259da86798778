//! The text form: printing with renumbering, parsing back, exact floats, quoting.

use expect_test::expect;
use scion_ir::attr::Attr;
use scion_ir::diag::FileId;
use scion_ir::tree::Op;
use scion_ir::types::FloatTy;
use scion_ir::{parse_module, print_module, verify, Builder, Module, OpSpec};

/// Paper Figure 4's closest-hit traversal as the front end would emit it, written with source
/// names; the printer renumbers everything.
const CLOSEST_HIT: &str = r#"
// The prelude's types.
tree.type @Ray(origin: vector<3xf32>, direction: vector<3xf32>, tmin: f32, tmax: f32)
tree.type @AABB(low: vector<3xf32>, high: vector<3xf32>)
tree.type @Triangle(p0: vector<3xf32>, p1: vector<3xf32>, p2: vector<3xf32>, id: u32)
tree.type @BVH(bounds: !tree.adt<"AABB">) = Interior(left: !tree.adt<"BVH">, right: !tree.adt<"BVH">) | Leaf(nprims: u16, data: array<? x !tree.adt<"Triangle">>)

func @"intersects(Ray,AABB)"(%ray: !tree.adt<"Ray">, %box: !tree.adt<"AABB">) -> i1 {
  %t = "tree.const"() {value = true} : () -> i1
  "tree.return"(%t) : (i1) -> ()
}

func @"distmin(Ray,AABB)"(%ray: !tree.adt<"Ray">, %box: !tree.adt<"AABB">) -> f32 {
  %inf = "tree.const"() {value = inf} : () -> f32
  "tree.return"(%inf) : (f32) -> ()
}

func @closest_hit(%ray: !tree.adt<"Ray">, %bvh: !tree.adt<"BVH">, %best: !tree.ref<tuple<f32, u32>>) -> () {
  "tree.match"(%bvh) ({
  ^interior(%bounds: !tree.adt<"AABB">, %left: !tree.adt<"BVH">, %right: !tree.adt<"BVH">):
    %hit = "tree.call"(%ray, %bounds) {callee = @"intersects(Ray,AABB)"} : (!tree.adt<"Ray">, !tree.adt<"AABB">) -> i1
    // `&&` is an `if` with a result.
    %go = "tree.if"(%hit) ({
      %d = "tree.call"(%ray, %bounds) {callee = @"distmin(Ray,AABB)"} : (!tree.adt<"Ray">, !tree.adt<"AABB">) -> f32
      %b = "tree.load"(%best) : (!tree.ref<tuple<f32, u32>>) -> tuple<f32, u32>
      %b0 = "tree.extract"(%b) {index = 0} : (tuple<f32, u32>) -> f32
      %le = "tree.cmp"(%d, %b0) {pred = "le"} : (f32, f32) -> i1
      "tree.yield"(%le) : (i1) -> ()
    }, {
      %no = "tree.const"() {value = false} : () -> i1
      "tree.yield"(%no) : (i1) -> ()
    }) : (i1) -> i1
    "tree.if"(%go) ({
      "tree.call"(%ray, %left, %best) {callee = @closest_hit} : (!tree.adt<"Ray">, !tree.adt<"BVH">, !tree.ref<tuple<f32, u32>>) -> ()
      "tree.call"(%ray, %right, %best) {callee = @closest_hit} : (!tree.adt<"Ray">, !tree.adt<"BVH">, !tree.ref<tuple<f32, u32>>) -> ()
      "tree.yield"() : () -> ()
    }, {
      "tree.yield"() : () -> ()
    }) : (i1) -> ()
    "tree.yield"() : () -> ()
  }, {
  ^leaf(%lb: !tree.adt<"AABB">, %n: u16, %data: array<? x !tree.adt<"Triangle">>):
    "tree.foreach"(%data) ({
    ^body(%tri: !tree.adt<"Triangle">):
      %id = "tree.field"(%tri) {index = 3, name = "id"} : (!tree.adt<"Triangle">) -> u32
      %b = "tree.load"(%best) : (!tree.ref<tuple<f32, u32>>) -> tuple<f32, u32>
      %nb = "tree.insert"(%b, %id) {index = 1} : (tuple<f32, u32>, u32) -> tuple<f32, u32>
      "tree.store"(%best, %nb) : (!tree.ref<tuple<f32, u32>>, tuple<f32, u32>) -> ()
      "tree.yield"() : () -> ()
    }) : (array<? x !tree.adt<"Triangle">>) -> ()
    "tree.yield"() : () -> ()
  }) {arms = ["Interior", "Leaf"]} : (!tree.adt<"BVH">) -> ()
  "tree.return"() : () -> ()
}
"#;

#[test]
fn closest_hit_prints_renumbered_and_round_trips() {
    let m = parse_module(CLOSEST_HIT, FileId(0)).unwrap_or_else(|d| panic!("{d:?}"));
    verify(&m).unwrap_or_else(|e| panic!("{e}"));
    let text = print_module(&m);
    expect![[r#"
        tree.type @Ray(origin: vector<3xf32>, direction: vector<3xf32>, tmin: f32, tmax: f32)
        tree.type @AABB(low: vector<3xf32>, high: vector<3xf32>)
        tree.type @Triangle(p0: vector<3xf32>, p1: vector<3xf32>, p2: vector<3xf32>, id: u32)
        tree.type @BVH(bounds: !tree.adt<"AABB">) = Interior(left: !tree.adt<"BVH">, right: !tree.adt<"BVH">) | Leaf(nprims: u16, data: array<? x !tree.adt<"Triangle">>)

        func @"intersects(Ray,AABB)"(%0: !tree.adt<"Ray">, %1: !tree.adt<"AABB">) -> (i1) {
          %2 = "tree.const"() {value = true} : () -> i1
          "tree.return"(%2) : (i1) -> ()
        }

        func @"distmin(Ray,AABB)"(%0: !tree.adt<"Ray">, %1: !tree.adt<"AABB">) -> (f32) {
          %2 = "tree.const"() {value = inf} : () -> f32
          "tree.return"(%2) : (f32) -> ()
        }

        func @closest_hit(%0: !tree.adt<"Ray">, %1: !tree.adt<"BVH">, %2: !tree.ref<tuple<f32, u32>>) -> () {
          "tree.match"(%1) ({
          ^bb1(%3: !tree.adt<"AABB">, %4: !tree.adt<"BVH">, %5: !tree.adt<"BVH">):
            %6 = "tree.call"(%0, %3) {callee = @"intersects(Ray,AABB)"} : (!tree.adt<"Ray">, !tree.adt<"AABB">) -> i1
            %7 = "tree.if"(%6) ({
            ^bb2:
              %8 = "tree.call"(%0, %3) {callee = @"distmin(Ray,AABB)"} : (!tree.adt<"Ray">, !tree.adt<"AABB">) -> f32
              %9 = "tree.load"(%2) : (!tree.ref<tuple<f32, u32>>) -> tuple<f32, u32>
              %10 = "tree.extract"(%9) {index = 0} : (tuple<f32, u32>) -> f32
              %11 = "tree.cmp"(%8, %10) {pred = "le"} : (f32, f32) -> i1
              "tree.yield"(%11) : (i1) -> ()
            }, {
            ^bb3:
              %12 = "tree.const"() {value = false} : () -> i1
              "tree.yield"(%12) : (i1) -> ()
            }) : (i1) -> i1
            "tree.if"(%7) ({
            ^bb4:
              "tree.call"(%0, %4, %2) {callee = @closest_hit} : (!tree.adt<"Ray">, !tree.adt<"BVH">, !tree.ref<tuple<f32, u32>>) -> ()
              "tree.call"(%0, %5, %2) {callee = @closest_hit} : (!tree.adt<"Ray">, !tree.adt<"BVH">, !tree.ref<tuple<f32, u32>>) -> ()
              "tree.yield"() : () -> ()
            }, {
            ^bb5:
              "tree.yield"() : () -> ()
            }) : (i1) -> ()
            "tree.yield"() : () -> ()
          }, {
          ^bb6(%13: !tree.adt<"AABB">, %14: u16, %15: array<? x !tree.adt<"Triangle">>):
            "tree.foreach"(%15) ({
            ^bb7(%16: !tree.adt<"Triangle">):
              %17 = "tree.field"(%16) {index = 3, name = "id"} : (!tree.adt<"Triangle">) -> u32
              %18 = "tree.load"(%2) : (!tree.ref<tuple<f32, u32>>) -> tuple<f32, u32>
              %19 = "tree.insert"(%18, %17) {index = 1} : (tuple<f32, u32>, u32) -> tuple<f32, u32>
              "tree.store"(%2, %19) : (!tree.ref<tuple<f32, u32>>, tuple<f32, u32>) -> ()
              "tree.yield"() : () -> ()
            }) : (array<? x !tree.adt<"Triangle">>) -> ()
            "tree.yield"() : () -> ()
          }) {arms = ["Interior", "Leaf"]} : (!tree.adt<"BVH">) -> ()
          "tree.return"() : () -> ()
        }
    "#]]
    .assert_eq(&text);
    let back = parse_module(&text, FileId(0)).unwrap();
    assert_eq!(print_module(&back), text);
}

#[test]
fn float_constants_round_trip_bit_exactly() {
    let mut m = Module::new();
    let f64t = m.types.float(FloatTy::F64);
    let (_, entry) = m.add_func("floats", &[], &[]);
    let mut bits: Vec<u64> = [
        0.0f64,
        -0.0,
        1.0,
        0.1,
        1e300,
        -1e-300,
        5e-324,
        f64::MAX,
        f64::MIN_POSITIVE,
    ]
    .iter()
    .map(|x| x.to_bits())
    .collect();
    bits.extend([
        f64::INFINITY.to_bits(),
        f64::NEG_INFINITY.to_bits(),
        f64::NAN.to_bits(),
        0x7ff0_0000_0000_0001, // signalling NaN
        0xfff8_0000_0000_0000, // negative quiet NaN
        0x7ff8_dead_beef_0001, // payload
        (0.1f32 as f64).to_bits(),
        (f32::MAX as f64).to_bits(),
    ]);
    let mut x: u64 = 0x1234_5678_9abc_def1;
    for _ in 0..500 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        bits.push(x);
    }
    let mut b = Builder::at_end(&mut m, entry);
    for &bv in &bits {
        b.insert(
            OpSpec::new(Op::Const)
                .attr("value", Attr::Float(bv))
                .results(&[f64t]),
        );
    }
    b.ret(&[]);
    let text = print_module(&m);
    let back = parse_module(&text, FileId(0)).unwrap();
    let entry = back.entry_block(back.func_order[0]).unwrap();
    let got: Vec<u64> = back.blocks[entry].ops[..bits.len()]
        .iter()
        .map(|&op| match back.ops[op].attr("value") {
            Some(Attr::Float(b)) => *b,
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(got, bits);
    assert!(
        text.contains("{value = -0.0}")
            && text.contains("{value = nan}")
            && text.contains("{value = -inf}")
    );
    assert!(text.contains("{value = nan(0x7ff0000000000001)}"));
}

#[test]
fn names_strings_and_comments() {
    let text = r#"
// A comment line.
func @"weird name\n\"x\""(%a.b$c: i32) -> i32 attributes {entry, abi = "c"} { // trailing comment
  %r = "tree.intrinsic"(%a.b$c) {name = "abs", note = "tab\there \u{1f600}", flags = [unit, 1, -2, @sym, f32]} : (i32) -> i32
  "tree.return"(%r) : (i32) -> ()
}
"#;
    let m = parse_module(text, FileId(0)).unwrap();
    let printed = print_module(&m);
    expect![[r#"
        func @"weird name\n\"x\""(%0: i32) -> (i32) attributes {abi = "c", entry} {
          %1 = "tree.intrinsic"(%0) {flags = [unit, 1, -2, @sym, f32], name = "abs", note = "tab\there 😀"} : (i32) -> i32
          "tree.return"(%1) : (i32) -> ()
        }
    "#]]
    .assert_eq(&printed);
    assert_eq!(
        print_module(&parse_module(&printed, FileId(0)).unwrap()),
        printed
    );
    verify(&m).unwrap();
}

#[test]
fn spans_are_kept_beside_the_ops() {
    let text = "func @f(%a: f32) -> (f32) {\n  %b = \"tree.neg\"(%a) : (f32) -> f32\n  \"tree.return\"(%b) : (f32) -> ()\n}\n";
    let m = parse_module(text, FileId(3)).unwrap();
    let entry = m.entry_block(m.func_order[0]).unwrap();
    let neg = m.blocks[entry].ops[0];
    let span = m.span(neg).unwrap();
    assert_eq!(span.file, FileId(3));
    assert_eq!(&text[span.range()], "%b = \"tree.neg\"(%a) : (f32) -> f32");
}

#[test]
fn f32_constants_print_short_and_round_trip_exactly() {
    let mut m = Module::new();
    let f32t = m.types.f32();
    let (_, entry) = m.add_func("floats", &[], &[]);
    let mut bits: Vec<u32> = vec![
        1.000_000_4f32.to_bits(),
        0.1f32.to_bits(),
        1.0f32.to_bits(),
        1e-45f32.to_bits(),
    ];
    let mut x: u32 = 0x9e37_79b9;
    for _ in 0..2000 {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        bits.push(x);
    }
    let mut b = Builder::at_end(&mut m, entry);
    for &bv in &bits {
        let v = f32::from_bits(bv) as f64;
        b.insert(
            OpSpec::new(Op::Const)
                .attr("value", Attr::float(v))
                .results(&[f32t]),
        );
    }
    b.ret(&[]);
    let text = print_module(&m);
    assert!(text.contains("{value = 1.0000004 : f32}"), "{text}");
    assert!(text.contains("{value = 0.1 : f32}") && text.contains("{value = 1.0}"));
    let back = parse_module(&text, FileId(0)).unwrap();
    assert_eq!(print_module(&back), text);
    let entry = back.entry_block(back.func_order[0]).unwrap();
    for (&op, &bv) in back.blocks[entry].ops.iter().zip(&bits) {
        let Some(Attr::Float(got)) = back.ops[op].attr("value") else {
            panic!()
        };
        let want = (f32::from_bits(bv) as f64).to_bits();
        // NaN payloads may be quieted by the f32 -> f64 conversion; every other value is exact.
        assert!(*got == want || f64::from_bits(want).is_nan(), "{bv:#x}");
    }
}

#[test]
fn declarations_have_a_signature_and_no_body() {
    let text = r#"
func @report_overflow(u32, !tree.ref<tuple<f32, u32>>) -> () attributes {abi = "scion_rt_overflow"}
func @f(%d: u32, %r: !tree.ref<tuple<f32, u32>>) -> () {
  "tree.call"(%d, %r) {callee = @report_overflow} : (u32, !tree.ref<tuple<f32, u32>>) -> ()
  "tree.return"() : () -> ()
}
"#;
    let m = parse_module(text, FileId(0)).unwrap();
    verify(&m).unwrap();
    let decl = m.func_by_name("report_overflow").unwrap();
    assert!(m.is_declaration(decl));
    let printed = print_module(&m);
    expect![[r#"
        func @report_overflow(u32, !tree.ref<tuple<f32, u32>>) -> () attributes {abi = "scion_rt_overflow"}

        func @f(%0: u32, %1: !tree.ref<tuple<f32, u32>>) -> () {
          "tree.call"(%0, %1) {callee = @report_overflow} : (u32, !tree.ref<tuple<f32, u32>>) -> ()
          "tree.return"() : () -> ()
        }
    "#]]
    .assert_eq(&printed);
    assert_eq!(
        print_module(&parse_module(&printed, FileId(0)).unwrap()),
        printed
    );
    let mut m2 = Module::new();
    let u = m2.types.u32();
    let g = m2.declare_func("g", &[u], &[u]);
    assert!(m2.is_declaration(g));
    assert_eq!(print_module(&m2), "func @g(u32) -> (u32)\n");
    let err = parse_module("func @h(u32) -> () {\n}\n", FileId(0)).unwrap_err();
    assert_eq!(
        err.list[0].message,
        "a parameter of a function with a body needs a name `%x: T`"
    );
}

/// The example at the top of docs/ir.md is valid IR, printed exactly as the printer would.
#[test]
fn docs_example_is_valid_and_canonical() {
    let doc = include_str!("../../docs/ir.md");
    let example = doc.split("```").nth(1).unwrap().trim_start_matches('\n');
    let m = parse_module(example, FileId(0)).unwrap_or_else(|d| panic!("{d:?}"));
    verify(&m).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(print_module(&m), example);
}

/// The text-form example in the crate's essay (lib.rs) is valid and canonical too.
#[test]
fn essay_example_is_valid_and_canonical() {
    let lib = include_str!("../src/lib.rs");
    let doc: String = lib
        .lines()
        .filter_map(|l| l.strip_prefix("//!"))
        .map(|l| format!("{}\n", l.strip_prefix(' ').unwrap_or(l)))
        .collect();
    let start = doc.find("# Reading the text form").unwrap();
    let example = doc[start..]
        .split("```text\n")
        .nth(1)
        .unwrap()
        .split("```")
        .next()
        .unwrap();
    let m = parse_module(example, FileId(0)).unwrap_or_else(|d| panic!("{d:?}"));
    verify(&m).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(print_module(&m), example);
}
