//! Written types (Figure 3, `T`): names, vector words, tuples, arrays `T[n]` / `T[x]`,
//! `set[T]` and `option[T]`.

use super::{Fail, PResult, Parser};
use crate::syntax::ast::{ArrayLen, Ident, TypeExpr, TypeExprKind};
use crate::syntax::errors::SyntaxError;
use crate::syntax::token::TokenKind;

impl Parser<'_> {
    /// `T`, followed by any number of array suffixes `[n]` / `[x]`.
    pub(crate) fn ty(&mut self) -> PResult<TypeExpr> {
        self.nested(|p| p.chained(|p| p.array_chain()))
    }

    fn array_chain(&mut self) -> PResult<TypeExpr> {
        let mut ty = self.type_atom()?;
        while self.at(&TokenKind::LBracket) {
            self.deepen()?;
            self.bump();
            let len = match self.peek().clone() {
                TokenKind::Int(v) => {
                    self.bump();
                    let span = self.prev_span();
                    ArrayLen::Const(self.int_to_u64(v, span, "array length"), span)
                }
                TokenKind::Ident(_) => ArrayLen::Name(self.ident("a name")?),
                _ => return Err(self.expected("an array length (an integer or a name)")),
            };
            let close = self.expect(&TokenKind::RBracket)?;
            let span = ty.span.to(close);
            ty = TypeExpr {
                kind: TypeExprKind::Array {
                    elem: Box::new(ty),
                    len,
                },
                span,
            };
        }
        Ok(ty)
    }

    fn type_atom(&mut self) -> PResult<TypeExpr> {
        let start = self.span();
        match self.peek().clone() {
            TokenKind::Ident(word)
                if (word == "set" || word == "option")
                    && *self.peek_at(1) == TokenKind::LBracket =>
            {
                self.bump();
                self.bump();
                let inner = self.with_no_bar(false, |p| p.ty())?;
                let close = self.expect(&TokenKind::RBracket)?;
                let kind = if word == "set" {
                    TypeExprKind::Set(Box::new(inner))
                } else {
                    TypeExprKind::Option(Box::new(inner))
                };
                Ok(TypeExpr {
                    kind,
                    span: start.to(close),
                })
            }
            TokenKind::Ident(_) => {
                let name = self.ident("a type")?;
                let span = name.span;
                Ok(TypeExpr {
                    kind: TypeExprKind::Named(name),
                    span,
                })
            }
            TokenKind::Vector { elem, lanes } => {
                self.bump();
                let elem = Ident {
                    name: elem,
                    span: start,
                };
                Ok(TypeExpr {
                    kind: TypeExprKind::Vector { elem, lanes },
                    span: start,
                })
            }
            TokenKind::LParen => {
                self.bump();
                let elems = self.comma_list(TokenKind::RParen, |p| p.ty())?;
                let span = start.to(self.prev_span());
                let trailing_comma = self.closed_after_comma();
                if elems.len() == 1 {
                    if trailing_comma {
                        self.report_at_node(SyntaxError::OneElementTuple { what: "type", span });
                    }
                    let mut only = elems.into_iter().next().ok_or(Fail)?;
                    only.span = span;
                    return Ok(only);
                }
                Ok(TypeExpr {
                    kind: TypeExprKind::Tuple(elems),
                    span,
                })
            }
            _ => Err(self.expected("a type")),
        }
    }

    /// Narrows a literal to `u64`, reporting `E0104` (and yielding 0) when it does not fit.
    pub(crate) fn int_to_u64(
        &mut self,
        v: u128,
        span: scion_ir::diag::Span,
        what: &'static str,
    ) -> u64 {
        match u64::try_from(v) {
            Ok(n) => n,
            Err(_) => {
                self.report_at_node(SyntaxError::IntegerTooLarge {
                    text: v.to_string(),
                    max: u64::MAX.to_string(),
                    what,
                    span,
                });
                0
            }
        }
    }
}
