//! The AST printer behind `scionc --emit=ast`: prints a [`Program`] back as Scion source in one
//! canonical form: two-space indentation; every layout member (but `---`), split arm, build
//! entry and item followed by `;`; parentheses only where precedence or the match-arm rule on
//! `|` needs them; integers in decimal; floats in their shortest round-trip form.
//!
//! Invariant (tested on every library file): parsing the printed text gives back the same tree
//! up to spans and node ids, so printing it again gives the same text.

use super::ast::*;
use super::parser::{binary_prec, is_comparison};

/// Prints a whole program, items separated by blank lines.
pub fn print_program(program: &Program) -> String {
    let mut p = Printer::default();
    for (i, item) in program.items.iter().enumerate() {
        if i > 0 {
            p.out.push('\n');
        }
        p.item(item);
    }
    p.out
}

/// Prints one expression (outermost level, no parentheses).
pub fn print_expr(e: &Expr) -> String {
    let mut p = Printer::default();
    p.expr(e, 0, false);
    p.out
}

/// Prints one written type.
pub fn print_type(t: &TypeExpr) -> String {
    let mut p = Printer::default();
    p.ty(t);
    p.out
}

/// Prints one statement at indentation level 0 (no trailing `;`).
pub fn print_stmt(s: &Stmt) -> String {
    let mut p = Printer::default();
    p.stmt(s, false);
    p.out
}

const PREC_UNARY: u8 = 10;
const PREC_CAST: u8 = 11;
const PREC_POSTFIX: u8 = 12;
const PREC_ATOM: u8 = 13;

fn expr_prec(e: &Expr) -> u8 {
    match &e.kind {
        ExprKind::Binary { op, .. } => binary_prec(*op),
        ExprKind::Unary { .. } => PREC_UNARY,
        ExprKind::Cast { .. } | ExprKind::BitCast { .. } => PREC_CAST,
        ExprKind::Field { .. }
        | ExprKind::Index { .. }
        | ExprKind::Slice { .. }
        | ExprKind::Call { .. } => PREC_POSTFIX,
        ExprKind::Name(_)
        | ExprKind::Int(_)
        | ExprKind::Float(_)
        | ExprKind::Bool(_)
        | ExprKind::Tuple(_)
        | ExprKind::Array(_)
        | ExprKind::This
        | ExprKind::Parent(_)
        | ExprKind::Build(_)
        | ExprKind::If { .. } => PREC_ATOM,
    }
}

/// True when `e` prints starting with the keyword `build` (`build x + 1`, `build x.y`) or `if`
/// (`if c { a } else { b } + 1`): as a statement that would read as a `build x` or an `if`
/// statement, so it is parenthesized there.
fn starts_with_build(e: &Expr) -> bool {
    match &e.kind {
        ExprKind::Build(_) | ExprKind::If { .. } => true,
        ExprKind::Binary { lhs: inner, .. }
        | ExprKind::Field { base: inner, .. }
        | ExprKind::Index { base: inner, .. }
        | ExprKind::Slice { base: inner, .. }
        | ExprKind::Cast { expr: inner, .. }
        | ExprKind::BitCast { expr: inner, .. } => starts_with_build(inner),
        _ => false,
    }
}

fn ends_in_brace(s: &Stmt) -> bool {
    match &s.kind {
        StmtKind::Block(_)
        | StmtKind::Match { .. }
        | StmtKind::If { .. }
        | StmtKind::Foreach { .. } => true,
        StmtKind::Expr(_)
        | StmtKind::Assign { .. }
        | StmtKind::Return(_)
        | StmtKind::Let { .. }
        | StmtKind::Build { .. } => false,
    }
}

#[derive(Default)]
struct Printer {
    out: String,
    indent: usize,
}

impl Printer {
    fn w(&mut self, s: &str) {
        self.out.push_str(s);
    }

    fn newline(&mut self) {
        self.out.push('\n');
        for _ in 0..self.indent {
            self.out.push_str("  ");
        }
    }

    fn sep_list<T>(&mut self, items: &[T], mut f: impl FnMut(&mut Self, &T)) {
        for (i, item) in items.iter().enumerate() {
            if i > 0 {
                self.w(", ");
            }
            f(self, item);
        }
    }

    // --- Items ------------------------------------------------------------------------------

    fn item(&mut self, item: &Item) {
        match item {
            Item::Type(d) => {
                self.w("type ");
                self.w(&d.name.name);
                if d.variants.is_none() || !d.fields.is_empty() {
                    self.fields(&d.fields);
                }
                if let Some(variants) = &d.variants {
                    self.w(" = ");
                    for (i, v) in variants.iter().enumerate() {
                        if i > 0 {
                            self.w(" | ");
                        }
                        self.w(&v.name.name);
                        if !v.fields.is_empty() {
                            self.fields(&v.fields);
                        }
                    }
                }
                self.w(";\n");
            }
            Item::Func(d) => {
                self.w("func ");
                self.w(&d.name.name);
                self.w("(");
                self.sep_list(&d.params, |p, param| {
                    p.w(&param.name.name);
                    p.w(": ");
                    if param.mutable {
                        p.w("mut ");
                    }
                    p.ty(&param.ty);
                    if let Some(d) = &param.default {
                        p.w(" = ");
                        p.expr(d, 0, false);
                    }
                });
                self.w(")");
                if let Some(ret) = &d.ret {
                    self.w(" -> ");
                    self.ty(ret);
                }
                if let Some(k) = &d.order_by {
                    self.w(" order by ");
                    self.w(&k.name);
                }
                self.w(" = ");
                self.stmt(&d.body, false);
                if !ends_in_brace(&d.body) {
                    self.w(";");
                }
                self.w("\n");
            }
            Item::Layout(d) => self.layout(d),
            Item::Build(d) => self.build(d),
        }
    }

    fn fields(&mut self, fields: &[FieldDecl]) {
        self.w("(");
        self.sep_list(fields, |p, f| {
            p.w(&f.name.name);
            p.w(": ");
            p.ty(&f.ty);
            if let Some(d) = &f.default {
                p.w(" = ");
                p.expr(d, 0, false);
            }
        });
        self.w(")");
    }

    // --- Types and patterns -----------------------------------------------------------------

    fn ty(&mut self, t: &TypeExpr) {
        match &t.kind {
            TypeExprKind::Named(n) => self.w(&n.name),
            TypeExprKind::Vector { elem, lanes } => {
                self.w(&elem.name);
                self.w(&format!("x{lanes}"));
            }
            TypeExprKind::Array { elem, len } => {
                self.ty(elem);
                match len {
                    ArrayLen::Const(n, _) => self.w(&format!("[{n}]")),
                    ArrayLen::Name(n) => {
                        self.w("[");
                        self.w(&n.name);
                        self.w("]");
                    }
                }
            }
            TypeExprKind::Tuple(elems) => {
                self.w("(");
                self.sep_list(elems, |p, t| p.ty(t));
                self.w(")");
            }
            TypeExprKind::Set(inner) => {
                self.w("set[");
                self.ty(inner);
                self.w("]");
            }
            TypeExprKind::Option(inner) => {
                self.w("option[");
                self.ty(inner);
                self.w("]");
            }
        }
    }

    fn pattern(&mut self, pat: &Pattern) {
        match &pat.kind {
            PatternKind::Wildcard => self.w("_"),
            PatternKind::Bind { name, ty } => {
                self.w(&name.name);
                if let Some(t) = ty {
                    self.w(": ");
                    self.ty(t);
                }
            }
            PatternKind::Variant { name, fields } => {
                self.w(&name.name);
                if !fields.is_empty() {
                    self.w("(");
                    self.sep_list(fields, |p, f| p.pattern(f));
                    self.w(")");
                }
            }
        }
    }

    // --- Statements -------------------------------------------------------------------------

    /// Prints `s` at the current indentation, without a trailing `;`. `no_bar` is set for the
    /// body of a match arm, where a top-level `|` must be parenthesized.
    fn stmt(&mut self, s: &Stmt, no_bar: bool) {
        match &s.kind {
            StmtKind::Expr(e) => self.stmt_head_expr(e, no_bar),
            StmtKind::Assign { target, value } => {
                self.stmt_head_expr(target, no_bar);
                self.w(" = ");
                self.expr(value, 0, no_bar);
            }
            StmtKind::Block(stmts) => self.block(stmts),
            StmtKind::Return(value) => {
                self.w("return");
                if let Some(v) = value {
                    self.w(" ");
                    self.expr(v, 0, no_bar);
                }
            }
            StmtKind::Match { scrutinee, arms } => {
                self.w("match ");
                self.expr(scrutinee, 0, false);
                self.w(" {");
                self.indent += 1;
                for arm in arms {
                    self.newline();
                    self.w("| ");
                    self.pattern(&arm.pattern);
                    self.w(" ->");
                    if matches!(arm.body.kind, StmtKind::Block(_)) {
                        self.w(" ");
                        self.stmt(&arm.body, true);
                    } else {
                        self.indent += 1;
                        self.newline();
                        self.stmt(&arm.body, true);
                        self.indent -= 1;
                    }
                }
                self.indent -= 1;
                self.newline();
                self.w("}");
            }
            StmtKind::Let {
                name,
                ty,
                value,
                mutable,
            } => {
                self.w(if *mutable { "let mut " } else { "let " });
                self.w(&name.name);
                if let Some(t) = ty {
                    self.w(": ");
                    self.ty(t);
                }
                self.w(" = ");
                self.expr(value, 0, no_bar);
            }
            StmtKind::If {
                branches,
                otherwise,
            } => self.if_chain(branches, otherwise.as_deref()),
            StmtKind::Foreach {
                var,
                index,
                iter,
                body,
            } => {
                self.w("foreach ");
                self.w(&var.name);
                if let Some(k) = index {
                    self.w(", ");
                    self.w(&k.name);
                }
                self.w(" in ");
                self.expr(iter, 0, false);
                self.w(" ");
                self.block_like(body);
            }
            StmtKind::Build { field, value } => {
                self.w("build ");
                self.w(&field.name);
                if let Some(v) = value {
                    self.w(" = ");
                    self.expr(v, 0, no_bar);
                }
            }
        }
    }

    /// `if c { } elif c { } else { }`, as a statement or an expression.
    fn if_chain(&mut self, branches: &[(Expr, Stmt)], otherwise: Option<&Stmt>) {
        for (i, (cond, body)) in branches.iter().enumerate() {
            self.w(if i == 0 { "if " } else { " elif " });
            self.expr(cond, 0, false);
            self.w(" ");
            self.block_like(body);
        }
        if let Some(o) = otherwise {
            self.w(" else ");
            self.block_like(o);
        }
    }

    /// An expression that starts a statement: parenthesized when it starts with `build` or `if`.
    fn stmt_head_expr(&mut self, e: &Expr, no_bar: bool) {
        if starts_with_build(e) {
            self.w("(");
            self.expr(e, 0, false);
            self.w(")");
        } else {
            self.expr(e, 0, no_bar);
        }
    }

    /// A branch or loop body: a block as is, any other statement wrapped in braces.
    fn block_like(&mut self, s: &Stmt) {
        match &s.kind {
            StmtKind::Block(stmts) => self.block(stmts),
            _ => self.block(std::slice::from_ref(s)),
        }
    }

    fn block(&mut self, stmts: &[Stmt]) {
        if stmts.is_empty() {
            self.w("{}");
            return;
        }
        self.w("{");
        self.indent += 1;
        for s in stmts {
            self.newline();
            self.stmt(s, false);
            if !ends_in_brace(s) {
                self.w(";");
            }
        }
        self.indent -= 1;
        self.newline();
        self.w("}");
    }

    // --- Expressions ------------------------------------------------------------------------

    /// Prints `e` where the context binds with strength `ctx`: parenthesized when `e` binds
    /// more loosely, or when it is a `|` and `no_bar` (a match arm's body) is set.
    fn expr(&mut self, e: &Expr, ctx: u8, no_bar: bool) {
        let bar = matches!(
            e.kind,
            ExprKind::Binary {
                op: BinaryOp::BitOr,
                ..
            }
        );
        if expr_prec(e) < ctx || (no_bar && bar) {
            self.w("(");
            self.expr(e, 0, false);
            self.w(")");
            return;
        }
        match &e.kind {
            ExprKind::Name(n) => self.w(&n.name),
            ExprKind::Int(v) => self.w(&v.to_string()),
            ExprKind::Float(v) => {
                if v.is_infinite() {
                    self.w("inf");
                } else {
                    self.w(&format!("{v:?}"));
                }
            }
            ExprKind::Bool(b) => self.w(if *b { "true" } else { "false" }),
            ExprKind::If {
                branches,
                otherwise,
            } => self.if_chain(branches, Some(otherwise)),
            ExprKind::Call { callee, args } => {
                self.w(&callee.name);
                self.w("(");
                self.sep_list(args, |p, a| p.expr(a, 0, false));
                self.w(")");
            }
            ExprKind::Field { base, name } => {
                self.expr(base, PREC_POSTFIX, no_bar);
                self.w(".");
                self.w(&name.name);
            }
            ExprKind::Index { base, index } => {
                self.expr(base, PREC_POSTFIX, no_bar);
                self.w("[");
                self.expr(index, 0, false);
                self.w("]");
            }
            ExprKind::Slice { base, lo, hi } => {
                self.expr(base, PREC_POSTFIX, no_bar);
                self.w("[");
                self.expr(lo, 0, false);
                self.w(" : ");
                self.expr(hi, 0, false);
                self.w("]");
            }
            ExprKind::Tuple(elems) => {
                self.w("(");
                self.sep_list(elems, |p, a| p.expr(a, 0, false));
                self.w(")");
            }
            ExprKind::Array(elems) => {
                self.w("[");
                self.sep_list(elems, |p, a| p.expr(a, 0, false));
                self.w("]");
            }
            ExprKind::Unary { op, operand } => {
                self.w(match op {
                    UnaryOp::Neg => "-",
                    UnaryOp::Not => "!",
                    UnaryOp::BitNot => "~",
                });
                // `- -x` would print as `--x` and three minuses lex as `---`: parenthesize.
                let ctx = if matches!(operand.kind, ExprKind::Unary { .. }) {
                    PREC_ATOM
                } else {
                    PREC_UNARY
                };
                self.expr(operand, ctx, no_bar);
            }
            ExprKind::Binary { op, lhs, rhs } => {
                let prec = binary_prec(*op);
                let lhs_ctx = if is_comparison(*op) { prec + 1 } else { prec };
                self.expr(lhs, lhs_ctx, no_bar);
                self.w(" ");
                self.w(op.as_str());
                self.w(" ");
                self.expr(rhs, prec + 1, no_bar);
            }
            ExprKind::Cast { expr, ty } | ExprKind::BitCast { expr, ty } => {
                self.expr(expr, PREC_CAST, no_bar);
                self.w(if matches!(e.kind, ExprKind::Cast { .. }) {
                    " as "
                } else {
                    " to "
                });
                self.ty(ty);
            }
            ExprKind::This => self.w("this"),
            ExprKind::Parent(n) => {
                self.w("parent.");
                self.w(&n.name);
            }
            ExprKind::Build(n) => {
                self.w("build ");
                self.w(&n.name);
            }
        }
    }

    // --- Layouts and builds -----------------------------------------------------------------

    fn layout(&mut self, d: &LayoutDecl) {
        self.w("layout ");
        self.w(&d.name.name);
        self.w("(");
        self.sep_list(&d.params, |p, param| {
            p.w(&param.name.name);
            p.w(": ");
            p.ty(&param.ty);
            if let Some(e) = &param.default {
                p.w(" = ");
                p.expr(e, 0, false);
            }
        });
        self.w(") ");
        self.members(&d.members);
        self.w(";\n");
    }

    fn members(&mut self, members: &[Member]) {
        if members.is_empty() {
            self.w("{}");
            return;
        }
        self.w("{");
        self.indent += 1;
        for m in members {
            self.newline();
            self.member(m);
            if m.kind != MemberKind::Separator {
                self.w(";");
            }
        }
        self.indent -= 1;
        self.newline();
        self.w("}");
    }

    fn member(&mut self, m: &Member) {
        match &m.kind {
            MemberKind::Field { name, ty } => {
                self.w(&name.name);
                self.w(": ");
                self.ty(ty);
            }
            MemberKind::Padding { bytes } => self.w(&bytes.to_string()),
            MemberKind::Derived { name, value } => {
                self.w(&name.name);
                self.w(" = ");
                self.expr(value, 0, false);
            }
            MemberKind::Let { name, ty, value } => {
                self.w("let ");
                self.w(&name.name);
                if let Some(t) = ty {
                    self.w(": ");
                    self.ty(t);
                }
                self.w(" = ");
                self.expr(value, 0, false);
            }
            MemberKind::Group(g) => self.group(g),
            MemberKind::Separator => self.w("---"),
            MemberKind::Split { discriminant, arms } => {
                self.w("split ");
                self.expr(discriminant, 0, false);
                self.w(" {");
                self.indent += 1;
                for arm in arms {
                    self.newline();
                    self.split_arm(arm);
                    self.w(";");
                }
                self.indent -= 1;
                self.newline();
                self.w("}");
            }
        }
    }

    fn group(&mut self, g: &GroupDecl) {
        if g.indirect {
            self.w("indirect ");
        }
        self.w("group ");
        self.w(&g.name.name);
        if !g.attrs.is_empty() {
            self.w("[");
            self.sep_list(&g.attrs, |p, a| match &a.kind {
                GroupAttrKind::Count(n) => p.w(&n.to_string()),
                GroupAttrKind::Size(e) => {
                    p.w("size=");
                    p.expr(e, 0, false);
                }
                GroupAttrKind::Align(n) => p.w(&format!("align={n}")),
            });
            self.w("]");
        }
        if let Some(by) = &g.by {
            self.w(" by ");
            self.expr(by, 0, false);
        }
        self.w(" ");
        self.members(&g.members);
    }

    fn split_arm(&mut self, arm: &SplitArm) {
        let pat = match arm.pattern.kind {
            SplitPatternKind::Eq(n) => n.to_string(),
            SplitPatternKind::Ne(n) => format!("~ {n}"),
            SplitPatternKind::Lt(n) => format!("< {n}"),
            SplitPatternKind::Le(n) => format!("<= {n}"),
            SplitPatternKind::Gt(n) => format!("> {n}"),
            SplitPatternKind::Ge(n) => format!(">= {n}"),
            SplitPatternKind::Wildcard => "_".to_string(),
        };
        self.w(&pat);
        self.w(" -> ");
        match &arm.body {
            SplitArmBody::Members { variant, members } => {
                self.w(&variant.name);
                self.w(" ");
                self.members(members);
            }
            SplitArmBody::From {
                variant,
                group,
                key,
            } => {
                self.w(&variant.name);
                self.w(" from ");
                self.w(&group.name);
                self.w("[");
                self.expr(key, 0, false);
                self.w("]");
            }
        }
    }

    fn build(&mut self, d: &BuildDecl) {
        self.w("build ");
        self.w(&d.name.name);
        // `order=pre` is the default: print the attribute only when it was written.
        match d.order {
            BuildOrder::Pre if d.order_span.is_none() => self.w(" {"),
            BuildOrder::Pre => self.w("[order=pre] {"),
            BuildOrder::Post => self.w("[order=post] {"),
        }
        self.indent += 1;
        if let Some(root) = &d.root {
            self.newline();
            self.w("build root ");
            self.block(&root.body);
            self.w(";");
        }
        for v in &d.variants {
            self.newline();
            self.w("build ");
            self.w(&v.name.name);
            if !v.params.is_empty() {
                self.fields(&v.params);
            }
            self.w(" ");
            self.block(&v.body);
            self.w(";");
        }
        self.indent -= 1;
        self.newline();
        self.w("};\n");
    }
}
