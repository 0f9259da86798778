//! One compilation: read the inputs, run the front end, generate and transform IR, write the
//! requested output.
//!
//! Input: [`Options`]. Output: text on standard output (or `-o`), diagnostics on standard
//! error, and an exit status (0 ok, 1 user errors, 101 internal error).

use super::cli::{Emit, Options};
use super::pipelines;
use crate::frontend::{self, Frontend};
use scion_ir::diag::{Diagnostic, Diagnostics, SourceMap};
use std::io::{IsTerminal, Write};

/// The prelude shipped inside the compiler, so `scionc` works from any directory.
pub const PRELUDE: &str = include_str!("../../../library/prelude.scion");
/// The name diagnostics use for the built-in prelude.
pub const PRELUDE_NAME: &str = "library/prelude.scion";

/// Exit status for input errors.
pub const EXIT_USER_ERROR: i32 = 1;
/// Exit status for internal compiler errors.
pub const EXIT_INTERNAL_ERROR: i32 = 101;

/// Runs one compilation and returns the process exit status.
pub fn run(opts: &Options) -> i32 {
    let mut err = std::io::stderr().lock();
    if opts.help_passes {
        let _ = write!(std::io::stdout(), "{}", pipelines::describe_passes());
        return 0;
    }
    if let Err(ni) = opts.check_implemented() {
        let d = Diagnostic::error("E0901", format!("`{}` is not implemented yet", ni.flag))
            .with_note(format!("it comes with {}", ni.planned))
            .with_note("see `scionc --help` for what works today");
        let _ = write!(err, "{}", d.render(&SourceMap::new()));
        return EXIT_USER_ERROR;
    }
    let early = super::cli::check_flags(opts).and_then(|()| {
        if opts.emit.is_llvm() {
            super::codegen::select_target(opts).map(|_| ())
        } else {
            Ok(())
        }
    });
    if let Err(d) = early {
        let _ = write!(err, "{}", d.render(&SourceMap::new()));
        return EXIT_USER_ERROR;
    }
    if opts.emit == Emit::Obj && opts.output.is_none() && std::io::stdout().is_terminal() {
        let d = Diagnostic::error("E0920", "`--emit=obj` writes a binary object file")
            .with_note("give the output file with -o PATH, or redirect standard output");
        let _ = write!(err, "{}", d.render(&SourceMap::new()));
        return EXIT_USER_ERROR;
    }
    let pipeline = match pipelines::select(opts) {
        Ok(p) => p,
        Err(d) => {
            let _ = write!(err, "{}", d.render(&SourceMap::new()));
            return EXIT_USER_ERROR;
        }
    };
    if opts.print_pipeline {
        let _ = writeln!(std::io::stdout(), "{}", pipeline.join(","));
        return 0;
    }
    if opts.files.is_empty() {
        let d = Diagnostic::error("E0903", "no input files")
            .with_note("usage: scionc [OPTIONS] FILE...; try `scionc --help`");
        let _ = write!(err, "{}", d.render(&SourceMap::new()));
        return EXIT_USER_ERROR;
    }

    let mut sources = SourceMap::new();
    let mut prelude_files = Vec::new();
    if !opts.no_prelude {
        match &opts.prelude {
            Some(path) => match std::fs::read_to_string(path) {
                Ok(text) => prelude_files.push(sources.add(path.display().to_string(), text)),
                Err(e) => return io_error(&mut err, &path.display().to_string(), &e),
            },
            None => prelude_files.push(sources.add(PRELUDE_NAME, PRELUDE)),
        }
    }
    let mut user_files = Vec::new();
    for path in &opts.files {
        match std::fs::read(path) {
            Ok(bytes) => match String::from_utf8(bytes) {
                Ok(text) => user_files.push(sources.add(path.display().to_string(), text)),
                Err(e) => {
                    let d = Diagnostic::error(
                        "E0904",
                        format!("`{}` is not valid UTF-8 text", path.display()),
                    )
                    .with_note(format!(
                        "first invalid byte at offset {}",
                        e.utf8_error().valid_up_to()
                    ));
                    let _ = write!(err, "{}", d.render(&sources));
                    return EXIT_USER_ERROR;
                }
            },
            Err(e) => return io_error(&mut err, &path.display().to_string(), &e),
        }
    }

    let fe = Frontend {
        sources: &sources,
        prelude: &prelude_files,
        inputs: &user_files,
    };
    let result = frontend::compile(
        &fe,
        opts.emit,
        &pipeline,
        &frontend::PassOptions::from(opts),
    );
    report(&mut err, &sources, &result.diagnostics, opts.error_limit);
    if let Some(ice) = result.internal_error {
        let _ = writeln!(err, "{ice}");
        return EXIT_INTERNAL_ERROR;
    }
    if result.diagnostics.has_errors() {
        return EXIT_USER_ERROR;
    }
    let bytes = match (&result.lo_module, result.output) {
        (Some(m), _) => match super::codegen::emit(m, opts) {
            Ok(b) => Some(b),
            Err(d) => {
                let _ = write!(err, "{}", d.render(&sources));
                return EXIT_USER_ERROR;
            }
        },
        (None, text) => text.map(String::into_bytes),
    };
    if let Some(bytes) = bytes {
        match &opts.output {
            Some(path) => {
                if let Err(e) = std::fs::write(path, bytes) {
                    return write_error(&mut err, &path.display().to_string(), &e);
                }
            }
            None => {
                let _ = std::io::stdout().lock().write_all(&bytes);
            }
        }
    }
    if !result.dumps.is_empty() {
        let _ = err.write_all(result.dumps.as_bytes());
    }
    0
}

fn io_error(err: &mut impl Write, path: &str, e: &std::io::Error) -> i32 {
    let d = Diagnostic::error("E0902", format!("cannot read `{path}`: {e}"));
    let _ = write!(err, "{}", d.render(&SourceMap::new()));
    EXIT_USER_ERROR
}

fn write_error(err: &mut impl Write, path: &str, e: &std::io::Error) -> i32 {
    let d = Diagnostic::error("E0902", format!("cannot write `{path}`: {e}"));
    let _ = write!(err, "{}", d.render(&SourceMap::new()));
    EXIT_USER_ERROR
}

fn report(err: &mut impl Write, sources: &SourceMap, diags: &Diagnostics, limit: usize) {
    let mut errors = 0;
    for d in &diags.list {
        if d.is_error() {
            errors += 1;
            if limit > 0 && errors > limit {
                let _ = writeln!(
                    err,
                    "error: too many errors ({limit}); stopping (see --error-limit)"
                );
                break;
            }
        }
        let _ = write!(err, "{}", d.render(sources));
    }
    let total = diags.list.iter().filter(|d| d.is_error()).count();
    if total > 0 {
        let plural = if total == 1 { "" } else { "s" };
        let _ = writeln!(err, "error: aborting due to {total} previous error{plural}");
    }
}
