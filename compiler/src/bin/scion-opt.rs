//! `scion-opt`: reads text IR of any level, runs passes, prints the result (like `mlir-opt`).
//!
//! Pass tests use it so they do not depend on the front end:
//! `scion-opt --passes=const-fold,dce input.tree | FileCheck input.tree`.
//! With `--split-input-file`, the input is cut at lines `// -----` and each piece is processed
//! on its own (errors in one piece do not stop the others; the exit status reports any).

use clap::Parser;
use scion_compiler::passes;
use scion_ir::diag::{Diagnostic, SourceMap};
use scion_ir::pass::{PassCx, PassError, PassManager};
use std::io::{Read, Write};
use std::path::PathBuf;

/// scion-opt: run Scion passes on text IR (tree, mem or lo level) and print the result, for
/// testing passes one at a time (docs/ir.md).
#[derive(Debug, Parser)]
#[command(name = "scion-opt", version)]
struct Args {
    /// Input file with text IR (`-` or nothing: standard input).
    #[arg(value_name = "FILE")]
    input: Option<PathBuf>,
    /// Passes to run, in order (comma-separated). None: parse, verify and print.
    #[arg(long, value_name = "P1,P2,...", value_delimiter = ',')]
    passes: Vec<String>,
    /// Treat `// -----` lines as separators between independent inputs.
    #[arg(long)]
    split_input_file: bool,
    /// Print the IR after every pass (to standard error).
    #[arg(long)]
    print_after_all: bool,
    /// Stop after the named pass.
    #[arg(long, value_name = "PASS")]
    stop_after: Option<String>,
    /// Do not verify the input before the first pass.
    #[arg(long)]
    no_verify_input: bool,
    /// List the passes and stop.
    #[arg(long)]
    help_passes: bool,
    /// What to print: the IR (`ir`, default) or, for a `lo` module, its Cranelift IR (`clif`),
    /// its LLVM IR as translated, before LLVM optimizes (`llvm`), its assembly (`asm`, PTX
    /// for nvptx64; LLVM -O2) or upstream MLIR (`mlir`).
    #[arg(long, value_name = "ir|clif|llvm|asm|mlir", default_value = "ir")]
    emit: String,
    /// The LLVM target of `--emit=llvm|asm`: x86_64, aarch64 or nvptx64 (default: this machine).
    #[arg(long, value_name = "TARGET")]
    target: Option<String>,
    /// The layout `destructor-specialize` and `constructor-specialize` specialize to: one of
    /// the module's `tree.layout` records (which `scionc --emit=tree` writes); without it, the
    /// only one.
    #[arg(long, value_name = "NAME")]
    layout: Option<String>,
    /// A pass option `pass:key=value` (repeatable), e.g. `recursion-to-stack:stack-size=8`.
    #[arg(long = "pass-option", value_name = "PASS:KEY=VALUE")]
    pass_options: Vec<String>,
}

fn main() {
    let args = Args::parse();
    std::process::exit(run(&args));
}

fn run(args: &Args) -> i32 {
    let registry = passes::registry();
    if !["ir", "clif", "llvm", "asm", "mlir"].contains(&args.emit.as_str()) {
        eprintln!(
            "error[E0907]: --emit={}: expected `ir`, `clif`, `llvm`, `asm` or `mlir`",
            args.emit
        );
        return 2;
    }
    let target = match args.target.as_deref() {
        None => scion_llvm::Target::host(),
        Some(t) => scion_llvm::Target::from_name(t),
    };
    let Some(target) = target else {
        eprintln!("error[E0907]: --target: expected x86_64, aarch64 or nvptx64");
        return 2;
    };
    if args.help_passes {
        println!("{}", registry.help().trim_end());
        return 0;
    }
    let (name, text) = match read_input(args.input.as_ref()) {
        Ok(x) => x,
        Err(d) => {
            eprint!("{}", d.render(&SourceMap::new()));
            return 1;
        }
    };
    let pieces: Vec<String> = if args.split_input_file {
        split(&text)
    } else {
        vec![text]
    };
    let mut status = 0;
    let mut out = std::io::stdout().lock();
    // The first failed write to standard output (a full disk, a closed pipe): an error.
    let mut failed: Option<std::io::Error> = None;
    for (i, piece) in pieces.iter().enumerate() {
        if i > 0 {
            if let Err(e) = writeln!(out, "// -----") {
                failed.get_or_insert(e);
            }
        }
        let mut sources = SourceMap::new();
        let file = sources.add(name.clone(), piece.clone());
        let mut module = match scion_ir::parse::parse_module(piece, file) {
            Ok(m) => m,
            Err(d) => {
                eprint!("{}", d.render(&sources));
                status = 1;
                continue;
            }
        };
        let mut pm = match PassManager::from_names(&registry, &args.passes) {
            Ok(pm) => pm,
            Err(d) => {
                eprint!("{}", d.render(&sources));
                return 1;
            }
        };
        pm.options.verify_input = !args.no_verify_input;
        pm.options.print_after_all = args.print_after_all;
        pm.options.stop_after = args.stop_after.clone();
        let mut cx = PassCx::new();
        if let Some(l) = &args.layout {
            cx.insert_ext(passes::tree_to_mem::LayoutChoice(l.clone()));
        }
        for o in &args.pass_options {
            if let Err(d) = cx.parse_option(o) {
                eprint!("{}", d.render(&sources));
                return 1;
            }
        }
        let mut dumps = String::new();
        let result = pm.run(&mut module, &mut cx, &mut dumps);
        eprint!("{dumps}");
        eprint!("{}", cx.diagnostics.render(&sources));
        match result {
            Ok(_) if args.emit == "clif" => match scion_clif::print_clif(&module) {
                Ok(text) => {
                    if let Err(e) = write!(out, "{text}") {
                        failed.get_or_insert(e);
                    }
                }
                Err(e) => {
                    eprintln!("error[E0907]: {e}");
                    status = 1;
                }
            },
            Ok(_) if args.emit == "mlir" => match scion_compiler::mlir::print_mlir(&module) {
                Ok(text) => {
                    if let Err(e) = write!(out, "{text}") {
                        failed.get_or_insert(e);
                    }
                }
                Err(d) => {
                    eprint!("{}", d.render(&sources));
                    status = 1;
                }
            },
            Ok(_) if args.emit == "llvm" || args.emit == "asm" => {
                let text = if args.emit == "llvm" {
                    scion_llvm::translate_to_ir(&module, target)
                } else {
                    let opts = scion_llvm::Options::new(target);
                    scion_llvm::emit(&module, &opts, scion_llvm::Output::Asm)
                        .map(|b| String::from_utf8_lossy(&b).into_owned())
                };
                match text {
                    Ok(text) => {
                        if let Err(e) = write!(out, "{text}") {
                            failed.get_or_insert(e);
                        }
                    }
                    Err(e) => {
                        eprintln!("error[E0907]: {e}");
                        status = 1;
                    }
                }
            }
            Ok(_) => {
                if let Err(e) = write!(out, "{}", scion_ir::print::print_module(&module)) {
                    failed.get_or_insert(e);
                }
            }
            Err(PassError::Diagnostics(d)) => {
                eprint!("{}", d.render(&sources));
                status = 1;
            }
            Err(PassError::Internal(e)) => {
                eprintln!("{e}");
                return 101;
            }
        }
    }
    match failed.or_else(|| out.flush().err()) {
        // A reader that stopped early (`scion-opt ... | head`) is not a failure.
        Some(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {}
        Some(e) => {
            eprintln!("error[E0902]: cannot write standard output: {e}");
            return 1;
        }
        None => {}
    }
    status
}

fn read_input(path: Option<&PathBuf>) -> Result<(String, String), Diagnostic> {
    match path {
        Some(p) if p.as_os_str() != "-" => std::fs::read_to_string(p)
            .map(|t| (p.display().to_string(), t))
            .map_err(|e| Diagnostic::error("E0902", format!("cannot read `{}`: {e}", p.display()))),
        _ => {
            let mut s = String::new();
            std::io::stdin()
                .read_to_string(&mut s)
                .map(|_| ("<stdin>".to_string(), s))
                .map_err(|e| Diagnostic::error("E0902", format!("cannot read standard input: {e}")))
        }
    }
}

/// Cuts at `// -----` lines, keeping line numbers of each piece aligned with the whole file by
/// replacing earlier pieces with blank lines.
fn split(text: &str) -> Vec<String> {
    let mut pieces = Vec::new();
    let mut current = String::new();
    for (lineno, line) in text.split_inclusive('\n').enumerate() {
        if line.trim_end() == "// -----" {
            pieces.push(std::mem::take(&mut current));
            current = "\n".repeat(lineno + 1);
            continue;
        }
        current.push_str(line);
    }
    pieces.push(current);
    pieces
}
