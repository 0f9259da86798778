//! Runs the lit suite in `lit-tests/` with the `scionc` built by this `cargo test`.
//!
//! A `harness = false` test: `cargo test` is the one test command, and it covers lit too. Ends
//! with a plain "N passed, N failed" line.

use std::path::PathBuf;
use std::process::Command;

fn main() {
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let lit = ["/usr/lib/llvm-22/bin/lit", "lit"].into_iter().find(|p| {
        Command::new(p)
            .arg("--version")
            .output()
            .is_ok_and(|o| o.status.success())
    });
    let Some(lit) = lit else {
        eprintln!("lit not found: run scripts/setup.sh (installs Debian's llvm-22-tools)");
        std::process::exit(1);
    };
    let scionc = env!("CARGO_BIN_EXE_scionc");
    let scion_opt = env!("CARGO_BIN_EXE_scion-opt");
    let out = Command::new(lit)
        .arg("-v")
        .arg("--param")
        .arg(format!("scionc={scionc}"))
        .arg("--param")
        .arg(format!("scion_opt={scion_opt}"))
        .arg(repo.join("lit-tests"))
        .output()
        .expect("running lit");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    print!("{stdout}");
    eprint!("{stderr}");
    // lit's summary lines look like "  Passed: 41" / "  Failed: 2".
    let count = |word: &str| -> usize {
        stdout
            .lines()
            .chain(stderr.lines())
            .filter_map(|l| l.trim().strip_prefix(word))
            .filter_map(|rest| rest.strip_prefix(':'))
            .filter_map(|n| n.split_whitespace().next()?.parse::<usize>().ok())
            .sum()
    };
    let passed = count("Passed") + count("Expectedly Failed");
    let failed =
        count("Failed") + count("Unresolved") + count("Unexpectedly Passed") + count("Timed Out");
    println!("lit: {passed} passed, {failed} failed");
    if !out.status.success() || failed > 0 || passed == 0 {
        std::process::exit(1);
    }
}
