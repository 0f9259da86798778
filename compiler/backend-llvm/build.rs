//! Writes the CPU names LLVM 22 knows for each target (from `llc -march=A -mcpu=help` of the
//! LLVM that llvm-sys links) to `$OUT_DIR/cpus.rs`, so `--cpu` is checked before LLVM sees it:
//! LLVM itself only warns about an unknown CPU and carries on with generic code (or aborts on
//! NVPTX). Without `llc` the lists are empty and the build says so; the check then falls back
//! to the shape of the name.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::Command;

fn main() {
    println!("cargo:rerun-if-env-changed=LLVM_SYS_221_PREFIX");
    let prefix = std::env::var("LLVM_SYS_221_PREFIX").unwrap_or_else(|_| "/usr/lib/llvm-22".into());
    let llc = PathBuf::from(&prefix).join("bin/llc");
    println!("cargo:rerun-if-changed={}", llc.display());
    let mut out = String::new();
    for (name, march) in [
        ("X86_64", "x86-64"),
        ("AARCH64", "aarch64"),
        ("NVPTX64", "nvptx64"),
    ] {
        let cpus = match Command::new(&llc)
            .arg(format!("-march={march}"))
            .arg("-mcpu=help")
            .output()
        {
            Ok(o) => {
                let text = String::from_utf8_lossy(&o.stdout).into_owned()
                    + &String::from_utf8_lossy(&o.stderr);
                cpu_names(&text)
            }
            Err(e) => {
                println!(
                    "cargo:warning={}: {e}; --cpu names are not checked",
                    llc.display()
                );
                Vec::new()
            }
        };
        writeln!(out, "/// The CPUs LLVM knows for `-march={march}`.").unwrap();
        writeln!(out, "pub const {name}_CPUS: &[&str] = &{cpus:?};").unwrap();
    }
    let dest = PathBuf::from(std::env::var("OUT_DIR").unwrap()).join("cpus.rs");
    std::fs::write(&dest, out).unwrap();
}

/// The names between "Available CPUs for this target:" and "Available features".
fn cpu_names(help: &str) -> Vec<String> {
    let mut names: Vec<String> = help
        .split("Available CPUs for this target:")
        .nth(1)
        .and_then(|rest| rest.split("Available features").next())
        .unwrap_or("")
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .filter(|w| *w != "-")
        .map(str::to_string)
        .collect();
    names.sort();
    names.dedup();
    names
}
