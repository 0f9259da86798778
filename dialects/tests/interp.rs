//! The `tree` interpreter: programs with matches, loops, references and calls; its errors; and
//! a differential property test showing `const-fold` and `dce` keep every random module's
//! meaning bit for bit.

use crate::common;

use expect_test::expect;
use proptest::prelude::*;
use scion_ir::diag::FileId;
use scion_ir::interp::{AdtVal, Interp, Val};
use scion_ir::types::{FloatTy, IntTy, Type};
use scion_ir::{parse_module, Module, PassCx, PassManager, PassRegistry, TypeId};
use std::rc::Rc;

const SUM: &str = r#"
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

func @first_negative(%xs: array<? x f32>) -> (i32) {
  "tree.foreach"(%xs) ({
  ^body(%x: f32, %i: i32):
    %z = "tree.const"() {value = 0.0} : () -> f32
    %neg = "tree.cmp"(%x, %z) {pred = "lt"} : (f32, f32) -> i1
    "tree.if"(%neg) ({
      "tree.return"(%i) : (i32) -> ()
    }, {
      "tree.yield"() : () -> ()
    }) : (i1) -> ()
    "tree.yield"() : () -> ()
  }) : (array<? x f32>) -> ()
  %none = "tree.const"() {value = -1} : () -> i32
  "tree.return"(%none) : (i32) -> ()
}

func @geometry(%a: vector<3xf32>, %b: vector<3xf32>) -> (vector<3xf32>, f32, f32, u32) {
  %c = "tree.intrinsic"(%a, %b) {name = "cross"} : (vector<3xf32>, vector<3xf32>) -> vector<3xf32>
  %d = "tree.intrinsic"(%a, %b) {name = "dot"} : (vector<3xf32>, vector<3xf32>) -> f32
  %nan = "tree.const"() {value = nan} : () -> f32
  %m = "tree.intrinsic"(%nan, %d) {name = "min"} : (f32, f32) -> f32
  %bits = "tree.bitcast"(%m) : (f32) -> u32
  %hi = "tree.bits"(%bits) {lo = 23, hi = 31} : (u32) -> u32
  "tree.return"(%c, %d, %m, %hi) : (vector<3xf32>, f32, f32, u32) -> ()
}
"#;

fn leaf(xs: &[f32]) -> Val {
    let arr = Val::Array(Rc::new(xs.iter().map(|&x| Val::F32(x)).collect()));
    Val::Adt(Rc::new(AdtVal {
        ty: "T".into(),
        variant: Some(1),
        fields: vec![Val::F32(0.0), arr],
    }))
}

fn node(l: Val, r: Val) -> Val {
    Val::Adt(Rc::new(AdtVal {
        ty: "T".into(),
        variant: Some(0),
        fields: vec![Val::F32(0.0), l, r],
    }))
}

fn vec3(x: f32, y: f32, z: f32) -> Val {
    Val::Vector(vec![Val::F32(x), Val::F32(y), Val::F32(z)])
}

#[test]
fn runs_matches_loops_references_and_calls() {
    let m = parse_module(SUM, FileId(0)).unwrap();
    scion_ir::verify(&m).unwrap();
    let mut it = Interp::new(&m);
    let tree = node(leaf(&[1.0, 2.0]), node(leaf(&[]), leaf(&[0.5, 0.25])));
    let acc = it.alloc(Val::F32(0.0));
    assert!(it.call("sum", vec![tree, acc.clone()]).unwrap().is_empty());
    assert!(it.read(&acc).unwrap().same(&Val::F32(3.75)));

    let xs = Val::Array(Rc::new(vec![
        Val::F32(1.0),
        Val::F32(-0.0),
        Val::F32(-2.0),
        Val::F32(-3.0),
    ]));
    let r = it.call("first_negative", vec![xs]).unwrap();
    assert!(r[0].same(&Val::Int(2, IntTy::I32)), "{}", r[0]);
    let r = it
        .call("first_negative", vec![Val::Array(Rc::new(vec![]))])
        .unwrap();
    assert!(r[0].same(&Val::Int(-1, IntTy::I32)));

    let r = it
        .call("geometry", vec![vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)])
        .unwrap();
    let shown: Vec<String> = r.iter().map(|v| v.to_string()).collect();
    expect![[r#"["<0.0_f32, 0.0_f32, 1.0_f32>", "0.0_f32", "0.0_f32", "0_u32"]"#]]
        .assert_eq(&format!("{shown:?}"));
}

#[test]
fn failures_are_errors_not_panics() {
    let text = r#"
func @div(%a: i32, %b: i32) -> (i32) {
  %q = "tree.div"(%a, %b) : (i32, i32) -> i32
  "tree.return"(%q) : (i32) -> ()
}
func @at(%xs: array<? x f32>, %i: u32) -> (f32) {
  %x = "tree.index"(%xs, %i) : (array<? x f32>, u32) -> f32
  "tree.return"(%x) : (f32) -> ()
}
func @forever(%a: i32) -> (i32) {
  %r = "tree.call"(%a) {callee = @forever} : (i32) -> i32
  "tree.return"(%r) : (i32) -> ()
}
func @host(i32) -> (i32)
func @via_host(%a: i32) -> (i32) {
  %r = "tree.call"(%a) {callee = @host} : (i32) -> i32
  "tree.return"(%r) : (i32) -> ()
}
"#;
    let m = parse_module(text, FileId(0)).unwrap();
    scion_ir::verify(&m).unwrap();
    let mut it = Interp::new(&m);
    let i32v = |v| Val::Int(v, IntTy::I32);
    let e = it.call("div", vec![i32v(1), i32v(0)]).unwrap_err();
    assert_eq!(e.message, "`tree.div`: integer division by zero");
    assert!(e.op.is_some());
    let r = it
        .call("div", vec![i32v(i32::MIN as i128), i32v(-1)])
        .unwrap();
    assert!(r[0].same(&i32v(i32::MIN as i128)), "wraps");
    let e = it
        .call(
            "at",
            vec![
                Val::Array(Rc::new(vec![Val::F32(1.0)])),
                Val::Int(1, IntTy::U32),
            ],
        )
        .unwrap_err();
    assert_eq!(
        e.message,
        "`tree.index`: index 1 out of bounds for length 1"
    );
    it.max_depth = 30;
    assert_eq!(
        it.call("forever", vec![i32v(0)]).unwrap_err().message,
        "call depth limit 30 reached"
    );
    assert_eq!(
        it.call("via_host", vec![i32v(4)]).unwrap_err().message,
        "call to declaration `@host` without a host function"
    );
    it.define_extern(
        "host",
        Box::new(|args: &[Val]| match args {
            [Val::Int(v, t)] => Ok(vec![Val::Int(v * 10, *t)]),
            _ => Err("bad arguments".into()),
        }),
    );
    assert!(it.call("via_host", vec![i32v(4)]).unwrap()[0].same(&i32v(40)));
    assert_eq!(
        it.call("nope", vec![]).unwrap_err().message,
        "no function `@nope`"
    );
}

/// A value of type `ty` for a random module's parameters (references are made by the caller).
fn arbitrary(m: &Module, ty: TypeId, rng: &mut common::Rng, depth: u32) -> Val {
    match m.types.get(ty).clone() {
        Type::Bool => Val::Bool(rng.chance(50)),
        Type::Int(t) => {
            let (lo, hi) = t.range();
            Val::Int((rng.next() as i128 % 2000 - 1000).clamp(lo, hi), t)
        }
        Type::Float(FloatTy::F32) => {
            Val::F32([0.0, -0.0, 1.5, -2.25, f32::INFINITY, f32::NAN, 1e-40][rng.below(7)])
        }
        Type::Float(_) => {
            Val::F64([0.0, -0.0, 1.5, -2.25, f64::INFINITY, f64::NAN, 1e-310][rng.below(7)])
        }
        Type::Vector { elem, lanes } => {
            Val::Vector((0..lanes).map(|_| arbitrary(m, elem, rng, depth)).collect())
        }
        Type::Tuple(elems) => {
            Val::Tuple(elems.iter().map(|&e| arbitrary(m, e, rng, depth)).collect())
        }
        Type::Array { elem, .. } => Val::Array(Rc::new(
            (0..rng.below(4))
                .map(|_| arbitrary(m, elem, rng, depth))
                .collect(),
        )),
        Type::Adt(name) => {
            let adt = m.adt(&name).unwrap();
            let variant = if adt.is_record() {
                None
            } else if depth > 2 {
                Some(adt.variants.len() - 1)
            } else {
                Some(rng.below(adt.variants.len()))
            };
            let fields = adt
                .fields_of(variant.map(|i| adt.variants[i].name.as_str()))
                .unwrap();
            let fields = fields
                .iter()
                .map(|f| arbitrary(m, f.ty, rng, depth + 1))
                .collect();
            Val::Adt(Rc::new(AdtVal {
                ty: name,
                variant,
                fields,
            }))
        }
        other => panic!("no arbitrary value for {other:?}"),
    }
}

/// Runs every function of `m` on `args`, with references allocated in order; returns each
/// function's results (or error message) and the referenced cells afterwards.
fn run_all(m: &Module, args: &[Vec<(Val, bool)>]) -> Vec<Result<Vec<Val>, String>> {
    let mut out = Vec::new();
    for (i, &f) in m.func_order.iter().enumerate() {
        if m.is_declaration(f) {
            continue;
        }
        let mut it = Interp::new(m);
        it.max_depth = 12;
        it.max_steps = 200_000;
        it.define_extern("ext", Box::new(|a: &[Val]| Ok(vec![a[0].clone()])));
        let mut refs = Vec::new();
        let call_args: Vec<Val> = args[i]
            .iter()
            .map(|(v, is_ref)| {
                if *is_ref {
                    let r = it.alloc(v.clone());
                    refs.push(r.clone());
                    r
                } else {
                    v.clone()
                }
            })
            .collect();
        let r = it
            .call(&m.funcs[f].name, call_args)
            .map_err(|e| e.message)
            .map(|mut vals| {
                vals.extend(refs.iter().map(|r| it.read(r).unwrap().clone()));
                vals
            });
        out.push(r);
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig { cases: std::env::var("PROPTEST_CASES").ok().and_then(|c| c.parse().ok()).unwrap_or(200), ..ProptestConfig::default() })]

    #[test]
    fn const_fold_and_dce_preserve_meaning(seed in any::<u64>()) {
        let m = common::random_module(seed);
        let mut rng = common::Rng(seed.rotate_left(17) | 1);
        let args: Vec<Vec<(Val, bool)>> = m
            .func_order
            .iter()
            .map(|&f| {
                m.funcs[f].params.iter().map(|&p| match m.types.get(p) {
                    Type::Ref(inner) => (arbitrary(&m, *inner, &mut rng, 0), true),
                    _ => (arbitrary(&m, p, &mut rng, 0), false),
                }).collect()
            })
            .collect();
        let before = run_all(&m, &args);
        let mut folded = m.clone();
        let reg = PassRegistry::with_builtin();
        let mut pm = PassManager::parse(&reg, "const-fold,dce,const-fold,dce").unwrap();
        pm.run(&mut folded, &mut PassCx::new(), &mut String::new()).unwrap();
        let after = run_all(&folded, &args);
        for (b, a) in before.iter().zip(&after) {
            // Removing dead code may remove a failure (integer division by zero is undefined),
            // never add one or change a result.
            if let Ok(bv) = b {
                let av = a.as_ref().unwrap_or_else(|e| panic!("folded module fails: {e}\n{}", scion_ir::print_module(&folded)));
                prop_assert_eq!(bv.len(), av.len());
                for (x, y) in bv.iter().zip(av) {
                    prop_assert!(x.same(y), "{} vs {}\n{}", x, y, scion_ir::print_module(&m));
                }
            }
        }
    }
}

/// The differential test is only as good as the runs that succeed: most must.
#[test]
fn most_random_functions_run_to_completion() {
    let (mut ok, mut total) = (0, 0);
    let mut errors = std::collections::BTreeMap::new();
    for seed in 1..150u64 {
        let m = common::random_module(seed.wrapping_mul(0x2545_f491_4f6c_dd1d));
        let mut rng = common::Rng(seed | 1);
        let args: Vec<Vec<(Val, bool)>> = m
            .func_order
            .iter()
            .map(|&f| {
                m.funcs[f]
                    .params
                    .iter()
                    .map(|&p| match m.types.get(p) {
                        Type::Ref(inner) => (arbitrary(&m, *inner, &mut rng, 0), true),
                        _ => (arbitrary(&m, p, &mut rng, 0), false),
                    })
                    .collect()
            })
            .collect();
        for r in run_all(&m, &args) {
            total += 1;
            match r {
                Ok(_) => ok += 1,
                Err(e) => *errors.entry(e).or_insert(0) += 1,
            }
        }
    }
    assert!(
        ok * 10 >= total * 6,
        "{ok} of {total} ran; errors: {errors:?}"
    );
}

/// The default depth limit is reached before the stack of a test thread (2 MiB) runs out, even
/// when every level nests regions.
#[test]
fn default_depth_limit_fits_a_small_stack() {
    let text = r#"
tree.type @T(w: f32) = Node(l: !tree.adt<"T">, r: !tree.adt<"T">) | Leaf(xs: array<? x f32>)
func @deep(%t: !tree.adt<"T">, %c: i1) -> (f32) {
  %r = "tree.match"(%t) ({
  ^n(%w: f32, %l: !tree.adt<"T">, %r: !tree.adt<"T">):
    %x = "tree.if"(%c) ({
      "tree.foreach"(%xs0) ({
      ^b(%e: f32):
        "tree.yield"() : () -> ()
      }) : (array<? x f32>) -> ()
      %y = "tree.call"(%t, %c) {callee = @deep} : (!tree.adt<"T">, i1) -> f32
      "tree.yield"(%y) : (f32) -> ()
    }, {
      "tree.yield"(%w) : (f32) -> ()
    }) : (i1) -> f32
    "tree.yield"(%x) : (f32) -> ()
  }, {
    "tree.yield"(%z) : (f32) -> ()
  }) {arms = ["Node", "_"]} : (!tree.adt<"T">) -> f32
  "tree.return"(%r) : (f32) -> ()
}
"#
    .replace("%xs0", "%arr")
    .replace(
        "func @deep(%t: !tree.adt<\"T\">, %c: i1) -> (f32) {",
        "func @deep(%t: !tree.adt<\"T\">, %c: i1, %arr: array<? x f32>, %z: f32) -> (f32) {",
    )
    .replace(
        "(%t, %c) {callee = @deep} : (!tree.adt<\"T\">, i1)",
        "(%t, %c, %arr, %z) {callee = @deep} : (!tree.adt<\"T\">, i1, array<? x f32>, f32)",
    );
    let m = parse_module(&text, FileId(0)).unwrap_or_else(|d| panic!("{d:?}"));
    scion_ir::verify(&m).unwrap_or_else(|e| panic!("{e}"));
    let handle = std::thread::Builder::new()
        .stack_size(2 << 20)
        .spawn(move || {
            let mut it = Interp::new(&m);
            let t = node(leaf(&[]), leaf(&[]));
            let arr = Val::Array(Rc::new(vec![Val::F32(1.0)]));
            it.call("deep", vec![t, Val::Bool(true), arr, Val::F32(0.0)])
                .unwrap_err()
                .message
        })
        .unwrap();
    assert_eq!(
        handle.join().unwrap(),
        format!(
            "call depth limit {} reached",
            Interp::new(&Module::new()).max_depth
        )
    );
}
