//! One test per construct of the three languages: the source is parsed (no diagnostics
//! allowed) and shown back, expressions as fully parenthesized S-expressions so that
//! precedence and associativity are visible, items through the canonical printer.

use crate::common;

use common::parse_str;
use expect_test::{expect, Expect};
use scion_compiler::syntax::ast::*;
use scion_compiler::syntax::print::{print_program, print_type};

/// Parses `src` (which must be clean) and returns the program.
fn parse_ok(src: &str) -> Program {
    let (program, diags, sources) = parse_str("test.scion", src);
    assert!(diags.is_empty(), "{}", diags.render(&sources));
    program
}

/// The canonical printing of `src`; the printed text must parse back to the same tree.
fn check_print(src: &str, expected: Expect) {
    let program = parse_ok(src);
    let printed = print_program(&program);
    let again = parse_ok(&printed);
    assert_eq!(
        common::strip_positions(&format!("{:?}", program.items)),
        common::strip_positions(&format!("{:?}", again.items)),
        "{printed}"
    );
    expected.assert_eq(&printed);
}

/// `func f() = <expr>`, shown as an S-expression.
fn check_expr(src: &str, expected: Expect) {
    let program = parse_ok(&format!("func f() = {src};"));
    let Item::Func(f) = &program.items[0] else {
        panic!("not a func")
    };
    let StmtKind::Expr(e) = &f.body.kind else {
        panic!("not an expression body: {:?}", f.body)
    };
    expected.assert_eq(&sexpr(e));
}

fn sexpr(e: &Expr) -> String {
    let list = |xs: &[Expr]| {
        xs.iter()
            .map(|x| format!(" {}", sexpr(x)))
            .collect::<String>()
    };
    match &e.kind {
        ExprKind::Name(n) => n.name.clone(),
        ExprKind::Int(v) => v.to_string(),
        ExprKind::Float(v) => format!("{v:?}"),
        ExprKind::Bool(b) => b.to_string(),
        ExprKind::Call { callee, args } => format!("(call {}{})", callee.name, list(args)),
        ExprKind::Field { base, name } => format!("(. {} {})", sexpr(base), name.name),
        ExprKind::Index { base, index } => format!("(index {} {})", sexpr(base), sexpr(index)),
        ExprKind::Slice { base, lo, hi } => {
            format!("(slice {} {} {})", sexpr(base), sexpr(lo), sexpr(hi))
        }
        ExprKind::Tuple(xs) => format!("(tuple{})", list(xs)),
        ExprKind::Array(xs) => format!("(array{})", list(xs)),
        ExprKind::Unary { op, operand } => format!("({op:?} {})", sexpr(operand)),
        ExprKind::Binary { op, lhs, rhs } => {
            format!("({} {} {})", op.as_str(), sexpr(lhs), sexpr(rhs))
        }
        ExprKind::Cast { expr, ty } => format!("(as {} {})", sexpr(expr), print_type(ty)),
        ExprKind::BitCast { expr, ty } => format!("(to {} {})", sexpr(expr), print_type(ty)),
        ExprKind::This => "this".to_string(),
        ExprKind::Parent(n) => format!("(parent {})", n.name),
        ExprKind::Build(n) => format!("(build {})", n.name),
        ExprKind::If {
            branches,
            otherwise,
        } => {
            let arms: String = branches
                .iter()
                .map(|(c, b)| format!(" {} {}", sexpr(c), tail_sexpr(b)))
                .collect();
            format!("(if{arms} else {})", tail_sexpr(otherwise))
        }
    }
}

/// A branch block by its tail expression (`{...}` when it has none).
fn tail_sexpr(s: &Stmt) -> String {
    match &s.kind {
        StmtKind::Block(b) => b.last().map_or("{}".to_string(), tail_sexpr),
        StmtKind::Expr(e) => sexpr(e),
        _ => "{...}".to_string(),
    }
}

// --- Expressions ----------------------------------------------------------------------------

#[test]
fn literals() {
    check_expr(
        "(42, 0x1F, 0b101, 1_000_000, 1.0, 1e-3, 2.5e+8, inf, true, false)",
        expect!["(tuple 42 31 5 1000000 1.0 0.001 250000000.0 inf true false)"],
    );
}

#[test]
fn precedence_loosest_to_tightest() {
    check_expr(
        "a || b && c == d | e ^ f & g << h + i * j",
        expect!["(|| a (&& b (== c (| d (^ e (& f (<< g (+ h (* i j)))))))))"],
    );
    check_expr(
        "a * b + c << d & e ^ f | g != h && i || j",
        expect!["(|| (&& (!= (| (^ (& (<< (+ (* a b) c) d) e) f) g) h) i) j)"],
    );
}

#[test]
fn if_expressions_are_primaries() {
    check_expr(
        "a + if c { b } elif d { let x = 1; x } else { e } * 2",
        expect!["(+ a (* (if c b d x else e) 2))"],
    );
    check_expr(
        "f(if c { (1, 2) } else { g(if d { 3 } else { 4 }) })",
        expect!["(call f (if c (tuple 1 2) else (call g (if d 3 else 4))))"],
    );
}

#[test]
fn left_associativity() {
    check_expr("a - b - c", expect!["(- (- a b) c)"]);
    check_expr("a / b * c % d", expect!["(% (* (/ a b) c) d)"]);
    check_expr("a || b || c", expect!["(|| (|| a b) c)"]);
}

#[test]
fn prefix_and_postfix() {
    check_expr(
        "-a.b[0] as f32 * !c to u32",
        expect!["(* (Neg (as (index (. a b) 0) f32)) (Not (to c u32)))"],
    );
    check_expr("~-x", expect!["(BitNot (Neg x))"]);
    check_expr("(-x) as u32 as f32", expect!["(as (as (Neg x) u32) f32)"]);
}

#[test]
fn calls_fields_indexing_slicing() {
    check_expr(
        "f32x3(1.0, 2.0, 3.0).x + g(a, (b, c),)[1]",
        expect!["(+ (. (call f32x3 1.0 2.0 3.0) x) (index (call g a (tuple b c)) 1))"],
    );
    check_expr(
        "primitives[p_o : p_o + nprims]",
        expect!["(slice primitives p_o (+ p_o nprims))"],
    );
    check_expr(
        "I[0:2] + I[5:64]",
        expect!["(+ (slice I 0 2) (slice I 5 64))"],
    );
    check_expr("f()", expect!["(call f)"]);
}

#[test]
fn unit_grouping_and_tuples() {
    check_expr("((a))", expect!["a"]);
    check_expr("()", expect!["(tuple)"]);
    check_expr("(a, (b, c))", expect!["(tuple a (tuple b c))"]);
    check_expr("[a, (b, c)][1]", expect!["(index (array a (tuple b c)) 1)"]);
}

#[test]
fn layout_and_build_expressions() {
    check_expr("parent.bounds", expect!["(parent bounds)"]);
    check_expr("(build right - this)", expect!["(- (build right) this)"]);
    check_expr("append(data, nprims)", expect!["(call append data nprims)"]);
}

// --- Traversal language ---------------------------------------------------------------------

#[test]
fn type_declarations() {
    check_print(
        "type Ray(origin: f32x3, direction: f32x3, tmin: f32 = 0.0, tmax: f32 = inf);
         type BVH(bounds: AABB) = Interior(left: BVH, right: BVH) | Leaf(nprims: u16, data: Triangle[nprims])
         type Shape = | Empty | Ball(r: f32);
         type T(a: (f32, u32), b: set[u32], c: option[Triangle], d: u8x8[4][2], e: ());",
        expect![[r#"
            type Ray(origin: f32x3, direction: f32x3, tmin: f32 = 0.0, tmax: f32 = inf);

            type BVH(bounds: AABB) = Interior(left: BVH, right: BVH) | Leaf(nprims: u16, data: Triangle[nprims]);

            type Shape = Empty | Ball(r: f32);

            type T(a: (f32, u32), b: set[u32], c: option[Triangle], d: u8x8[4][2], e: ());
        "#]],
    );
}

#[test]
fn functions_and_parameters() {
    check_print(
        "func f(ray: Ray, best: mut (f32, u32), n: u32 = 4) -> bool = n < 4
         func g() = { return; }
         func h(x: f32) -> f32 = { let y = x * 2.0; let z: f32 = y; return z; };",
        expect![[r#"
            func f(ray: Ray, best: mut (f32, u32), n: u32 = 4) -> bool = n < 4;

            func g() = {
              return;
            }

            func h(x: f32) -> f32 = {
              let y = x * 2.0;
              let z: f32 = y;
              return z;
            }
        "#]],
    );
}

#[test]
fn statements() {
    check_print(
        "func f(a: mut u32, t: mut (u32, u32)) = {
           if a == 0 { a = 1; } elif a == 1 { a = 2 } elif a == 2 { } else { return; }
           foreach x in data[0 : 4] { t[0] = x; }
           { a = 3; };;
           g(a)
         }",
        expect![[r#"
            func f(a: mut u32, t: mut (u32, u32)) = {
              if a == 0 {
                a = 1;
              } elif a == 1 {
                a = 2;
              } elif a == 2 {} else {
                return;
              }
              foreach x in data[0 : 4] {
                t[0] = x;
              }
              {
                a = 3;
              }
              g(a);
            }
        "#]],
    );
}

#[test]
fn match_arms() {
    check_print(
        "func f(b: BVH) = match b {
           Interior(bounds, left: BVH, _) -> g(left)
           | Leaf -> { return; }
           | _ -> match b { | Leaf(_, n, _) -> h(n) | _ -> (a | b) }
         }",
        expect![[r#"
            func f(b: BVH) = match b {
              | Interior(bounds, left: BVH, _) ->
                g(left)
              | Leaf -> {
                return;
              }
              | _ ->
                match b {
                  | Leaf(_, n, _) ->
                    h(n)
                  | _ ->
                    (a | b)
                }
            }
        "#]],
    );
}

#[test]
fn bar_in_an_arm_body_ends_the_arm_but_not_inside_brackets() {
    let program = parse_ok("func f(b: BVH) = match b { | A -> x + g(a | b) | B -> y[a | b] }");
    let Item::Func(f) = &program.items[0] else {
        panic!()
    };
    let StmtKind::Match { arms, .. } = &f.body.kind else {
        panic!()
    };
    assert_eq!(arms.len(), 2);
    // Inside an `if` condition the bar is an operator: the block ends the condition.
    let program = parse_ok("func f(b: BVH) = match b { | A -> if a | b { x; } | B -> y }");
    let Item::Func(f) = &program.items[0] else {
        panic!()
    };
    let StmtKind::Match { arms, .. } = &f.body.kind else {
        panic!()
    };
    assert_eq!(arms.len(), 2);
}

// --- Layout language ------------------------------------------------------------------------

#[test]
fn layout_members() {
    check_print(
        "layout L(I: u32, B: AABB = parent.bounds) {
           P: u32; primitives: Triangle[P];
           let scale: f32 = 2.0;
           wlo: f32x3;
           group nodes[size=N + 1, align=32] by I {
             4;
             lo = B.low * scale;
             ---
             split I[0:2] {
               0 -> Interior { c: u32; };
               ~ 1 -> Other { };
               < 3 -> A { }; <= 4 -> B { }; > -5 -> C { }; >= 6 -> D { };
               -7 -> E from leaves[I[2:32]];
               _ -> F from leaves[0]
             };
           };
           indirect group leaves[align=16] {
             group tile[4] { x: f32; y: f32; }
             ---;
             count: u8;
           };
         }",
        expect![[r#"
            layout L(I: u32, B: AABB = parent.bounds) {
              P: u32;
              primitives: Triangle[P];
              let scale: f32 = 2.0;
              wlo: f32x3;
              group nodes[size=N + 1, align=32] by I {
                4;
                lo = B.low * scale;
                ---
                split I[0 : 2] {
                  0 -> Interior {
                    c: u32;
                  };
                  ~ 1 -> Other {};
                  < 3 -> A {};
                  <= 4 -> B {};
                  > -5 -> C {};
                  >= 6 -> D {};
                  -7 -> E from leaves[I[2 : 32]];
                  _ -> F from leaves[0];
                };
              };
              indirect group leaves[align=16] {
                group tile[4] {
                  x: f32;
                  y: f32;
                };
                ---
                count: u8;
              };
            };
        "#]],
    );
}

// --- Build language -------------------------------------------------------------------------

#[test]
fn build_declarations() {
    check_print(
        "build L[order=post] {
           build root { wlo = bounds.low; };
           build Interior(bounds: AABB, left: BVH, right: BVH) {
             build bounds; let R: u32 = build right; build c_o = R - this;
             this[0:2] = 1; this[48:64] = meta;
             return this;
           }
           build Leaf(nprims: u16) { build p_o = append(data, nprims); return this; };
         };
         build M { build A { return this; }; }",
        expect![[r#"
            build L[order=post] {
              build root {
                wlo = bounds.low;
              };
              build Interior(bounds: AABB, left: BVH, right: BVH) {
                build bounds;
                let R: u32 = build right;
                build c_o = R - this;
                this[0 : 2] = 1;
                this[48 : 64] = meta;
                return this;
              };
              build Leaf(nprims: u16) {
                build p_o = append(data, nprims);
                return this;
              };
            };

            build M {
              build A {
                return this;
              };
            };
        "#]],
    );
}

#[test]
fn node_ids_continue_across_files() {
    use scion_compiler::syntax::parse_file;
    use scion_ir::diag::SourceMap;
    let mut sources = SourceMap::new();
    let a = sources.add("a.scion", "func f() = 1 + 2;");
    let b = sources.add("b.scion", "func g() = x;");
    let mut program = Program::default();
    assert!(parse_file(&sources, a, &mut program).is_empty());
    assert_eq!(program.node_count, 4);
    assert!(parse_file(&sources, b, &mut program).is_empty());
    assert_eq!(program.node_count, 6);
    let Item::Func(g) = &program.items[1] else {
        panic!()
    };
    assert_eq!(g.body.id, NodeId(5));
    assert_eq!(g.body.span.file, b);
}
