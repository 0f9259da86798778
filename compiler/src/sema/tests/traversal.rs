//! The traversal language: resolution, inference, operators, overloads, match, `mut`.

use super::{check, err, ok};
use crate::sema::{Prim, Resolution, Ty};
use crate::syntax::ast::{ExprKind, Item, StmtKind};

fn func_ret(typed: &crate::sema::TypedProgram, name: &str) -> Ty {
    typed
        .funcs
        .iter()
        .find(|f| f.name == name)
        .map(|f| f.ret.clone())
        .expect("function")
}

#[test]
fn literals_default_to_i32_and_f32() {
    let t = ok("func a() = 1\nfunc b() = 1.5\nfunc c() -> u8 = 200");
    assert_eq!(func_ret(&t, "a"), Ty::Prim(Prim::I32));
    assert_eq!(func_ret(&t, "b"), Ty::Prim(Prim::F32));
    assert_eq!(func_ret(&t, "c"), Ty::Prim(Prim::U8));
}

#[test]
fn literal_out_of_range_is_e0229() {
    err("func c() -> u8 = 256", "E0229");
    ok("func c() -> u32 = 0xFFFFFFFF");
}

#[test]
fn int_literal_cannot_be_float() {
    err("func c() -> f32 = 1", "E0206");
    err("func c() -> i32 = 1.0", "E0206");
}

#[test]
fn result_type_is_inferred_through_recursion() {
    let t = ok(
        "func f(n: u32) = { if n == 0 { return 1; } return g(n - 1); }\nfunc g(n: u32) = f(n) * 2",
    );
    assert_eq!(func_ret(&t, "f"), Ty::Prim(Prim::I32));
    assert_eq!(func_ret(&t, "g"), Ty::Prim(Prim::I32));
}

#[test]
fn unknown_name_and_type() {
    let text = err("func f() -> f32 = y", "E0201");
    assert!(text.contains("unknown name `y`"), "{text}");
    err("func f(x: Foo) = 1", "E0202");
    err("func f() = foo(1)", "E0204");
}

#[test]
fn duplicate_definitions() {
    err("type A(x: f32);\ntype A(y: f32);", "E0203");
    err("type A(x: f32, x: f32);", "E0203");
    err("func f(x: f32, x: f32) = x", "E0203");
    err("func f(x: f32) = x\nfunc f(y: f32) = y", "E0210");
    err("type B(x: f32) = V(a: f32) | V(b: f32);", "E0203");
}

#[test]
fn let_types_checked_and_optional() {
    ok("func f(x: f32) -> f32 = { let y = x * 2.0; let z: f32 = y; return z; }");
    err(
        "func f(x: f32) -> f32 = { let y: u32 = x; return 1.0; }",
        "E0206",
    );
}

#[test]
fn arithmetic_needs_one_type() {
    ok("func f(a: f32x3, b: f32x3) -> f32x3 = a * b + a");
    err("func f(a: f32, b: f64) = a + b", "E0206");
    err("func f(a: bool, b: bool) = a + b", "E0217");
    err("func f(a: f32x3, b: f32x4) = a + b", "E0206");
}

#[test]
fn narrower_integers_widen() {
    let src = "func f(a: u32, b: u16) -> u32 = a + b";
    let (program, typed, diags, _) = check(src);
    assert!(diags.is_empty());
    let Item::Func(f) = &program.items[0] else {
        panic!()
    };
    let StmtKind::Expr(e) = &f.body.kind else {
        panic!()
    };
    let ExprKind::Binary { rhs, .. } = &e.kind else {
        panic!()
    };
    assert_eq!(typed.widenings.get(&rhs.id), Some(&Ty::Prim(Prim::U32)));
    err("func f(a: u32, b: i16) = a + b", "E0206");
}

#[test]
fn comparisons_logic_bits_and_shifts() {
    ok("func f(a: f32, b: f32) -> bool = a < b && !(a == b) || a >= b");
    ok("func f(a: u32) -> u32 = (a << 28) | (a >> 2) & ~a ^ 1");
    err("func f(a: f32) = a << 1", "E0217");
    err("func f(a: f32) = a & a", "E0217");
    err("func f(a: u32) = a && true", "E0217");
    err("func f(a: u32) = !a", "E0217");
    err("func f(a: bool) = -a", "E0217");
    err("func f(a: u32) = -a", "E0217");
    ok("func f(a: i32) -> i8 = -128");
}

#[test]
fn casts_and_bitcasts() {
    ok("func f(a: u16x3) -> f32x3 = a as f32x3");
    ok("func f(a: u32) -> f32 = a as f32");
    ok("func f(a: u32) -> f32 = a to f32");
    ok("func f(a: u32) -> f32 = f32(a)");
    err("func f(a: u16x3) = a as f32x4", "E0218");
    err("func f(a: AABB) = a as f32", "E0218");
    err("func f(a: u16) = a to f32", "E0219");
}

#[test]
fn fields_components_tuples() {
    ok("func f(r: Ray) -> f32 = r.origin.x + r.direction.z + r.tmax");
    ok("func f(t: (f32, u32)) -> u32 = t[1]");
    err("func f(r: Ray) = r.nope", "E0216");
    err("func f(v: f32x3) = v.w", "E0216");
    err("func f(t: (f32, u32), i: u32) = t[i]", "E0224");
    err("func f(t: (f32, u32)) = t[2]", "E0225");
    err("func f(a: f32) = a[0]", "E0226");
    ok("func f(v: f32x3, a: u32[4]) -> f32 = v[2] + a[3] as f32");
    err("func f(v: f32x3) = v[3]", "E0238");
    err("func f(a: u32[4]) = a[4]", "E0238");
}

#[test]
fn arrays_slices_and_bits() {
    ok("func f(a: Triangle[8], i: u32) -> Triangle = a[i]");
    ok("func f(a: u32[8]) -> u32 = { let s = a[2:4]; return s[0]; }");
    ok("func f(w: u32) -> u32 = w[0:28] + w[28:32]");
    err("func f(a: f32) = a[0:2]", "E0227");
    err("func f(a: u32[8], x: f32) = a[x]", "E0217");
}

#[test]
fn foreach_over_arrays() {
    ok("func f(a: u32[4]) -> u32 = { let s: u32 = 0; foreach x in a { let y: u32 = x; } return s; }");
    err("func f(a: u32) = { foreach x in a { } }", "E0228");
}

#[test]
fn constructors_records_variants_vectors() {
    ok("func f(o: f32x3) -> Ray = Ray(o, o)");
    ok("func f(o: f32x3) -> Ray = Ray(o, o, 0.0, 1.0)");
    ok("func f(b: AABB, n: u16, d: Triangle[n]) -> BVH = Leaf(b, n, d)");
    ok("func f(b: AABB, l: BVH) -> BVH = Interior(b, l, l)");
    err(
        "func f(b: AABB, l: BVH) -> BVH = Interior(b, l, 1)",
        "E0206",
    );
    err("func f(o: f32x3) = Ray(o)", "E0205");
    err("func f() = f32x3(1.0, 2.0)", "E0205");
    err("func f() = f32x3(1, 2.0, 3.0)", "E0206");
    err("func f(b: AABB) = BVH(b)", "E0230");
}

#[test]
fn builtins() {
    ok("func f(a: f32x3, b: f32x3) -> f32 = dot(cross(a, b), a) + length(a) + sqrt(2.0)");
    ok("func f(a: u32, b: u32) -> u32 = min(a, max(b, 3))");
    ok("func f(a: f32x3) -> f32x3 = fma(a, a, floor(a)) + with_axis(a, 1, 2.0)");
    err("func f(a: f32) = dot(a, a)", "E0231");
    err("func f(a: bool) = min(a, a)", "E0231");
    err("func f(a: f32x4) = cross(a, a)", "E0231");
    err("func f(a: f32) = sqrt(a, a)", "E0205");
    ok("func f(s: mut set[(u32, u32)], a: u32) = insert(s, (a, 1))");
    err("func f(s: set[u32]) = insert(s, 1)", "E0223");
    err("func f(s: mut u32[4]) = insert(s, 1)", "E0231");
    err("func f(s: mut set[u32]) = insert(s, 1.0)", "E0206");
    ok("func f(a: u32[4]) -> u32 = len(a)");
    ok("func f(lo: f32x3, hi: f32x3) -> u16x3 = { let o = frame_origin(lo); let s = frame_step(o, hi, 65535); return quant_lo(lo, o, s, 65535) as u16x3; }");
    err("func f(lo: f32x3) = frame_step(lo, lo, 1.0)", "E0231");
    err("func f(lo: f32x3) = quant_hi(lo, lo, lo)", "E0205");
    // The quantization builtins are defined on f32 lanes only (scion_ir::tree::quant).
    err("func f(lo: f64x3) -> f64x3 = frame_origin(lo)", "E0231");
    err(
        "func f(v: f64x3) -> u32x3 = quant_lo(v, v, v, 65535)",
        "E0231",
    );
    // Directed rounding is exact on f32 (scion_ir::tree::directed); a float literal becomes f32.
    ok("func f(a: f32, b: f32x2) -> f32 = fadd_ru(a, 1.5) + fmul_rd(b, b).x + fsub_ru(a, a)");
    ok("func f() -> f32 = fadd_rd(0.1, 0.2)");
    err("func f(a: f64) -> f64 = fadd_ru(a, a)", "E0231");
    err("func f(a: f64x3) -> f64x3 = fmul_rd(a, a)", "E0231");
    err("func f() -> f32 = fadd_ru(1, 2)", "E0231");
}

#[test]
fn overloads_resolve_by_argument_types() {
    let src = "func g(r: Ray, b: AABB, t: Triangle) -> bool = intersects(r, b) && intersects(r, t)";
    let (program, typed, diags, sm) = super::check_with_prelude(src);
    assert!(diags.is_empty(), "{}", diags.render(&sm));
    let Some(Item::Func(f)) = program.items.last() else {
        panic!()
    };
    let StmtKind::Expr(e) = &f.body.kind else {
        panic!()
    };
    let ExprKind::Binary { lhs, rhs, .. } = &e.kind else {
        panic!()
    };
    let (Some(Resolution::Func(a)), Some(Resolution::Func(b))) =
        (typed.resolution(lhs.id), typed.resolution(rhs.id))
    else {
        panic!()
    };
    assert_ne!(a, b);
    assert_eq!(
        typed.func(*a).params[1].ty,
        Ty::Adt(typed.adts.by_name("AABB").unwrap())
    );
    assert_ne!(typed.func(*a).unique_name, typed.func(*b).unique_name);
}

#[test]
fn overload_errors() {
    let text = err("func g(r: Ray) = intersects(r, 1.0)", "E0207");
    assert!(text.contains("intersects(Ray, AABB)"), "{text}");
    let text = err(
        "func h(a: u32) = 1\nfunc h(a: u64) = 2\nfunc g() = h(5)",
        "E0207",
    );
    assert!(text.contains("candidates"), "{text}");
    err(
        "func h(a: u8, b: u32) = 1\nfunc h(a: u8, b: u64) = 2\nfunc g(x: u8) = h(x, x)",
        "E0207",
    );
}

#[test]
fn overload_defers_until_arguments_are_known() {
    ok("func h(a: u32) -> u32 = a\nfunc h(a: f32) -> f32 = a\nfunc g(x: f32) -> f32 = { let y = h(x); return h(y); }");
    // The expected result type decides between candidates that take the same arguments.
    ok("func h(a: u32) -> u32 = a\nfunc h(a: u32, b: u32 = 0) -> f32 = 1.0\nfunc g(x: u32) -> f32 = h(x)");
    err("func h(a: u32) -> u32 = a\nfunc h(a: u32, b: u32 = 0) -> u32 = b\nfunc g(x: u32) -> u32 = h(x)", "E0208");
    // Literals default before the last round: `h(1)` picks the i32 candidate.
    ok("func h(a: i32) -> i32 = a\nfunc h(a: f32) -> f32 = a\nfunc g() -> i32 = h(1)");
    err(
        "func h(a: u32) = a\nfunc h(a: u64) = a\nfunc h(a: u16) = a\nfunc g(x: u8) = h(x)",
        "E0207",
    );
}

#[test]
fn ambiguous_overload_is_e0208() {
    let text = err(
        "type P(x: f32) = A(a: f32) | B(b: f32);\ntype Q(y: f32) = A(a: f32) | C(c: f32);\nfunc g() = A(1.0, 2.0)",
        "E0208",
    );
    assert!(text.contains("P.A") && text.contains("Q.A"), "{text}");
}

#[test]
fn match_patterns_and_exhaustiveness() {
    ok("func f(b: BVH) -> u32 = match b { | Interior(x, l, r) -> 0 | Leaf(x, n, d) -> n as u32 }");
    ok("func f(b: BVH) -> u32 = match b { | Leaf(_, n, _) -> n as u32 | _ -> 0 }");
    ok("func f(b: BVH) -> u32 = match b { | Leaf -> 1 | Interior -> 0 }");
    let text = err(
        "func f(b: BVH) -> u32 = match b { | Leaf(x, n, d) -> 0 }",
        "E0214",
    );
    assert!(text.contains("`Interior`"), "{text}");
    err(
        "func f(b: BVH) -> u32 = match b { | Leaf(x, n) -> 0 | _ -> 1 }",
        "E0212",
    );
    err(
        "func f(b: BVH) -> u32 = match b { | Nope(x) -> 0 | _ -> 1 }",
        "E0211",
    );
    err(
        "func f(b: Ray) -> u32 = match b { | Leaf(x, n, d) -> 0 | _ -> 1 }",
        "E0213",
    );
    err(
        "func f(b: BVH) -> u32 = match b { | _ -> 1 | Leaf(x, n, d) -> 0 }",
        "E0215",
    );
    err(
        "func f(b: BVH) -> u32 = match b { | Leaf(x: f32, n, d) -> 0 | _ -> 1 }",
        "E0206",
    );
}

#[test]
fn pattern_bindings_have_field_types() {
    let t = ok("func f(b: BVH) -> u16 = match b { | Leaf(x, n, d) -> n | Interior(x, l, r) -> 0 }");
    // The function's own bindings come after the prelude's.
    let n = t.bindings.iter().rev().find(|b| b.name == "n").unwrap();
    assert_eq!(n.ty, Ty::Prim(Prim::U16));
    let d = t.bindings.iter().rev().find(|b| b.name == "d").unwrap();
    assert!(matches!(d.ty, Ty::Slice(_)));
}

#[test]
fn mut_parameters() {
    ok("func f(b: mut (f32, u32)) = { b = (1.0, 2); b[0] = 3.0; }");
    ok("func g(b: mut u32) = { b = b + 1; }\nfunc f(b: mut u32) = g(b)");
    err("func f(b: u32) = { b = 1; }", "E0221");
    err("func f(b: u32) = { let c: u32 = 1; c = 2; }", "E0221");
    err("func f() = { this[0:2] = 1; }", "E0222");
    err(
        "func g(b: mut u32) = { b = 1; }\nfunc f(b: u32) = g(b)",
        "E0223",
    );
}

#[test]
fn implicit_result_and_missing_value() {
    ok("func f(c: bool) -> u32 = if c { 1 } else { 2 }");
    ok("func f(c: bool) -> u32 = { if c { return 1; } else { return 2; } }");
    err("func f(c: bool) -> u32 = { if c { return 1; } }", "E0220");
    err("func f(c: bool) -> u32 = { let x: u32 = 1; }", "E0220");
    err("func f(c: bool) -> u32 = if c { 1 } else { 2.0 }", "E0206");
    err("func f() -> u32 = { return; }", "E0236");
}

#[test]
fn defaults_are_typed() {
    ok("func f(a: u32, b: u32 = 4) -> u32 = a + b\nfunc g() -> u32 = f(1)");
    err("func f(a: u32, b: u32 = 4.0) -> u32 = a + b", "E0206");
    err("type R(a: u32 = 1.5);", "E0206");
}

#[test]
fn dependent_array_length_must_be_a_field() {
    err("type R(n: u32, d: f32[m]);", "E0233");
    ok("type R(n: u32, d: f32[n]);");
}

#[test]
fn records_may_not_contain_themselves() {
    err("type R(x: u32, next: R);", "E0237");
    err("type R(x: S);\ntype S(y: (u32, R[2]));", "E0237");
    ok("type R(n: u32, rest: R[n]);");
    ok("type T(x: u32) = Node(l: T, r: T) | Tip;");
}

#[test]
fn context_only_expressions() {
    err("func f() = this", "E0232");
    err("func f() = parent.x", "E0232");
    err("func f() = { build x; }", "E0232");
}

#[test]
fn variant_value_without_fields() {
    ok("type E = A | B;\nfunc f() -> E = A");
    // Two types with a variant `A`: the expected type decides.
    ok("type E = A | B;\ntype F = A | C;\nfunc f() -> E = A\nfunc g() -> F = { let x: F = A; return x; }");
    err("type E = A | B;\ntype F = A | C;\nfunc f() = A", "E0208");
    err("func f() = Leaf", "E0234");
}

#[test]
fn uninferable_types_are_errors() {
    err("func f() = f()", "E0209");
    err("func f() = f().x", "E0209");
    err("func f() = (f(), 1)", "E0235");
}

#[test]
fn no_inference_variables_remain() {
    let t = ok("func f(x: u32) = { let a = 1; let b = 2.0; let c = (a, b); return c; }");
    assert!(t.expr_types.values().all(|t| !t.has_vars()));
    assert!(t.bindings.iter().all(|b| !b.ty.has_vars()));
}
