//! Types and attributes of the text form (`vector<3xf32>`, `!tree.adt<"BVH">`, `{value = -0.0}`).

use super::lexer::Tok;
use super::{describe, PResult, Parser};
use crate::attr::{Attr, CANONICAL_NAN_BITS};
use crate::entity::TypeId;
use crate::types::{FloatTy, IntTy, Type};

impl Parser<'_> {
    pub(super) fn ty(&mut self) -> PResult<TypeId> {
        self.enter()?;
        let t = self.ty_inner();
        self.leave();
        t
    }

    fn ty_inner(&mut self) -> PResult<TypeId> {
        let span = self.span();
        let tok = self.peek().clone();
        if !matches!(tok, Tok::Ident(_) | Tok::Bang(_)) {
            return Err(self.error(
                "E0956",
                span,
                format!("expected a type, found {}", describe(&tok)),
            ));
        }
        self.bump();
        let ty = match tok {
            Tok::Ident(name) => match name.as_str() {
                "vector" => {
                    self.expect_punct('<')?;
                    let lanes = self.int_in_type()?;
                    let elem = self.x_then_type()?;
                    self.expect_punct('>')?;
                    let lanes = u32::try_from(lanes)
                        .ok()
                        .filter(|&l| l > 0)
                        .ok_or_else(|| {
                            self.error(
                                "E0956",
                                span,
                                "vector lane count must be between 1 and 2^32-1",
                            )
                        })?;
                    Type::Vector { elem, lanes }
                }
                "array" => {
                    self.expect_punct('<')?;
                    let len =
                        if self.eat_punct('?') {
                            None
                        } else {
                            let n = self.int_in_type()?;
                            Some(u64::try_from(n).map_err(|_| {
                                self.error("E0956", span, "array length out of range")
                            })?)
                        };
                    let elem = self.x_then_type()?;
                    self.expect_punct('>')?;
                    Type::Array { elem, len }
                }
                "tuple" => {
                    self.expect_punct('<')?;
                    let mut elems = Vec::new();
                    if !self.eat_punct('>') {
                        loop {
                            elems.push(self.ty()?);
                            if !self.eat_punct(',') {
                                break;
                            }
                        }
                        self.expect_punct('>')?;
                    }
                    Type::Tuple(elems)
                }
                "set" | "option" => {
                    self.expect_punct('<')?;
                    let e = self.ty()?;
                    self.expect_punct('>')?;
                    if name == "set" {
                        Type::Set(e)
                    } else {
                        Type::Option(e)
                    }
                }
                other => match scalar_type(other) {
                    Some(t) => t,
                    None => {
                        return Err(self.error("E0956", span, format!("unknown type `{other}`")))
                    }
                },
            },
            Tok::Bang(name) if name == "tree.adt" => {
                self.expect_punct('<')?;
                let Tok::Str(s) = self.peek().clone() else {
                    return Err(self.unexpected("a quoted type name"));
                };
                self.bump();
                self.expect_punct('>')?;
                Type::Adt(s)
            }
            Tok::Bang(name) if name == "tree.ref" => {
                self.expect_punct('<')?;
                let e = self.ty()?;
                self.expect_punct('>')?;
                Type::Ref(e)
            }
            Tok::Bang(name) if name == "mem.view" => {
                self.expect_punct('<')?;
                let e = self.ty()?;
                self.expect_punct('>')?;
                Type::View(e)
            }
            other => {
                return Err(self.error(
                    "E0956",
                    span,
                    format!("expected a type, found {}", describe(&other)),
                ))
            }
        };
        Ok(self.m.ty(ty))
    }

    fn int_in_type(&mut self) -> PResult<i128> {
        match self.peek().clone() {
            Tok::Int(v) => {
                self.bump();
                Ok(v)
            }
            _ => Err(self.unexpected("a number")),
        }
    }

    /// After the count of `vector<3xf32>` or `array<8 x T>`: the `x` and the element type,
    /// written together (`xf32`) or apart (`x T`).
    fn x_then_type(&mut self) -> PResult<TypeId> {
        let span = self.span();
        match self.peek().clone() {
            Tok::Ident(s) if s == "x" => {
                self.bump();
                self.ty()
            }
            Tok::Ident(s) if s.starts_with('x') => {
                self.bump();
                match scalar_type(&s[1..]) {
                    Some(t) => Ok(self.m.ty(t)),
                    None => Err(self.error(
                        "E0956",
                        span,
                        format!("unknown element type `{}`", &s[1..]),
                    )),
                }
            }
            _ => Err(self.unexpected("`x` and an element type")),
        }
    }

    pub(super) fn attr(&mut self) -> PResult<Attr> {
        self.enter()?;
        let a = self.attr_inner();
        self.leave();
        a
    }

    fn attr_inner(&mut self) -> PResult<Attr> {
        let span = self.span();
        match self.peek().clone() {
            Tok::Int(v) => {
                self.bump();
                Ok(Attr::Int(v))
            }
            Tok::Float(s) => {
                self.bump();
                let bad = self.error("E0957", span, format!("bad float literal `{s}`"));
                // `1.0000004 : f32` is read as an `f32` directly (no double rounding through
                // `f64`), then widened exactly.
                if self.eat_punct(':') {
                    match self.peek() {
                        Tok::Ident(t) if t == "f32" => {
                            self.bump();
                            return s
                                .parse::<f32>()
                                .map(|x| Attr::float(x as f64))
                                .map_err(|_| bad);
                        }
                        Tok::Ident(t) if t == "f64" => self.bump(),
                        _ => return Err(self.unexpected("`f32` or `f64` after a typed float")),
                    };
                }
                s.parse::<f64>().map(Attr::float).map_err(|_| bad)
            }
            Tok::Str(s) => {
                self.bump();
                Ok(Attr::Str(s))
            }
            Tok::Sym(s) => {
                self.bump();
                Ok(Attr::Sym(s))
            }
            Tok::Punct('-') => {
                self.bump();
                match self.peek() {
                    Tok::Ident(s) if s == "inf" => {
                        self.bump();
                        Ok(Attr::float(f64::NEG_INFINITY))
                    }
                    _ => Err(self.unexpected("`inf` after `-`")),
                }
            }
            Tok::Punct('[') => {
                self.bump();
                let mut items = Vec::new();
                if !self.eat_punct(']') {
                    loop {
                        items.push(self.attr()?);
                        if !self.eat_punct(',') {
                            break;
                        }
                    }
                    self.expect_punct(']')?;
                }
                Ok(Attr::List(items))
            }
            Tok::Ident(s) => match s.as_str() {
                "true" | "false" => {
                    self.bump();
                    Ok(Attr::Bool(s == "true"))
                }
                "unit" => {
                    self.bump();
                    Ok(Attr::Unit)
                }
                "inf" => {
                    self.bump();
                    Ok(Attr::float(f64::INFINITY))
                }
                "nan" => {
                    self.bump();
                    if !self.eat_punct('(') {
                        return Ok(Attr::Float(CANONICAL_NAN_BITS));
                    }
                    let bits = match self.peek().clone() {
                        Tok::Int(v) => {
                            self.bump();
                            v
                        }
                        _ => return Err(self.unexpected("the bits of a NaN")),
                    };
                    self.expect_punct(')')?;
                    match u64::try_from(bits) {
                        Ok(b) if f64::from_bits(b).is_nan() => Ok(Attr::Float(b)),
                        _ => Err(self.error(
                            "E0957",
                            span,
                            "`nan(...)` needs the bits of an f64 NaN",
                        )),
                    }
                }
                _ => Ok(Attr::Type(self.ty()?)),
            },
            Tok::Bang(_) => Ok(Attr::Type(self.ty()?)),
            _ => Err(self.unexpected("an attribute value")),
        }
    }
}

/// The scalar type spelled `s`.
fn scalar_type(s: &str) -> Option<Type> {
    Some(match s {
        "i1" => Type::Bool,
        "f16" => Type::Float(FloatTy::F16),
        "f32" => Type::Float(FloatTy::F32),
        "f64" => Type::Float(FloatTy::F64),
        "ptr" => Type::Ptr,
        _ => Type::Int(IntTy::ALL.into_iter().find(|t| t.name() == s)?),
    })
}
