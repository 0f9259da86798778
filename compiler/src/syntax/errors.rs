//! Every syntax error of the lexer and the parser, with its code (`E01xx`) and its wording.
//!
//! The lexer and the parser build a [`SyntaxError`] where they find a problem and turn it into a
//! [`Diagnostic`] with [`SyntaxError::to_diagnostic`]; all user-facing text of the syntax phase
//! lives here, so codes and messages stay consistent and are easy to review.
//!
//! | code  | meaning |
//! |-------|---------|
//! | E0101 | unexpected token (says what was expected and what was found) |
//! | E0102 | malformed numeric literal (missing digits, bad digit, bad exponent, bad suffix) |
//! | E0103 | character that starts no token |
//! | E0104 | integer literal too large for where it is used |
//! | E0105 | malformed vector type word (`f32x0`) |
//! | E0106 | nesting too deep (the parser's recursion limit) |
//! | E0107 | chained comparison (`a < b < c`) |
//! | E0108 | invalid assignment target |
//! | E0109 | one-element tuple (value or type) |
//! | E0110 | second `build root` in one build |
//! | E0111 | unknown attribute in `group g[...]` or `build L[...]` |
//! | E0112 | call of something that is not a name |
//! | E0113 | `by` on an `indirect group` |

use scion_ir::diag::{Diagnostic, Span};

/// A syntax error, one variant per code.
#[derive(Clone, Debug, PartialEq)]
pub enum SyntaxError {
    /// E0101: `expected` describes what the grammar allows here; `found` the token read.
    UnexpectedToken {
        /// What would have been accepted (e.g. "`;` or `}`").
        expected: String,
        /// The token found, described (e.g. "keyword `type`").
        found: String,
        /// Where the token is.
        span: Span,
        /// For a missing separator (`;`, `,`): the token it should follow. The error is then
        /// shown right after that token, where the separator goes, as rustc does.
        missing_after: Option<Span>,
    },
    /// E0102: a numeric literal that does not follow the literal grammar.
    MalformedLiteral {
        /// The literal's text.
        text: String,
        /// What is wrong with it.
        reason: &'static str,
        /// Where.
        span: Span,
    },
    /// E0103: a character that starts no token.
    UnknownCharacter {
        /// The character.
        ch: char,
        /// Where.
        span: Span,
    },
    /// E0104: an integer literal too large for its use.
    IntegerTooLarge {
        /// The literal as written.
        text: String,
        /// The largest value allowed here.
        max: String,
        /// What the literal is used as ("integer literal", "padding", ...).
        what: &'static str,
        /// Where.
        span: Span,
    },
    /// E0105: a vector type word whose lane count is zero or too large.
    BadVectorLanes {
        /// The word.
        text: String,
        /// Where.
        span: Span,
    },
    /// E0106: recursion limit reached.
    NestingTooDeep {
        /// The limit.
        limit: usize,
        /// Where the limit was crossed.
        span: Span,
    },
    /// E0107: `a < b < c`.
    ChainedComparison {
        /// The second comparison operator.
        op: &'static str,
        /// Its position.
        span: Span,
        /// The first comparison.
        first: Span,
    },
    /// E0108: the left side of `=` cannot be written to.
    InvalidAssignTarget {
        /// The target.
        span: Span,
    },
    /// E0109: `(e,)` or `(T,)`.
    OneElementTuple {
        /// "value" or "type".
        what: &'static str,
        /// Where.
        span: Span,
    },
    /// E0110: a second `build root { ... }`.
    DuplicateRoot {
        /// The second root.
        span: Span,
        /// The first root.
        first: Span,
    },
    /// E0111: an attribute that the construct does not know.
    UnknownAttribute {
        /// The attribute's name as written.
        name: String,
        /// "group" or "build".
        construct: &'static str,
        /// The attributes it accepts.
        allowed: &'static str,
        /// Where.
        span: Span,
    },
    /// E0112: `(f)(x)`, `a.f(x)`, ...
    NotCallable {
        /// The callee expression.
        span: Span,
    },
    /// E0113: `indirect group g by e { ... }`.
    IndirectGroupBy {
        /// The `by` clause.
        span: Span,
    },
}

impl SyntaxError {
    /// The error code.
    pub fn code(&self) -> &'static str {
        match self {
            SyntaxError::UnexpectedToken { .. } => "E0101",
            SyntaxError::MalformedLiteral { .. } => "E0102",
            SyntaxError::UnknownCharacter { .. } => "E0103",
            SyntaxError::IntegerTooLarge { .. } => "E0104",
            SyntaxError::BadVectorLanes { .. } => "E0105",
            SyntaxError::NestingTooDeep { .. } => "E0106",
            SyntaxError::ChainedComparison { .. } => "E0107",
            SyntaxError::InvalidAssignTarget { .. } => "E0108",
            SyntaxError::OneElementTuple { .. } => "E0109",
            SyntaxError::DuplicateRoot { .. } => "E0110",
            SyntaxError::UnknownAttribute { .. } => "E0111",
            SyntaxError::NotCallable { .. } => "E0112",
            SyntaxError::IndirectGroupBy { .. } => "E0113",
        }
    }

    /// The primary span.
    pub fn span(&self) -> Span {
        match self {
            SyntaxError::UnexpectedToken {
                missing_after: Some(after),
                ..
            } => Span::new(after.file, after.end, after.end),
            SyntaxError::UnexpectedToken { span, .. }
            | SyntaxError::MalformedLiteral { span, .. }
            | SyntaxError::UnknownCharacter { span, .. }
            | SyntaxError::IntegerTooLarge { span, .. }
            | SyntaxError::BadVectorLanes { span, .. }
            | SyntaxError::NestingTooDeep { span, .. }
            | SyntaxError::ChainedComparison { span, .. }
            | SyntaxError::InvalidAssignTarget { span }
            | SyntaxError::OneElementTuple { span, .. }
            | SyntaxError::DuplicateRoot { span, .. }
            | SyntaxError::UnknownAttribute { span, .. }
            | SyntaxError::NotCallable { span }
            | SyntaxError::IndirectGroupBy { span } => *span,
        }
    }

    /// The user-facing diagnostic.
    pub fn to_diagnostic(&self) -> Diagnostic {
        let code = self.code();
        match self {
            SyntaxError::UnexpectedToken {
                expected,
                found,
                span,
                missing_after: None,
            } => Diagnostic::error(code, format!("expected {expected}, found {found}"))
                .with_primary(*span, format!("expected {expected}")),
            SyntaxError::UnexpectedToken {
                expected,
                found,
                span,
                missing_after: Some(after),
            } => {
                let gap = Span::new(after.file, after.end, after.end);
                Diagnostic::error(code, format!("expected {expected}, found {found}"))
                    .with_primary(gap, format!("expected {expected} here"))
                    .with_secondary(*span, "unexpected token")
            }
            SyntaxError::MalformedLiteral { text, reason, span } => {
                Diagnostic::error(code, format!("malformed numeric literal `{text}`"))
                    .with_primary(*span, *reason)
                    .with_note(
                        "literals are decimal (`42`, `1_000`), hex (`0x1F`), binary (`0b101`) \
                         or floats (`1.0`, `1e-3`, `2.5e+8`, `inf`)",
                    )
            }
            SyntaxError::UnknownCharacter { ch, span } => {
                Diagnostic::error(code, format!("unknown character `{}`", ch.escape_debug()))
                    .with_primary(*span, "no token starts with this character")
            }
            SyntaxError::IntegerTooLarge {
                text,
                max,
                what,
                span,
            } => Diagnostic::error(code, format!("{what} `{text}` is too large"))
                .with_primary(*span, format!("the largest value allowed here is {max}")),
            SyntaxError::BadVectorLanes { text, span } => {
                Diagnostic::error(code, format!("invalid vector type `{text}`"))
                    .with_primary(*span, "the lane count must be between 1 and 2^32 - 1")
            }
            SyntaxError::NestingTooDeep { limit, span } => {
                Diagnostic::error(code, "the input is nested too deeply")
                    .with_primary(*span, format!("more than {limit} levels of nesting here"))
                    .with_note("split the expression or statement into smaller parts")
            }
            SyntaxError::ChainedComparison { op, span, first } => {
                Diagnostic::error(code, "comparison operators cannot be chained")
                    .with_primary(*span, format!("`{op}` compares the result of a comparison"))
                    .with_secondary(*first, "first comparison")
                    .with_note("use `&&` to combine comparisons, or parentheses to group them")
            }
            SyntaxError::InvalidAssignTarget { span } => {
                Diagnostic::error(code, "invalid left-hand side of `=`")
                    .with_primary(*span, "cannot assign to this expression")
                    .with_note(
                        "a target is a name, a field `e.x`, an element `e[i]` or a bit range \
                         `e[a:b]` (such as `this[a:b]` in a build)",
                    )
            }
            SyntaxError::OneElementTuple { what, span } => Diagnostic::error(
                code,
                format!("a tuple {what} needs at least two components"),
            )
            .with_primary(*span, "one component and a trailing comma")
            .with_note("remove the comma: parentheses around one component only group it"),
            SyntaxError::DuplicateRoot { span, first } => {
                Diagnostic::error(code, "a build has at most one `build root { ... }`")
                    .with_primary(*span, "second root entry")
                    .with_secondary(*first, "first root entry")
            }
            SyntaxError::UnknownAttribute {
                name,
                construct,
                allowed,
                span,
            } => Diagnostic::error(code, format!("unknown {construct} attribute `{name}`"))
                .with_primary(*span, "not an attribute here")
                .with_note(format!("a {construct} accepts {allowed}")),
            SyntaxError::NotCallable { span } => {
                Diagnostic::error(code, "only a function, type or variant name can be called")
                    .with_primary(*span, "this is not a name")
            }
            SyntaxError::IndirectGroupBy { span } => {
                Diagnostic::error(code, "an indirect group has no `by` index")
                    .with_primary(*span, "remove this clause")
                    .with_note("indirect groups are reached only through `Variant from g[e]`")
            }
        }
    }
}
