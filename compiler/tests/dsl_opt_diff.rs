//! Differential tests of the DSL optimizations (paper §7.3; `mem-inline`, `const-fold`,
//! `mem-cse`, `dce`, the `-O3` tree/mem pipeline): the `tree` interpreter gives bit-identical
//! results (NaN payloads and signed zeros included) and leaves `mut` arguments bit-identical
//! before and after the pipeline, on the prelude's geometric functions and on functions built
//! to stress the single-exit rewrite of `mem-inline` (early returns in nested `if`s and
//! `match` arms, returns from unit functions writing a `mut` parameter), with the default
//! inlining threshold and with one large enough to inline everything that is not recursive.

use crate::common;

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use scion_compiler::driver::pipelines::for_level;
use scion_ir::interp::{AdtVal, Interp, Val};
use scion_ir::pass::{PassCx, PassManager};
use scion_ir::types::{FloatTy, IntTy, Type};
use scion_ir::{Module, TypeId};
use std::rc::Rc;

const USES: &str = r#"
type Sh = Ci(r: f32) | Sq(s: f32, t: f32) | Em;

func pick(a: f32, b: f32) -> f32 = {
  if a > b { if a > 0.0 { return a; } return b * 2.0; }
  let c: f32 = a - b;
  if c == 0.0 { return 1.0; }
  return c * a;
}

func area(s: Sh, k: f32) -> f32 = {
  match s {
    | Ci(r) -> if r < 0.0 { return -1.0; }
    | Sq(a, b) -> return a * b;
    | Em -> { }
  };
  return k * 3.0;
}

func bump(acc: mut f32, x: f32) = {
  if x > 0.0 { acc = acc + x; return; }
  acc = acc - x;
}

func t_pick(a: f32, b: f32) -> f32 = pick(a, b) + pick(b, a) * pick(a, a)

func t_area(x: f32, y: f32, k: f32, sel: u32) -> f32 = {
  if sel % 3 == 0 { return area(Ci(x), k); }
  if sel % 3 == 1 { return area(Sq(x, y), k) + area(Sq(x, y), k); }
  return area(Em(), k);
}

func t_bump(a: f32, b: f32, acc: mut f32) -> f32 = {
  bump(acc, a);
  let first: f32 = acc;
  bump(acc, b);
  return acc + first + pick(a, b);
}

func t_hit(ray: Ray, tri: Triangle) -> f32 = hit_distance(ray, tri)
func t_slab(ray: Ray, box: AABB) -> (f32, f32) = slab_interval(ray, box)
func t_box(ray: Ray, box: AABB) -> f32 = {
  if intersects(ray, box) && distmin(ray, box) <= ray.tmax { return distmin(ray, box); }
  return -1.0;
}
func t_tri(ray: Ray, tri: Triangle) -> f32 = {
  if intersects(ray, tri) { return distmin(ray, tri); }
  return -1.0;
}
func t_cpt(p: f32x3, tri: Triangle) -> f32x3 = closest_point(p, tri)
func t_sat(a: Triangle, b: Triangle) -> bool = intersects(a, b)
func t_d2(p: f32x3, box: AABB) -> f32 = distance_squared(p, box)
func t_logic(a: f32, b: f32, acc: mut f32) -> f32 = {
  if a < 0.0 || b > acc || (a == b && acc < 1.0) || !(a <= b) { return 1.0; }
  if a > 0.0 && a / b > 2.0 && b - a < acc { return 2.0; }
  return 3.0;
}
"#;

const FUNCS: &[&str] = &[
    "t_pick", "t_area", "t_bump", "t_hit", "t_slab", "t_box", "t_tri", "t_cpt", "t_sat", "t_d2",
    "t_logic",
];

/// The `tree` module of the functions above, unoptimized.
fn tree_module() -> Module {
    common::tree_module_of(&[("uses.scion", USES)], true).unwrap_or_else(|e| panic!("{e}"))
}

/// `m` after the `-O3` tree/mem passes, with `mem-inline:max-ops` set to `max_ops`.
fn optimized(m: &Module, max_ops: usize) -> Module {
    let mut out = m.clone();
    let names = for_level(3);
    assert_eq!(
        names,
        [
            "mem-inline",
            "const-fold",
            "mem-cse",
            "dce",
            "mem-split-loads",
            "mem-sink"
        ]
    );
    let registry = scion_compiler::passes::registry();
    let mut pm = PassManager::from_names(&registry, &names).expect("known passes");
    pm.options.verify_each = true;
    let mut cx = PassCx::new();
    cx.set_option("mem-inline", "max-ops", &max_ops.to_string());
    let mut dumps = String::new();
    pm.run(&mut out, &mut cx, &mut dumps)
        .unwrap_or_else(|e| panic!("-O3 passes fail: {e}"));
    out
}

/// The number of `tree.call` ops left in function `name`.
fn calls_in(m: &Module, name: &str) -> usize {
    let f = m.func_by_name(name).expect("function");
    scion_ir::walk::func_ops(m, f, scion_ir::walk::Order::Pre)
        .into_iter()
        .filter(|&op| m.ops[op].kind.is_tree(scion_ir::tree::Op::Call))
        .count()
}

/// An argument of type `ty` drawn from `src`; `mut` parameters get a fresh cell.
fn make(
    interp: &mut Interp<'_>,
    m: &Module,
    ty: TypeId,
    src: &mut impl Iterator<Item = f32>,
) -> Val {
    match m.types.get(ty) {
        Type::Float(FloatTy::F32) => Val::F32(src.next().unwrap_or(0.0)),
        Type::Int(t) => Val::Int(
            t.wrap(i128::from(src.next().unwrap_or(0.0).to_bits() % 1000)),
            *t,
        ),
        Type::Vector { elem, lanes } => {
            Val::Vector((0..*lanes).map(|_| make(interp, m, *elem, src)).collect())
        }
        Type::Adt(name) => {
            let def = m.adt(name).expect("declared");
            Val::Adt(Rc::new(AdtVal {
                ty: name.clone(),
                variant: None,
                fields: def
                    .shared
                    .iter()
                    .map(|f| make(interp, m, f.ty, src))
                    .collect(),
            }))
        }
        Type::Ref(inner) => {
            let v = make(interp, m, *inner, src);
            interp.alloc(v)
        }
        other => panic!("no generator for {other:?}"),
    }
}

/// Bits and kind of every scalar leaf, so that NaN payloads and signed zeros count.
fn bits(v: &Val, out: &mut Vec<(u8, u64)>) {
    match v {
        Val::Vector(l) | Val::Tuple(l) => l.iter().for_each(|x| bits(x, out)),
        Val::Adt(a) => a.fields.iter().for_each(|x| bits(x, out)),
        Val::Bool(b) => out.push((0, u64::from(*b))),
        Val::Int(x, _) => out.push((1, *x as u64)),
        Val::F32(x) => out.push((2, u64::from(x.to_bits()))),
        Val::F64(x) => out.push((3, x.to_bits())),
        other => panic!("unexpected value {other:?}"),
    }
}

/// The results of `name` and the final contents of its `mut` arguments, as bits.
fn run(m: &Module, name: &str, floats: &[f32]) -> Result<Vec<(u8, u64)>, String> {
    let f = m.func_by_name(name).ok_or("missing function")?;
    let mut interp = Interp::new(m);
    let mut src = floats.iter().copied().cycle();
    let args: Vec<Val> = m.funcs[f]
        .params
        .iter()
        .map(|&p| make(&mut interp, m, p, &mut src))
        .collect();
    let results = interp
        .call(name, args.clone())
        .map_err(|e| format!("{name}: {e}"))?;
    let mut out = Vec::new();
    results.iter().for_each(|v| bits(v, &mut out));
    for a in &args {
        if let Some(cell) = interp.read(a) {
            bits(cell, &mut out);
        }
    }
    Ok(out)
}

#[test]
fn dsl_optimizations_keep_every_result_bit() {
    let base = tree_module();
    let small = optimized(&base, scion_compiler::passes::mem::inline::DEFAULT_MAX_OPS);
    let all = optimized(&base, 100_000);
    // The optimizations did fire: the helpers are gone from the wrappers, and with the large
    // threshold nothing non-recursive is called any more.
    assert_eq!(calls_in(&small, "t_pick"), 0);
    assert_eq!(calls_in(&small, "t_bump"), 0);
    assert_eq!(calls_in(&small, "t_area"), 0);
    // intersects and distmin share one slab test (three distmin/intersects calls before): one
    // call to prepare the ray (`slab_ray`) and one to test it against the box.
    assert_eq!(calls_in(&base, "t_box"), 3);
    assert_eq!(calls_in(&small, "t_box"), 2);
    assert_eq!(calls_in(&small, "t_tri"), 1);
    for name in FUNCS {
        assert_eq!(
            calls_in(&all, name),
            0,
            "{name} still calls at max-ops=100000"
        );
    }
    let cases = common::cases(if cfg!(debug_assertions) { 200 } else { 2000 });
    let mut runner = TestRunner::new(Config {
        cases,
        ..Config::default()
    });
    let result = runner.run(
        &prop::collection::vec(common::special_f32(), 24),
        |floats| {
            for name in FUNCS {
                let want = run(&base, name, &floats).map_err(TestCaseError::fail)?;
                for (label, m) in [("default threshold", &small), ("inline all", &all)] {
                    let got = run(m, name, &floats).map_err(TestCaseError::fail)?;
                    if got != want {
                        return Err(TestCaseError::fail(format!(
                            "{name}({floats:?}) {label}: {got:?}, unoptimized {want:?}"
                        )));
                    }
                }
            }
            Ok(())
        },
    );
    if let Err(e) = result {
        panic!("{e}");
    }
}

/// Every selector value of `t_area` reaches a different `match` arm; make sure each is hit.
#[test]
fn every_match_arm_is_compared() {
    let base = tree_module();
    let all = optimized(&base, 100_000);
    for sel in 0..3u32 {
        for x in [-1.5f32, 2.0, f32::NAN] {
            let f = base.func_by_name("t_area").expect("t_area");
            assert_eq!(base.funcs[f].params.len(), 4);
            let args = vec![
                Val::F32(x),
                Val::F32(0.5),
                Val::F32(-0.0),
                Val::Int(i128::from(sel), IntTy::U32),
            ];
            let want = Interp::new(&base).call("t_area", args.clone()).unwrap();
            let got = Interp::new(&all).call("t_area", args).unwrap();
            let (mut w, mut g) = (Vec::new(), Vec::new());
            want.iter().for_each(|v| bits(v, &mut w));
            got.iter().for_each(|v| bits(v, &mut g));
            assert_eq!(w, g, "t_area({x}, 0.5, -0.0, {sel})");
        }
    }
}
