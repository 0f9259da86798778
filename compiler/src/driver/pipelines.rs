//! Pass pipelines per optimization level: the only place that knows pass order.
//!
//! * `-O0`: nothing (the IR exactly as generated, for reading and for pass tests).
//! * `-O1` and up: `const-fold` first, so that `dce` sees the operands it made dead.
//! * `-O2` and up: `mem-cse` between them (after the specializations, which `select` puts
//!   first), so that `dce` drops the copies it made dead.
//! * `-O3`: the full DSL pipeline of paper §7.3: `mem-inline` first, so that `mem-cse` sees the
//!   inlined bodies side by side (the slab tests of `intersects` and `distmin` on one box).
//! * `-O2` and up end with `mem-split-loads` and `mem-sink`, after `dce` (dead uses would hold
//!   ops back): a layout array read whole only to be indexed is read one element at a time (an
//!   eight-wide node's child taken by a sorted key), and loads used only in a conditional region
//!   move into it (a DOP-14's cold diagonal slabs, the child a branch visits).
//! * `--no-dsl-opt`: none of these tree/mem optimizations at any level ([`DSL_PASSES`]); the
//!   specializations, the lowering and the backend's own optimizations stay. It is the
//!   baseline of the benchmark of what the DSL optimizations gain (`scripts/bench-dslopt.sh`).
//! * `--emit=mem` (with `--layout`), and `--emit=lo|clif` with `--layout`:
//!   `destructor-specialize` and `constructor-specialize` first, then the level's passes.
//!   `--emit=header` always specializes (it needs `--layout` and `--entry`).
//! * Then `prune-functions`, and for an output made from `lo` the lowering (`mem-to-lo`,
//!   `recursion-to-stack`, `lo-inline`) and with `--entry A` the exported entry points
//!   (`add-entries`) last: [`super::lower::complete`], also after an explicit `--passes` list
//!   (which may do its own lowering by naming `mem-to-lo`).

use super::cli::{Emit, Options};
use crate::passes;
use scion_ir::diag::Diagnostic;

/// The tree/mem optimizations (paper §7.3) that `--no-dsl-opt` leaves out.
pub const DSL_PASSES: &[&str] = &[
    "mem-inline",
    "const-fold",
    "mem-cse",
    "dce",
    "mem-split-loads",
    "mem-sink",
];

/// The passes of optimization level `level`.
pub fn for_level(level: u8) -> Vec<String> {
    let names: &[&str] = match level {
        0 => &[],
        1 => &["const-fold", "dce"],
        2 => &[
            "const-fold",
            "mem-cse",
            "dce",
            "mem-split-loads",
            "mem-sink",
        ],
        _ => &[
            "mem-inline",
            "const-fold",
            "mem-cse",
            "dce",
            "mem-split-loads",
            "mem-sink",
        ],
    };
    names.iter().map(|s| s.to_string()).collect()
}

/// The passes of level `level`, without the DSL optimizations when `dsl_opt` is false.
pub fn for_level_with(level: u8, dsl_opt: bool) -> Vec<String> {
    for_level(level)
        .into_iter()
        .filter(|n| dsl_opt || !DSL_PASSES.contains(&n.as_str()))
        .collect()
}

/// The pipeline the options ask for: `--passes` when given, else the `-O` level's. Unknown
/// pass names are reported (E0905) with the list of known ones.
pub fn select(opts: &Options) -> Result<Vec<String>, Diagnostic> {
    let names = match &opts.passes {
        Some(list) => list
            .iter()
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect(),
        None => {
            let mut names = Vec::new();
            let specialize = matches!(opts.emit, Emit::Mem | Emit::Header)
                || (opts.emit.lowers_to_lo() && opts.layout.is_some());
            if specialize {
                names.push("destructor-specialize".to_string());
                names.push("constructor-specialize".to_string());
            }
            names.extend(for_level_with(opts.opt_level, !opts.no_dsl_opt));
            names
        }
    };
    let names = super::lower::complete(names, opts.emit, opts.entry.is_some());
    let reg = passes::registry();
    for n in &names {
        if reg.get(n).is_none() {
            let known: Vec<&str> = reg.infos().iter().map(|i| i.name).collect();
            return Err(Diagnostic::error("E0905", format!("unknown pass `{n}`"))
                .with_note(format!("known passes: {}", known.join(", ")))
                .with_note("`scionc --help-passes` describes each"));
        }
    }
    if let Some(stop) = &opts.stop_after {
        if !names.iter().any(|n| n == stop) {
            return Err(Diagnostic::error(
                "E0906",
                format!("--stop-after={stop}: `{stop}` is not in the pipeline"),
            )
            .with_note(format!(
                "the pipeline is: {}",
                if names.is_empty() {
                    "(empty)".to_string()
                } else {
                    names.join(",")
                }
            )));
        }
    }
    Ok(names)
}

/// The `--help-passes` text.
pub fn describe_passes() -> String {
    let mut s = passes::registry().help();
    if !s.ends_with('\n') {
        s.push('\n');
    }
    s
}
