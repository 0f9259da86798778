//! The printer's invariant on random trees: for a randomly generated AST of every construct,
//! `parse(print(ast))` has no diagnostics and is the same tree up to spans and node ids. This
//! checks the printer's parentheses (precedence, non-associative comparisons, `|` in match
//! arms, statements starting with `build`) against the parser.

use crate::common;

use common::{parse_str, strip_positions};
use proptest::prelude::*;
use scion_compiler::syntax::ast::*;
use scion_compiler::syntax::print::print_program;
use scion_ir::diag::Span;

/// A small deterministic generator (xorshift64*), seeded by proptest.
struct Gen {
    state: u64,
    ids: u32,
}

const NAMES: &[&str] = &[
    "a", "b", "x", "bounds", "left", "I", "root", "size", "pre", "_t",
];
const TYPES: &[&str] = &["f32", "u32", "bool", "ptr", "AABB", "Triangle"];
const VARIANTS: &[&str] = &["Leaf", "Interior", "A"];
const BINOPS: &[BinaryOp] = &[
    BinaryOp::Or,
    BinaryOp::And,
    BinaryOp::Eq,
    BinaryOp::Ne,
    BinaryOp::Lt,
    BinaryOp::Le,
    BinaryOp::Gt,
    BinaryOp::Ge,
    BinaryOp::BitOr,
    BinaryOp::BitXor,
    BinaryOp::BitAnd,
    BinaryOp::Shl,
    BinaryOp::Shr,
    BinaryOp::Add,
    BinaryOp::Sub,
    BinaryOp::Mul,
    BinaryOp::Div,
    BinaryOp::Rem,
];

impl Gen {
    fn next(&mut self) -> u64 {
        self.state ^= self.state >> 12;
        self.state ^= self.state << 25;
        self.state ^= self.state >> 27;
        self.state.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    fn pick<T: Clone>(&mut self, xs: &[T]) -> T {
        xs[self.below(xs.len())].clone()
    }

    fn id(&mut self) -> NodeId {
        self.ids += 1;
        NodeId(self.ids)
    }

    fn ident(&mut self, from: &[&str]) -> Ident {
        Ident {
            name: self.pick(from).to_string(),
            span: Span::default(),
        }
    }

    fn count(&mut self, max: usize) -> usize {
        self.below(max + 1)
    }

    fn ty(&mut self, depth: u32) -> TypeExpr {
        let choice = if depth == 0 {
            self.below(2)
        } else {
            self.below(6)
        };
        let kind = match choice {
            0 => TypeExprKind::Named(self.ident(TYPES)),
            1 => TypeExprKind::Vector {
                elem: self.ident(&["f32", "u8", "i16"]),
                lanes: 1 + self.below(8) as u32,
            },
            2 => TypeExprKind::Array {
                elem: Box::new(self.ty(depth - 1)),
                len: if self.below(2) == 0 {
                    ArrayLen::Const(self.next() >> self.below(64), Span::default())
                } else {
                    ArrayLen::Name(self.ident(NAMES))
                },
            },
            3 => {
                let n = if self.below(3) == 0 {
                    0
                } else {
                    2 + self.count(2)
                };
                TypeExprKind::Tuple((0..n).map(|_| self.ty(depth - 1)).collect())
            }
            4 => TypeExprKind::Set(Box::new(self.ty(depth - 1))),
            _ => TypeExprKind::Option(Box::new(self.ty(depth - 1))),
        };
        TypeExpr {
            kind,
            span: Span::default(),
        }
    }

    fn expr(&mut self, depth: u32) -> Expr {
        let choice = if depth == 0 {
            self.below(8)
        } else {
            self.below(19)
        };
        let kind = match choice {
            0 => ExprKind::Name(self.ident(NAMES)),
            1 => ExprKind::Int(u128::from(self.next()) << self.below(64)),
            2 => ExprKind::Float(match self.below(4) {
                0 => f64::INFINITY,
                1 => f64::from_bits(self.next() >> 2), // finite, non-negative
                _ => self.below(1000) as f64 / 8.0,
            }),
            3 => ExprKind::Bool(self.below(2) == 0),
            4 => ExprKind::This,
            5 => ExprKind::Parent(self.ident(NAMES)),
            6 => ExprKind::Build(self.ident(NAMES)),
            7 => ExprKind::Tuple(Vec::new()),
            8 => ExprKind::Call {
                callee: self.ident(&["f", "append", "f32x3", "Leaf"]),
                args: (0..self.count(3)).map(|_| self.expr(depth - 1)).collect(),
            },
            9 => ExprKind::Field {
                base: Box::new(self.expr(depth - 1)),
                name: self.ident(NAMES),
            },
            10 => ExprKind::Index {
                base: Box::new(self.expr(depth - 1)),
                index: Box::new(self.expr(depth - 1)),
            },
            11 => ExprKind::Slice {
                base: Box::new(self.expr(depth - 1)),
                lo: Box::new(self.expr(depth - 1)),
                hi: Box::new(self.expr(depth - 1)),
            },
            12 => ExprKind::Tuple(
                (0..2 + self.count(2))
                    .map(|_| self.expr(depth - 1))
                    .collect(),
            ),
            13 => ExprKind::Unary {
                op: self.pick(&[UnaryOp::Neg, UnaryOp::Not, UnaryOp::BitNot]),
                operand: Box::new(self.expr(depth - 1)),
            },
            14 => ExprKind::Cast {
                expr: Box::new(self.expr(depth - 1)),
                ty: self.ty(1),
            },
            15 => ExprKind::BitCast {
                expr: Box::new(self.expr(depth - 1)),
                ty: self.ty(1),
            },
            16 => ExprKind::If {
                branches: (0..1 + self.count(2))
                    .map(|_| (self.expr(depth - 1), self.block(0)))
                    .collect(),
                otherwise: Box::new(self.block(0)),
            },
            17 => ExprKind::Array(
                (0..1 + self.count(3))
                    .map(|_| self.expr(depth - 1))
                    .collect(),
            ),
            _ => ExprKind::Binary {
                op: self.pick(BINOPS),
                lhs: Box::new(self.expr(depth - 1)),
                rhs: Box::new(self.expr(depth - 1)),
            },
        };
        Expr {
            id: self.id(),
            kind,
            span: Span::default(),
        }
    }

    /// An assignable target: a name or `this`, then fields, indices and slices.
    fn target(&mut self, depth: u32) -> Expr {
        let mut e = if self.below(3) == 0 {
            Expr {
                id: self.id(),
                kind: ExprKind::This,
                span: Span::default(),
            }
        } else {
            Expr {
                id: self.id(),
                kind: ExprKind::Name(self.ident(NAMES)),
                span: Span::default(),
            }
        };
        for _ in 0..self.count(2) {
            let kind = match self.below(3) {
                0 => ExprKind::Field {
                    base: Box::new(e),
                    name: self.ident(NAMES),
                },
                1 => ExprKind::Index {
                    base: Box::new(e),
                    index: Box::new(self.expr(depth)),
                },
                _ => ExprKind::Slice {
                    base: Box::new(e),
                    lo: Box::new(self.expr(depth)),
                    hi: Box::new(self.expr(depth)),
                },
            };
            e = Expr {
                id: self.id(),
                kind,
                span: Span::default(),
            };
        }
        if matches!(e.kind, ExprKind::This) {
            self.ident(NAMES); // keep the stream moving; a bare `this` is not assignable
            e = Expr {
                id: self.id(),
                kind: ExprKind::Name(self.ident(NAMES)),
                span: e.span,
            };
        }
        e
    }

    fn block(&mut self, depth: u32) -> Stmt {
        let stmts = (0..self.count(3)).map(|_| self.stmt(depth)).collect();
        Stmt {
            id: self.id(),
            kind: StmtKind::Block(stmts),
            span: Span::default(),
        }
    }

    fn stmt(&mut self, depth: u32) -> Stmt {
        let choice = if depth == 0 {
            self.below(5)
        } else {
            self.below(9)
        };
        let d = depth.saturating_sub(1);
        let kind = match choice {
            0 => StmtKind::Expr(self.expr(2)),
            1 => StmtKind::Assign {
                target: self.target(1),
                value: self.expr(2),
            },
            2 => StmtKind::Return(if self.below(3) == 0 {
                None
            } else {
                Some(self.expr(2))
            }),
            3 => StmtKind::Let {
                name: self.ident(NAMES),
                ty: if self.below(2) == 0 {
                    None
                } else {
                    Some(self.ty(1))
                },
                value: self.expr(2),
                mutable: self.below(2) == 0,
            },
            4 => StmtKind::Build {
                field: self.ident(NAMES),
                value: if self.below(2) == 0 {
                    None
                } else {
                    Some(self.expr(2))
                },
            },
            5 => StmtKind::If {
                branches: (0..1 + self.count(2))
                    .map(|_| (self.expr(2), self.block(d)))
                    .collect(),
                otherwise: if self.below(2) == 0 {
                    None
                } else {
                    Some(Box::new(self.block(d)))
                },
            },
            6 => StmtKind::Foreach {
                var: self.ident(NAMES),
                index: if self.count(2) == 0 {
                    None
                } else {
                    Some(self.ident(NAMES))
                },
                iter: self.expr(2),
                body: Box::new(self.block(d)),
            },
            7 => StmtKind::Match {
                scrutinee: self.expr(2),
                arms: (0..1 + self.count(3))
                    .map(|_| MatchArm {
                        pattern: self.pattern(),
                        body: self.stmt(d),
                        span: Span::default(),
                    })
                    .collect(),
            },
            _ => return self.block(d),
        };
        Stmt {
            id: self.id(),
            kind,
            span: Span::default(),
        }
    }

    fn pattern(&mut self) -> Pattern {
        let kind = if self.below(4) == 0 {
            PatternKind::Wildcard
        } else {
            let fields = (0..self.count(3))
                .map(|_| {
                    let kind = if self.below(3) == 0 {
                        PatternKind::Wildcard
                    } else {
                        PatternKind::Bind {
                            name: self.ident(NAMES),
                            ty: if self.below(2) == 0 {
                                None
                            } else {
                                Some(self.ty(1))
                            },
                        }
                    };
                    Pattern {
                        id: self.id(),
                        kind,
                        span: Span::default(),
                    }
                })
                .collect();
            PatternKind::Variant {
                name: self.ident(VARIANTS),
                fields,
            }
        };
        Pattern {
            id: self.id(),
            kind,
            span: Span::default(),
        }
    }

    fn field(&mut self) -> FieldDecl {
        FieldDecl {
            name: self.ident(NAMES),
            ty: self.ty(2),
            default: if self.below(3) == 0 {
                Some(self.expr(2))
            } else {
                None
            },
            span: Span::default(),
        }
    }

    fn members(&mut self, depth: u32) -> Vec<Member> {
        (0..self.count(4)).map(|_| self.member(depth)).collect()
    }

    fn member(&mut self, depth: u32) -> Member {
        let choice = if depth == 0 {
            self.below(5)
        } else {
            self.below(7)
        };
        let d = depth.saturating_sub(1);
        let kind = match choice {
            0 => MemberKind::Field {
                name: self.ident(NAMES),
                ty: self.ty(2),
            },
            1 => MemberKind::Padding {
                bytes: self.next() >> self.below(64),
            },
            2 => MemberKind::Derived {
                name: self.ident(NAMES),
                value: self.expr(2),
            },
            3 => MemberKind::Let {
                name: self.ident(NAMES),
                ty: if self.below(2) == 0 {
                    None
                } else {
                    Some(self.ty(1))
                },
                value: self.expr(2),
            },
            4 => MemberKind::Separator,
            5 => {
                let indirect = self.below(3) == 0;
                let attrs = (0..self.count(2))
                    .map(|_| {
                        let kind = match self.below(3) {
                            0 => GroupAttrKind::Count(self.next()),
                            1 => GroupAttrKind::Size(self.expr(2)),
                            _ => GroupAttrKind::Align(1 << self.below(8)),
                        };
                        GroupAttr {
                            kind,
                            span: Span::default(),
                        }
                    })
                    .collect();
                MemberKind::Group(GroupDecl {
                    name: self.ident(NAMES),
                    indirect,
                    attrs,
                    by: if indirect || self.below(2) == 0 {
                        None
                    } else {
                        Some(self.expr(2))
                    },
                    members: self.members(d),
                    span: Span::default(),
                })
            }
            _ => MemberKind::Split {
                discriminant: self.expr(2),
                arms: (0..1 + self.count(3))
                    .map(|_| {
                        let n = (self.next() as i128) << self.below(64);
                        let kind = match self.below(7) {
                            0 => SplitPatternKind::Eq(n),
                            1 => SplitPatternKind::Ne(n),
                            2 => SplitPatternKind::Lt(n),
                            3 => SplitPatternKind::Le(n),
                            4 => SplitPatternKind::Gt(i128::MIN),
                            5 => SplitPatternKind::Ge(-n),
                            _ => SplitPatternKind::Wildcard,
                        };
                        let variant = self.ident(VARIANTS);
                        let body = if self.below(2) == 0 {
                            SplitArmBody::Members {
                                variant,
                                members: self.members(d),
                            }
                        } else {
                            SplitArmBody::From {
                                variant,
                                group: self.ident(NAMES),
                                key: self.expr(2),
                            }
                        };
                        SplitArm {
                            pattern: SplitPattern {
                                kind,
                                span: Span::default(),
                            },
                            body,
                            span: Span::default(),
                        }
                    })
                    .collect(),
            },
        };
        Member {
            kind,
            span: Span::default(),
        }
    }

    fn item(&mut self) -> Item {
        let mut item = self.item_inner();
        if let Item::Build(b) = &mut item {
            // `order=post` is always written.
            if b.order == BuildOrder::Post {
                b.order_span = Some(Span::default());
            }
        }
        item
    }

    fn item_inner(&mut self) -> Item {
        let name = self.ident(&["L", "BVH", "f"]);
        match self.below(4) {
            0 => Item::Type(TypeDecl {
                name,
                fields: (0..self.count(3)).map(|_| self.field()).collect(),
                variants: if self.below(2) == 0 {
                    None
                } else {
                    Some(
                        (0..1 + self.count(2))
                            .map(|_| VariantDecl {
                                name: self.ident(VARIANTS),
                                fields: (0..self.count(2)).map(|_| self.field()).collect(),
                                span: Span::default(),
                            })
                            .collect(),
                    )
                },
                span: Span::default(),
            }),
            1 => Item::Func(FuncDecl {
                name,
                params: (0..self.count(3))
                    .map(|_| Param {
                        name: self.ident(NAMES),
                        mutable: self.below(2) == 0,
                        ty: self.ty(2),
                        default: if self.below(3) == 0 {
                            Some(self.expr(2))
                        } else {
                            None
                        },
                        span: Span::default(),
                    })
                    .collect(),
                ret: if self.below(2) == 0 {
                    None
                } else {
                    Some(self.ty(2))
                },
                order_by: if self.below(4) == 0 {
                    Some(self.ident(NAMES))
                } else {
                    None
                },
                body: self.stmt(3),
                span: Span::default(),
            }),
            2 => Item::Layout(LayoutDecl {
                name,
                params: (0..self.count(2))
                    .map(|_| LayoutParam {
                        name: self.ident(NAMES),
                        ty: self.ty(1),
                        default: if self.below(2) == 0 {
                            Some(self.expr(1))
                        } else {
                            None
                        },
                        span: Span::default(),
                    })
                    .collect(),
                members: self.members(3),
                span: Span::default(),
            }),
            _ => Item::Build(BuildDecl {
                name,
                order: if self.below(2) == 0 {
                    BuildOrder::Pre
                } else {
                    BuildOrder::Post
                },
                order_span: if self.below(2) == 0 {
                    Some(Span::default())
                } else {
                    None
                },
                root: if self.below(2) == 0 {
                    None
                } else {
                    Some(BuildRoot {
                        body: (0..self.count(3)).map(|_| self.stmt(2)).collect(),
                        span: Span::default(),
                    })
                },
                variants: (0..self.count(3))
                    .map(|_| BuildVariant {
                        name: self.ident(VARIANTS),
                        params: (0..self.count(3)).map(|_| self.field()).collect(),
                        body: (0..self.count(3)).map(|_| self.stmt(2)).collect(),
                        span: Span::default(),
                    })
                    .collect(),
                span: Span::default(),
            }),
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn printed_random_programs_parse_back_to_the_same_tree(seed in any::<u64>()) {
        let mut gen = Gen { state: seed | 1, ids: 0 };
        let program = Program { items: (0..1 + gen.count(3)).map(|_| gen.item()).collect(), node_count: 0 };
        let printed = print_program(&program);
        let (parsed, diags, sources) = parse_str("printed.scion", &printed);
        prop_assert!(diags.is_empty(), "{printed}\n{}", diags.render(&sources));
        prop_assert_eq!(
            strip_positions(&format!("{:?}", program.items)),
            strip_positions(&format!("{:?}", parsed.items)),
            "{}", printed
        );
    }
}
