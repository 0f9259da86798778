//! What `scion` reads and writes around the long work: the report on standard output (a write
//! error is reported with a non-zero exit, never a panic), output files checked before loading
//! and written whole, and the command line's resource checks (threads, memory).
//!
//! Input: the parsed command line; output: `Ok` or a [`CliError`] naming the flag and the path
//! (usage errors exit 2, as the help says; failures of the machine or the files exit 1).

use crate::CliError;
use std::fmt;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The first error writing the report to standard output.
static STDOUT_ERROR: Mutex<Option<std::io::Error>> = Mutex::new(None);

/// `println!` for the report: a failed write is remembered (and later lines are dropped), and
/// [`finish_stdout`] turns it into an error.
macro_rules! outln {
    ($($arg:tt)*) => { $crate::io::out_line(format_args!($($arg)*)) };
}
pub(crate) use outln;

/// Writes one line of the report (see [`outln!`]).
pub fn out_line(args: fmt::Arguments<'_>) {
    let mut failed = STDOUT_ERROR.lock().unwrap_or_else(|e| e.into_inner());
    if failed.is_some() {
        return;
    }
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_fmt(args).and_then(|()| out.write_all(b"\n")) {
        *failed = Some(e);
    }
}

/// Flushes standard output; `Err` when any line of the report could not be written. A reader
/// that closed the pipe early (`scion layouts | head -3`) is not an error.
pub fn finish_stdout() -> Result<(), CliError> {
    let flushed = std::io::stdout().flush();
    let mut failed = STDOUT_ERROR.lock().unwrap_or_else(|e| e.into_inner());
    match failed.take().map_or(flushed, Err) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => Err(CliError::new(format!(
            "cannot write the report to standard output: {e}"
        ))),
    }
}

/// True when `a` and `b` name the same existing file (also through links).
fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// Checks, before any long work, that `output` (the value of `flag`) can be written: it is not
/// one of `inputs` (flag, path), not a folder, and its folder takes a new file. The write
/// itself is [`write_whole`].
pub fn check_output(flag: &str, output: &Path, inputs: &[(&str, &Path)]) -> Result<(), CliError> {
    for (input_flag, input) in inputs {
        if same_file(output, input) {
            return Err(CliError::usage(format!(
                "{flag} {} is the {input_flag} file: writing it would destroy the input",
                output.display()
            ))
            .note("name another output file"));
        }
    }
    if output.is_dir() {
        return Err(CliError::usage(format!(
            "{flag} {} is a folder; give a file name",
            output.display()
        )));
    }
    let probe = temp_beside(output, "probe");
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(
            CliError::new(format!("cannot write {flag} {}: {e}", output.display()))
                .note("checked before loading the scene, so no work is lost"),
        ),
    }
}

/// A temporary name in `path`'s folder (hidden, with this process's id).
fn temp_beside(path: &Path, what: &str) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
    path.with_file_name(format!(".{name}.scion-{what}-{}.tmp", std::process::id()))
}

/// Writes `bytes` to `path` whole or not at all (the runtime's temporary file and rename).
pub use scion_runtime::query::write_whole;

/// Most threads per core `--threads` may ask for: beyond it the threads only wait for one
/// another (2,000 threads on 2 cores took 41 s for a thousand triangles).
pub const THREADS_PER_CORE: usize = 8;

/// Checks `--threads`: 0 (one per core) or at most [`THREADS_PER_CORE`] per core; a note when
/// it is more than the cores (the timings then measure the scheduler too).
pub fn check_threads(threads: usize) -> Result<(), CliError> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if threads > cores * THREADS_PER_CORE {
        return Err(CliError::usage(format!(
            "--threads {threads}: this machine has {cores} core(s); at most {} threads ({} per \
             core) make sense",
            cores * THREADS_PER_CORE,
            THREADS_PER_CORE
        ))
        .note("--threads 0 starts one per core"));
    }
    if threads > cores {
        eprintln!(
            "scion: note: --threads {threads} on {cores} core(s): the threads share cores, so the \
             timings are not per-core throughput"
        );
    }
    Ok(())
}

/// The memory the machine has available now (`MemAvailable` of /proc/meminfo), when known.
fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Checks that `bytes` (what `what` needs) fit in the memory available, before allocating:
/// a clear error instead of the allocator's abort.
pub fn check_memory(what: &str, bytes: u64) -> Result<(), CliError> {
    let Some(available) = available_memory() else {
        return Ok(());
    };
    if bytes > available {
        let gib = |b: u64| b as f64 / (1u64 << 30) as f64;
        return Err(CliError::new(format!(
            "{what} need about {:.1} GiB; this machine has {:.1} GiB available",
            gib(bytes),
            gib(available)
        ))
        .note("trace fewer rays at a time (--n), or on a machine with more memory"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_writes_replace_and_leave_no_temporary() {
        let dir = std::env::temp_dir().join(format!("scion-cli-io-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("hits.bin");
        write_whole(&f, b"old").unwrap();
        write_whole(&f, b"new bytes").unwrap();
        assert_eq!(std::fs::read(&f).unwrap(), b"new bytes");
        assert_eq!(
            std::fs::read_dir(&dir).unwrap().count(),
            1,
            "no temporary left"
        );
        // A write into a missing folder fails and leaves nothing.
        assert!(write_whole(&dir.join("missing/hits.bin"), b"x").is_err());
        // The checks: an input, a folder, a missing folder.
        let e = check_output("-o", &f, &[("--scene", &f)]).unwrap_err();
        assert!(e.usage && e.message.contains("--scene"), "{}", e.message);
        assert!(check_output("-o", &dir, &[]).unwrap_err().usage);
        let e = check_output("-o", &dir.join("missing/x.bin"), &[]).unwrap_err();
        assert!(
            !e.usage && e.message.contains("cannot write"),
            "{}",
            e.message
        );
        assert!(check_output("-o", &dir.join("new.bin"), &[("--scene", &f)]).is_ok());
        assert_eq!(
            std::fs::read_dir(&dir).unwrap().count(),
            1,
            "the probe is removed"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
