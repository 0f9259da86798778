//! Source positions and diagnostics shared by every phase of the compiler.
//!
//! A [`Span`] is a byte range in one file of a [`SourceMap`]. A [`Diagnostic`] is rustc's data
//! model: a severity, an error code (grouped by phase: `E01xx` syntax, `E02xx` names and types,
//! `E03xx` layout well-formedness, `E04xx` build well-formedness, `E09xx` driver and I/O), a
//! message, labelled spans (one primary, any number of secondary) and notes. Rendering goes
//! through codespan-reporting in plain text, so the output is stable enough for FileCheck.
//!
//! User errors are `Diagnostic`s; compiler bugs are [`InternalError`]s, kept apart so the driver
//! can exit with 1 for the former and 101 for the latter.

use codespan_reporting::diagnostic as cs;
use codespan_reporting::files::{self, Files};
use codespan_reporting::term;
use std::fmt;
use std::ops::Range;

/// Identifies one source file inside a [`SourceMap`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct FileId(pub u32);

/// A half-open byte range `[start, end)` in one source file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct Span {
    /// The file the range lies in.
    pub file: FileId,
    /// First byte.
    pub start: u32,
    /// One past the last byte.
    pub end: u32,
}

impl Span {
    /// A span from `start` to `end` in `file`.
    pub fn new(file: FileId, start: u32, end: u32) -> Span {
        Span { file, start, end }
    }

    /// The smallest span covering both `self` and `other` (same file assumed).
    pub fn to(self, other: Span) -> Span {
        Span {
            file: self.file,
            start: self.start.min(other.start),
            end: self.end.max(other.end),
        }
    }

    /// The byte range as `usize`s.
    pub fn range(self) -> Range<usize> {
        self.start as usize..self.end as usize
    }
}

/// One file known to the compiler: its display name and its text.
#[derive(Clone, Debug)]
pub struct SourceFile {
    /// The name printed in diagnostics (usually the path as given on the command line).
    pub name: String,
    /// The full text.
    pub text: String,
    line_starts: Vec<usize>,
}

/// All source files of one compilation, addressed by [`FileId`].
#[derive(Clone, Debug, Default)]
pub struct SourceMap {
    files: Vec<SourceFile>,
}

impl SourceMap {
    /// An empty map.
    pub fn new() -> SourceMap {
        SourceMap::default()
    }

    /// Adds a file and returns its id.
    pub fn add(&mut self, name: impl Into<String>, text: impl Into<String>) -> FileId {
        let text = text.into();
        let line_starts = files::line_starts(&text).collect();
        self.files.push(SourceFile {
            name: name.into(),
            text,
            line_starts,
        });
        FileId(self.files.len() as u32 - 1)
    }

    /// The file with id `id`.
    ///
    /// # Panics
    /// If `id` was not returned by [`SourceMap::add`] on this map (a compiler bug).
    pub fn file(&self, id: FileId) -> &SourceFile {
        &self.files[id.0 as usize]
    }

    /// The text covered by `span`.
    pub fn snippet(&self, span: Span) -> &str {
        self.file(span.file).text.get(span.range()).unwrap_or("")
    }

    /// The 1-based line and column of the start of `span`.
    pub fn line_col(&self, span: Span) -> (usize, usize) {
        let f = self.file(span.file);
        let line = match f.line_starts.binary_search(&(span.start as usize)) {
            Ok(i) => i,
            Err(i) => i - 1,
        };
        (line + 1, span.start as usize - f.line_starts[line] + 1)
    }

    /// Number of files.
    pub fn len(&self) -> usize {
        self.files.len()
    }

    /// True when no file was added.
    pub fn is_empty(&self) -> bool {
        self.files.is_empty()
    }
}

impl<'a> Files<'a> for SourceMap {
    type FileId = FileId;
    type Name = &'a str;
    type Source = &'a str;

    fn name(&'a self, id: FileId) -> Result<&'a str, files::Error> {
        self.files
            .get(id.0 as usize)
            .map(|f| f.name.as_str())
            .ok_or(files::Error::FileMissing)
    }

    fn source(&'a self, id: FileId) -> Result<&'a str, files::Error> {
        self.files
            .get(id.0 as usize)
            .map(|f| f.text.as_str())
            .ok_or(files::Error::FileMissing)
    }

    fn line_index(&'a self, id: FileId, byte_index: usize) -> Result<usize, files::Error> {
        let f = self
            .files
            .get(id.0 as usize)
            .ok_or(files::Error::FileMissing)?;
        Ok(match f.line_starts.binary_search(&byte_index) {
            Ok(i) => i,
            Err(i) => i - 1,
        })
    }

    fn line_range(&'a self, id: FileId, line_index: usize) -> Result<Range<usize>, files::Error> {
        let f = self
            .files
            .get(id.0 as usize)
            .ok_or(files::Error::FileMissing)?;
        let start = *f
            .line_starts
            .get(line_index)
            .ok_or(files::Error::LineTooLarge {
                given: line_index,
                max: f.line_starts.len() - 1,
            })?;
        let end = f
            .line_starts
            .get(line_index + 1)
            .copied()
            .unwrap_or(f.text.len());
        Ok(start..end)
    }
}

/// How serious a diagnostic is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Severity {
    /// Extra information attached to nothing else.
    Note,
    /// Suspicious but accepted input (e.g. an unreachable `split` arm).
    Warning,
    /// Rejected input.
    Error,
}

/// A labelled span inside a diagnostic.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Label {
    /// Where.
    pub span: Span,
    /// What to say there (may be empty).
    pub message: String,
    /// The primary label marks the place the diagnostic is about; secondary ones add context.
    pub primary: bool,
}

/// A user-facing message about the input: code, message, labelled spans and notes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostic {
    /// Error, warning or note.
    pub severity: Severity,
    /// A stable code such as `E0307`; see the module docs for the grouping by phase.
    pub code: Option<String>,
    /// One line saying what is wrong.
    pub message: String,
    /// Labelled spans; the first primary label is the diagnostic's position.
    pub labels: Vec<Label>,
    /// Free-text notes printed after the source excerpt.
    pub notes: Vec<String>,
}

impl Diagnostic {
    /// A new error with a code and a message.
    pub fn error(code: &str, message: impl Into<String>) -> Diagnostic {
        Diagnostic::new(Severity::Error, code, message)
    }

    /// A new warning with a code and a message.
    pub fn warning(code: &str, message: impl Into<String>) -> Diagnostic {
        Diagnostic::new(Severity::Warning, code, message)
    }

    /// A new diagnostic of any severity.
    pub fn new(severity: Severity, code: &str, message: impl Into<String>) -> Diagnostic {
        Diagnostic {
            severity,
            code: if code.is_empty() {
                None
            } else {
                Some(code.to_string())
            },
            message: message.into(),
            labels: Vec::new(),
            notes: Vec::new(),
        }
    }

    /// Adds the primary label.
    pub fn with_primary(mut self, span: Span, message: impl Into<String>) -> Diagnostic {
        self.labels.push(Label {
            span,
            message: message.into(),
            primary: true,
        });
        self
    }

    /// Adds a secondary label.
    pub fn with_secondary(mut self, span: Span, message: impl Into<String>) -> Diagnostic {
        self.labels.push(Label {
            span,
            message: message.into(),
            primary: false,
        });
        self
    }

    /// Adds a note.
    pub fn with_note(mut self, note: impl Into<String>) -> Diagnostic {
        self.notes.push(note.into());
        self
    }

    /// The span of the first primary label, if any.
    pub fn primary_span(&self) -> Option<Span> {
        self.labels.iter().find(|l| l.primary).map(|l| l.span)
    }

    /// True for errors.
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }

    fn to_codespan(&self) -> cs::Diagnostic<FileId> {
        let severity = match self.severity {
            Severity::Note => cs::Severity::Note,
            Severity::Warning => cs::Severity::Warning,
            Severity::Error => cs::Severity::Error,
        };
        let mut d = cs::Diagnostic::new(severity).with_message(self.message.clone());
        if let Some(code) = &self.code {
            d = d.with_code(code.clone());
        }
        let labels = self
            .labels
            .iter()
            .map(|l| {
                let style = if l.primary {
                    cs::LabelStyle::Primary
                } else {
                    cs::LabelStyle::Secondary
                };
                cs::Label::new(style, l.span.file, l.span.range()).with_message(l.message.clone())
            })
            .collect();
        d.with_labels(labels).with_notes(self.notes.clone())
    }

    /// Renders this diagnostic as plain text (no colour) against `sources`.
    pub fn render(&self, sources: &SourceMap) -> String {
        let config = term::Config::default();
        match term::emit_into_string(&config, sources, &self.to_codespan()) {
            Ok(s) => s,
            // A span outside its file is a compiler bug; still say something useful.
            Err(_) => format!("{}: {}\n", severity_word(self.severity), self.message),
        }
    }
}

fn severity_word(s: Severity) -> &'static str {
    match s {
        Severity::Note => "note",
        Severity::Warning => "warning",
        Severity::Error => "error",
    }
}

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.code {
            Some(c) => write!(
                f,
                "{}[{}]: {}",
                severity_word(self.severity),
                c,
                self.message
            ),
            None => write!(f, "{}: {}", severity_word(self.severity), self.message),
        }
    }
}

/// A list of diagnostics collected by one phase.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Diagnostics {
    /// In the order reported.
    pub list: Vec<Diagnostic>,
}

impl Diagnostics {
    /// An empty list.
    pub fn new() -> Diagnostics {
        Diagnostics::default()
    }

    /// Adds one.
    pub fn push(&mut self, d: Diagnostic) {
        self.list.push(d);
    }

    /// Adds all of `other`.
    pub fn extend(&mut self, other: Diagnostics) {
        self.list.extend(other.list);
    }

    /// True when at least one is an error.
    pub fn has_errors(&self) -> bool {
        self.list.iter().any(Diagnostic::is_error)
    }

    /// Number of diagnostics.
    pub fn len(&self) -> usize {
        self.list.len()
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// Renders all of them, in order, as plain text.
    pub fn render(&self, sources: &SourceMap) -> String {
        self.list.iter().map(|d| d.render(sources)).collect()
    }
}

impl From<Diagnostic> for Diagnostics {
    fn from(d: Diagnostic) -> Diagnostics {
        Diagnostics { list: vec![d] }
    }
}

/// A compiler bug: an invariant broken by the compiler itself, never by user input.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InternalError {
    /// What broke.
    pub message: String,
    /// Context, typically the printed IR of the offending function with a marker.
    pub context: String,
}

impl InternalError {
    /// A new internal error.
    pub fn new(message: impl Into<String>) -> InternalError {
        InternalError {
            message: message.into(),
            context: String::new(),
        }
    }

    /// Attaches context (printed IR).
    pub fn with_context(mut self, context: impl Into<String>) -> InternalError {
        self.context = context.into();
        self
    }
}

impl fmt::Display for InternalError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "internal compiler error: {}", self.message)?;
        if !self.context.is_empty() {
            writeln!(f, "{}", self.context)?;
        }
        write!(
            f,
            "note: this is a bug in scionc; please report it with the input that caused it"
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_code_line_and_label() {
        let mut sm = SourceMap::new();
        let f = sm.add("a.scion", "type A(x: f32);\nfunc f() = y;\n");
        let d = Diagnostic::error("E0201", "unknown name `y`")
            .with_primary(Span::new(f, 27, 28), "not found in this scope")
            .with_note("names are looked up in the function, then globally");
        let s = d.render(&sm);
        assert!(s.contains("error[E0201]: unknown name `y`"), "{s}");
        assert!(s.contains("a.scion:2:12"), "{s}");
        assert!(s.contains("not found in this scope"), "{s}");
        assert_eq!(sm.line_col(Span::new(f, 27, 28)), (2, 12));
    }
}
