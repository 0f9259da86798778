//! The builder shorthands irgen uses: every `tree` op built from Rust, verified and printed.

use expect_test::expect;
use scion_ir::diag::{FileId, Span};
use scion_ir::module::{AdtDef, Field, Variant};
use scion_ir::tree::{CmpPred, Op};
use scion_ir::types::IntTy;
use scion_ir::{print_module, verify, Builder, Module};

#[test]
fn every_shorthand_builds_valid_ir() {
    let mut m = Module::new();
    let f32t = m.types.f32();
    let u32t = m.types.u32();
    let u8t = m.types.int(IntTy::U8);
    let slice = m.types.array(f32t, None);
    let arr4 = m.types.array(f32t, Some(4));
    let node = m.types.adt("Node");
    m.declare_adt(AdtDef {
        name: "Node".into(),
        shared: vec![Field {
            name: "w".into(),
            ty: f32t,
        }],
        variants: vec![
            Variant {
                name: "Pair".into(),
                fields: vec![
                    Field {
                        name: "l".into(),
                        ty: node,
                    },
                    Field {
                        name: "r".into(),
                        ty: node,
                    },
                ],
            },
            Variant {
                name: "Tip".into(),
                fields: vec![Field {
                    name: "xs".into(),
                    ty: slice,
                }],
            },
        ],
    })
    .unwrap();
    let (_, entry) = m.add_func("sum", &[node, arr4, u32t], &[f32t]);
    let args = m.blocks[entry].args.clone();
    let (n, a, k) = (args[0], args[1], args[2]);
    let mut b = Builder::at_end(&mut m, entry);
    b.set_span(Some(Span::new(FileId(0), 10, 20)));
    let zero = b.const_float(f32t, 0.0);
    let acc = b.var(zero);
    let one = b.const_int(u32t, 1);
    let two = b.binary(Op::Add, one, one);
    let s = b.slice(a, one, two).unwrap();
    let first = b.index(a, one).unwrap();
    let lanes = b.vector(&[first, first, zero]).unwrap();
    let y = b.lane(lanes, 1).unwrap();
    let d = b.intrinsic(scion_ir::tree::Intrinsic::Dot, &[lanes, lanes], f32t);
    let low = b.bits(k, 0, 8, u8t);
    let lowf = b.cast(low, f32t);
    let raw = b.bitcast(d, u32t);
    let pair = b.tuple(&[y, raw]);
    let y2 = b.extract(pair, 0).unwrap();
    let pair2 = b.insert_elem(pair, 1, k);
    let _ = b.extract(pair2, 1).unwrap();
    let is_tip = b.is_variant(n, "Tip");
    let w = b.field(n, "w").unwrap();
    let bigger = b.cmp(CmpPred::Gt, w, y2);
    let pick = b.select(bigger, w, lowf);
    b.store(acc, pick);
    b.foreach(s, |b, e| {
        let cur = b.load(acc).unwrap();
        let sum = b.binary(Op::Add, cur, e);
        b.store(acc, sum);
        b.yield_(&[]);
    })
    .unwrap();
    let matched = b
        .match_(n, &["Tip", "_"], &[f32t], |b, arm, _fields| {
            if arm == 0 {
                let inner = b.if_(
                    is_tip,
                    &[f32t],
                    |b| {
                        b.yield_(&[w]);
                    },
                    |b| {
                        b.ret(&[w]);
                    },
                );
                let r = b.result(inner, 0);
                b.yield_(&[r]);
            } else {
                let c = b.call("sum", &[n, a, k], &[]);
                let r = b.result(c, 0);
                b.yield_(&[r]);
            }
        })
        .unwrap();
    let mres = b.result(matched, 0);
    let total = b.load(acc).unwrap();
    let out = b.binary(Op::Add, total, mres);
    let neg = b.unary(Op::Neg, out);
    let tip = b.m.types.adt("Node");
    let rebuilt = b.ctor(tip, Some("Tip"), &[neg, s]);
    let _ = b.field(rebuilt, "w").unwrap();
    b.ret(&[neg]);
    verify(&m).unwrap_or_else(|e| panic!("{e}"));
    assert!(m.spans.values().all(|s| s.start == 10));
    expect![[r#"
        tree.type @Node(w: f32) = Pair(l: !tree.adt<"Node">, r: !tree.adt<"Node">) | Tip(xs: array<? x f32>)

        func @sum(%0: !tree.adt<"Node">, %1: array<4 x f32>, %2: u32) -> (f32) {
          %3 = "tree.const"() {value = 0.0} : () -> f32
          %4 = "tree.var"(%3) : (f32) -> !tree.ref<f32>
          %5 = "tree.const"() {value = 1} : () -> u32
          %6 = "tree.add"(%5, %5) : (u32, u32) -> u32
          %7 = "tree.slice"(%1, %5, %6) : (array<4 x f32>, u32, u32) -> array<? x f32>
          %8 = "tree.index"(%1, %5) : (array<4 x f32>, u32) -> f32
          %9 = "tree.vector"(%8, %8, %3) : (f32, f32, f32) -> vector<3xf32>
          %10 = "tree.lane"(%9) {index = 1} : (vector<3xf32>) -> f32
          %11 = "tree.intrinsic"(%9, %9) {name = "dot"} : (vector<3xf32>, vector<3xf32>) -> f32
          %12 = "tree.bits"(%2) {hi = 8, lo = 0} : (u32) -> u8
          %13 = "tree.cast"(%12) : (u8) -> f32
          %14 = "tree.bitcast"(%11) : (f32) -> u32
          %15 = "tree.tuple"(%10, %14) : (f32, u32) -> tuple<f32, u32>
          %16 = "tree.extract"(%15) {index = 0} : (tuple<f32, u32>) -> f32
          %17 = "tree.insert"(%15, %2) {index = 1} : (tuple<f32, u32>, u32) -> tuple<f32, u32>
          %18 = "tree.extract"(%17) {index = 1} : (tuple<f32, u32>) -> u32
          %19 = "tree.is"(%0) {variant = "Tip"} : (!tree.adt<"Node">) -> i1
          %20 = "tree.field"(%0) {index = 0, name = "w"} : (!tree.adt<"Node">) -> f32
          %21 = "tree.cmp"(%20, %16) {pred = "gt"} : (f32, f32) -> i1
          %22 = "tree.select"(%21, %20, %13) : (i1, f32, f32) -> f32
          "tree.store"(%4, %22) : (!tree.ref<f32>, f32) -> ()
          "tree.foreach"(%7) ({
          ^bb1(%23: f32):
            %24 = "tree.load"(%4) : (!tree.ref<f32>) -> f32
            %25 = "tree.add"(%24, %23) : (f32, f32) -> f32
            "tree.store"(%4, %25) : (!tree.ref<f32>, f32) -> ()
            "tree.yield"() : () -> ()
          }) : (array<? x f32>) -> ()
          %26 = "tree.match"(%0) ({
          ^bb2(%27: f32, %28: array<? x f32>):
            %29 = "tree.if"(%19) ({
            ^bb3:
              "tree.yield"(%20) : (f32) -> ()
            }, {
            ^bb4:
              "tree.return"(%20) : (f32) -> ()
            }) : (i1) -> f32
            "tree.yield"(%29) : (f32) -> ()
          }, {
          ^bb5:
            %30 = "tree.call"(%0, %1, %2) {callee = @sum} : (!tree.adt<"Node">, array<4 x f32>, u32) -> f32
            "tree.yield"(%30) : (f32) -> ()
          }) {arms = ["Tip", "_"]} : (!tree.adt<"Node">) -> f32
          %31 = "tree.load"(%4) : (!tree.ref<f32>) -> f32
          %32 = "tree.add"(%31, %26) : (f32, f32) -> f32
          %33 = "tree.neg"(%32) : (f32) -> f32
          %34 = "tree.ctor"(%33, %7) {variant = "Tip"} : (f32, array<? x f32>) -> !tree.adt<"Node">
          %35 = "tree.field"(%34) {index = 0, name = "w"} : (!tree.adt<"Node">) -> f32
          "tree.return"(%33) : (f32) -> ()
        }
    "#]]
    .assert_eq(&print_module(&m));
}

#[test]
fn shorthands_refuse_wrong_types_instead_of_panicking() {
    let mut m = Module::new();
    let f32t = m.types.f32();
    let (_, entry) = m.add_func("f", &[f32t], &[]);
    let x = m.blocks[entry].args[0];
    let mut b = Builder::at_end(&mut m, entry);
    assert!(b.extract(x, 0).is_none());
    assert!(b.lane(x, 0).is_none());
    assert!(b.index(x, x).is_none());
    assert!(b.slice(x, x, x).is_none());
    assert!(b.load(x).is_none());
    assert!(b.field(x, "w").is_none());
    assert!(b.vector(&[]).is_none());
    assert!(b.foreach(x, |_, _| {}).is_none());
    assert!(b.match_(x, &["_"], &[], |_, _, _| {}).is_none());
    assert!(b.m.blocks[entry].ops.is_empty());
}

#[test]
fn foreach_over_a_set_of_pairs() {
    let mut m = Module::new();
    let u32t = m.types.u32();
    let pair = m.types.tuple(vec![u32t, u32t]);
    let set = m.types.intern(scion_ir::Type::Set(pair));
    let (_, entry) = m.add_func("count", &[set], &[]);
    let s = m.blocks[entry].args[0];
    let mut b = Builder::at_end(&mut m, entry);
    let zero = b.const_int(u32t, 0);
    let n = b.var(zero);
    b.foreach(s, |b, p| {
        let a = b.extract(p, 0).unwrap();
        let cur = b.load(n).unwrap();
        let next = b.binary(Op::Add, cur, a);
        b.store(n, next);
        b.yield_(&[]);
    })
    .unwrap();
    b.ret(&[]);
    verify(&m).unwrap_or_else(|e| panic!("{e}"));
    let text = print_module(&m);
    assert!(
        text.contains(r#""tree.foreach"(%0) ({"#) && text.contains("set<tuple<u32, u32>>"),
        "{text}"
    );
}
