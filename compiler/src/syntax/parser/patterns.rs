//! Patterns: match patterns of the traversal language (Figure 3: `Variant(x, y: T, _)`, a bare
//! `Variant`, `_`) and split patterns of the layout language (Figure 6: `n`, `-n`, `~ n`,
//! `< n`, `<= n`, `> n`, `>= n`, `_`).

use super::{PResult, Parser};
use crate::syntax::ast::{Pattern, PatternKind, SplitPattern, SplitPatternKind};
use crate::syntax::errors::SyntaxError;
use crate::syntax::token::TokenKind;
use scion_ir::diag::Span;

impl Parser<'_> {
    fn mk_pattern(&mut self, kind: PatternKind, span: Span) -> Pattern {
        Pattern {
            id: self.fresh_id(),
            kind,
            span,
        }
    }

    /// A match arm's pattern: `_`, `Variant` or `Variant(p, ...)`.
    pub(crate) fn match_pattern(&mut self) -> PResult<Pattern> {
        let start = self.span();
        if self.eat(&TokenKind::Underscore) {
            return Ok(self.mk_pattern(PatternKind::Wildcard, start));
        }
        let name = self.ident("a pattern (`Variant(...)` or `_`)")?;
        let mut fields = Vec::new();
        if self.eat(&TokenKind::LParen) {
            fields = self.comma_list(TokenKind::RParen, |p| p.sub_pattern())?;
        }
        let span = start.to(self.prev_span());
        Ok(self.mk_pattern(PatternKind::Variant { name, fields }, span))
    }

    /// Inside `Variant(...)`: `_`, `x` or `x: T`.
    fn sub_pattern(&mut self) -> PResult<Pattern> {
        let start = self.span();
        if self.eat(&TokenKind::Underscore) {
            return Ok(self.mk_pattern(PatternKind::Wildcard, start));
        }
        let name = self.ident("a binding name or `_`")?;
        let ty = if self.eat(&TokenKind::Colon) {
            Some(self.ty()?)
        } else {
            None
        };
        let span = start.to(self.prev_span());
        Ok(self.mk_pattern(PatternKind::Bind { name, ty }, span))
    }

    /// A split arm's pattern.
    pub(crate) fn split_pattern(&mut self) -> PResult<SplitPattern> {
        let start = self.span();
        let kind = match self.peek() {
            TokenKind::Underscore => {
                self.bump();
                SplitPatternKind::Wildcard
            }
            TokenKind::Int(_) | TokenKind::Minus => SplitPatternKind::Eq(self.signed_literal()?),
            TokenKind::Tilde => {
                self.bump();
                SplitPatternKind::Ne(self.signed_literal()?)
            }
            TokenKind::Lt => {
                self.bump();
                SplitPatternKind::Lt(self.signed_literal()?)
            }
            TokenKind::Le => {
                self.bump();
                SplitPatternKind::Le(self.signed_literal()?)
            }
            TokenKind::Gt => {
                self.bump();
                SplitPatternKind::Gt(self.signed_literal()?)
            }
            TokenKind::Ge => {
                self.bump();
                SplitPatternKind::Ge(self.signed_literal()?)
            }
            _ => {
                return Err(self
                    .expected("a split pattern (`n`, `~ n`, `< n`, `<= n`, `> n`, `>= n` or `_`)"))
            }
        };
        Ok(SplitPattern {
            kind,
            span: start.to(self.prev_span()),
        })
    }

    /// `n` or `-n` as an `i128`.
    fn signed_literal(&mut self) -> PResult<i128> {
        let start = self.span();
        let negative = self.eat(&TokenKind::Minus);
        let TokenKind::Int(v) = *self.peek() else {
            return Err(self.expected("an integer literal"));
        };
        self.bump();
        let span = start.to(self.prev_span());
        let value = if negative {
            // -2^127 is the one negative value whose magnitude is no `i128`.
            0i128.checked_sub_unsigned(v)
        } else {
            i128::try_from(v).ok()
        };
        match value {
            Some(n) => Ok(n),
            None => {
                self.report_at_node(SyntaxError::IntegerTooLarge {
                    text: format!("{}{v}", if negative { "-" } else { "" }),
                    max: if negative { i128::MIN } else { i128::MAX }.to_string(),
                    what: "split pattern literal",
                    span,
                });
                Ok(0)
            }
        }
    }
}
