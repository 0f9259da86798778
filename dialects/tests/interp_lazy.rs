//! Lazy ADT values in the `tree` interpreter: a `Val::Extern` handle is destructured on demand
//! through the provider, gives the same results as the materialized value, is asked for only
//! where the program looks, and fails with an error (never a panic) without a provider or when
//! the provider refuses.

use scion_ir::diag::FileId;
use scion_ir::interp::{AdtVal, Interp, Val};
use scion_ir::parse_module;
use scion_ir::types::IntTy;
use std::cell::Cell;
use std::rc::Rc;

const PROG: &str = r#"
tree.type @T(w: f32) = Node(l: !tree.adt<"T">, r: !tree.adt<"T">) | Leaf(xs: array<? x f32>)

func @sum(%t: !tree.adt<"T">, %acc: !tree.ref<f32>) -> () {
  "tree.match"(%t) ({
  ^node(%w: f32, %l: !tree.adt<"T">, %r: !tree.adt<"T">):
    "tree.call"(%l, %acc) {callee = @sum} : (!tree.adt<"T">, !tree.ref<f32>) -> ()
    "tree.call"(%r, %acc) {callee = @sum} : (!tree.adt<"T">, !tree.ref<f32>) -> ()
    "tree.yield"() : () -> ()
  }, {
  ^leaf(%w2: f32, %xs: array<? x f32>):
    "tree.foreach"(%xs) ({
    ^body(%x: f32, %i: u32):
      %old = "tree.load"(%acc) : (!tree.ref<f32>) -> f32
      %new = "tree.add"(%old, %x) : (f32, f32) -> f32
      "tree.store"(%acc, %new) : (!tree.ref<f32>, f32) -> ()
      "tree.yield"() : () -> ()
    }) : (array<? x f32>) -> ()
    "tree.yield"() : () -> ()
  }) {arms = ["Node", "Leaf"]} : (!tree.adt<"T">) -> ()
  "tree.return"() : () -> ()
}

func @leftmost_weight(%t: !tree.adt<"T">) -> (f32) {
  %leaf = "tree.is"(%t) {variant = "Leaf"} : (!tree.adt<"T">) -> i1
  "tree.if"(%leaf) ({
    %w = "tree.field"(%t) {index = 0, name = "w"} : (!tree.adt<"T">) -> f32
    "tree.return"(%w) : (f32) -> ()
  }, {
    "tree.yield"() : () -> ()
  }) : (i1) -> ()
  %r = "tree.match"(%t) ({
  ^node(%w3: f32, %l: !tree.adt<"T">, %rt: !tree.adt<"T">):
    %x = "tree.call"(%l) {callee = @leftmost_weight} : (!tree.adt<"T">) -> f32
    "tree.yield"(%x) : (f32) -> ()
  }, {
  ^leaf(%w4: f32, %xs: array<? x f32>):
    "tree.yield"(%w4) : (f32) -> ()
  }) {arms = ["Node", "Leaf"]} : (!tree.adt<"T">) -> f32
  "tree.return"(%r) : (f32) -> ()
}
"#;

/// A complete binary tree in heap order: handle 1 is the root, `h` has children `2h` and
/// `2h + 1`, handles at `depth` levels below the root are leaves holding `[h as f32]` and
/// weight `h as f32`.
fn provider(depth: u32, calls: Rc<Cell<u64>>) -> impl FnMut(u64) -> Result<Rc<AdtVal>, String> {
    let first_leaf = 1u64 << depth;
    move |h| {
        calls.set(calls.get() + 1);
        if h == 0 || h >= 2 * first_leaf {
            return Err(format!("no node {h}"));
        }
        Ok(Rc::new(if h >= first_leaf {
            AdtVal {
                ty: "T".into(),
                variant: Some(1),
                fields: vec![
                    Val::F32(h as f32),
                    Val::Array(Rc::new(vec![Val::F32(h as f32)])),
                ],
            }
        } else {
            AdtVal {
                ty: "T".into(),
                variant: Some(0),
                fields: vec![Val::F32(0.0), Val::Extern(2 * h), Val::Extern(2 * h + 1)],
            }
        }))
    }
}

/// The same tree as [`provider`], materialized.
fn materialize(h: u64, depth: u32) -> Val {
    let first_leaf = 1u64 << depth;
    Val::Adt(Rc::new(if h >= first_leaf {
        AdtVal {
            ty: "T".into(),
            variant: Some(1),
            fields: vec![
                Val::F32(h as f32),
                Val::Array(Rc::new(vec![Val::F32(h as f32)])),
            ],
        }
    } else {
        AdtVal {
            ty: "T".into(),
            variant: Some(0),
            fields: vec![
                Val::F32(0.0),
                materialize(2 * h, depth),
                materialize(2 * h + 1, depth),
            ],
        }
    }))
}

#[test]
fn lazy_and_materialized_values_agree() {
    let m = parse_module(PROG, FileId(0)).unwrap();
    scion_ir::verify(&m).unwrap();
    let depth = 5;
    let calls = Rc::new(Cell::new(0));

    let mut eager = Interp::new(&m);
    let acc = eager.alloc(Val::F32(0.0));
    eager
        .call("sum", vec![materialize(1, depth), acc.clone()])
        .unwrap();
    let want = eager.read(&acc).unwrap().clone();

    let mut lazy = Interp::new(&m);
    lazy.set_adt_provider(Box::new(provider(depth, calls.clone())));
    let acc = lazy.alloc(Val::F32(0.0));
    lazy.call("sum", vec![Val::Extern(1), acc.clone()]).unwrap();
    let got = lazy.read(&acc).unwrap().clone();
    // Leaves 32..64 sum to 1520.
    assert!(got.same(&Val::F32(1520.0)), "{got}");
    assert!(got.same(&want), "lazy {got} vs materialized {want}");
    // Every node is matched exactly once.
    assert_eq!(calls.get(), (1 << (depth + 1)) - 1);
}

#[test]
fn only_the_visited_nodes_are_asked_for() {
    let m = parse_module(PROG, FileId(0)).unwrap();
    // 2^41 nodes: impossible to materialize.
    let depth = 40;
    let calls = Rc::new(Cell::new(0));
    let mut it = Interp::new(&m);
    it.max_depth = 64;
    it.set_adt_provider(Box::new(provider(depth, calls.clone())));
    let r = it.call("leftmost_weight", vec![Val::Extern(1)]).unwrap();
    assert!(r[0].same(&Val::F32((1u64 << depth) as f32)), "{}", r[0]);
    // Each interior level: one `is` and one `match`; the leaf: one `is` and one `field`.
    assert_eq!(calls.get(), 2 * (u64::from(depth) + 1));
}

#[test]
fn lazy_values_fail_cleanly() {
    let m = parse_module(PROG, FileId(0)).unwrap();
    let mut it = Interp::new(&m);
    let acc = it.alloc(Val::F32(0.0));
    let e = it
        .call("sum", vec![Val::Extern(7), acc.clone()])
        .unwrap_err();
    assert!(e.message.contains("without an ADT provider"), "{e}");
    assert!(e.op.is_some());

    let calls = Rc::new(Cell::new(0));
    it.set_adt_provider(Box::new(provider(2, calls)));
    let e = it.call("sum", vec![Val::Extern(99), acc]).unwrap_err();
    assert!(e.message.contains("no node 99"), "{e}");

    // A handle is not an integer or a box: other ops reject it.
    let e = it.call("leftmost_weight", vec![Val::Int(1, IntTy::U32)]);
    assert!(e.unwrap_err().message.contains("not an ADT value"));
}

#[test]
fn handles_print_and_order() {
    assert_eq!(Val::Extern(42).to_string(), "extern#42");
    assert!(Val::Extern(3).same(&Val::Extern(3)));
    assert!(!Val::Extern(3).same(&Val::Extern(4)));
    assert!(Val::Extern(3).total_cmp(&Val::Extern(4)).is_lt());
    assert!(Val::Ref(9).total_cmp(&Val::Extern(0)).is_lt());
}
