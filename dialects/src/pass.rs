//! The pass manager: passes as small named values, a registry of them, and pipelines (lists of
//! names) run with verification, IR dumps, early stop and timing between passes.
//!
//! Input: a [`Module`] and a pipeline; output: the transformed module, a [`PipelineReport`],
//! and the requested dumps written into a text sink. After each pass the manager resolves the
//! module's pending aliases (see [`crate::rewrite`]), checks the pass's output level (no op of
//! a dialect the level excludes survives) and, with `verify_each`, runs the verifier. A
//! verifier failure after a pass is a compiler bug: an [`InternalError`] naming the pass, with
//! the printed IR and the errors shown above the offending ops.
//!
//! ```text
//! // -----// IR Dump After dce //----- //
//! func @f(...) -> (...) { ... }
//! ```

use crate::diag::{Diagnostic, Diagnostics, InternalError};
use crate::module::Module;
use crate::op::Dialect;
use crate::print::print_module;
use crate::verify::verify;
use crate::walk;
use rustc_hash::FxHashMap;
use std::any::{Any, TypeId as AnyTypeId};
use std::fmt::Write;
use std::time::{Duration, Instant};

/// Why a pass (or the pipeline) failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum PassError {
    /// Problems with the user's input, reported as diagnostics.
    Diagnostics(Diagnostics),
    /// A compiler bug.
    Internal(InternalError),
}

impl std::fmt::Display for PassError {
    /// Diagnostics one per line (code and message; render them against the source map for
    /// positions), or the internal error with its IR.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PassError::Diagnostics(ds) => {
                for d in &ds.list {
                    writeln!(f, "{d}")?;
                }
                Ok(())
            }
            PassError::Internal(e) => write!(f, "{e}"),
        }
    }
}

impl From<Diagnostics> for PassError {
    fn from(d: Diagnostics) -> PassError {
        PassError::Diagnostics(d)
    }
}

impl From<Diagnostic> for PassError {
    fn from(d: Diagnostic) -> PassError {
        PassError::Diagnostics(d.into())
    }
}

impl From<InternalError> for PassError {
    fn from(e: InternalError) -> PassError {
        PassError::Internal(e)
    }
}

/// What a pass may read besides the module: options, a diagnostics sink and typed extensions
/// (the compiler puts the layout and build specifications there for the specializations).
#[derive(Default)]
pub struct PassCx {
    /// `--pass-opt=name:key=value` options, by pass name then key.
    pub options: FxHashMap<String, FxHashMap<String, String>>,
    /// Warnings and notes passes report without failing.
    pub diagnostics: Diagnostics,
    ext: FxHashMap<AnyTypeId, Box<dyn Any>>,
}

impl PassCx {
    /// An empty context.
    pub fn new() -> PassCx {
        PassCx::default()
    }

    /// The option `key` of pass `pass`.
    pub fn option(&self, pass: &str, key: &str) -> Option<&str> {
        self.options.get(pass)?.get(key).map(String::as_str)
    }

    /// Sets option `key` of `pass`.
    pub fn set_option(&mut self, pass: &str, key: &str, value: &str) {
        self.options
            .entry(pass.to_string())
            .or_default()
            .insert(key.to_string(), value.to_string());
    }

    /// Reads one `--pass-opt` value, `pass:key=value`. A malformed one is a user error (`E0962`).
    pub fn parse_option(&mut self, text: &str) -> Result<(), Diagnostic> {
        let parsed = text
            .split_once(':')
            .and_then(|(pass, kv)| Some((pass, kv.split_once('=')?)));
        match parsed {
            Some((pass, (key, value))) if !pass.is_empty() && !key.is_empty() => {
                self.set_option(pass, key, value);
                Ok(())
            }
            _ => Err(
                Diagnostic::error("E0962", format!("malformed pass option `{text}`"))
                    .with_note("expected `pass:key=value`, e.g. `inline:threshold=40`"),
            ),
        }
    }

    /// Stores an extension value, one per type.
    pub fn insert_ext<T: Any>(&mut self, value: T) {
        self.ext.insert(AnyTypeId::of::<T>(), Box::new(value));
    }

    /// The extension value of type `T`.
    pub fn ext<T: Any>(&self) -> Option<&T> {
        self.ext.get(&AnyTypeId::of::<T>())?.downcast_ref()
    }

    /// The extension value of type `T`, mutably.
    pub fn ext_mut<T: Any>(&mut self) -> Option<&mut T> {
        self.ext.get_mut(&AnyTypeId::of::<T>())?.downcast_mut()
    }
}

/// One transformation of a module.
pub trait Pass {
    /// The kebab-case name, also its command-line name (`const-fold`).
    fn name(&self) -> &'static str;
    /// One line saying what it does.
    fn summary(&self) -> &'static str;
    /// Runs the pass; returns whether the IR changed.
    fn run(&mut self, m: &mut Module, cx: &mut PassCx) -> Result<bool, PassError>;
}

/// The IR levels, for stating what a pass accepts and produces.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Level {
    /// Any level: the pass keeps the level of its input.
    Any,
    /// Only `tree` ops.
    Tree,
    /// `tree` and `mem` ops (after specialization to a layout).
    Mem,
}

impl Level {
    /// True when an op of `d` may exist at this level.
    pub fn allows(self, d: Dialect) -> bool {
        match self {
            Level::Any => true,
            Level::Tree => d == Dialect::Tree,
            Level::Mem => matches!(d, Dialect::Tree | Dialect::Mem),
        }
    }
}

/// A registry entry: how to make a pass and what it promises.
#[derive(Clone, Copy)]
pub struct PassInfo {
    /// Its name.
    pub name: &'static str,
    /// One line saying what it does.
    pub summary: &'static str,
    /// The level it expects.
    pub input: Level,
    /// The level it leaves (checked after it runs).
    pub output: Level,
    /// Makes a fresh instance.
    pub create: fn() -> Box<dyn Pass>,
}

/// The known passes, in a literal list.
#[derive(Clone, Default)]
pub struct PassRegistry {
    infos: Vec<PassInfo>,
}

impl PassRegistry {
    /// An empty registry.
    pub fn new() -> PassRegistry {
        PassRegistry::default()
    }

    /// The generic passes of this crate (`dce`, `const-fold`).
    pub fn with_builtin() -> PassRegistry {
        let mut r = PassRegistry::new();
        for info in crate::transforms::builtin_passes() {
            r.register(info);
        }
        r
    }

    /// Adds a pass; a later entry with the same name replaces the earlier one.
    pub fn register(&mut self, info: PassInfo) {
        self.infos.retain(|i| i.name != info.name);
        self.infos.push(info);
    }

    /// The entry called `name`.
    pub fn get(&self, name: &str) -> Option<&PassInfo> {
        self.infos.iter().find(|i| i.name == name)
    }

    /// All entries in registration order.
    pub fn infos(&self) -> &[PassInfo] {
        &self.infos
    }

    /// `name  summary` lines, for `--help-passes`.
    pub fn help(&self) -> String {
        let width = self.infos.iter().map(|i| i.name.len()).max().unwrap_or(0);
        let mut out = String::new();
        for i in &self.infos {
            let _ = writeln!(out, "  {:width$}  {}", i.name, i.summary);
        }
        out
    }
}

/// What to do between passes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PipelineOptions {
    /// Verify the input before the first pass (failures are user diagnostics, `E0960`).
    pub verify_input: bool,
    /// Verify after every pass (failures are internal errors naming the pass).
    pub verify_each: bool,
    /// Dump the module after every pass.
    pub print_after_all: bool,
    /// Dump the module after these passes.
    pub print_after: Vec<String>,
    /// Dump the module before these passes.
    pub print_before: Vec<String>,
    /// Dump the module before every pass.
    pub print_before_all: bool,
    /// Stop after the first run of this pass.
    pub stop_after: Option<String>,
    /// Record each pass's wall time in the report.
    pub time_passes: bool,
}

impl Default for PipelineOptions {
    fn default() -> PipelineOptions {
        PipelineOptions {
            verify_input: true,
            verify_each: true,
            print_after_all: false,
            print_after: Vec::new(),
            print_before: Vec::new(),
            print_before_all: false,
            stop_after: None,
            time_passes: false,
        }
    }
}

/// One pass's outcome in a pipeline run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PassRecord {
    /// The pass.
    pub name: &'static str,
    /// Whether it changed the IR.
    pub changed: bool,
    /// Its wall time, when timing was asked for.
    pub time: Option<Duration>,
}

/// The outcome of a pipeline run.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PipelineReport {
    /// The passes that ran, in order.
    pub passes: Vec<PassRecord>,
    /// True when `stop_after` ended the run early.
    pub stopped_early: bool,
}

impl PipelineReport {
    /// A `--time-passes` table: one line per pass with milliseconds, then the total.
    pub fn timing_table(&self) -> String {
        let mut out = String::from("===-------------------------------------------===\n  Pass execution timing report\n===-------------------------------------------===\n");
        let mut total = Duration::ZERO;
        for p in &self.passes {
            let t = p.time.unwrap_or_default();
            total += t;
            let _ = writeln!(out, "  {:>10.3} ms  {}", t.as_secs_f64() * 1e3, p.name);
        }
        let _ = writeln!(out, "  {:>10.3} ms  Total", total.as_secs_f64() * 1e3);
        out
    }
}

/// A pipeline ready to run.
pub struct PassManager {
    passes: Vec<(PassInfo, Box<dyn Pass>)>,
    /// What to do between passes.
    pub options: PipelineOptions,
}

impl PassManager {
    /// A pipeline of the named passes. An unknown name is a user error (`E0961`).
    pub fn from_names<S: AsRef<str>>(
        registry: &PassRegistry,
        names: &[S],
    ) -> Result<PassManager, Diagnostic> {
        let mut passes = Vec::new();
        for n in names {
            let n = n.as_ref();
            let info = registry.get(n).ok_or_else(|| {
                let known: Vec<&str> = registry.infos().iter().map(|i| i.name).collect();
                Diagnostic::error("E0961", format!("unknown pass `{n}`"))
                    .with_note(format!("known passes: {}", known.join(", ")))
            })?;
            passes.push((*info, (info.create)()));
        }
        Ok(PassManager {
            passes,
            options: PipelineOptions::default(),
        })
    }

    /// A pipeline from a comma-separated list (`"const-fold,dce"`).
    pub fn parse(registry: &PassRegistry, pipeline: &str) -> Result<PassManager, Diagnostic> {
        let names: Vec<&str> = pipeline
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .collect();
        PassManager::from_names(registry, &names)
    }

    /// The pass names in order (`--print-pipeline`).
    pub fn names(&self) -> Vec<&'static str> {
        self.passes.iter().map(|(i, _)| i.name).collect()
    }

    /// Runs the pipeline on `m`, writing requested dumps into `sink`.
    pub fn run(
        &mut self,
        m: &mut Module,
        cx: &mut PassCx,
        sink: &mut String,
    ) -> Result<PipelineReport, PassError> {
        let mut report = PipelineReport::default();
        // Aliases left by whoever built the module count as already applied.
        crate::rewrite::resolve_aliases(m);
        if self.options.verify_input {
            if let Err(e) = verify(m) {
                return Err(PassError::Diagnostics(e.to_diagnostics(m)));
            }
        }
        for (info, pass) in &mut self.passes {
            let name = info.name;
            if self.options.print_before_all || self.options.print_before.iter().any(|p| p == name)
            {
                dump(sink, "Before", name, m);
            }
            let start = Instant::now();
            let changed = pass.run(m, cx)?;
            let elapsed = start.elapsed();
            crate::rewrite::resolve_aliases(m);
            check_level(m, info.output, name)?;
            if self.options.verify_each {
                if let Err(e) = verify(m) {
                    return Err(PassError::Internal(
                        e.to_internal_error(&format!("after pass `{name}`")),
                    ));
                }
            }
            report.passes.push(PassRecord {
                name,
                changed,
                time: self.options.time_passes.then_some(elapsed),
            });
            if self.options.print_after_all || self.options.print_after.iter().any(|p| p == name) {
                dump(sink, "After", name, m);
            }
            if self.options.stop_after.as_deref() == Some(name) {
                report.stopped_early = true;
                break;
            }
        }
        Ok(report)
    }
}

fn dump(sink: &mut String, when: &str, name: &str, m: &Module) {
    let _ = writeln!(sink, "// -----// IR Dump {when} {name} //----- //");
    sink.push_str(&print_module(m));
    sink.push('\n');
}

/// Fails when an op of a dialect `level` excludes survives in a live function.
fn check_level(m: &Module, level: Level, pass: &str) -> Result<(), InternalError> {
    for &f in &m.func_order {
        for op in walk::func_ops(m, f, walk::Order::Pre) {
            let d = m.ops[op].kind.dialect();
            if !level.allows(d) {
                return Err(InternalError::new(format!(
                    "after pass `{pass}`: a `{}` op survives at level {level:?}",
                    m.ops[op].kind.name()
                ))
                .with_context(crate::print::print_func(m, f)));
            }
        }
    }
    Ok(())
}
