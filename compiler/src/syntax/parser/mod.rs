//! The parser: tokens → AST (`ast.rs`) for the traversal, layout and build languages
//! (paper Figures 3, 6 and 10; the concrete syntax is `docs/language.md`).
//!
//! Recursive descent, with precedence climbing for binary operators (`exprs.rs`). The parser
//! always returns what it could parse together with every error it found: a failed construct
//! reports one `E01xx` diagnostic and the enclosing list (statements of a block, members of a
//! layout, arms, items) skips to the next `;` or `}` at its own nesting level (items: to the
//! next item keyword) and carries on. Recursion is bounded by [`MAX_DEPTH`], so deeply nested
//! input is an error (`E0106`), never a stack overflow. Every loop consumes a token or stops,
//! so the parser terminates on any input.
//!
//! Files: `items.rs` (top level, `type`, `func`), `types.rs`, `exprs.rs`, `stmts.rs`,
//! `patterns.rs` (match and split patterns), `layout.rs`, `build.rs`.

mod build;
mod exprs;
mod items;
mod layout;
mod patterns;
mod stmts;
mod types;

pub(crate) use exprs::{binary_prec, is_comparison};

use super::ast::{Ident, Item, NodeId, Program};
use super::errors::SyntaxError;
use super::lexer::lex;
use super::token::{Keyword, Token, TokenKind};
use scion_ir::diag::{Diagnostics, FileId, SourceMap, Span};

/// How deeply expressions, statements, types and members may nest.
pub const MAX_DEPTH: usize = 256;

/// Parses `file` of `sources`, appending its items to `program`. NodeIds continue from
/// `program.node_count`, which is advanced past the last id handed out. Returns the lexical and
/// syntax errors of the file (empty when the file is well formed).
pub fn parse_file(sources: &SourceMap, file: FileId, program: &mut Program) -> Diagnostics {
    // Recursive descent on unoptimized builds takes several KiB of stack per nesting level, so
    // [`MAX_DEPTH`] levels need more than a test thread's 2 MiB: parse on a thread of our own
    // with a large stack (only the pages touched are committed), as rustc does. If no thread
    // can be started, parse here.
    let first_id = program.node_count;
    let parsed = std::thread::scope(|scope| {
        let worker = std::thread::Builder::new()
            .name("scion-parser".to_string())
            .stack_size(PARSER_STACK_BYTES)
            .spawn_scoped(scope, || parse_tokens(sources, file, first_id));
        match worker {
            Ok(handle) => handle
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic)),
            Err(_) => parse_tokens(sources, file, first_id),
        }
    });
    let (items, node_count, diags) = parsed;
    program.items.extend(items);
    program.node_count = node_count;
    diags
}

/// The stack of the parser's thread: ample for [`MAX_DEPTH`] levels in a debug build.
const PARSER_STACK_BYTES: usize = 64 << 20;

/// Lexes and parses one file: its items, the next free NodeId, and its diagnostics.
fn parse_tokens(sources: &SourceMap, file: FileId, first_id: u32) -> (Vec<Item>, u32, Diagnostics) {
    let mut diags = Diagnostics::new();
    let tokens = lex(&sources.file(file).text, file, &mut diags);
    let mut parser = Parser::new(tokens, file, first_id, &mut diags);
    let items = parser.items();
    let next_id = parser.next_id;
    // Lexical errors were found first; report everything in source order.
    diags
        .list
        .sort_by_key(|d| d.primary_span().map(|s| s.start));
    (items, next_id, diags)
}

/// Parses `files` in order into one program (the prelude, when wanted, is the caller's first
/// file). Diagnostics of all files are returned together, in file order.
pub fn parse_program(sources: &SourceMap, files: &[FileId]) -> (Program, Diagnostics) {
    let mut program = Program::default();
    let mut diags = Diagnostics::new();
    for &file in files {
        diags.extend(parse_file(sources, file, &mut program));
    }
    (program, diags)
}

/// The error already reported: unwind to the nearest list that recovers.
#[derive(Debug)]
pub(crate) struct Fail;

pub(crate) type PResult<T> = Result<T, Fail>;

pub(crate) struct Parser<'d> {
    tokens: Vec<Token>,
    pos: usize,
    file: FileId,
    next_id: u32,
    depth: usize,
    /// Set inside a match arm's body: a top-level `|` ends the arm instead of being `BitOr`.
    no_bar: bool,
    /// The token index of the last error, to report one error per position.
    last_error_at: Option<usize>,
    /// Set after the nesting limit: the rest of the file is skipped silently.
    bailed: bool,
    diags: &'d mut Diagnostics,
}

impl<'d> Parser<'d> {
    fn new(tokens: Vec<Token>, file: FileId, first_id: u32, diags: &'d mut Diagnostics) -> Self {
        Parser {
            tokens,
            pos: 0,
            file,
            next_id: first_id,
            depth: 0,
            no_bar: false,
            last_error_at: None,
            bailed: false,
            diags,
        }
    }

    // --- Token access -----------------------------------------------------------------------

    fn eof_index(&self) -> usize {
        self.tokens.len().saturating_sub(1)
    }

    fn tok(&self, n: usize) -> Option<&Token> {
        self.tokens.get((self.pos + n).min(self.eof_index()))
    }

    pub(crate) fn peek(&self) -> &TokenKind {
        self.peek_at(0)
    }

    pub(crate) fn peek_at(&self, n: usize) -> &TokenKind {
        self.tok(n).map_or(&TokenKind::Eof, |t| &t.kind)
    }

    pub(crate) fn span(&self) -> Span {
        self.tok(0).map_or(Span::new(self.file, 0, 0), |t| t.span)
    }

    /// The span of the last consumed token.
    pub(crate) fn prev_span(&self) -> Span {
        match self.pos.checked_sub(1).and_then(|i| self.tokens.get(i)) {
            Some(t) => t.span,
            None => Span::new(self.file, 0, 0),
        }
    }

    /// True when the list just closed ended with a comma (`(a,)`).
    pub(crate) fn closed_after_comma(&self) -> bool {
        self.pos
            .checked_sub(2)
            .and_then(|i| self.tokens.get(i))
            .is_some_and(|t| t.kind == TokenKind::Comma)
    }

    pub(crate) fn prev_is(&self, kind: &TokenKind) -> bool {
        self.pos
            .checked_sub(1)
            .and_then(|i| self.tokens.get(i))
            .is_some_and(|t| &t.kind == kind)
    }

    pub(crate) fn at(&self, kind: &TokenKind) -> bool {
        self.peek() == kind
    }

    pub(crate) fn at_kw(&self, kw: Keyword) -> bool {
        self.peek().is_kw(kw)
    }

    /// True at `type Name`, `func name` or `layout Name`: the start of an item, which occurs
    /// nowhere else (`build` also starts statements and expressions, so it is no anchor).
    /// Recovery stops there, so that a missing `}` or `)` costs one error, not the next item.
    pub(crate) fn at_item_anchor(&self) -> bool {
        matches!(
            self.peek(),
            TokenKind::Keyword(Keyword::Type | Keyword::Func | Keyword::Layout)
        ) && matches!(self.peek_at(1), TokenKind::Ident(_))
    }

    /// True when the current token is the contextual keyword `word`.
    pub(crate) fn at_word(&self, word: &str) -> bool {
        matches!(self.peek(), TokenKind::Ident(w) if w == word)
    }

    pub(crate) fn at_eof(&self) -> bool {
        self.at(&TokenKind::Eof)
    }

    pub(crate) fn bump(&mut self) {
        if self.pos < self.eof_index() {
            self.pos += 1;
        }
    }

    pub(crate) fn eat(&mut self, kind: &TokenKind) -> bool {
        let hit = self.at(kind);
        if hit {
            self.bump();
        }
        hit
    }

    pub(crate) fn eat_kw(&mut self, kw: Keyword) -> bool {
        let hit = self.at_kw(kw);
        if hit {
            self.bump();
        }
        hit
    }

    /// Consumes `kind` or reports "expected `kind`".
    pub(crate) fn expect(&mut self, kind: &TokenKind) -> PResult<Span> {
        if self.at(kind) {
            self.bump();
            Ok(self.prev_span())
        } else {
            Err(self.expected(&format!("`{}`", kind.punct_str())))
        }
    }

    pub(crate) fn expect_kw(&mut self, kw: Keyword) -> PResult<Span> {
        if self.eat_kw(kw) {
            Ok(self.prev_span())
        } else {
            Err(self.expected(&format!("`{}`", kw.as_str())))
        }
    }

    /// A name (contextual keywords included; reserved words are not names).
    pub(crate) fn ident(&mut self, what: &str) -> PResult<Ident> {
        match self.peek().clone() {
            TokenKind::Ident(name) => {
                self.bump();
                Ok(Ident {
                    name,
                    span: self.prev_span(),
                })
            }
            _ => Err(self.expected(what)),
        }
    }

    pub(crate) fn fresh_id(&mut self) -> NodeId {
        let id = NodeId(self.next_id);
        self.next_id = self.next_id.saturating_add(1);
        id
    }

    // --- Errors and recovery ----------------------------------------------------------------

    /// Reports `err` unless an error was already reported at this token or the parser bailed.
    pub(crate) fn report(&mut self, err: SyntaxError) {
        if self.bailed || self.last_error_at == Some(self.pos) {
            return;
        }
        self.last_error_at = Some(self.pos);
        self.diags.push(err.to_diagnostic());
    }

    /// Reports a problem that does not stop parsing (its position is not the current token).
    pub(crate) fn report_at_node(&mut self, err: SyntaxError) {
        if !self.bailed {
            self.diags.push(err.to_diagnostic());
        }
    }

    /// Reports "expected `expected`, found <current token>" and returns the failure.
    pub(crate) fn expected(&mut self, expected: &str) -> Fail {
        let err = SyntaxError::UnexpectedToken {
            expected: expected.to_string(),
            found: self.peek().describe(),
            span: self.span(),
            missing_after: None,
        };
        self.report(err);
        Fail
    }

    /// Reports a missing separator (`expected` is e.g. "`;` or `}`"): shown right after the
    /// last consumed token, where the separator belongs, rather than on the next line.
    pub(crate) fn expected_separator(&mut self, expected: &str) -> Fail {
        let err = SyntaxError::UnexpectedToken {
            expected: expected.to_string(),
            found: self.peek().describe(),
            span: self.span(),
            missing_after: (self.pos > 0).then(|| self.prev_span()),
        };
        self.report(err);
        Fail
    }

    /// Skips tokens up to (not including) a token in `stops` at the current nesting level.
    /// Bracketed groups are skipped whole. An unmatched `}` always stops; an unmatched `)` or
    /// `]` stops when it is in `stops` and is skipped otherwise. An item anchor (`type T`,
    /// `func f`, `layout L`) stops at any depth: reaching one means a closing bracket is
    /// missing, and the next item should still be parsed.
    pub(crate) fn skip_until(&mut self, stops: &[TokenKind]) {
        let mut depth = 0usize;
        loop {
            let kind = self.peek();
            if *kind == TokenKind::Eof || self.at_item_anchor() {
                return;
            }
            if depth == 0 && stops.contains(kind) {
                return;
            }
            match kind {
                TokenKind::LParen | TokenKind::LBracket | TokenKind::LBrace => depth += 1,
                TokenKind::RParen | TokenKind::RBracket | TokenKind::RBrace => {
                    if depth == 0 {
                        if *kind == TokenKind::RBrace {
                            return;
                        }
                    } else {
                        depth -= 1;
                    }
                }
                _ => {}
            }
            self.bump();
        }
    }

    /// Runs `f` one nesting level deeper, failing with `E0106` past [`MAX_DEPTH`].
    pub(crate) fn nested<T>(&mut self, f: impl FnOnce(&mut Self) -> PResult<T>) -> PResult<T> {
        if self.depth >= MAX_DEPTH {
            let err = SyntaxError::NestingTooDeep {
                limit: MAX_DEPTH,
                span: self.span(),
            };
            self.report(err);
            // Nothing sensible can follow: skip the rest of the file without further errors.
            self.bailed = true;
            self.pos = self.eof_index();
            return Err(Fail);
        }
        self.depth += 1;
        let result = f(self);
        self.depth -= 1;
        result
    }

    /// Runs `f`, then drops the levels that [`Parser::deepen`] added meanwhile. Used around
    /// loops that build left-deep trees (`a + b + c`, `x[0][1]`, `T[2][3]`), so that the depth
    /// of every tree the parser returns is bounded, not only the depth of its recursion.
    pub(crate) fn chained<T>(&mut self, f: impl FnOnce(&mut Self) -> PResult<T>) -> PResult<T> {
        let base = self.depth;
        let result = f(self);
        self.depth = base;
        result
    }

    /// Counts one more level of a left-deep chain (see [`Parser::chained`]).
    pub(crate) fn deepen(&mut self) -> PResult<()> {
        self.nested(|_| Ok(()))?;
        self.depth += 1;
        Ok(())
    }

    /// Runs `f` with the match-arm restriction on `|` set to `no_bar`.
    pub(crate) fn with_no_bar<T>(&mut self, no_bar: bool, f: impl FnOnce(&mut Self) -> T) -> T {
        let saved = std::mem::replace(&mut self.no_bar, no_bar);
        let result = f(self);
        self.no_bar = saved;
        result
    }

    /// Parses `elem (, elem)* ,?` up to and including `close` (the opener is already consumed).
    /// A failed element skips to the next `,` or `close`.
    pub(crate) fn comma_list<T>(
        &mut self,
        close: TokenKind,
        mut elem: impl FnMut(&mut Self) -> PResult<T>,
    ) -> PResult<Vec<T>> {
        let mut out = Vec::new();
        self.with_no_bar(false, |p| loop {
            if p.eat(&close) {
                return Ok(out);
            }
            let start = p.pos;
            match elem(p) {
                Ok(v) => out.push(v),
                Err(Fail) => {
                    // `;` never occurs inside a list (bodies with statements are not
                    // expressions), so it marks the end of the construct left open.
                    p.skip_until(&[TokenKind::Comma, TokenKind::Semi, close.clone()]);
                    let lost = p.at(&TokenKind::Semi) || p.at_item_anchor();
                    if lost || p.at_eof() || p.at(&TokenKind::RBrace) {
                        return Err(Fail);
                    }
                }
            }
            if p.eat(&TokenKind::Comma) {
                continue;
            }
            if p.eat(&close) {
                return Ok(out);
            }
            let stuck = p.at(&TokenKind::Semi) || p.at_item_anchor();
            if p.pos == start || p.at_eof() || p.at(&TokenKind::RBrace) || stuck || p.bailed {
                return Err(p.expected_separator(&format!("`,` or `{}`", close.punct_str())));
            }
            p.expected_separator(&format!("`,` or `{}`", close.punct_str()));
            p.skip_until(&[TokenKind::Comma, TokenKind::Semi, close.clone()]);
            if !p.eat(&TokenKind::Comma) && !p.at(&close) {
                return Err(Fail);
            }
        })
    }

    /// Parses `{ entry ; entry ; ... }` (the `{` already consumed) up to and including `}`.
    /// Entries are separated by `;`; one that ends in `}` (or a `---` separator) needs none. A failed entry skips to
    /// the next `;` or `}` of this level. Used for blocks, layout members, split arms and build
    /// entries.
    pub(crate) fn braced_list<T>(
        &mut self,
        what: &str,
        mut entry: impl FnMut(&mut Self) -> PResult<T>,
    ) -> Vec<T> {
        let mut out = Vec::new();
        self.with_no_bar(false, |p| loop {
            while p.eat(&TokenKind::Semi) {}
            if p.eat(&TokenKind::RBrace) {
                return out;
            }
            if p.at_eof() || p.at_item_anchor() {
                // A missing `}`: end the list here so the next item is parsed as one.
                p.expected(&format!("{what} or `}}`"));
                return out;
            }
            let start = p.pos;
            match entry(p) {
                Ok(v) => {
                    out.push(v);
                    // `}` and `---` end an entry by themselves.
                    let self_ended =
                        p.prev_is(&TokenKind::RBrace) || p.prev_is(&TokenKind::Separator);
                    if !(p.at(&TokenKind::Semi) || p.at(&TokenKind::RBrace) || self_ended) {
                        p.expected_separator("`;` or `}`");
                        p.skip_until(&[TokenKind::Semi]);
                    }
                }
                Err(Fail) => p.skip_until(&[TokenKind::Semi]),
            }
            if p.pos == start {
                p.bump();
            }
        })
    }
}
