//! The build language's declarations (Figure 10):
//! `build Name[order=pre|post] { build root { stmts }; build Variant(x: T, ...) { stmts }; }`.
//! Its statements (`build x`, `build x = e`, `this[a:b] = e`) and its expressions (`this`,
//! `build x`, `append(x, n)`) are parsed by `stmts.rs` and `exprs.rs`.

use super::{Fail, PResult, Parser};
use crate::syntax::ast::{BuildDecl, BuildOrder, BuildRoot, BuildVariant};
use crate::syntax::errors::SyntaxError;
use crate::syntax::token::{Keyword, TokenKind};
use scion_ir::diag::Span;

/// One entry of a build body.
enum Entry {
    Root(BuildRoot),
    Variant(BuildVariant),
}

impl Parser<'_> {
    pub(crate) fn build_decl(&mut self) -> PResult<BuildDecl> {
        let start = self.expect_kw(Keyword::Build)?;
        let name = self.ident("the name of the layout to build")?;
        let mut order = BuildOrder::Pre;
        let mut order_span = None;
        if self.eat(&TokenKind::LBracket) {
            let attrs = self.comma_list(TokenKind::RBracket, |p| p.build_attr())?;
            if let Some(&(o, span)) = attrs.last() {
                order = o;
                order_span = Some(span);
            }
        }
        self.expect(&TokenKind::LBrace)?;
        let entries = self.braced_list(
            "`build root { ... }` or `build Variant(...) { ... }`",
            |p| p.build_entry(),
        );
        let mut root: Option<BuildRoot> = None;
        let mut variants = Vec::new();
        for entry in entries {
            match entry {
                Entry::Root(r) => match &root {
                    Some(first) => {
                        let err = SyntaxError::DuplicateRoot {
                            span: r.span,
                            first: first.span,
                        };
                        self.report_at_node(err);
                    }
                    None => root = Some(r),
                },
                Entry::Variant(v) => variants.push(v),
            }
        }
        let span = start.to(self.prev_span());
        Ok(BuildDecl {
            name,
            order,
            order_span,
            root,
            variants,
            span,
        })
    }

    /// `order = pre` or `order = post`.
    fn build_attr(&mut self) -> PResult<(BuildOrder, Span)> {
        let start = self.span();
        let key = self.ident("`order`")?;
        if key.name != "order" {
            self.report_at_node(SyntaxError::UnknownAttribute {
                name: key.name,
                construct: "build",
                allowed: "`order = pre` and `order = post`",
                span: key.span,
            });
            return Err(Fail);
        }
        self.expect(&TokenKind::Assign)?;
        let order = if self.at_word("pre") {
            BuildOrder::Pre
        } else if self.at_word("post") {
            BuildOrder::Post
        } else {
            return Err(self.expected("`pre` or `post`"));
        };
        self.bump();
        Ok((order, start.to(self.prev_span())))
    }

    fn build_entry(&mut self) -> PResult<Entry> {
        let start = self.expect_kw(Keyword::Build)?;
        if self.at_word("root") && *self.peek_at(1) == TokenKind::LBrace {
            self.bump();
            self.bump();
            let body = self.nested(|p| Ok(p.block_rest()))?;
            return Ok(Entry::Root(BuildRoot {
                body,
                span: start.to(self.prev_span()),
            }));
        }
        let name = self.ident("`root` or a variant name")?;
        let params = if self.eat(&TokenKind::LParen) {
            self.field_list()?
        } else {
            Vec::new()
        };
        self.expect(&TokenKind::LBrace)?;
        let body = self.nested(|p| Ok(p.block_rest()))?;
        Ok(Entry::Variant(BuildVariant {
            name,
            params,
            body,
            span: start.to(self.prev_span()),
        }))
    }
}
