//! One compilation: read the inputs, run the front end, generate and transform IR, write the
//! requested output.
//!
//! Input: [`Options`]. Output: text on standard output (or `-o`), diagnostics on standard
//! error, and an exit status (0 ok, 1 input errors, 2 a bad command line, 101 internal error).

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
/// Exit status for a bad command line (what `--help` promises, as the argument parser does).
pub const EXIT_USAGE: i32 = 2;
/// Exit status for internal compiler errors.
pub const EXIT_INTERNAL_ERROR: i32 = 101;

/// Runs one compilation and returns the process exit status.
pub fn run(opts: &Options) -> i32 {
    let mut err = std::io::stderr().lock();
    if opts.help_passes {
        return write_output(&mut err, None, pipelines::describe_passes().as_bytes());
    }
    if let Err(ni) = opts.check_implemented() {
        let d = Diagnostic::error("E0901", format!("`{}` is not implemented yet", ni.flag))
            .with_note(format!("it comes with {}", ni.planned))
            .with_note("see `scionc --help` for what works today");
        let _ = write!(err, "{}", d.render(&SourceMap::new()));
        return EXIT_USAGE;
    }
    let early = super::cli::check_flags(opts).and_then(|()| {
        // Cranelift's text needs the code generators too (E0922 in a build without them).
        #[cfg(not(feature = "backends"))]
        if opts.emit == Emit::Clif {
            return Err(super::codegen::missing(Emit::Clif));
        }
        if opts.emit.is_llvm() {
            super::codegen::select_target(opts).map(|_| ())
        } else {
            Ok(())
        }
    });
    if let Err(d) = early {
        let _ = write!(err, "{}", d.render(&SourceMap::new()));
        return EXIT_USAGE;
    }
    if opts.emit == Emit::Obj && opts.output_path().is_none() && std::io::stdout().is_terminal() {
        let d = Diagnostic::error("E0920", "`--emit=obj` writes a binary object file")
            .with_note("give the output file with -o PATH, or redirect standard output");
        let _ = write!(err, "{}", d.render(&SourceMap::new()));
        return EXIT_USAGE;
    }
    let pipeline = match pipelines::select(opts) {
        Ok(p) => p,
        Err(d) => {
            let _ = write!(err, "{}", d.render(&SourceMap::new()));
            return EXIT_USAGE;
        }
    };
    if opts.print_pipeline {
        return write_output(
            &mut err,
            None,
            format!("{}\n", pipeline.join(",")).as_bytes(),
        );
    }
    if opts.files.is_empty() {
        let d = Diagnostic::error("E0903", "no input files")
            .with_note("usage: scionc [OPTIONS] FILE...; try `scionc --help`");
        let _ = write!(err, "{}", d.render(&SourceMap::new()));
        return EXIT_USAGE;
    }
    if let Some(out) = opts.output_path() {
        let same =
            |p: &std::path::Path| match (std::fs::canonicalize(p), std::fs::canonicalize(out)) {
                (Ok(a), Ok(b)) => a == b,
                _ => false,
            };
        if let Some(input) = opts
            .files
            .iter()
            .chain(opts.prelude.iter())
            .find(|p| same(p))
        {
            let d = Diagnostic::error(
                "E0902",
                format!(
                    "`-o {}` would overwrite the input `{}`",
                    out.display(),
                    input.display()
                ),
            )
            .with_note("write the output to another file");
            let _ = write!(err, "{}", d.render(&SourceMap::new()));
            return EXIT_USAGE;
        }
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
        let status = write_output(&mut err, opts.output_path(), &bytes);
        if status != 0 {
            return status;
        }
    }
    if !result.dumps.is_empty() {
        let _ = err.write_all(result.dumps.as_bytes());
    }
    0
}

/// Writes `bytes` to `path` or, without one, to standard output; reports a failure (E0902,
/// exit status 1). A file is written whole or not at all: to a temporary file beside it, then
/// renamed over it, so a failed or interrupted write leaves the previous file as it was.
fn write_output(err: &mut impl Write, path: Option<&std::path::Path>, bytes: &[u8]) -> i32 {
    let Some(path) = path else {
        let mut out = std::io::stdout().lock();
        return match out.write_all(bytes).and_then(|()| out.flush()) {
            Ok(()) => 0,
            // A reader that stopped early (`scionc ... | head`) is not a failure.
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => 0,
            Err(e) => write_error(err, "standard output", &e),
        };
    };
    let name = path
        .file_name()
        .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
    let tmp = path.with_file_name(format!(".{name}.scionc-{}.tmp", std::process::id()));
    let written = std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, path));
    match written {
        Ok(()) => 0,
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            write_error(err, &format!("`{}`", path.display()), &e)
        }
    }
}

fn io_error(err: &mut impl Write, path: &str, e: &std::io::Error) -> i32 {
    let d = Diagnostic::error("E0902", format!("cannot read `{path}`: {e}"));
    let _ = write!(err, "{}", d.render(&SourceMap::new()));
    EXIT_USER_ERROR
}

fn write_error(err: &mut impl Write, path: &str, e: &std::io::Error) -> i32 {
    let d = Diagnostic::error("E0902", format!("cannot write {path}: {e}"));
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
