//! What the tests that drive the command-line tools share: the repository root, whether a tool
//! runs, and building `scionc` (and the runtime's static library) with the `cargo` that runs
//! the test, in the release profile.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// The repository root.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// True when `tool --version` runs and succeeds.
pub fn have(tool: &str) -> bool {
    Command::new(tool)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

/// The newest modification time of the files under `dirs` (recursively) and of `files`.
fn newest(dirs: &[PathBuf], files: &[PathBuf]) -> Option<std::time::SystemTime> {
    let mut out: Option<std::time::SystemTime> = None;
    let mut see = |p: &Path| {
        if let Ok(t) = std::fs::metadata(p).and_then(|m| m.modified()) {
            out = Some(out.map_or(t, |o| o.max(t)));
        }
    };
    files.iter().for_each(|f| see(f));
    let mut stack: Vec<PathBuf> = dirs.to_vec();
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).ok()?.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else {
                see(&p);
            }
        }
    }
    out
}

/// Builds the release `scionc` (and with `runtime_lib`, `libscion_runtime.a`) and returns the
/// folder they are in.
///
/// A `scionc` newer than every source it is built from is taken as it is: the whole suite
/// (`cargo test --workspace --release`) has just built it, with the features that the
/// workspace's crates and their dev-dependencies unify to, where `cargo build -p
/// scion-compiler` would build a second variant of the compiler and the crates under it with
/// fewer features (flate2's and others' defaults, which other crates of the workspace turn on):
/// two minutes on two cores.
pub fn build_tools(runtime_lib: bool) -> PathBuf {
    let dir = match std::env::var_os("CARGO_TARGET_DIR") {
        Some(d) => PathBuf::from(d).join("release"),
        None => repo().join("target").join("release"),
    };
    let r = repo();
    let sources = ["compiler", "dialects", "runtime", "library"].map(|d| r.join(d));
    let manifests = [r.join("Cargo.toml"), r.join("Cargo.lock")];
    let built = std::fs::metadata(dir.join("scionc"))
        .and_then(|m| m.modified())
        .ok();
    let fresh = matches!((built, newest(&sources, &manifests)), (Some(b), Some(s)) if b > s);
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    let mut builds: Vec<&[&str]> = Vec::new();
    if !fresh {
        builds.push(&[
            "build",
            "--release",
            "-p",
            "scion-compiler",
            "--bin",
            "scionc",
        ]);
    }
    if runtime_lib {
        builds.push(&["build", "--release", "-p", "scion-runtime-c", "--lib"]);
    }
    for args in builds {
        let out = Command::new(&cargo)
            .current_dir(repo())
            .args(args)
            .output()
            .expect("runs cargo");
        assert!(
            out.status.success(),
            "cargo {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    dir
}
