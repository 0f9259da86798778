//! Differential tests of the lowering to `lo` and of the Cranelift JIT: the prelude's geometric
//! functions (`hit_distance`, the slab test, `closest_point` on boxes and triangles, the
//! triangle-triangle separating-axis test), `with_axis` (a lane index in and out of range), the
//! directed-rounding builtins, the lane and bit builtins (`hmin`, `hsum`, `rsqrt`, `isnan`,
//! `popcount`, `clz`, `ctz`, ...), `let mut` locals (cells passed to `mut` parameters, components
//! assigned) and `if`
//! expressions give bit-identical results in the `tree` interpreter, the `lo` interpreter (after
//! `mem-to-lo`) and the JIT-compiled code (Cranelift, and LLVM at -O0 and -O3), on random inputs
//! rich in NaN (with payloads), signed zeros, infinities and subnormals.

use crate::common;

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use scion_clif::JitModule;
use scion_compiler::passes::mem_to_lo::lower_module;
use scion_ir::backend::{Backend, JitCode};
use scion_ir::diag::FileId;
use scion_ir::entity::TypeId;
use scion_ir::interp::lo::LoInterp;
use scion_ir::interp::{AdtVal, Interp, Val};
use scion_ir::types::{FloatTy, IntTy, Type};
use scion_ir::Module;
use std::rc::Rc;

const USES: &str = r#"
func t_hit(ray: Ray, tri: Triangle) -> f32 = hit_distance(ray, tri)
func t_slab(ray: Ray, box: AABB) -> (f32, f32) = slab_interval(ray, box)
func t_box(ray: Ray, box: AABB) -> bool = intersects(ray, box)
func t_tri(ray: Ray, tri: Triangle) -> bool = intersects(ray, tri)
func t_cpb(p: f32x3, box: AABB) -> f32x3 = closest_point(p, box)
func t_cpt(p: f32x3, tri: Triangle) -> f32x3 = closest_point(p, tri)
func t_cpc(p: f32x3, tri: Triangle) -> (f32, f32x3) = {
  let c: f32x3 = closest_point(closest_point(p, tri), bounds(tri));
  return (length_squared(c - p), c);
}
func t_sat(a: Triangle, b: Triangle) -> bool = intersects(a, b)
func t_bb(a: AABB, b: AABB) -> bool = intersects(a, b)
func t_d2(p: f32x3, box: AABB) -> f32 = distance_squared(p, box)
func t_axis(v: f32x3, k: u32, x: f32) -> f32x3 = with_axis(v, k % 4, x)
func t_dir(a: f32x3, b: f32x3) -> (f32x3, f32x3, f32x3) =
  (fadd_rd(a, b), fsub_ru(a, b), fmul_rd(a, b) - fmul_ru(b, a))
func t_lanes(a: f32x3, x: f32) -> (f32, f32, f32, f32, f32, bool) =
  (hmin(a), hmax(a), hsum(a), rsqrt(x), trunc(x), isnan(x))
func t_bits(n: u32, k: i16, v: u8x4) -> (u32, u32, u32, i16, u8x4, u8) =
  (popcount(n), clz(n), ctz(n), ctz(k), clz(v), hmax(v))
// min/max of an arithmetic result against a constant neither NaN nor zero (the slab test's NaN
// clamps; LLVM's `llvm.minnum`/`llvm.maxnum`, docs/backends.md), exact whatever the NaN.
func t_clamp(a: f32x3, b: f32x3, x: f32) -> (f32x3, f32x3, f32) =
  (min(max(a * b, splat(-2.5)), splat(7.0)), max(min(a - b, splat(inf)), splat(-inf)),
   max(x / x, -1.0))
func keep_min(best: mut (f32, u32), t: f32, id: u32) = {
  if t < best[0] { best = (t, id); }
}
func t_mut(a: f32x3, k: u32) -> ((f32, u32), f32, u32) = {
  let mut best = (inf, 0xFFFFFFFF);
  keep_min(best, a.x, 0);
  keep_min(best, a.y, 1);
  keep_min(best, a.z, 2);
  let mut acc: f32 = 0.0;
  let mut n: u32 = k;
  if a.x > a.y { acc = a.x; n = n + 1; } elif a.z < 1.0 { acc = a.z; } else { acc = -a.y; }
  acc = max(acc, a.z) * 2.0;
  best[1] = best[1] + n;
  return (best, acc, n);
}
// Components assigned: an array element at a computed index (out of range: no change), at a
// literal one, a vector lane by name and by computed index, an element of a tuple in an
// array, a lane of a record's field, elements of a `mut` parameter.
func bump(best: mut (f32, u32), v: f32x3, k: u32) = {
  best[1] = best[1] + k;
  best[0] = v[k % 3];
}
func t_assign(a: f32x3, k: u32, x: f32) -> (f32x3, f32, f32, f32, f32x3, f32x3, (f32, u32)) = {
  let mut d: f32[4] = [a.x, a.y, a.z, x];
  d[k % 5] = x * 2.0;
  d[1] = d[1] + 1.0;
  let mut v: f32x3 = a;
  v.y = x;
  v[k % 3] = d[0];
  let mut p: (f32, f32)[2] = [(a.x, a.y), (a.z, x)];
  p[k % 2][1] = d[3];
  let mut b: AABB = AABB(a, v);
  b.high.z = p[1][1];
  b.low = scale(v, 2.0);
  let mut best = (x, 7);
  bump(best, a, k);
  return (v, d[0] + d[2], p[0][1], p[1][1], b.low, b.high, best);
}
// A value array at a computed index and the bits of several
// conditions: the LLVM backend translates them as one variable `extractelement` and the bits
// of one `<N x i1>` (docs/backends.md), the other engines as selects and an `or` of shifts.
func t_pick(a: f32x3, b: f32x3, k: u32) -> (f32, u32, f32, f32) = {
  let d: f32[8] = [a.x, a.y, a.z, b.x, b.y, b.z, a.x * b.y, -a.z];
  let ks: u32[5] = [k, k + 1, k * 3, 7 - k, k >> 1];
  return (d[k % 8], ks[k % 5], d[(k >> 3) % 8], d[7 - k % 8]);
}
func t_mask(a: f32x3, b: f32x3, x: f32) -> (u32, u32, u16, u64) = {
  let d: f32[8] = [a.x, a.y, a.z, b.x, b.y, b.z, a.x * b.y, -a.z];
  let m: u32 = ((d[0] < x) as u32) | (((d[1] < x) as u32) << 1) | (((d[2] < x) as u32) << 2)
             | (((d[3] < x) as u32) << 3) | (((d[4] < x) as u32) << 4)
             | (((d[5] < x) as u32) << 5) | (((d[6] < x) as u32) << 6) | (((d[7] < x) as u32) << 7);
  let m4: u16 = (((a.y < b.y) as u16) << 1) | ((a.x < b.x) as u16) | (((a.z < b.z) as u16) << 2)
              | ((isnan(x) as u16) << 3);
  let w: u64 = (((d[0] <= x) as u64) << 5) | (((d[1] <= x) as u64) << 1)
             | (((d[2] <= x) as u64) << 2) | ((d[3] <= x) as u64) | (((d[4] <= x) as u64) << 4)
             | (((d[5] <= x) as u64) << 3);
  return (m, popcount(m), m4, w);
}
// Four-lane operations (one vector instruction each in Cranelift and LLVM, lane groups):
// arithmetic, compares into masks, mask logic, selects, bitcasts, integer lanes.
func t_v4(a: f32x4, b: f32x4, c: u32x4, d: u32x4) -> (f32x4, f32x4, u32x4, u32x4) = {
  let m = (a < b) | (!(a == b) & (c > d));
  let s: f32x4 = select(m, a - b, a * b / (a + b));
  let t: u32x4 = ((a to u32x4) ^ (c + d)) & ~(c - d);
  return (s, -a, t, select(c >= d, c, d));
}
// The prelude's four-triangle test (`hit_lanes`, `hit_block`) on four random triangles.
func t_tri4(ray: Ray, x0: f32x4, y0: f32x4, z0: f32x4, x1: f32x4, y1: f32x4, z1: f32x4,
            x2: f32x4, y2: f32x4, z2: f32x4) -> (f32x4, (f32, u32)) = {
  let b: Triangle4 = Triangle4([x0[0], x0[1], x0[2], x0[3]], [y0[0], y0[1], y0[2], y0[3]],
                               [z0[0], z0[1], z0[2], z0[3]], [x1[0], x1[1], x1[2], x1[3]],
                               [y1[0], y1[1], y1[2], y1[3]], [z1[0], z1[1], z1[2], z1[3]],
                               [x2[0], x2[1], x2[2], x2[3]], [y2[0], y2[1], y2[2], y2[3]],
                               [z2[0], z2[1], z2[2], z2[3]], [7, 3, 5, 1]);
  return (hit_lanes(ray, b), hit_block(ray, b));
}
// Lane-wise min and max (one `minps`/`maxps` in Cranelift where no lane can be NaN, else per
// lane), a lane permutation (one shuffle), and the prelude's four-lane box test against the
// three-lane one it mirrors.
func t_v4mm(a: f32x4, b: f32x4) -> (f32x4, f32x4, f32x4, f32x4) = {
  let c: f32x4 = max(a * b, splat4(-inf));
  let d: f32x4 = min(b - a, splat4(inf));
  let e: f32x4 = f32x4(d.y, d.z, d.w, d.x);
  return (min(c, e), max(c, e), min(a, b), max(e, a));
}
func t_slab4(lo: f32x3, hi: f32x3, o: f32x3, dir: f32x3, tmin: f32) -> (f32, f32, f32, f32, f32) = {
  let r: SlabRay = slab_ray(Ray(o, dir, tmin, inf));
  let b: AABB = AABB(lo, hi);
  let s3: (f32, f32) = slab_span(r, b);
  let s4: (f32, f32) = slab_span(slab_lanes(r), b);
  return (s3[0], s3[1], s4[0], s4[1], distmin(slab_lanes(r), b, 1.5));
}
// Two boxes on eight lanes (`distmin_pair`) against the four-lane test of each.
func t_pair(lo: f32x3, hi: f32x3, lo2: f32x3, hi2: f32x3, o: f32x3, dir: f32x3, tmin: f32,
            tmax: f32) -> (f32, f32, f32, f32) = {
  let r: SlabLanes = slab_lanes(slab_ray(Ray(o, dir, tmin, inf)));
  let p: (f32, f32) = distmin_pair(slab_pair(r), AABB(lo, hi), AABB(lo2, hi2), tmax);
  return (distmin(r, AABB(lo, hi), tmax), distmin(r, AABB(lo2, hi2), tmax), p[0], p[1]);
}
func t_ifx(a: f32x3, k: u32) -> (f32, u32) = {
  let lo: f32 = if a.x <= a.y { a.x } elif isnan(a.y) { a.z } else { a.y };
  let which: u32 = if lo < a.z { if k > 500 { k - 500 } else { 0 } } else { 2 };
  return (if which == 2 { lo * a.z } else { lo + 1.0 }, which);
}
"#;

const FUNCS: &[&str] = &[
    "t_hit", "t_slab", "t_box", "t_tri", "t_cpb", "t_cpt", "t_cpc", "t_sat", "t_bb", "t_d2",
    "t_axis", "t_dir", "t_lanes", "t_bits", "t_mut", "t_ifx", "t_clamp", "t_assign", "t_pick",
    "t_mask", "t_v4", "t_tri4", "t_v4mm", "t_slab4", "t_pair",
];

/// The `tree` module of the prelude functions above.
fn tree_module() -> Module {
    common::tree_module_of(&[("uses.scion", USES)], true).unwrap_or_else(|e| panic!("{e}"))
}

/// A value of `ty` drawn from `src` (floats; integers from their bits).
fn make(m: &Module, ty: TypeId, src: &mut impl Iterator<Item = f32>) -> Val {
    match m.types.get(ty) {
        Type::Float(FloatTy::F32) => Val::F32(src.next().unwrap_or(0.0)),
        Type::Int(t) => Val::Int(
            t.wrap(i128::from(src.next().unwrap_or(0.0).to_bits() % 1000)),
            *t,
        ),
        Type::Vector { elem, lanes } => {
            Val::Vector((0..*lanes).map(|_| make(m, *elem, src)).collect())
        }
        Type::Tuple(es) => Val::Tuple(es.iter().map(|&e| make(m, e, src)).collect()),
        Type::Adt(name) => {
            let def = m.adt(name).expect("declared");
            Val::Adt(Rc::new(AdtVal {
                ty: name.clone(),
                variant: None,
                fields: def.shared.iter().map(|f| make(m, f.ty, src)).collect(),
            }))
        }
        other => panic!("no generator for {other:?}"),
    }
}

/// The arguments of function `name` of `tree` drawn from `floats` in order.
fn args_of(tree: &Module, name: &str, floats: &[f32]) -> Vec<Val> {
    let f = tree.func_by_name(name).expect("declared");
    let mut src = floats.iter().copied();
    tree.funcs[f]
        .params
        .iter()
        .map(|&p| make(tree, p, &mut src))
        .collect()
}

/// The scalar leaves of a value, in `mem-to-lo`'s order.
fn flatten(v: &Val, out: &mut Vec<Val>) {
    match v {
        Val::Vector(l) | Val::Tuple(l) => l.iter().for_each(|x| flatten(x, out)),
        Val::Adt(a) => a.fields.iter().for_each(|x| flatten(x, out)),
        other => out.push(other.clone()),
    }
}

fn keys(vs: &[Val]) -> Vec<(u8, u64)> {
    vs.iter().map(Val::bits_key).collect()
}

/// Every code generator under test, with its name: Cranelift and LLVM at -O0 and -O3.
fn backends() -> Vec<Box<dyn Backend>> {
    vec![
        Box::new(scion_clif::Cranelift),
        Box::new(scion_llvm::Llvm { opt_level: 0 }),
        Box::new(scion_llvm::Llvm { opt_level: 3 }),
    ]
}

/// `m` compiled by every backend of [`backends`].
fn compiled(m: &Module) -> Vec<(String, Box<dyn JitCode>)> {
    backends()
        .iter()
        .map(|b| {
            (
                b.name(),
                b.jit(m).unwrap_or_else(|e| panic!("{}: {e}", b.name())),
            )
        })
        .collect()
}

fn check_all(
    tree: &Module,
    lo: &Module,
    engines: &[(String, Box<dyn JitCode>)],
    floats: &[f32],
) -> Result<(), String> {
    check_funcs(tree, lo, engines, floats, FUNCS)
}

/// [`check_all`] for the functions `names`.
fn check_funcs(
    tree: &Module,
    lo: &Module,
    engines: &[(String, Box<dyn JitCode>)],
    floats: &[f32],
    names: &[&str],
) -> Result<(), String> {
    for &name in names {
        let f = tree.func_by_name(name).ok_or("missing function")?;
        let mut src = floats.iter().copied().cycle();
        let args: Vec<Val> = tree.funcs[f]
            .params
            .iter()
            .map(|&p| make(tree, p, &mut src))
            .collect();
        let mut flat = Vec::new();
        args.iter().for_each(|a| flatten(a, &mut flat));
        let want = Interp::new(tree)
            .call(name, args.clone())
            .map_err(|e| format!("{name}: tree interpreter: {e}"))?;
        let mut want_flat = Vec::new();
        want.iter().for_each(|v| flatten(v, &mut want_flat));
        // The four-lane box test gives the three-lane one's (enter, far) bit for bit.
        if name == "t_slab4" && keys(&want_flat[0..2]) != keys(&want_flat[2..4]) {
            return Err(format!(
                "t_slab4({flat:?}): slab_span of SlabRay {:?}, of SlabLanes {:?}",
                &want_flat[0..2],
                &want_flat[2..4]
            ));
        }
        // The eight-lane test of two boxes gives each box's four-lane `distmin` bit for bit.
        if name == "t_pair" && keys(&want_flat[0..2]) != keys(&want_flat[2..4]) {
            return Err(format!(
                "t_pair({flat:?}): distmin of SlabLanes {:?}, distmin_pair {:?}",
                &want_flat[0..2],
                &want_flat[2..4]
            ));
        }
        let lo_out = LoInterp::new(lo)
            .call(name, flat.clone())
            .map_err(|e| format!("{name}: lo interpreter: {e}"))?;
        if keys(&want_flat) != keys(&lo_out) {
            return Err(format!(
                "{name}({flat:?}): tree {want_flat:?} but lo interpreter {lo_out:?}"
            ));
        }
        for (engine, code) in engines {
            let out = code
                .call(name, &flat)
                .map_err(|e| format!("{name}: {engine}: {e}"))?;
            if keys(&want_flat) != keys(&out) {
                return Err(format!(
                    "{name}({:x?}): tree {:x?} but {engine} {:x?}",
                    keys(&flat),
                    keys(&want_flat),
                    keys(&out)
                ));
            }
        }
    }
    Ok(())
}

#[test]
fn prelude_functions_agree_in_tree_lo_cranelift_and_llvm() {
    let tree = tree_module();
    let (lo, skipped) = lower_module(&tree, false).expect("lowers");
    assert!(skipped.is_empty());
    scion_ir::verify(&lo).expect("lo verifies");
    // The JIT runs the module after lo-inline (the slab test inlined into its callers).
    let mut inlined = lo.clone();
    scion_compiler::passes::lo::inline::run(&mut inlined, 48);
    scion_ir::verify(&inlined).expect("inlined lo verifies");
    let engines = compiled(&inlined);
    let cases = common::cases(if cfg!(debug_assertions) { 300 } else { 3000 });
    let mut runner = TestRunner::new(Config {
        cases,
        ..Config::default()
    });
    let result = runner.run(
        &prop::collection::vec(common::special_f32(), 24),
        |floats| check_all(&tree, &lo, &engines, &floats).map_err(TestCaseError::fail),
    );
    if let Err(e) = result {
        panic!("{e}");
    }
}

#[test]
fn a_real_hit_is_found_by_every_engine() {
    let tree = tree_module();
    let (lo, _) = lower_module(&tree, false).expect("lowers");
    let jit = JitModule::compile(&lo).expect("compiles");
    // Ray from (0.25, 0.25, -1) along +z through the triangle (0,0,0) (1,0,0) (0,1,0).
    let floats = [
        0.25,
        0.25,
        -1.0,
        0.0,
        0.0,
        1.0,
        0.0,
        f32::INFINITY, // ray
        0.0,
        0.0,
        0.0,
        1.0,
        0.0,
        0.0,
        0.0,
        1.0,
        0.0,
        0.0, // triangle (id from 0.0's bits)
    ];
    let args = args_of(&tree, "t_hit", &floats);
    let mut flat = Vec::new();
    args.iter().for_each(|a| flatten(a, &mut flat));
    let out = jit.call("t_hit", &flat).unwrap();
    assert!(matches!(out[0], Val::F32(t) if t == 1.0), "{out:?}");
    check_all(&tree, &lo, &compiled(&lo), &floats).unwrap();
}

/// Integer intrinsics and conversions on every width: bit counts, shifts, division (including
/// `MIN / -1`), casts between integers and floats (saturating, NaN to 0), bits fields.
#[test]
fn integer_ops_agree_on_every_width() {
    let mut text = String::new();
    for t in ["u8", "i8", "u16", "i16", "u32", "i32", "u64", "i64"] {
        text.push_str(&format!(
            r#"
func @ints_{t}(%a: {t}, %b: {t}, %f: f32) -> ({t}, {t}, {t}, {t}, {t}, {t}, {t}, {t}, f64, {t}) {{
  %p = "tree.intrinsic"(%a) {{name = "popcount"}} : ({t}) -> {t}
  %l = "tree.intrinsic"(%a) {{name = "clz"}} : ({t}) -> {t}
  %z = "tree.intrinsic"(%b) {{name = "ctz"}} : ({t}) -> {t}
  %s = "tree.shr"(%a, %b) : ({t}, {t}) -> {t}
  %h = "tree.shl"(%a, %b) : ({t}, {t}) -> {t}
  %one = "tree.const"() {{value = 1}} : () -> {t}
  %b1 = "tree.or"(%b, %one) : ({t}, {t}) -> {t}
  %d = "tree.div"(%a, %b1) : ({t}, {t}) -> {t}
  %r = "tree.rem"(%a, %b1) : ({t}, {t}) -> {t}
  %c = "tree.cast"(%f) : (f32) -> {t}
  %w = "tree.cast"(%a) : ({t}) -> f64
  %x = "tree.bits"(%a) {{hi = 7, lo = 2}} : ({t}) -> {t}
  "tree.return"(%p, %l, %z, %s, %h, %d, %r, %c, %w, %x) : ({t}, {t}, {t}, {t}, {t}, {t}, {t}, {t}, f64, {t}) -> ()
}}
"#
        ));
    }
    let tree = scion_ir::parse_module(&text, FileId(0)).expect("parses");
    scion_ir::verify(&tree).expect("verifies");
    let (lo, _) = lower_module(&tree, false).expect("lowers");
    let jit = JitModule::compile(&lo).expect("compiles");
    let mut rng = 0x1234_5678_9abc_def0u64;
    let mut next = || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        rng
    };
    let floats = [
        0.0f32,
        -0.0,
        1.5,
        -1.5,
        300.7,
        -40000.0,
        3e9,
        -3e19,
        f32::NAN,
        f32::INFINITY,
    ];
    for t in IntTy::ALL {
        let name = format!("ints_{}", t.name());
        for k in 0..300 {
            let (lo_v, hi_v) = t.range();
            let pick = |r: u64| match r % 5 {
                0 => lo_v,
                1 => hi_v,
                2 => -1i128,
                _ => r as i128,
            };
            let a = Val::Int(t.wrap(pick(next())), t);
            let b = Val::Int(t.wrap(pick(next())), t);
            let f = Val::F32(floats[k % floats.len()]);
            let args = vec![a, b, f];
            let want = Interp::new(&tree).call(&name, args.clone()).expect("tree");
            let got_lo = LoInterp::new(&lo).call(&name, args.clone()).expect("lo");
            let got_jit = jit.call(&name, &args).expect("jit");
            assert_eq!(keys(&want), keys(&got_lo), "{name}{args:?}: lo");
            assert_eq!(keys(&want), keys(&got_jit), "{name}{args:?}: jit");
        }
    }
}

/// The JITs (Cranelift, LLVM at -O0 and -O3) canonicalize an arithmetic NaN only where its
/// bits can be observed (`scion_ir::lo::nan`; lit-tests/clif/nan-canonical.lo shows where); the
/// lo interpreter canonicalizes after every op. On NaN payloads of both signs, quiet and signalling, every result bit agrees: the
/// payload-blind chains and each kind of observing use (return, neg, min, bitcast, select,
/// cast, call, branch argument).
#[test]
fn nan_canonicalization_only_where_observable_keeps_every_bit() {
    let text = include_str!("../../lit-tests/clif/nan-canonical.lo");
    let lo = scion_ir::parse_module(text, FileId(0)).expect("parses");
    scion_ir::verify(&lo).expect("verifies");
    let jit = JitModule::compile(&lo).expect("compiles");
    let llvm0 = scion_llvm::JitModule::compile(&lo, 0).expect("LLVM -O0 compiles");
    let llvm3 = scion_llvm::JitModule::compile(&lo, 3).expect("LLVM -O3 compiles");
    let specials = [
        0.0f32,
        -0.0,
        1.5,
        -3.0,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        -f32::NAN,
        f32::from_bits(0x7fa0_1234),
        f32::from_bits(0xffc0_0001),
        f32::from_bits(0x7f80_0001),
        f32::from_bits(1),
    ];
    let mut nan_results = 0;
    for &a in &specials {
        for &b in &specials {
            for &c in &specials {
                let args = [Val::F32(a), Val::F32(b), Val::F32(c)];
                for name in ["blind", "observed"] {
                    let want = LoInterp::new(&lo)
                        .call(name, args.to_vec())
                        .unwrap_or_else(|e| panic!("{name}: lo interpreter: {e}"));
                    let engines = [
                        (
                            "Cranelift",
                            jit.call(name, &args).map_err(|e| e.to_string()),
                        ),
                        (
                            "LLVM -O0",
                            llvm0.call(name, &args).map_err(|e| e.to_string()),
                        ),
                        (
                            "LLVM -O3",
                            llvm3.call(name, &args).map_err(|e| e.to_string()),
                        ),
                    ];
                    for (engine, got) in engines {
                        let got = got.unwrap_or_else(|e| panic!("{name}: {engine}: {e}"));
                        assert_eq!(
                            keys(&want),
                            keys(&got),
                            "{name}({a:?}, {b:?}, {c:?}): lo interpreter {want:?}, {engine} {got:?}"
                        );
                    }
                    nan_results += want
                        .iter()
                        .filter(|v| matches!(v, Val::F32(x) if x.is_nan()))
                        .count();
                }
            }
        }
    }
    assert!(
        nan_results > 1000,
        "too few NaN results compared: {nan_results}"
    );
}

/// A wide traversal never enters an empty slot: the prelude's `slot_distmin` (used by
/// closest_hit8.scion and the hair BVH's traversals) returns +inf for an inverted box
/// (`Aabb::EMPTY`, or the finite inverted box a quantized layout decodes from the codes 255
/// and 0), which the slab test alone would take for the whole of space, and the entry distance
/// for a box the ray meets; the same in every engine.
#[test]
fn an_empty_slot_is_never_entered() {
    let uses = "func t_enter(o: f32x3, d: f32x3, lo: f32x3, hi: f32x3) -> f32 =\n  \
                slot_distmin(slab_ray(Ray(o, d, 0.0, inf)), AABB(lo, hi), inf)\n";
    let tree =
        common::tree_module_of(&[("uses.scion", uses)], true).unwrap_or_else(|e| panic!("{e}"));
    let (lo, _) = lower_module(&tree, false).expect("lowers");
    let engines = compiled(&lo);
    let inf = f32::INFINITY;
    let dirs = [
        [1.0, 0.5, -0.25],
        [-1.0, 0.0, 0.0],
        [0.0, -0.0, 1.0],
        [-0.3, -0.7, 0.2],
    ];
    let boxes = [
        ([inf, inf, inf], [-inf, -inf, -inf], None),
        ([4.0, -1.0, -1.0], [-4.0, 1.0, 1.0], None),
        ([9.0, -9.0, -9.0], [-9.0, 9.0, 9.0], None),
        ([-1.0, -1.0, -1.0], [1.0, 1.0, 1.0], Some(0.0f32)),
    ];
    for d in dirs {
        for (lo_c, hi_c, want) in boxes {
            let floats: Vec<f32> = [[0.0, 0.0, 0.0], d, lo_c, hi_c].concat();
            let args = args_of(&tree, "t_enter", &floats);
            let got = Interp::new(&tree).call("t_enter", args).expect("tree");
            let want = want.unwrap_or(inf);
            assert!(
                matches!(got[0], Val::F32(t) if t == want),
                "{d:?} {lo_c:?} {hi_c:?}: {got:?}"
            );
            check_funcs(&tree, &lo, &engines, &floats, &["t_enter"]).unwrap();
        }
    }
}
