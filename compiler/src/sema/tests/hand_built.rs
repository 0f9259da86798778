//! Tests on ASTs built by hand with a small builder: semantic analysis without the parser.

use crate::sema::{check_program, Prim, Resolution, Ty};
use crate::syntax::ast::*;
use scion_ir::diag::Span;

/// Builds AST nodes with fresh ids and empty spans.
#[derive(Default)]
struct B {
    next: u32,
}

fn ident(s: &str) -> Ident {
    Ident {
        name: s.to_string(),
        span: Span::default(),
    }
}

/// `u32`, `f32x3`, `Triangle[n]`, `u32[8]`.
fn ty(s: &str) -> TypeExpr {
    let kind = match s.split_once('[') {
        Some((elem, len)) => {
            let len = len.trim_end_matches(']');
            let len = match len.parse::<u64>() {
                Ok(n) => ArrayLen::Const(n, Span::default()),
                Err(_) => ArrayLen::Name(ident(len)),
            };
            TypeExprKind::Array {
                elem: Box::new(ty(elem)),
                len,
            }
        }
        None => TypeExprKind::Named(ident(s)),
    };
    TypeExpr {
        kind,
        span: Span::default(),
    }
}

fn field(name: &str, t: &str) -> FieldDecl {
    FieldDecl {
        name: ident(name),
        ty: ty(t),
        default: None,
        span: Span::default(),
    }
}

impl B {
    fn id(&mut self) -> NodeId {
        self.next += 1;
        NodeId(self.next)
    }
    fn e(&mut self, kind: ExprKind) -> Expr {
        Expr {
            id: self.id(),
            kind,
            span: Span::default(),
        }
    }
    fn s(&mut self, kind: StmtKind) -> Stmt {
        Stmt {
            id: self.id(),
            kind,
            span: Span::default(),
        }
    }
    fn name(&mut self, n: &str) -> Expr {
        self.e(ExprKind::Name(ident(n)))
    }
    fn int(&mut self, v: u128) -> Expr {
        self.e(ExprKind::Int(v))
    }
    fn float(&mut self, v: f64) -> Expr {
        self.e(ExprKind::Float(v))
    }
    fn call(&mut self, f: &str, args: Vec<Expr>) -> Expr {
        self.e(ExprKind::Call {
            callee: ident(f),
            args,
        })
    }
    fn bin(&mut self, op: BinaryOp, l: Expr, r: Expr) -> Expr {
        self.e(ExprKind::Binary {
            op,
            lhs: Box::new(l),
            rhs: Box::new(r),
        })
    }
    fn get(&mut self, base: Expr, name: &str) -> Expr {
        self.e(ExprKind::Field {
            base: Box::new(base),
            name: ident(name),
        })
    }
    fn expr(&mut self, e: Expr) -> Stmt {
        self.s(StmtKind::Expr(e))
    }
    fn assign(&mut self, target: Expr, value: Expr) -> Stmt {
        self.s(StmtKind::Assign { target, value })
    }
    fn pat(&mut self, variant: &str, binds: &[&str]) -> Pattern {
        let fields = binds
            .iter()
            .map(|b| Pattern {
                id: self.id(),
                kind: if *b == "_" {
                    PatternKind::Wildcard
                } else {
                    PatternKind::Bind {
                        name: ident(b),
                        ty: None,
                    }
                },
                span: Span::default(),
            })
            .collect();
        Pattern {
            id: self.id(),
            kind: PatternKind::Variant {
                name: ident(variant),
                fields,
            },
            span: Span::default(),
        }
    }
    fn matches(&mut self, scrutinee: Expr, arms: Vec<(Pattern, Stmt)>) -> Stmt {
        let arms = arms
            .into_iter()
            .map(|(pattern, body)| MatchArm {
                pattern,
                body,
                span: Span::default(),
            })
            .collect();
        self.s(StmtKind::Match { scrutinee, arms })
    }
}

fn func(name: &str, params: &[(&str, &str, bool)], ret: Option<&str>, body: Stmt) -> Item {
    let params = params
        .iter()
        .map(|(n, t, m)| Param {
            name: ident(n),
            mutable: *m,
            ty: ty(t),
            default: None,
            span: Span::default(),
        })
        .collect();
    Item::Func(FuncDecl {
        name: ident(name),
        params,
        ret: ret.map(ty),
        order_by: None,
        body,
        span: Span::default(),
    })
}

fn record(name: &str, fields: &[(&str, &str)]) -> Item {
    let fields = fields.iter().map(|(n, t)| field(n, t)).collect();
    Item::Type(TypeDecl {
        name: ident(name),
        fields,
        variants: None,
        span: Span::default(),
    })
}

/// `type BVH(bounds: AABB) = Interior(left: BVH, right: BVH) | Leaf(nprims: u16, data: Tri[nprims]);`
fn geometry() -> Vec<Item> {
    let bvh = TypeDecl {
        name: ident("BVH"),
        fields: vec![field("bounds", "AABB")],
        variants: Some(vec![
            VariantDecl {
                name: ident("Interior"),
                fields: vec![field("left", "BVH"), field("right", "BVH")],
                span: Span::default(),
            },
            VariantDecl {
                name: ident("Leaf"),
                fields: vec![field("nprims", "u16"), field("data", "Tri[nprims]")],
                span: Span::default(),
            },
        ]),
        span: Span::default(),
    };
    vec![
        record("AABB", &[("low", "f32x3"), ("high", "f32x3")]),
        record("Tri", &[("p0", "f32x3"), ("id", "u32")]),
        Item::Type(bvh),
    ]
}

fn check(items: Vec<Item>, b: &B) -> (crate::sema::TypedProgram, Vec<String>) {
    let program = Program {
        items,
        node_count: b.next + 1,
    };
    let (typed, diags) = check_program(&program);
    let codes = diags
        .list
        .iter()
        .map(|d| d.code.clone().unwrap_or_default())
        .collect();
    (typed, codes)
}

#[test]
fn literals_default_and_results_are_inferred() {
    let mut b = B::default();
    let one = b.int(1);
    let body = b.expr(one);
    let x = b.name("x");
    let lit = b.int(2);
    let sum = b.bin(BinaryOp::Add, x, lit);
    let body2 = b.expr(sum);
    let items = vec![
        func("f", &[], None, body),
        func("g", &[("x", "u16", false)], None, body2),
    ];
    let (t, codes) = check(items, &b);
    assert!(codes.is_empty(), "{codes:?}");
    assert_eq!(t.funcs[0].ret, Ty::Prim(Prim::I32));
    assert_eq!(t.funcs[1].ret, Ty::Prim(Prim::U16));
    assert!(t.expr_types.values().all(|t| !t.has_vars()));
}

#[test]
fn unknown_name_and_mismatch() {
    let mut b = B::default();
    let y = b.name("y");
    let body = b.expr(y);
    let fl = b.float(1.0);
    let body2 = b.expr(fl);
    let items = vec![
        func("f", &[], None, body),
        func("g", &[], Some("u32"), body2),
    ];
    let (_, codes) = check(items, &b);
    assert_eq!(codes, vec!["E0201", "E0206"]);
}

#[test]
fn overloads_resolve_by_argument_type() {
    let mut b = B::default();
    let mut items = geometry();
    let t1 = b.e(ExprKind::Bool(true));
    let body_box = b.expr(t1);
    let t2 = b.e(ExprKind::Bool(false));
    let body_tri = b.expr(t2);
    items.push(func("hit", &[("b", "AABB", false)], Some("bool"), body_box));
    items.push(func("hit", &[("t", "Tri", false)], Some("bool"), body_tri));
    let arg = b.name("t");
    let call = b.call("hit", vec![arg]);
    let call_id = call.id;
    let body = b.expr(call);
    items.push(func("use_tri", &[("t", "Tri", false)], None, body));
    let one = b.float(1.0);
    let bad = b.call("hit", vec![one]);
    let body = b.expr(bad);
    items.push(func("bad", &[], None, body));
    let (t, codes) = check(items, &b);
    assert_eq!(codes, vec!["E0207"]);
    let Some(Resolution::Func(f)) = t.resolution(call_id) else {
        panic!()
    };
    assert_eq!(t.func(*f).unique_name, "hit.1");
}

#[test]
fn match_binds_fields_and_checks_exhaustiveness() {
    let mut b = B::default();
    let mut items = geometry();
    let scrut = b.name("n");
    let p = b.pat("Leaf", &["bx", "k", "_"]);
    let k = b.name("k");
    let arm = b.expr(k);
    let m = b.matches(scrut, vec![(p, arm)]);
    items.push(func("count", &[("n", "BVH", false)], Some("u16"), m));
    let (t, codes) = check(items, &b);
    assert_eq!(codes, vec!["E0214"]);
    let k = t.bindings.iter().find(|x| x.name == "k").unwrap();
    assert_eq!(k.ty, Ty::Prim(Prim::U16));
}

#[test]
fn only_mut_parameters_are_assigned() {
    let mut b = B::default();
    let (t1, v1) = (b.name("a"), b.int(1));
    let s1 = b.assign(t1, v1);
    let (t2, v2) = (b.name("c"), b.int(2));
    let s2 = b.assign(t2, v2);
    let body = b.s(StmtKind::Block(vec![s1, s2]));
    let items = vec![func(
        "f",
        &[("a", "u32", true), ("c", "u32", false)],
        None,
        body,
    )];
    let (_, codes) = check(items, &b);
    assert_eq!(codes, vec!["E0221"]);
}

#[test]
fn field_access_and_vector_components() {
    let mut b = B::default();
    let mut items = geometry();
    let base = b.name("bx");
    let low = b.get(base, "low");
    let x = b.get(low, "x");
    let body = b.expr(x);
    items.push(func("lx", &[("bx", "AABB", false)], None, body));
    let (t, codes) = check(items, &b);
    assert!(codes.is_empty(), "{codes:?}");
    assert_eq!(t.funcs[0].ret, Ty::Prim(Prim::F32));
}
