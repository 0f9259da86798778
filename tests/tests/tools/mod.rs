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

/// Builds the release `scionc` (and with `runtime_lib`, `libscion_runtime.a`) and returns the
/// folder they are in.
pub fn build_tools(runtime_lib: bool) -> PathBuf {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    let mut builds: Vec<&[&str]> = vec![&[
        "build",
        "--release",
        "-p",
        "scion-compiler",
        "--bin",
        "scionc",
    ]];
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
    match std::env::var_os("CARGO_TARGET_DIR") {
        Some(d) => PathBuf::from(d).join("release"),
        None => repo().join("target").join("release"),
    }
}
