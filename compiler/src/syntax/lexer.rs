//! The lexer: source text → [`Token`]s with spans (docs/language.md, "Lexical structure").
//!
//! Lexing never stops at an error: a malformed literal still yields a token (with value 0) and
//! an unknown character is skipped, each with a diagnostic (`E0102`–`E0105`), so the parser sees
//! a usable token stream and can report its own errors too. The result always ends with
//! [`TokenKind::Eof`].

use super::errors::SyntaxError;
use super::token::{Keyword, Token, TokenKind, VECTOR_ELEMS};
use scion_ir::diag::{Diagnostics, FileId, Span};

/// Lexes `src` (the text of `file`), appending lexical errors to `diags`.
pub fn lex(src: &str, file: FileId, diags: &mut Diagnostics) -> Vec<Token> {
    let mut lexer = Lexer {
        src: src.as_bytes(),
        text: src,
        pos: 0,
        file,
        tokens: Vec::new(),
        diags,
    };
    lexer.run();
    lexer.tokens
}

struct Lexer<'a, 'd> {
    src: &'a [u8],
    text: &'a str,
    pos: usize,
    file: FileId,
    tokens: Vec<Token>,
    diags: &'d mut Diagnostics,
}

fn to_u32(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

fn is_word_byte(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_'
}

impl Lexer<'_, '_> {
    fn peek(&self, off: usize) -> u8 {
        self.src.get(self.pos + off).copied().unwrap_or(0)
    }

    fn span(&self, start: usize, end: usize) -> Span {
        Span::new(self.file, to_u32(start), to_u32(end))
    }

    fn error(&mut self, e: SyntaxError) {
        self.diags.push(e.to_diagnostic());
    }

    fn push(&mut self, kind: TokenKind, start: usize) {
        let span = self.span(start, self.pos);
        self.tokens.push(Token { kind, span });
    }

    fn run(&mut self) {
        // Editors on some systems start UTF-8 files with a byte order mark; it is no token.
        if self.text.starts_with('\u{feff}') {
            self.pos = '\u{feff}'.len_utf8();
        }
        while self.pos < self.src.len() {
            let b = self.src[self.pos];
            let start = self.pos;
            if b.is_ascii_whitespace() {
                self.pos += 1;
            } else if b == b'/' && self.peek(1) == b'/' {
                while self.pos < self.src.len() && self.src[self.pos] != b'\n' {
                    self.pos += 1;
                }
            } else if b.is_ascii_digit() {
                self.number();
            } else if b.is_ascii_alphabetic() || b == b'_' {
                self.word();
            } else if let Some((kind, len)) = self.punct() {
                self.pos += len;
                self.push(kind, start);
            } else {
                // Skip one whole UTF-8 character so that spans stay on character boundaries.
                let ch = self.text[start..].chars().next().unwrap_or('\u{fffd}');
                self.pos += ch.len_utf8().max(1);
                let span = self.span(start, self.pos);
                self.error(SyntaxError::UnknownCharacter { ch, span });
            }
        }
        let end = self.src.len();
        self.tokens.push(Token {
            kind: TokenKind::Eof,
            span: self.span(end, end),
        });
    }

    fn punct(&self) -> Option<(TokenKind, usize)> {
        use TokenKind::*;
        let (a, b, c) = (self.peek(0), self.peek(1), self.peek(2));
        let two = |kind| Some((kind, 2));
        let one = |kind| Some((kind, 1));
        match (a, b) {
            (b'-', b'-') if c == b'-' => Some((Separator, 3)),
            (b'-', b'>') => two(Arrow),
            (b'=', b'=') => two(EqEq),
            (b'!', b'=') => two(NotEq),
            (b'<', b'=') => two(Le),
            (b'>', b'=') => two(Ge),
            (b'<', b'<') => two(Shl),
            (b'>', b'>') => two(Shr),
            (b'&', b'&') => two(AmpAmp),
            (b'|', b'|') => two(BarBar),
            (b'(', _) => one(LParen),
            (b')', _) => one(RParen),
            (b'{', _) => one(LBrace),
            (b'}', _) => one(RBrace),
            (b'[', _) => one(LBracket),
            (b']', _) => one(RBracket),
            (b',', _) => one(Comma),
            (b';', _) => one(Semi),
            (b':', _) => one(Colon),
            (b'.', _) => one(Dot),
            (b'=', _) => one(Assign),
            (b'<', _) => one(Lt),
            (b'>', _) => one(Gt),
            (b'+', _) => one(Plus),
            (b'-', _) => one(Minus),
            (b'*', _) => one(Star),
            (b'/', _) => one(Slash),
            (b'%', _) => one(Percent),
            (b'&', _) => one(Amp),
            (b'|', _) => one(Bar),
            (b'^', _) => one(Caret),
            (b'~', _) => one(Tilde),
            (b'!', _) => one(Bang),
            _ => None,
        }
    }

    fn word(&mut self) {
        let start = self.pos;
        while is_word_byte(self.peek(0)) {
            self.pos += 1;
        }
        let text = &self.text[start..self.pos];
        let kind = if text == "_" {
            TokenKind::Underscore
        } else if let Some(kw) = Keyword::from_word(text) {
            TokenKind::Keyword(kw)
        } else if let Some((elem, digits)) = split_vector_word(text) {
            let lanes = match digits.parse::<u32>() {
                Ok(n) if n >= 1 => n,
                _ => {
                    let span = self.span(start, self.pos);
                    self.error(SyntaxError::BadVectorLanes {
                        text: text.to_string(),
                        span,
                    });
                    1
                }
            };
            TokenKind::Vector {
                elem: elem.to_string(),
                lanes,
            }
        } else {
            TokenKind::Ident(text.to_string())
        };
        self.push(kind, start);
    }

    fn eat_digits(&mut self, accept: fn(u8) -> bool) -> usize {
        let mut n = 0;
        while accept(self.peek(0)) || self.peek(0) == b'_' {
            if self.peek(0) != b'_' {
                n += 1;
            }
            self.pos += 1;
        }
        n
    }

    fn number(&mut self) {
        let start = self.pos;
        let radix = match (self.peek(0), self.peek(1)) {
            (b'0', b'x' | b'X') => 16,
            (b'0', b'b' | b'B') => 2,
            _ => 10,
        };
        let mut problem: Option<&'static str> = None;
        let mut is_float = false;
        if radix != 10 {
            self.pos += 2;
            // Take every word character; bad digits are reported below, as one token.
            let digits_start = self.pos;
            while is_word_byte(self.peek(0)) {
                self.pos += 1;
            }
            let digits = &self.text[digits_start..self.pos];
            if !digits.bytes().any(|b| b != b'_') {
                problem = Some(if radix == 16 {
                    "no digits after `0x`"
                } else {
                    "no digits after `0b`"
                });
            } else if !digits
                .bytes()
                .all(|b| b == b'_' || (b as char).is_digit(radix))
            {
                problem = Some(if radix == 16 {
                    "invalid digit in a hexadecimal literal"
                } else {
                    "invalid digit in a binary literal (only 0 and 1)"
                });
            }
        } else {
            self.eat_digits(|b| b.is_ascii_digit());
            if self.peek(0) == b'.' && self.peek(1).is_ascii_digit() {
                is_float = true;
                self.pos += 1;
                self.eat_digits(|b| b.is_ascii_digit());
            }
            if matches!(self.peek(0), b'e' | b'E') {
                let sign = usize::from(matches!(self.peek(1), b'+' | b'-'));
                if self.peek(1 + sign).is_ascii_digit() {
                    is_float = true;
                    self.pos += 1 + sign;
                    self.eat_digits(|b| b.is_ascii_digit());
                } else {
                    self.pos += 1;
                    problem = Some("the exponent has no digits");
                }
            }
            if is_word_byte(self.peek(0)) {
                while is_word_byte(self.peek(0)) {
                    self.pos += 1;
                }
                problem = problem.or(Some("a literal cannot be followed by letters or `_`"));
            }
        }
        let text = &self.text[start..self.pos];
        let span = self.span(start, self.pos);
        if let Some(reason) = problem {
            self.error(SyntaxError::MalformedLiteral {
                text: text.to_string(),
                reason,
                span,
            });
            let kind = if is_float {
                TokenKind::Float(0.0)
            } else {
                TokenKind::Int(0)
            };
            self.push(kind, start);
            return;
        }
        let clean: String = text.chars().filter(|&c| c != '_').collect();
        let kind = if is_float {
            match clean.parse::<f64>() {
                Ok(v) if v.is_finite() => TokenKind::Float(v),
                _ => {
                    let reason = "the value is out of the range of `f64`";
                    self.error(SyntaxError::MalformedLiteral {
                        text: text.to_string(),
                        reason,
                        span,
                    });
                    TokenKind::Float(0.0)
                }
            }
        } else {
            let digits = if radix == 10 { &clean[..] } else { &clean[2..] };
            match u128::from_str_radix(digits, radix) {
                Ok(v) => TokenKind::Int(v),
                Err(_) => {
                    self.error(SyntaxError::IntegerTooLarge {
                        text: text.to_string(),
                        max: u128::MAX.to_string(),
                        what: "integer literal",
                        span,
                    });
                    TokenKind::Int(0)
                }
            }
        };
        self.push(kind, start);
    }
}

/// Splits `f32x3` into (`f32`, `3`) when `text` is a vector type word.
fn split_vector_word(text: &str) -> Option<(&str, &str)> {
    let x = text.find('x')?;
    let (elem, rest) = (&text[..x], &text[x + 1..]);
    let is_vector = VECTOR_ELEMS.contains(&elem)
        && !rest.is_empty()
        && rest.bytes().all(|b| b.is_ascii_digit());
    is_vector.then_some((elem, rest))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinds(src: &str) -> (Vec<String>, Vec<String>) {
        let mut diags = Diagnostics::new();
        let toks = lex(src, FileId(0), &mut diags);
        let kinds = toks.iter().map(|t| format!("{:?}", t.kind)).collect();
        let errs = diags.list.iter().map(|d| d.to_string()).collect();
        (kinds, errs)
    }

    #[test]
    fn literals() {
        let (k, e) = kinds("42 0x1F 0b101 1_000 1.0 1e-3 2.5e+8 inf 0xFFFF_FFFF");
        assert!(e.is_empty(), "{e:?}");
        assert_eq!(
            k,
            [
                "Int(42)",
                "Int(31)",
                "Int(5)",
                "Int(1000)",
                "Float(1.0)",
                "Float(0.001)",
                "Float(250000000.0)",
                "Keyword(Inf)",
                "Int(4294967295)",
                "Eof"
            ]
        );
    }

    #[test]
    fn malformed_literals_are_reported_and_lexing_continues() {
        let (k, e) = kinds("0x 0b102 1e 12ab 340282366920938463463374607431768211456 x");
        assert_eq!(e.len(), 5, "{e:?}");
        assert!(e[0].contains("E0102"));
        assert!(e[4].contains("E0104"));
        assert_eq!(k.last().map(String::as_str), Some("Eof"));
        assert_eq!(k[k.len() - 2], "Ident(\"x\")");
    }

    #[test]
    fn spans_are_byte_ranges() {
        let mut diags = Diagnostics::new();
        let toks = lex("\u{feff}let x_1 = 0x1F;// c\n---", FileId(3), &mut diags);
        assert!(diags.is_empty());
        let spans: Vec<(u32, u32)> = toks.iter().map(|t| (t.span.start, t.span.end)).collect();
        assert_eq!(
            spans,
            [
                (3, 6),
                (7, 10),
                (11, 12),
                (13, 17),
                (17, 18),
                (23, 26),
                (26, 26)
            ]
        );
        assert!(toks.iter().all(|t| t.span.file == FileId(3)));
    }

    #[test]
    fn punctuation_vectors_and_comments() {
        let (k, e) = kinds("--- -> - a.b f32x3 u8x8 f32x0 _ // comment\n|| | € ;");
        assert_eq!(e.len(), 2, "{e:?}");
        assert!(e[0].contains("E0105") && e[1].contains("E0103"));
        let k: Vec<&str> = k.iter().map(String::as_str).collect();
        assert_eq!(
            k,
            [
                "Separator",
                "Arrow",
                "Minus",
                "Ident(\"a\")",
                "Dot",
                "Ident(\"b\")",
                "Vector { elem: \"f32\", lanes: 3 }",
                "Vector { elem: \"u8\", lanes: 8 }",
                "Vector { elem: \"f32\", lanes: 1 }",
                "Underscore",
                "BarBar",
                "Bar",
                "Semi",
                "Eof"
            ]
        );
    }
}
