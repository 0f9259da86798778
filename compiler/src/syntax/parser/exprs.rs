//! Expressions of the three languages, by precedence climbing (docs/language.md, loosest
//! first): `||`; `&&`; comparisons (non-associative); `|`; `^`; `&`; `<< >>`; `+ -`;
//! `* / %`; prefix `- ! ~`; postfix `as T` / `to T`; then calls, fields, indexing and slicing.
//!
//! Inside a match arm's body the parser's `no_bar` restriction stops the climb at a top-level
//! `|`, which starts the next arm; parentheses, brackets and call arguments lift it.

use super::{Fail, PResult, Parser};
use crate::syntax::ast::{BinaryOp, Expr, ExprKind, Ident, UnaryOp};
use crate::syntax::errors::SyntaxError;
use crate::syntax::token::{Keyword, TokenKind};
use scion_ir::diag::Span;

/// Binding strength of a binary operator (higher binds tighter).
pub(crate) fn binary_prec(op: BinaryOp) -> u8 {
    use BinaryOp::*;
    match op {
        Or => 1,
        And => 2,
        Eq | Ne | Lt | Le | Gt | Ge => 3,
        BitOr => 4,
        BitXor => 5,
        BitAnd => 6,
        Shl | Shr => 7,
        Add | Sub => 8,
        Mul | Div | Rem => 9,
    }
}

/// True for the non-associative comparison operators.
pub(crate) fn is_comparison(op: BinaryOp) -> bool {
    binary_prec(op) == 3
}

fn binary_op(kind: &TokenKind) -> Option<BinaryOp> {
    use BinaryOp::*;
    Some(match kind {
        TokenKind::BarBar => Or,
        TokenKind::AmpAmp => And,
        TokenKind::EqEq => Eq,
        TokenKind::NotEq => Ne,
        TokenKind::Lt => Lt,
        TokenKind::Le => Le,
        TokenKind::Gt => Gt,
        TokenKind::Ge => Ge,
        TokenKind::Bar => BitOr,
        TokenKind::Caret => BitXor,
        TokenKind::Amp => BitAnd,
        TokenKind::Shl => Shl,
        TokenKind::Shr => Shr,
        TokenKind::Plus => Add,
        TokenKind::Minus => Sub,
        TokenKind::Star => Mul,
        TokenKind::Slash => Div,
        TokenKind::Percent => Rem,
        _ => return None,
    })
}

impl Parser<'_> {
    /// True when the current token can start an expression.
    pub(crate) fn at_expr_start(&self) -> bool {
        match self.peek() {
            TokenKind::Ident(_)
            | TokenKind::Vector { .. }
            | TokenKind::Int(_)
            | TokenKind::Float(_)
            | TokenKind::LParen
            | TokenKind::LBracket
            | TokenKind::Minus
            | TokenKind::Bang
            | TokenKind::Tilde => true,
            TokenKind::Keyword(k) => matches!(
                k,
                Keyword::This
                    | Keyword::Parent
                    | Keyword::Build
                    | Keyword::If
                    | Keyword::True
                    | Keyword::False
                    | Keyword::Inf
            ),
            _ => false,
        }
    }

    pub(crate) fn mk_expr(&mut self, kind: ExprKind, span: Span) -> Expr {
        Expr {
            id: self.fresh_id(),
            kind,
            span,
        }
    }

    /// An expression.
    pub(crate) fn expr(&mut self) -> PResult<Expr> {
        self.expr_prec(0)
    }

    /// An expression without the match-arm restriction on `|`.
    pub(crate) fn expr_free(&mut self) -> PResult<Expr> {
        self.with_no_bar(false, |p| p.expr())
    }

    fn expr_prec(&mut self, min_prec: u8) -> PResult<Expr> {
        self.nested(|p| p.chained(|p| p.binary_chain(min_prec)))
    }

    fn binary_chain(&mut self, min_prec: u8) -> PResult<Expr> {
        let mut lhs = self.unary()?;
        // The span of the comparison just built at this level, to reject `a < b < c`.
        let mut last_comparison: Option<Span> = None;
        while let Some(op) = binary_op(self.peek()) {
            let prec = binary_prec(op);
            if prec < min_prec || (op == BinaryOp::BitOr && self.no_bar) {
                break;
            }
            let op_span = self.span();
            self.deepen()?;
            self.bump();
            if is_comparison(op) {
                if let Some(first) = last_comparison {
                    self.report_at_node(SyntaxError::ChainedComparison {
                        op: op.as_str(),
                        span: op_span,
                        first,
                    });
                }
                last_comparison = Some(op_span);
            } else {
                last_comparison = None;
            }
            let rhs = self.expr_prec(prec + 1)?;
            let span = lhs.span.to(rhs.span);
            let kind = ExprKind::Binary {
                op,
                lhs: Box::new(lhs),
                rhs: Box::new(rhs),
            };
            lhs = self.mk_expr(kind, span);
        }
        Ok(lhs)
    }

    fn unary(&mut self) -> PResult<Expr> {
        let op = match self.peek() {
            TokenKind::Minus => UnaryOp::Neg,
            TokenKind::Bang => UnaryOp::Not,
            TokenKind::Tilde => UnaryOp::BitNot,
            _ => return self.cast(),
        };
        let start = self.span();
        self.bump();
        let operand = self.nested(|p| p.unary())?;
        let span = start.to(operand.span);
        Ok(self.mk_expr(
            ExprKind::Unary {
                op,
                operand: Box::new(operand),
            },
            span,
        ))
    }

    fn cast(&mut self) -> PResult<Expr> {
        self.chained(|p| p.cast_chain())
    }

    fn cast_chain(&mut self) -> PResult<Expr> {
        let mut e = self.postfix()?;
        loop {
            let bitcast = if self.at_kw(Keyword::As) {
                false
            } else if self.at_kw(Keyword::To) {
                true
            } else {
                break;
            };
            self.deepen()?;
            self.bump();
            let ty = self.ty()?;
            let span = e.span.to(ty.span);
            let kind = if bitcast {
                ExprKind::BitCast {
                    expr: Box::new(e),
                    ty,
                }
            } else {
                ExprKind::Cast {
                    expr: Box::new(e),
                    ty,
                }
            };
            e = self.mk_expr(kind, span);
        }
        Ok(e)
    }

    fn postfix(&mut self) -> PResult<Expr> {
        let mut e = self.primary()?;
        loop {
            if matches!(self.peek(), TokenKind::Dot | TokenKind::LBracket) {
                self.deepen()?;
            }
            match self.peek() {
                TokenKind::Dot => {
                    self.bump();
                    let name = self.ident("a field name")?;
                    let span = e.span.to(name.span);
                    e = self.mk_expr(
                        ExprKind::Field {
                            base: Box::new(e),
                            name,
                        },
                        span,
                    );
                }
                TokenKind::LBracket => {
                    self.bump();
                    e = self.with_no_bar(false, |p| p.index_or_slice(e))?;
                }
                TokenKind::LParen => {
                    // `(f)(x)`, `a.f(x)`: report, then read the arguments to stay in sync.
                    self.report(SyntaxError::NotCallable { span: e.span });
                    self.bump();
                    self.comma_list(TokenKind::RParen, |p| p.expr())?;
                    return Err(Fail);
                }
                _ => return Ok(e),
            }
        }
    }

    /// After `base[`: `i]` or `a:b]`.
    fn index_or_slice(&mut self, base: Expr) -> PResult<Expr> {
        let first = self.expr()?;
        if self.eat(&TokenKind::Colon) {
            let hi = self.expr()?;
            let close = self.expect(&TokenKind::RBracket)?;
            let span = base.span.to(close);
            let kind = ExprKind::Slice {
                base: Box::new(base),
                lo: Box::new(first),
                hi: Box::new(hi),
            };
            return Ok(self.mk_expr(kind, span));
        }
        if !self.at(&TokenKind::RBracket) {
            return Err(self.expected("`]` or `:`"));
        }
        self.bump();
        let span = base.span.to(self.prev_span());
        Ok(self.mk_expr(
            ExprKind::Index {
                base: Box::new(base),
                index: Box::new(first),
            },
            span,
        ))
    }

    fn primary(&mut self) -> PResult<Expr> {
        let start = self.span();
        let kind = match self.peek().clone() {
            TokenKind::Ident(name) => {
                self.bump();
                return self.name_or_call(Ident { name, span: start });
            }
            TokenKind::Vector { elem, lanes } => {
                self.bump();
                return self.name_or_call(Ident {
                    name: format!("{elem}x{lanes}"),
                    span: start,
                });
            }
            TokenKind::Int(v) => {
                self.bump();
                ExprKind::Int(v)
            }
            TokenKind::Float(v) => {
                self.bump();
                ExprKind::Float(v)
            }
            TokenKind::Keyword(Keyword::Inf) => {
                self.bump();
                ExprKind::Float(f64::INFINITY)
            }
            TokenKind::Keyword(Keyword::True) => {
                self.bump();
                ExprKind::Bool(true)
            }
            TokenKind::Keyword(Keyword::False) => {
                self.bump();
                ExprKind::Bool(false)
            }
            TokenKind::Keyword(Keyword::This) => {
                self.bump();
                ExprKind::This
            }
            TokenKind::Keyword(Keyword::Parent) => {
                self.bump();
                self.expect(&TokenKind::Dot)?;
                let name = self.ident("a field name after `parent.`")?;
                let span = start.to(name.span);
                return Ok(self.mk_expr(ExprKind::Parent(name), span));
            }
            TokenKind::Keyword(Keyword::Build) => {
                self.bump();
                let name = self.ident("the name of a child field after `build`")?;
                let span = start.to(name.span);
                return Ok(self.mk_expr(ExprKind::Build(name), span));
            }
            TokenKind::LParen => {
                self.bump();
                return self.paren_or_tuple(start);
            }
            TokenKind::LBracket => {
                self.bump();
                let elems = self.comma_list(TokenKind::RBracket, |p| p.expr())?;
                let span = start.to(self.prev_span());
                return Ok(self.mk_expr(ExprKind::Array(elems), span));
            }
            TokenKind::Keyword(Keyword::If) => {
                let (branches, otherwise) = self.with_no_bar(false, |p| p.if_parts())?;
                let Some(otherwise) = otherwise else {
                    return Err(self.expected("`else` (an `if` expression needs one)"));
                };
                let span = start.to(self.prev_span());
                return Ok(self.mk_expr(
                    ExprKind::If {
                        branches,
                        otherwise,
                    },
                    span,
                ));
            }
            _ => return Err(self.expected("an expression")),
        };
        Ok(self.mk_expr(kind, start))
    }

    fn name_or_call(&mut self, name: Ident) -> PResult<Expr> {
        if !self.at(&TokenKind::LParen) {
            let span = name.span;
            return Ok(self.mk_expr(ExprKind::Name(name), span));
        }
        self.bump();
        let args = self.comma_list(TokenKind::RParen, |p| p.expr())?;
        let span = name.span.to(self.prev_span());
        Ok(self.mk_expr(ExprKind::Call { callee: name, args }, span))
    }

    /// After `(`: `()`, `(e)` (grouping) or `(a, b, ...)`.
    fn paren_or_tuple(&mut self, start: Span) -> PResult<Expr> {
        let elems = self.comma_list(TokenKind::RParen, |p| p.expr())?;
        let span = start.to(self.prev_span());
        let trailing_comma = self.closed_after_comma();
        if elems.len() == 1 {
            if trailing_comma {
                self.report_at_node(SyntaxError::OneElementTuple {
                    what: "value",
                    span,
                });
            }
            let mut only = elems.into_iter().next().ok_or(Fail)?;
            only.span = span;
            return Ok(only);
        }
        Ok(self.mk_expr(ExprKind::Tuple(elems), span))
    }
}
