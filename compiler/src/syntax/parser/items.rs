//! The top level of a file and the traversal language's declarations (Figure 3):
//! `type R(fields);`, `type S(shared) = A(fields) | B(fields);` and
//! `func f(params) -> T = body`. Any item may be followed by `;`.
//!
//! A failed item header skips to the next item keyword (`type`, `func`, `layout`, `build`)
//! outside brackets.

use super::{PResult, Parser};
use crate::syntax::ast::{FieldDecl, FuncDecl, Item, Param, TypeDecl, VariantDecl};
use crate::syntax::token::{Keyword, TokenKind};

fn is_item_keyword(kind: &TokenKind) -> bool {
    matches!(
        kind,
        TokenKind::Keyword(Keyword::Type | Keyword::Func | Keyword::Layout | Keyword::Build)
    )
}

impl Parser<'_> {
    /// Every item of the file.
    pub(crate) fn items(&mut self) -> Vec<Item> {
        let mut items = Vec::new();
        loop {
            while self.eat(&TokenKind::Semi) {}
            if self.at_eof() {
                return items;
            }
            let start = self.pos;
            let item = match self.peek() {
                TokenKind::Keyword(Keyword::Type) => self.type_decl().map(Item::Type),
                TokenKind::Keyword(Keyword::Func) => self.func_decl().map(Item::Func),
                TokenKind::Keyword(Keyword::Layout) => self.layout_decl().map(Item::Layout),
                TokenKind::Keyword(Keyword::Build) => self.build_decl().map(Item::Build),
                _ => Err(self.expected("an item (`type`, `func`, `layout` or `build`)")),
            };
            match item {
                Ok(item) => {
                    items.push(item);
                    if !self.eat(&TokenKind::Semi)
                        && !self.at_eof()
                        && !is_item_keyword(self.peek())
                    {
                        self.expected_separator("`;` or the next item");
                        self.skip_to_item();
                    }
                }
                Err(_) => {
                    if self.pos == start {
                        self.bump();
                    }
                    self.skip_to_item();
                }
            }
        }
    }

    /// Skips to the next item keyword outside brackets (unmatched closers are skipped too).
    fn skip_to_item(&mut self) {
        let mut depth = 0usize;
        while !self.at_eof() {
            match self.peek() {
                kind if depth == 0 && is_item_keyword(kind) => return,
                TokenKind::LParen | TokenKind::LBracket | TokenKind::LBrace => depth += 1,
                TokenKind::RParen | TokenKind::RBracket | TokenKind::RBrace => {
                    depth = depth.saturating_sub(1)
                }
                _ => {}
            }
            self.bump();
        }
    }

    fn type_decl(&mut self) -> PResult<TypeDecl> {
        let start = self.expect_kw(Keyword::Type)?;
        let name = self.ident("the type's name")?;
        let fields = if self.eat(&TokenKind::LParen) {
            self.field_list()?
        } else {
            Vec::new()
        };
        let mut variants = None;
        if self.eat(&TokenKind::Assign) {
            let mut list = Vec::new();
            self.eat(&TokenKind::Bar);
            loop {
                list.push(self.variant_decl()?);
                if !self.eat(&TokenKind::Bar) {
                    break;
                }
            }
            variants = Some(list);
        }
        let span = start.to(self.prev_span());
        Ok(TypeDecl {
            name,
            fields,
            variants,
            span,
        })
    }

    fn variant_decl(&mut self) -> PResult<VariantDecl> {
        let name = self.ident("a variant name")?;
        let fields = if self.eat(&TokenKind::LParen) {
            self.field_list()?
        } else {
            Vec::new()
        };
        let span = name.span.to(self.prev_span());
        Ok(VariantDecl { name, fields, span })
    }

    /// After `(`: `x: T (= e)?, ...)`.
    pub(crate) fn field_list(&mut self) -> PResult<Vec<FieldDecl>> {
        self.comma_list(TokenKind::RParen, |p| p.field_decl())
    }

    fn field_decl(&mut self) -> PResult<FieldDecl> {
        let name = self.ident("a field name")?;
        self.expect(&TokenKind::Colon)?;
        let ty = self.ty()?;
        let default = if self.eat(&TokenKind::Assign) {
            Some(self.expr()?)
        } else {
            None
        };
        let span = name.span.to(self.prev_span());
        Ok(FieldDecl {
            name,
            ty,
            default,
            span,
        })
    }

    fn func_decl(&mut self) -> PResult<FuncDecl> {
        let start = self.expect_kw(Keyword::Func)?;
        let name = self.ident("the function's name")?;
        self.expect(&TokenKind::LParen)?;
        let params = self.comma_list(TokenKind::RParen, |p| p.param())?;
        let ret = if self.eat(&TokenKind::Arrow) {
            Some(self.ty()?)
        } else {
            None
        };
        let order_by = if self.at_word("order") {
            self.bump();
            self.expect_kw(Keyword::By)?;
            Some(self.ident("the parameter that orders the calls")?)
        } else {
            None
        };
        self.expect(&TokenKind::Assign)?;
        let body = self.stmt()?;
        let span = start.to(body.span);
        Ok(FuncDecl {
            name,
            params,
            ret,
            order_by,
            body,
            span,
        })
    }

    fn param(&mut self) -> PResult<Param> {
        let name = self.ident("a parameter name")?;
        self.expect(&TokenKind::Colon)?;
        let mutable = self.eat_kw(Keyword::Mut);
        let ty = self.ty()?;
        let default = if self.eat(&TokenKind::Assign) {
            Some(self.expr()?)
        } else {
            None
        };
        let span = name.span.to(self.prev_span());
        Ok(Param {
            name,
            mutable,
            ty,
            default,
            span,
        })
    }
}
