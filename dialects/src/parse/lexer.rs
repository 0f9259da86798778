//! Tokens of the IR text form. Comments run from `//` to the end of the line.

use crate::diag::{Diagnostic, FileId, Span};

/// One token kind, with its value where it has one.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Tok {
    /// `func`, `tree.type`, `i32`, `vector`, `xf32`, `inf`, ...
    Ident(String),
    /// `!tree.adt`
    Bang(String),
    /// `%name`
    Value(String),
    /// `^name`
    Block(String),
    /// `@name` or `@"name"`
    Sym(String),
    /// `"text"`
    Str(String),
    /// An integer literal (with its sign).
    Int(i128),
    /// A float literal (its text, parsed exactly later).
    Float(String),
    /// Punctuation: one of `( ) { } [ ] < > , : = | ? -`.
    Punct(char),
    /// `->`
    Arrow,
    /// End of input.
    Eof,
}

/// A token and where it is.
#[derive(Clone, Debug)]
pub(crate) struct Token {
    pub tok: Tok,
    pub start: u32,
    pub end: u32,
}

fn is_ident_start(c: u8) -> bool {
    c.is_ascii_alphabetic() || c == b'_'
}

fn is_ident_char(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_' || c == b'.' || c == b'$'
}

fn error(file: FileId, start: usize, end: usize, msg: impl Into<String>) -> Diagnostic {
    Diagnostic::error("E0950", msg).with_primary(Span::new(file, start as u32, end as u32), "")
}

/// Splits `text` into tokens, ending with [`Tok::Eof`].
pub(crate) fn lex(text: &str, file: FileId) -> Result<Vec<Token>, Diagnostic> {
    let bytes = text.as_bytes();
    let mut toks = Vec::new();
    let mut i = 0usize;
    while i < bytes.len() {
        let c = bytes[i];
        if c.is_ascii_whitespace() {
            i += 1;
            continue;
        }
        if c == b'/' && bytes.get(i + 1) == Some(&b'/') {
            while i < bytes.len() && bytes[i] != b'\n' {
                i += 1;
            }
            continue;
        }
        let start = i;
        let tok = match c {
            b'%' | b'^' | b'!' => {
                i += 1;
                let s = i;
                while i < bytes.len() && is_ident_char(bytes[i]) {
                    i += 1;
                }
                if s == i {
                    return Err(error(
                        file,
                        start,
                        start + 1,
                        format!("expected a name after `{}`", c as char),
                    ));
                }
                let name = text[s..i].to_string();
                match c {
                    b'%' => Tok::Value(name),
                    b'^' => Tok::Block(name),
                    _ => Tok::Bang(name),
                }
            }
            b'@' => {
                i += 1;
                if bytes.get(i) == Some(&b'"') {
                    let (s, next) = lex_string(text, i, file)?;
                    i = next;
                    Tok::Sym(s)
                } else {
                    let s = i;
                    while i < bytes.len() && is_ident_char(bytes[i]) {
                        i += 1;
                    }
                    if s == i {
                        return Err(error(
                            file,
                            start,
                            start + 1,
                            "expected a symbol name after `@`",
                        ));
                    }
                    Tok::Sym(text[s..i].to_string())
                }
            }
            b'"' => {
                let (s, next) = lex_string(text, i, file)?;
                i = next;
                Tok::Str(s)
            }
            b'-' if bytes.get(i + 1) == Some(&b'>') => {
                i += 2;
                Tok::Arrow
            }
            b'-' if bytes.get(i + 1).is_some_and(u8::is_ascii_digit) => {
                i += 1;
                lex_number(text, &mut i, start, file, true)?
            }
            b'0'..=b'9' => lex_number(text, &mut i, start, file, false)?,
            c if is_ident_start(c) => {
                while i < bytes.len() && is_ident_char(bytes[i]) {
                    i += 1;
                }
                Tok::Ident(text[start..i].to_string())
            }
            b'(' | b')' | b'{' | b'}' | b'[' | b']' | b'<' | b'>' | b',' | b':' | b'=' | b'|'
            | b'?' | b'-' => {
                i += 1;
                Tok::Punct(c as char)
            }
            _ => {
                let ch = text[i..].chars().next().unwrap_or('?');
                return Err(error(
                    file,
                    start,
                    start + ch.len_utf8(),
                    format!("unexpected character `{}`", ch.escape_debug()),
                ));
            }
        };
        toks.push(Token {
            tok,
            start: start as u32,
            end: i as u32,
        });
    }
    toks.push(Token {
        tok: Tok::Eof,
        start: bytes.len() as u32,
        end: bytes.len() as u32,
    });
    Ok(toks)
}

/// Lexes a number whose digits start at `*i` (after a `-` at `start` when `negative`).
fn lex_number(
    text: &str,
    i: &mut usize,
    start: usize,
    file: FileId,
    negative: bool,
) -> Result<Tok, Diagnostic> {
    let bytes = text.as_bytes();
    if bytes[*i] == b'0'
        && bytes.get(*i + 1) == Some(&b'x')
        && bytes.get(*i + 2).is_some_and(u8::is_ascii_hexdigit)
    {
        *i += 2;
        let s = *i;
        while *i < bytes.len() && bytes[*i].is_ascii_hexdigit() {
            *i += 1;
        }
        let too_large = || error(file, start, *i, "integer literal too large");
        let v = u128::from_str_radix(&text[s..*i], 16).map_err(|_| too_large())?;
        let v = i128::try_from(v).map_err(|_| too_large())?;
        return Ok(Tok::Int(if negative { -v } else { v }));
    }
    let mut is_float = false;
    while *i < bytes.len() && bytes[*i].is_ascii_digit() {
        *i += 1;
    }
    if bytes.get(*i) == Some(&b'.') && bytes.get(*i + 1).is_some_and(u8::is_ascii_digit) {
        is_float = true;
        *i += 1;
        while *i < bytes.len() && bytes[*i].is_ascii_digit() {
            *i += 1;
        }
    }
    if matches!(bytes.get(*i), Some(b'e' | b'E')) {
        let mut j = *i + 1;
        if matches!(bytes.get(j), Some(b'+' | b'-')) {
            j += 1;
        }
        if bytes.get(j).is_some_and(u8::is_ascii_digit) {
            is_float = true;
            *i = j;
            while *i < bytes.len() && bytes[*i].is_ascii_digit() {
                *i += 1;
            }
        }
    }
    let s = &text[start..*i];
    if is_float {
        Ok(Tok::Float(s.to_string()))
    } else {
        s.parse::<i128>()
            .map(Tok::Int)
            .map_err(|_| error(file, start, *i, "integer literal too large"))
    }
}

/// Lexes a string literal starting at the `"` at `start`; returns its value and the next index.
fn lex_string(text: &str, start: usize, file: FileId) -> Result<(String, usize), Diagnostic> {
    let mut out = String::new();
    let mut chars = text[start + 1..].char_indices();
    let at = |k: usize| start + 1 + k;
    while let Some((k, c)) = chars.next() {
        match c {
            '"' => return Ok((out, at(k) + 1)),
            '\n' => break,
            '\\' => match chars.next() {
                Some((_, '"')) => out.push('"'),
                Some((_, '\\')) => out.push('\\'),
                Some((_, 'n')) => out.push('\n'),
                Some((_, 't')) => out.push('\t'),
                Some((_, 'u')) => {
                    if !matches!(chars.next(), Some((_, '{'))) {
                        return Err(error(file, at(k), at(k) + 2, "expected `{` after `\\u`"));
                    }
                    let mut hex = String::new();
                    let mut closed = false;
                    for (_, h) in chars.by_ref() {
                        if h == '}' {
                            closed = true;
                            break;
                        }
                        hex.push(h);
                    }
                    let ch = if closed {
                        u32::from_str_radix(&hex, 16).ok().and_then(char::from_u32)
                    } else {
                        None
                    };
                    match ch {
                        Some(ch) => out.push(ch),
                        None => {
                            return Err(error(file, at(k), at(k) + 2, "invalid `\\u{...}` escape"))
                        }
                    }
                }
                _ => return Err(error(file, at(k), at(k) + 1, "unknown escape in string")),
            },
            c => out.push(c),
        }
    }
    Err(error(file, start, start + 1, "unterminated string"))
}
