//! Statements of the traversal language (Figure 3) and the build language (Figure 10):
//! expressions, assignments (including `this[a:b] = e`), `let`, `return`, `if`/`elif`/`else`,
//! `foreach`, `match`, blocks, and `build x` / `build x = e`.

use super::{PResult, Parser};
use crate::syntax::ast::{Expr, ExprKind, MatchArm, Stmt, StmtKind};
use crate::syntax::errors::SyntaxError;
use crate::syntax::token::{Keyword, TokenKind};
use scion_ir::diag::Span;

/// The parts of an `if`: each condition with its block, and the `else` block.
pub(crate) type IfParts = (Vec<(Expr, Stmt)>, Option<Box<Stmt>>);

impl Parser<'_> {
    pub(crate) fn mk_stmt(&mut self, kind: StmtKind, span: Span) -> Stmt {
        Stmt {
            id: self.fresh_id(),
            kind,
            span,
        }
    }

    /// One statement.
    pub(crate) fn stmt(&mut self) -> PResult<Stmt> {
        self.nested(|p| p.stmt_inner())
    }

    fn stmt_inner(&mut self) -> PResult<Stmt> {
        let start = self.span();
        match self.peek() {
            TokenKind::LBrace => {
                self.bump();
                let body = self.block_rest();
                let span = start.to(self.prev_span());
                Ok(self.mk_stmt(StmtKind::Block(body), span))
            }
            TokenKind::Keyword(Keyword::Let) => {
                self.bump();
                let mutable = self.eat_kw(Keyword::Mut);
                let name = self.ident("a name after `let`")?;
                let ty = if self.eat(&TokenKind::Colon) {
                    Some(self.ty()?)
                } else {
                    None
                };
                self.expect(&TokenKind::Assign)?;
                let value = self.expr()?;
                let span = start.to(value.span);
                Ok(self.mk_stmt(
                    StmtKind::Let {
                        name,
                        ty,
                        value,
                        mutable,
                    },
                    span,
                ))
            }
            TokenKind::Keyword(Keyword::Return) => {
                self.bump();
                let value = if self.at_expr_start() {
                    Some(self.expr()?)
                } else {
                    None
                };
                let span = value.as_ref().map_or(start, |v| start.to(v.span));
                Ok(self.mk_stmt(StmtKind::Return(value), span))
            }
            TokenKind::Keyword(Keyword::If) => self.if_stmt(start),
            TokenKind::Keyword(Keyword::Foreach) => {
                self.bump();
                let var = self.ident("the loop variable")?;
                let index = if self.eat(&TokenKind::Comma) {
                    Some(self.ident("the index variable")?)
                } else {
                    None
                };
                self.expect_kw(Keyword::In)?;
                let iter = self.expr_free()?;
                let body = self.block_stmt()?;
                let span = start.to(body.span);
                Ok(self.mk_stmt(
                    StmtKind::Foreach {
                        var,
                        index,
                        iter,
                        body: Box::new(body),
                    },
                    span,
                ))
            }
            TokenKind::Keyword(Keyword::Match) => self.match_stmt(start),
            TokenKind::Keyword(Keyword::Build)
                if matches!(self.peek_at(1), TokenKind::Ident(_)) =>
            {
                self.bump();
                let field = self.ident("a field name")?;
                let value = if self.eat(&TokenKind::Assign) {
                    Some(self.expr()?)
                } else {
                    None
                };
                let span = value
                    .as_ref()
                    .map_or(start.to(field.span), |v| start.to(v.span));
                Ok(self.mk_stmt(StmtKind::Build { field, value }, span))
            }
            _ if self.at_expr_start() => {
                let target = self.expr()?;
                if !self.eat(&TokenKind::Assign) {
                    let span = target.span;
                    return Ok(self.mk_stmt(StmtKind::Expr(target), span));
                }
                if !is_assignable(&target) {
                    self.report_at_node(SyntaxError::InvalidAssignTarget { span: target.span });
                }
                let value = self.expr()?;
                let span = target.span.to(value.span);
                Ok(self.mk_stmt(StmtKind::Assign { target, value }, span))
            }
            _ => Err(self.expected("a statement")),
        }
    }

    /// After `{`: statements up to and including the closing `}`.
    pub(crate) fn block_rest(&mut self) -> Vec<Stmt> {
        self.braced_list("a statement", |p| p.stmt())
    }

    /// A `{ ... }` block as a statement (the body of `if`, `elif`, `else`, `foreach`).
    fn block_stmt(&mut self) -> PResult<Stmt> {
        let start = self.expect(&TokenKind::LBrace)?;
        let body = self.nested(|p| Ok(p.block_rest()))?;
        let span = start.to(self.prev_span());
        Ok(self.mk_stmt(StmtKind::Block(body), span))
    }

    fn if_stmt(&mut self, start: Span) -> PResult<Stmt> {
        let (branches, otherwise) = self.if_parts()?;
        let span = start.to(self.prev_span());
        Ok(self.mk_stmt(
            StmtKind::If {
                branches,
                otherwise,
            },
            span,
        ))
    }

    /// After `if`: the conditions with their blocks and the `else` block, if any.
    pub(crate) fn if_parts(&mut self) -> PResult<IfParts> {
        self.bump();
        let mut branches = Vec::new();
        let cond = self.expr_free()?;
        let body = self.block_stmt()?;
        branches.push((cond, body));
        let mut otherwise = None;
        loop {
            if self.eat_kw(Keyword::Elif) {
                let cond = self.expr_free()?;
                let body = self.block_stmt()?;
                branches.push((cond, body));
            } else if self.eat_kw(Keyword::Else) {
                if self.at_kw(Keyword::If) {
                    return Err(self.expected("`{` (`else if` is written `elif`)"));
                }
                otherwise = Some(Box::new(self.block_stmt()?));
                break;
            } else {
                break;
            }
        }
        Ok((branches, otherwise))
    }

    /// `match e { | P -> s | P -> s ... }` (the `|` before the first arm is optional).
    fn match_stmt(&mut self, start: Span) -> PResult<Stmt> {
        self.bump();
        let scrutinee = self.expr_free()?;
        self.expect(&TokenKind::LBrace)?;
        let arms = self.with_no_bar(false, |p| p.match_arms());
        let span = start.to(self.prev_span());
        Ok(self.mk_stmt(StmtKind::Match { scrutinee, arms }, span))
    }

    /// After `match e {`: arms up to and including `}`.
    fn match_arms(&mut self) -> Vec<MatchArm> {
        let mut arms = Vec::new();
        self.eat(&TokenKind::Bar);
        loop {
            if self.at(&TokenKind::RBrace) && !arms.is_empty() {
                self.bump();
                return arms;
            }
            if self.at_eof() || self.at_item_anchor() {
                self.expected("`}`");
                return arms;
            }
            let start = self.pos;
            match self.match_arm() {
                Ok(arm) => {
                    arms.push(arm);
                    self.eat(&TokenKind::Semi);
                    if !self.at(&TokenKind::Bar) && !self.at(&TokenKind::RBrace) {
                        self.expected_separator("`|` (the next arm) or `}`");
                        self.skip_until(&[TokenKind::Bar]);
                    }
                }
                Err(_) => self.skip_until(&[TokenKind::Bar]),
            }
            if self.eat(&TokenKind::Bar) {
                continue;
            }
            if self.at(&TokenKind::RBrace) {
                self.bump();
                return arms;
            }
            if self.pos == start {
                self.bump();
            }
        }
    }

    fn match_arm(&mut self) -> PResult<MatchArm> {
        let pattern = self.match_pattern()?;
        self.expect(&TokenKind::Arrow)?;
        let body = self.with_no_bar(true, |p| p.stmt())?;
        let span = pattern.span.to(body.span);
        Ok(MatchArm {
            pattern,
            body,
            span,
        })
    }
}

/// The forms `=` may write to: a name, a field, an element or a bit range (`this[a:b]`).
fn is_assignable(e: &Expr) -> bool {
    match &e.kind {
        ExprKind::Name(_) => true,
        ExprKind::Field { base, .. }
        | ExprKind::Index { base, .. }
        | ExprKind::Slice { base, .. } => {
            is_assignable(base) || matches!(base.kind, ExprKind::This)
        }
        _ => false,
    }
}
