//! Tokens of the Scion languages (shared by the traversal, layout and build languages).
//!
//! The lexer (`lexer.rs`) turns source text into a list of [`Token`]s, each with the [`Span`] it
//! covers; the parser reads names and literal values back from the token kinds. Keywords are
//! those of `docs/language.md` ("Lexical structure"); contextual keywords (`root`, `order`,
//! `pre`, `post`, `size`, `align`, `set`, `option`) stay [`TokenKind::Ident`] and the parser
//! recognises them by their text where they matter.

use scion_ir::diag::Span;
use std::fmt;

/// One token with its position.
#[derive(Clone, Debug, PartialEq)]
pub struct Token {
    /// What was read.
    pub kind: TokenKind,
    /// Where.
    pub span: Span,
}

/// Reserved words (never identifiers).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Keyword {
    Type,
    Func,
    Layout,
    Build,
    Group,
    Indirect,
    Split,
    By,
    From,
    Let,
    Mut,
    Match,
    If,
    Elif,
    Else,
    Foreach,
    In,
    Return,
    As,
    To,
    This,
    Parent,
    True,
    False,
    Inf,
}

impl Keyword {
    /// Every keyword, for the lexer's lookup.
    pub const ALL: [Keyword; 25] = [
        Keyword::Type,
        Keyword::Func,
        Keyword::Layout,
        Keyword::Build,
        Keyword::Group,
        Keyword::Indirect,
        Keyword::Split,
        Keyword::By,
        Keyword::From,
        Keyword::Let,
        Keyword::Mut,
        Keyword::Match,
        Keyword::If,
        Keyword::Elif,
        Keyword::Else,
        Keyword::Foreach,
        Keyword::In,
        Keyword::Return,
        Keyword::As,
        Keyword::To,
        Keyword::This,
        Keyword::Parent,
        Keyword::True,
        Keyword::False,
        Keyword::Inf,
    ];

    /// The keyword as written.
    pub fn as_str(self) -> &'static str {
        match self {
            Keyword::Type => "type",
            Keyword::Func => "func",
            Keyword::Layout => "layout",
            Keyword::Build => "build",
            Keyword::Group => "group",
            Keyword::Indirect => "indirect",
            Keyword::Split => "split",
            Keyword::By => "by",
            Keyword::From => "from",
            Keyword::Let => "let",
            Keyword::Mut => "mut",
            Keyword::Match => "match",
            Keyword::If => "if",
            Keyword::Elif => "elif",
            Keyword::Else => "else",
            Keyword::Foreach => "foreach",
            Keyword::In => "in",
            Keyword::Return => "return",
            Keyword::As => "as",
            Keyword::To => "to",
            Keyword::This => "this",
            Keyword::Parent => "parent",
            Keyword::True => "true",
            Keyword::False => "false",
            Keyword::Inf => "inf",
        }
    }

    /// The keyword spelled `word`, if any.
    pub fn from_word(word: &str) -> Option<Keyword> {
        Keyword::ALL.iter().copied().find(|k| k.as_str() == word)
    }
}

/// Token kinds.
#[derive(Clone, Debug, PartialEq)]
pub enum TokenKind {
    /// A name (including contextual keywords such as `root` or `size`).
    Ident(String),
    /// A vector type word such as `f32x3`: the element type's name and the lane count.
    Vector {
        /// Element primitive (`f32`, `u8`, ...).
        elem: String,
        /// Number of lanes.
        lanes: u32,
    },
    /// An integer literal (value already checked to fit `u128`).
    Int(u128),
    /// A float literal (not `inf`, which is a keyword).
    Float(f64),
    /// A reserved word.
    Keyword(Keyword),
    /// `_`
    Underscore,
    /// `(`
    LParen,
    /// `)`
    RParen,
    /// `{`
    LBrace,
    /// `}`
    RBrace,
    /// `[`
    LBracket,
    /// `]`
    RBracket,
    /// `,`
    Comma,
    /// `;`
    Semi,
    /// `:`
    Colon,
    /// `.`
    Dot,
    /// `->`
    Arrow,
    /// `---`
    Separator,
    /// `=`
    Assign,
    /// `==`
    EqEq,
    /// `!=`
    NotEq,
    /// `<`
    Lt,
    /// `<=`
    Le,
    /// `>`
    Gt,
    /// `>=`
    Ge,
    /// `+`
    Plus,
    /// `-`
    Minus,
    /// `*`
    Star,
    /// `/`
    Slash,
    /// `%`
    Percent,
    /// `&`
    Amp,
    /// `&&`
    AmpAmp,
    /// `|`
    Bar,
    /// `||`
    BarBar,
    /// `^`
    Caret,
    /// `~`
    Tilde,
    /// `!`
    Bang,
    /// `<<`
    Shl,
    /// `>>`
    Shr,
    /// End of input (always the last token).
    Eof,
}

impl TokenKind {
    /// True for `kw`.
    pub fn is_kw(&self, kw: Keyword) -> bool {
        matches!(self, TokenKind::Keyword(k) if *k == kw)
    }

    /// How the token is described in "expected ..., found ..." messages.
    pub fn describe(&self) -> String {
        match self {
            TokenKind::Ident(name) => format!("name `{name}`"),
            TokenKind::Vector { elem, lanes } => format!("vector type `{elem}x{lanes}`"),
            TokenKind::Int(v) => format!("integer `{v}`"),
            TokenKind::Float(v) => format!("float `{v:?}`"),
            TokenKind::Keyword(k) => format!("keyword `{}`", k.as_str()),
            TokenKind::Eof => "end of file".to_string(),
            other => format!("`{}`", other.punct_str()),
        }
    }

    /// The spelling of a punctuation token (empty for tokens that carry data).
    pub fn punct_str(&self) -> &'static str {
        match self {
            TokenKind::Underscore => "_",
            TokenKind::LParen => "(",
            TokenKind::RParen => ")",
            TokenKind::LBrace => "{",
            TokenKind::RBrace => "}",
            TokenKind::LBracket => "[",
            TokenKind::RBracket => "]",
            TokenKind::Comma => ",",
            TokenKind::Semi => ";",
            TokenKind::Colon => ":",
            TokenKind::Dot => ".",
            TokenKind::Arrow => "->",
            TokenKind::Separator => "---",
            TokenKind::Assign => "=",
            TokenKind::EqEq => "==",
            TokenKind::NotEq => "!=",
            TokenKind::Lt => "<",
            TokenKind::Le => "<=",
            TokenKind::Gt => ">",
            TokenKind::Ge => ">=",
            TokenKind::Plus => "+",
            TokenKind::Minus => "-",
            TokenKind::Star => "*",
            TokenKind::Slash => "/",
            TokenKind::Percent => "%",
            TokenKind::Amp => "&",
            TokenKind::AmpAmp => "&&",
            TokenKind::Bar => "|",
            TokenKind::BarBar => "||",
            TokenKind::Caret => "^",
            TokenKind::Tilde => "~",
            TokenKind::Bang => "!",
            TokenKind::Shl => "<<",
            TokenKind::Shr => ">>",
            TokenKind::Ident(_)
            | TokenKind::Vector { .. }
            | TokenKind::Int(_)
            | TokenKind::Float(_)
            | TokenKind::Keyword(_)
            | TokenKind::Eof => "",
        }
    }
}

impl fmt::Display for TokenKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TokenKind::Ident(name) => f.write_str(name),
            TokenKind::Vector { elem, lanes } => write!(f, "{elem}x{lanes}"),
            TokenKind::Int(v) => write!(f, "{v}"),
            TokenKind::Float(v) => write!(f, "{v:?}"),
            TokenKind::Keyword(k) => f.write_str(k.as_str()),
            TokenKind::Eof => Ok(()),
            other => f.write_str(other.punct_str()),
        }
    }
}

/// The element types that may start a vector type word (`f32x3`).
pub const VECTOR_ELEMS: [&str; 11] = [
    "i8", "i16", "i32", "i64", "u8", "u16", "u32", "u64", "f16", "f32", "f64",
];
