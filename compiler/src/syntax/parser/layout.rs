//! The layout language (Figure 6): `layout Name(params) { members }` with stored fields,
//! padding, derived fields, `let`, `group`, nested and `indirect` groups, `---` separators and
//! `split` with its arms (`pattern -> Variant { members }` / `pattern -> Variant from g[e]`).

use super::{PResult, Parser};
use crate::syntax::ast::{
    GroupAttr, GroupAttrKind, GroupDecl, LayoutDecl, LayoutParam, Member, MemberKind, SplitArm,
    SplitArmBody,
};
use crate::syntax::errors::SyntaxError;
use crate::syntax::token::{Keyword, TokenKind};
use scion_ir::diag::Span;

impl Parser<'_> {
    pub(crate) fn layout_decl(&mut self) -> PResult<LayoutDecl> {
        let start = self.expect_kw(Keyword::Layout)?;
        let name = self.ident("the layout's name")?;
        let params = if self.eat(&TokenKind::LParen) {
            self.comma_list(TokenKind::RParen, |p| p.layout_param())?
        } else {
            Vec::new()
        };
        self.expect(&TokenKind::LBrace)?;
        let members = self.member_list_rest();
        let span = start.to(self.prev_span());
        Ok(LayoutDecl {
            name,
            params,
            members,
            span,
        })
    }

    fn layout_param(&mut self) -> PResult<LayoutParam> {
        let name = self.ident("a reference component's name")?;
        self.expect(&TokenKind::Colon)?;
        let ty = self.ty()?;
        let default = if self.eat(&TokenKind::Assign) {
            Some(self.expr()?)
        } else {
            None
        };
        let span = name.span.to(self.prev_span());
        Ok(LayoutParam {
            name,
            ty,
            default,
            span,
        })
    }

    /// After `{`: members up to and including `}`.
    fn member_list_rest(&mut self) -> Vec<Member> {
        self.braced_list("a layout member", |p| p.member())
    }

    fn member(&mut self) -> PResult<Member> {
        self.nested(|p| p.member_inner())
    }

    fn member_inner(&mut self) -> PResult<Member> {
        let start = self.span();
        let kind = match self.peek().clone() {
            TokenKind::Int(v) => {
                self.bump();
                MemberKind::Padding {
                    bytes: self.int_to_u64(v, start, "padding"),
                }
            }
            TokenKind::Separator => {
                self.bump();
                MemberKind::Separator
            }
            TokenKind::Keyword(Keyword::Let) => {
                self.bump();
                let name = self.ident("a name after `let`")?;
                let ty = if self.eat(&TokenKind::Colon) {
                    Some(self.ty()?)
                } else {
                    None
                };
                self.expect(&TokenKind::Assign)?;
                let value = self.expr()?;
                MemberKind::Let { name, ty, value }
            }
            TokenKind::Keyword(Keyword::Group) => {
                self.bump();
                MemberKind::Group(self.group_rest(start, false)?)
            }
            TokenKind::Keyword(Keyword::Indirect) => {
                self.bump();
                self.expect_kw(Keyword::Group)?;
                MemberKind::Group(self.group_rest(start, true)?)
            }
            TokenKind::Keyword(Keyword::Split) => {
                self.bump();
                let discriminant = self.expr()?;
                self.expect(&TokenKind::LBrace)?;
                let arms = self.braced_list("a split arm", |p| p.split_arm());
                MemberKind::Split { discriminant, arms }
            }
            TokenKind::Ident(_) => {
                let name = self.ident("a member name")?;
                if self.eat(&TokenKind::Colon) {
                    MemberKind::Field {
                        name,
                        ty: self.ty()?,
                    }
                } else if self.eat(&TokenKind::Assign) {
                    MemberKind::Derived {
                        name,
                        value: self.expr()?,
                    }
                } else {
                    return Err(self.expected("`:` (a stored field) or `=` (a derived field)"));
                }
            }
            _ => return Err(self.expected("a layout member")),
        };
        Ok(Member {
            kind,
            span: start.to(self.prev_span()),
        })
    }

    /// After `group` / `indirect group`: `name [attrs]? (by e)? { members }`.
    fn group_rest(&mut self, start: Span, indirect: bool) -> PResult<GroupDecl> {
        let name = self.ident("the group's name")?;
        let attrs = if self.eat(&TokenKind::LBracket) {
            self.comma_list(TokenKind::RBracket, |p| p.group_attr())?
        } else {
            Vec::new()
        };
        let by = if self.at_kw(Keyword::By) {
            let by_start = self.span();
            self.bump();
            let e = self.expr()?;
            if indirect {
                self.report_at_node(SyntaxError::IndirectGroupBy {
                    span: by_start.to(e.span),
                });
            }
            Some(e)
        } else {
            None
        };
        self.expect(&TokenKind::LBrace)?;
        let members = self.member_list_rest();
        let span = start.to(self.prev_span());
        Ok(GroupDecl {
            name,
            indirect,
            attrs,
            by,
            members,
            span,
        })
    }

    /// `n`, `size = e` or `align = n`.
    fn group_attr(&mut self) -> PResult<GroupAttr> {
        let start = self.span();
        let kind = match self.peek().clone() {
            TokenKind::Int(v) => {
                self.bump();
                GroupAttrKind::Count(self.int_to_u64(v, start, "tile count"))
            }
            TokenKind::Ident(word) if word == "size" => {
                self.bump();
                self.expect(&TokenKind::Assign)?;
                GroupAttrKind::Size(self.expr()?)
            }
            TokenKind::Ident(word) if word == "align" => {
                self.bump();
                self.expect(&TokenKind::Assign)?;
                let TokenKind::Int(v) = *self.peek() else {
                    return Err(self.expected("an integer alignment"));
                };
                self.bump();
                let span = self.prev_span();
                GroupAttrKind::Align(self.int_to_u64(v, span, "alignment"))
            }
            TokenKind::Ident(word) => {
                self.report(SyntaxError::UnknownAttribute {
                    name: word,
                    construct: "group",
                    allowed: "a tile count `n`, `size = e` and `align = n`",
                    span: start,
                });
                return Err(super::Fail);
            }
            _ => return Err(self.expected("a group attribute (`n`, `size = e` or `align = n`)")),
        };
        Ok(GroupAttr {
            kind,
            span: start.to(self.prev_span()),
        })
    }

    /// `pattern -> Variant { members }` or `pattern -> Variant from g[e]`.
    fn split_arm(&mut self) -> PResult<SplitArm> {
        let pattern = self.split_pattern()?;
        self.expect(&TokenKind::Arrow)?;
        let variant = self.ident("the variant this arm realizes")?;
        let body = if self.eat_kw(Keyword::From) {
            let group = self.ident("an indirect group's name")?;
            self.expect(&TokenKind::LBracket)?;
            let key = self.expr_free()?;
            self.expect(&TokenKind::RBracket)?;
            SplitArmBody::From {
                variant,
                group,
                key,
            }
        } else if self.eat(&TokenKind::LBrace) {
            SplitArmBody::Members {
                variant,
                members: self.member_list_rest(),
            }
        } else {
            return Err(self.expected("`{` (the variant's members) or `from`"));
        };
        let span = pattern.span.to(self.prev_span());
        Ok(SplitArm {
            pattern,
            body,
            span,
        })
    }
}
