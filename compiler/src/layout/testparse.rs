//! A small parser for tests only: turns layout, build and `type` source text into the AST so
//! that this module's tests can be written as real Scion text while the project's parser
//! (`syntax`) is being written. `func` items are skipped. It panics on malformed input, which
//! is acceptable for test fixtures only; it is compiled under `cfg(test)` alone.

use crate::syntax::ast::*;
use scion_ir::diag::{FileId, Span};

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    Int(u128),
    Float(f64),
    Punct(&'static str),
}

const PUNCTS: [&str; 32] = [
    "---", "->", "<=", ">=", "==", "!=", "&&", "||", "<<", ">>", "(", ")", "{", "}", "[", "]", ",",
    ";", ":", "=", "<", ">", "+", "-", "*", "/", "%", "|", "&", "^", "~", ".",
];

fn lex(src: &str) -> Vec<(Tok, Span)> {
    let b = src.as_bytes();
    let mut i = 0;
    let mut out = Vec::new();
    let sp = |s: usize, e: usize| Span::new(FileId(0), s as u32, e as u32);
    'outer: while i < b.len() {
        let c = b[i];
        if c.is_ascii_whitespace() {
            i += 1;
            continue;
        }
        if src[i..].starts_with("//") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
            continue;
        }
        let start = i;
        if c.is_ascii_alphabetic() || c == b'_' {
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            out.push((Tok::Ident(src[start..i].to_string()), sp(start, i)));
            continue;
        }
        if c.is_ascii_digit() {
            if src[i..].starts_with("0x") || src[i..].starts_with("0b") {
                let radix = if b[i + 1] == b'x' { 16 } else { 2 };
                i += 2;
                let s = i;
                while i < b.len() && (b[i].is_ascii_hexdigit() || b[i] == b'_') {
                    i += 1;
                }
                let digits: String = src[s..i].chars().filter(|c| *c != '_').collect();
                out.push((
                    Tok::Int(u128::from_str_radix(&digits, radix).unwrap()),
                    sp(start, i),
                ));
                continue;
            }
            while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'_') {
                i += 1;
            }
            let mut float = false;
            if i + 1 < b.len() && b[i] == b'.' && b[i + 1].is_ascii_digit() {
                float = true;
                i += 1;
                while i < b.len() && b[i].is_ascii_digit() {
                    i += 1;
                }
            }
            if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
                float = true;
                i += 1;
                if b[i] == b'+' || b[i] == b'-' {
                    i += 1;
                }
                while i < b.len() && b[i].is_ascii_digit() {
                    i += 1;
                }
            }
            let text: String = src[start..i].chars().filter(|c| *c != '_').collect();
            let tok = if float {
                Tok::Float(text.parse().unwrap())
            } else {
                Tok::Int(text.parse().unwrap())
            };
            out.push((tok, sp(start, i)));
            continue;
        }
        for p in PUNCTS {
            if src[i..].starts_with(p) {
                i += p.len();
                out.push((Tok::Punct(p), sp(start, i)));
                continue 'outer;
            }
        }
        panic!("test parser: unexpected character {:?} at {i}", c as char);
    }
    out
}

struct P {
    toks: Vec<(Tok, Span)>,
    pos: usize,
    next_id: u32,
}

/// Parses `src` (types, layouts, builds; funcs skipped) into a [`Program`] in file 0.
pub fn parse(src: &str) -> Program {
    let mut p = P {
        toks: lex(src),
        pos: 0,
        next_id: 0,
    };
    let mut items = Vec::new();
    while p.pos < p.toks.len() {
        if p.eat(";") {
            continue;
        }
        if p.is_ident("func") {
            p.skip_item();
        } else if p.is_ident("type") {
            items.push(Item::Type(p.type_decl()));
        } else if p.is_ident("layout") {
            items.push(Item::Layout(p.layout()));
        } else if p.is_ident("build") {
            items.push(Item::Build(p.build_decl()));
        } else {
            panic!("test parser: unexpected item at {:?}", p.toks[p.pos]);
        }
    }
    Program {
        items,
        node_count: p.next_id,
    }
}

impl P {
    fn peek(&self) -> Option<&Tok> {
        self.toks.get(self.pos).map(|t| &t.0)
    }
    fn span(&self) -> Span {
        self.toks
            .get(self.pos)
            .map(|t| t.1)
            .unwrap_or_else(|| self.toks.last().unwrap().1)
    }
    fn prev(&self) -> Span {
        self.toks[self.pos.saturating_sub(1)].1
    }
    fn id(&mut self) -> NodeId {
        self.next_id += 1;
        NodeId(self.next_id - 1)
    }
    fn is(&self, p: &str) -> bool {
        matches!(self.peek(), Some(Tok::Punct(q)) if *q == p)
    }
    fn is_ident(&self, s: &str) -> bool {
        matches!(self.peek(), Some(Tok::Ident(q)) if q == s)
    }
    fn eat(&mut self, p: &str) -> bool {
        if self.is(p) {
            self.pos += 1;
            true
        } else {
            false
        }
    }
    fn eat_ident(&mut self, s: &str) -> bool {
        if self.is_ident(s) {
            self.pos += 1;
            true
        } else {
            false
        }
    }
    fn expect(&mut self, p: &str) {
        assert!(
            self.eat(p),
            "test parser: expected `{p}` at {:?}",
            self.toks.get(self.pos)
        );
    }
    fn ident(&mut self) -> Ident {
        match self.toks.get(self.pos).cloned() {
            Some((Tok::Ident(name), span)) => {
                self.pos += 1;
                Ident { name, span }
            }
            t => panic!("test parser: expected a name, found {t:?}"),
        }
    }
    fn int(&mut self) -> u128 {
        match self.peek().cloned() {
            Some(Tok::Int(n)) => {
                self.pos += 1;
                n
            }
            t => panic!("test parser: expected an integer, found {t:?}"),
        }
    }

    fn skip_item(&mut self) {
        self.pos += 1;
        let mut depth = 0i32;
        while let Some(t) = self.peek() {
            match t {
                Tok::Punct("(") | Tok::Punct("{") | Tok::Punct("[") => depth += 1,
                Tok::Punct(")") | Tok::Punct("}") | Tok::Punct("]") => depth -= 1,
                Tok::Ident(s)
                    if depth == 0 && matches!(s.as_str(), "func" | "type" | "layout" | "build") =>
                {
                    return
                }
                _ => {}
            }
            self.pos += 1;
        }
    }

    // ---------------------------------------------------------------- types

    fn ty(&mut self) -> TypeExpr {
        let start = self.span();
        let mut t = if self.eat("(") {
            let mut parts = Vec::new();
            while !self.eat(")") {
                parts.push(self.ty());
                self.eat(",");
            }
            TypeExpr {
                kind: TypeExprKind::Tuple(parts),
                span: start.to(self.prev()),
            }
        } else {
            let id = self.ident();
            if (id.name == "set" || id.name == "option") && self.is("[") {
                self.expect("[");
                let inner = Box::new(self.ty());
                self.expect("]");
                let kind = if id.name == "set" {
                    TypeExprKind::Set(inner)
                } else {
                    TypeExprKind::Option(inner)
                };
                TypeExpr {
                    kind,
                    span: start.to(self.prev()),
                }
            } else {
                TypeExpr {
                    kind: vector_or_named(id),
                    span: start,
                }
            }
        };
        while self.is("[") {
            self.expect("[");
            let len = match self.peek().cloned() {
                Some(Tok::Int(n)) => {
                    let s = self.span();
                    self.pos += 1;
                    ArrayLen::Const(n as u64, s)
                }
                _ => ArrayLen::Name(self.ident()),
            };
            self.expect("]");
            t = TypeExpr {
                kind: TypeExprKind::Array {
                    elem: Box::new(t),
                    len,
                },
                span: start.to(self.prev()),
            };
        }
        t
    }

    fn fields(&mut self) -> Vec<FieldDecl> {
        self.expect("(");
        let mut out = Vec::new();
        while !self.eat(")") {
            let name = self.ident();
            self.expect(":");
            let ty = self.ty();
            let default = if self.eat("=") {
                Some(self.expr())
            } else {
                None
            };
            out.push(FieldDecl {
                span: name.span.to(self.prev()),
                name,
                ty,
                default,
            });
            self.eat(",");
        }
        out
    }

    fn type_decl(&mut self) -> TypeDecl {
        let start = self.span();
        self.eat_ident("type");
        let name = self.ident();
        let fields = if self.is("(") {
            self.fields()
        } else {
            Vec::new()
        };
        let variants = if self.eat("=") {
            let mut vs = Vec::new();
            loop {
                let vname = self.ident();
                let vf = if self.is("(") {
                    self.fields()
                } else {
                    Vec::new()
                };
                vs.push(VariantDecl {
                    span: vname.span.to(self.prev()),
                    name: vname,
                    fields: vf,
                });
                if !self.eat("|") {
                    break;
                }
            }
            Some(vs)
        } else {
            None
        };
        let span = start.to(self.prev());
        self.eat(";");
        TypeDecl {
            name,
            fields,
            variants,
            span,
        }
    }

    // ---------------------------------------------------------------- layouts

    fn layout(&mut self) -> LayoutDecl {
        let start = self.span();
        self.eat_ident("layout");
        let name = self.ident();
        self.expect("(");
        let mut params = Vec::new();
        while !self.eat(")") {
            let n = self.ident();
            self.expect(":");
            let ty = self.ty();
            let default = if self.eat("=") {
                Some(self.expr())
            } else {
                None
            };
            params.push(LayoutParam {
                span: n.span.to(self.prev()),
                name: n,
                ty,
                default,
            });
            self.eat(",");
        }
        let members = self.members();
        let span = start.to(self.prev());
        self.eat(";");
        LayoutDecl {
            name,
            params,
            members,
            span,
        }
    }

    fn members(&mut self) -> Vec<Member> {
        self.expect("{");
        let mut out = Vec::new();
        while !self.eat("}") {
            if self.eat(";") {
                continue;
            }
            out.push(self.member());
        }
        out
    }

    fn member(&mut self) -> Member {
        let start = self.span();
        let kind = if self.eat("---") {
            MemberKind::Separator
        } else if let Some(Tok::Int(n)) = self.peek().cloned() {
            self.pos += 1;
            MemberKind::Padding { bytes: n as u64 }
        } else if self.is_ident("group") || self.is_ident("indirect") {
            MemberKind::Group(self.group())
        } else if self.eat_ident("split") {
            let discriminant = self.expr();
            self.expect("{");
            let mut arms = Vec::new();
            while !self.eat("}") {
                if self.eat(";") {
                    continue;
                }
                arms.push(self.arm());
            }
            MemberKind::Split { discriminant, arms }
        } else if self.eat_ident("let") {
            let name = self.ident();
            let ty = if self.eat(":") { Some(self.ty()) } else { None };
            self.expect("=");
            MemberKind::Let {
                name,
                ty,
                value: self.expr(),
            }
        } else {
            let name = self.ident();
            if self.eat(":") {
                MemberKind::Field {
                    name,
                    ty: self.ty(),
                }
            } else {
                self.expect("=");
                MemberKind::Derived {
                    name,
                    value: self.expr(),
                }
            }
        };
        let span = start.to(self.prev());
        self.eat(";");
        Member { kind, span }
    }

    fn group(&mut self) -> GroupDecl {
        let start = self.span();
        let indirect = self.eat_ident("indirect");
        assert!(self.eat_ident("group"));
        let name = self.ident();
        let mut attrs = Vec::new();
        if self.eat("[") {
            while !self.eat("]") {
                let s = self.span();
                let kind = if let Some(Tok::Int(n)) = self.peek().cloned() {
                    self.pos += 1;
                    GroupAttrKind::Count(n as u64)
                } else if self.eat_ident("size") {
                    self.expect("=");
                    GroupAttrKind::Size(self.expr())
                } else {
                    assert!(self.eat_ident("align"));
                    self.expect("=");
                    GroupAttrKind::Align(self.int() as u64)
                };
                attrs.push(GroupAttr {
                    kind,
                    span: s.to(self.prev()),
                });
                self.eat(",");
            }
        }
        let by = if self.eat_ident("by") {
            Some(self.expr())
        } else {
            None
        };
        let members = self.members();
        GroupDecl {
            name,
            indirect,
            attrs,
            by,
            members,
            span: start.to(self.prev()),
        }
    }

    fn arm(&mut self) -> SplitArm {
        let start = self.span();
        let num = |p: &mut P| -> i128 {
            let neg = p.eat("-");
            let n = p.int() as i128;
            if neg {
                -n
            } else {
                n
            }
        };
        let kind = if self.eat_ident("_") {
            SplitPatternKind::Wildcard
        } else if self.eat("~") {
            SplitPatternKind::Ne(num(self))
        } else if self.eat("<=") {
            SplitPatternKind::Le(num(self))
        } else if self.eat(">=") {
            SplitPatternKind::Ge(num(self))
        } else if self.eat("<") {
            SplitPatternKind::Lt(num(self))
        } else if self.eat(">") {
            SplitPatternKind::Gt(num(self))
        } else {
            SplitPatternKind::Eq(num(self))
        };
        let pattern = SplitPattern {
            kind,
            span: start.to(self.prev()),
        };
        self.expect("->");
        let variant = self.ident();
        let body = if self.eat_ident("from") {
            let group = self.ident();
            self.expect("[");
            let key = self.expr();
            self.expect("]");
            SplitArmBody::From {
                variant,
                group,
                key,
            }
        } else {
            SplitArmBody::Members {
                variant,
                members: self.members(),
            }
        };
        let span = start.to(self.prev());
        self.eat(";");
        SplitArm {
            pattern,
            body,
            span,
        }
    }

    // ---------------------------------------------------------------- builds

    fn build_decl(&mut self) -> BuildDecl {
        let start = self.span();
        self.eat_ident("build");
        let name = self.ident();
        let mut order = BuildOrder::Pre;
        let mut order_span = None;
        if self.eat("[") {
            let s = self.span();
            assert!(self.eat_ident("order"));
            self.expect("=");
            order = if self.ident().name == "post" {
                BuildOrder::Post
            } else {
                BuildOrder::Pre
            };
            order_span = Some(s.to(self.prev()));
            self.expect("]");
        }
        self.expect("{");
        let mut root = None;
        let mut variants = Vec::new();
        while !self.eat("}") {
            if self.eat(";") {
                continue;
            }
            let s = self.span();
            assert!(self.eat_ident("build"));
            if self.is_ident("root") {
                self.pos += 1;
                let body = self.block();
                root = Some(BuildRoot {
                    body,
                    span: s.to(self.prev()),
                });
            } else {
                let vname = self.ident();
                let params = if self.is("(") {
                    self.fields()
                } else {
                    Vec::new()
                };
                let body = self.block();
                variants.push(BuildVariant {
                    name: vname,
                    params,
                    body,
                    span: s.to(self.prev()),
                });
            }
        }
        let span = start.to(self.prev());
        self.eat(";");
        BuildDecl {
            name,
            order,
            order_span,
            root,
            variants,
            span,
        }
    }

    fn block(&mut self) -> Vec<Stmt> {
        self.expect("{");
        let mut out = Vec::new();
        while !self.eat("}") {
            if self.eat(";") {
                continue;
            }
            out.push(self.stmt());
        }
        out
    }

    fn stmt(&mut self) -> Stmt {
        let start = self.span();
        let kind = if self.is_ident("build") {
            self.pos += 1;
            let field = self.ident();
            let value = if self.eat("=") {
                Some(self.expr())
            } else {
                None
            };
            StmtKind::Build { field, value }
        } else if self.eat_ident("let") {
            let name = self.ident();
            let ty = if self.eat(":") { Some(self.ty()) } else { None };
            self.expect("=");
            StmtKind::Let {
                name,
                ty,
                value: self.expr(),
            }
        } else if self.eat_ident("return") {
            if self.is(";") || self.is("}") {
                StmtKind::Return(None)
            } else {
                StmtKind::Return(Some(self.expr()))
            }
        } else if self.eat_ident("if") {
            let mut branches = Vec::new();
            let c = self.expr();
            let b = self.block_stmt();
            branches.push((c, b));
            let mut otherwise = None;
            loop {
                if self.eat_ident("elif") {
                    let c = self.expr();
                    let b = self.block_stmt();
                    branches.push((c, b));
                } else if self.eat_ident("else") {
                    otherwise = Some(Box::new(self.block_stmt()));
                    break;
                } else {
                    break;
                }
            }
            StmtKind::If {
                branches,
                otherwise,
            }
        } else if self.eat_ident("foreach") {
            let var = self.ident();
            assert!(self.eat_ident("in"));
            let iter = self.expr();
            StmtKind::Foreach {
                var,
                iter,
                body: Box::new(self.block_stmt()),
            }
        } else if self.is("{") {
            StmtKind::Block(self.block())
        } else {
            let e = self.expr();
            if self.eat("=") {
                StmtKind::Assign {
                    target: e,
                    value: self.expr(),
                }
            } else {
                StmtKind::Expr(e)
            }
        };
        let span = start.to(self.prev());
        self.eat(";");
        Stmt {
            id: self.id(),
            kind,
            span,
        }
    }

    fn block_stmt(&mut self) -> Stmt {
        let start = self.span();
        let body = self.block();
        Stmt {
            id: self.id(),
            kind: StmtKind::Block(body),
            span: start.to(self.prev()),
        }
    }

    // ---------------------------------------------------------------- expressions

    fn mk(&mut self, kind: ExprKind, span: Span) -> Expr {
        Expr {
            id: self.id(),
            kind,
            span,
        }
    }

    fn expr(&mut self) -> Expr {
        self.binary(0)
    }

    fn binop(&self, level: usize) -> Option<BinaryOp> {
        use BinaryOp::*;
        let Some(Tok::Punct(p)) = self.peek() else {
            return None;
        };
        let table: &[(&str, BinaryOp)] = match level {
            0 => &[("||", Or)],
            1 => &[("&&", And)],
            2 => &[
                ("==", Eq),
                ("!=", Ne),
                ("<=", Le),
                (">=", Ge),
                ("<", Lt),
                (">", Gt),
            ],
            3 => &[("|", BitOr)],
            4 => &[("^", BitXor)],
            5 => &[("&", BitAnd)],
            6 => &[("<<", Shl), (">>", Shr)],
            7 => &[("+", Add), ("-", Sub)],
            8 => &[("*", Mul), ("/", Div), ("%", Rem)],
            _ => &[],
        };
        table.iter().find(|(s, _)| s == p).map(|(_, o)| *o)
    }

    fn binary(&mut self, level: usize) -> Expr {
        if level > 8 {
            return self.unary();
        }
        let mut lhs = self.binary(level + 1);
        while let Some(op) = self.binop(level) {
            self.pos += 1;
            let rhs = self.binary(level + 1);
            let span = lhs.span.to(rhs.span);
            lhs = self.mk(
                ExprKind::Binary {
                    op,
                    lhs: Box::new(lhs),
                    rhs: Box::new(rhs),
                },
                span,
            );
        }
        lhs
    }

    fn unary(&mut self) -> Expr {
        let start = self.span();
        let op = if self.eat("-") {
            Some(UnaryOp::Neg)
        } else if self.eat("!") {
            Some(UnaryOp::Not)
        } else if self.eat("~") {
            Some(UnaryOp::BitNot)
        } else {
            None
        };
        if let Some(op) = op {
            let e = self.unary();
            let span = start.to(e.span);
            return self.mk(
                ExprKind::Unary {
                    op,
                    operand: Box::new(e),
                },
                span,
            );
        }
        let mut e = self.postfix();
        loop {
            if self.eat_ident("as") {
                let ty = self.ty();
                let span = e.span.to(ty.span);
                e = self.mk(
                    ExprKind::Cast {
                        expr: Box::new(e),
                        ty,
                    },
                    span,
                );
            } else if self.eat_ident("to") {
                let ty = self.ty();
                let span = e.span.to(ty.span);
                e = self.mk(
                    ExprKind::BitCast {
                        expr: Box::new(e),
                        ty,
                    },
                    span,
                );
            } else {
                return e;
            }
        }
    }

    fn postfix(&mut self) -> Expr {
        let mut e = self.primary();
        loop {
            if self.eat(".") {
                let name = self.ident();
                let span = e.span.to(name.span);
                e = self.mk(
                    ExprKind::Field {
                        base: Box::new(e),
                        name,
                    },
                    span,
                );
            } else if self.eat("[") {
                let a = self.expr();
                if self.eat(":") {
                    let b = self.expr();
                    self.expect("]");
                    let span = e.span.to(self.prev());
                    e = self.mk(
                        ExprKind::Slice {
                            base: Box::new(e),
                            lo: Box::new(a),
                            hi: Box::new(b),
                        },
                        span,
                    );
                } else {
                    self.expect("]");
                    let span = e.span.to(self.prev());
                    e = self.mk(
                        ExprKind::Index {
                            base: Box::new(e),
                            index: Box::new(a),
                        },
                        span,
                    );
                }
            } else {
                return e;
            }
        }
    }

    fn primary(&mut self) -> Expr {
        let start = self.span();
        match self.peek().cloned() {
            Some(Tok::Int(n)) => {
                self.pos += 1;
                self.mk(ExprKind::Int(n), start)
            }
            Some(Tok::Float(f)) => {
                self.pos += 1;
                self.mk(ExprKind::Float(f), start)
            }
            Some(Tok::Punct("(")) => {
                self.pos += 1;
                let mut parts = Vec::new();
                while !self.eat(")") {
                    parts.push(self.expr());
                    self.eat(",");
                }
                let span = start.to(self.prev());
                if parts.len() == 1 {
                    parts.pop().unwrap()
                } else {
                    self.mk(ExprKind::Tuple(parts), span)
                }
            }
            Some(Tok::Ident(s)) => {
                let id = self.ident();
                match s.as_str() {
                    "inf" => self.mk(ExprKind::Float(f64::INFINITY), start),
                    "true" => self.mk(ExprKind::Bool(true), start),
                    "false" => self.mk(ExprKind::Bool(false), start),
                    "this" => self.mk(ExprKind::This, start),
                    "parent" => {
                        self.expect(".");
                        let x = self.ident();
                        let span = start.to(x.span);
                        self.mk(ExprKind::Parent(x), span)
                    }
                    "build" => {
                        let x = self.ident();
                        let span = start.to(x.span);
                        self.mk(ExprKind::Build(x), span)
                    }
                    _ if self.is("(") => {
                        self.pos += 1;
                        let mut args = Vec::new();
                        while !self.eat(")") {
                            args.push(self.expr());
                            self.eat(",");
                        }
                        let span = start.to(self.prev());
                        self.mk(ExprKind::Call { callee: id, args }, span)
                    }
                    _ => self.mk(ExprKind::Name(id), start),
                }
            }
            t => panic!("test parser: unexpected token {t:?} in an expression"),
        }
    }
}

fn vector_or_named(id: Ident) -> TypeExprKind {
    let n = &id.name;
    if let Some(x) = n.find('x') {
        let (elem, lanes) = (&n[..x], &n[x + 1..]);
        if crate::layout::types::primitive(elem).is_some() && !lanes.is_empty() {
            if let Ok(l) = lanes.parse::<u32>() {
                let elem = Ident {
                    name: elem.to_string(),
                    span: id.span,
                };
                return TypeExprKind::Vector { elem, lanes: l };
            }
        }
    }
    TypeExprKind::Named(id)
}
