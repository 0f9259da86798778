//! The compilation pipeline as a library call: sources in, diagnostics and output text out.
//!
//! `scionc` (through `driver::session`) and the tests call [`compile`]: parse the prelude and the
//! inputs, run `sema` and the well-formedness checks, generate the `tree` dialect, run the pass
//! pipeline and print what `--emit` asks for. Every failure is a value: user errors are
//! [`Diagnostics`], compiler bugs an [`InternalError`]; nothing here panics on user input.

use crate::abi::{self, EntrySig, EntryTarget};
use crate::driver::cli::{Emit, Options, Target};
use crate::driver::lower;
use crate::layout::model::Models;
use crate::layout::{check_build, check_layout};
use crate::passes::lo::entries::EntryRequest;
use crate::passes::prune::UserFiles;
use crate::passes::tree_to_mem::LayoutSpec;
use crate::syntax::ast::{Item, Program};
use crate::{irgen, passes, sema, syntax};
use scion_ir::diag::{Diagnostic, Diagnostics, FileId, InternalError, SourceMap};
use scion_ir::pass::{PassCx, PassError, PassManager};
use scion_ir::Module;

/// The files of one compilation.
pub struct Frontend<'a> {
    /// Every file's text.
    pub sources: &'a SourceMap,
    /// Prelude files, loaded first (their functions are printed only when used).
    pub prelude: &'a [FileId],
    /// The user's files, in command-line order.
    pub inputs: &'a [FileId],
}

/// Instrumentation of the pass pipeline.
#[derive(Clone, Debug, Default)]
pub struct PassOptions {
    /// Dump the IR after every pass.
    pub print_after_all: bool,
    /// Dump the IR before every pass.
    pub print_before_all: bool,
    /// Stop after this pass.
    pub stop_after: Option<String>,
    /// Record pass times.
    pub time_passes: bool,
    /// `--layout NAME`: the layout the specialization passes target.
    pub layout: Option<String>,
    /// Entries of a traversal's explicit stack (`--stack-size`, for `--emit=lo|clif`).
    pub stack_size: Option<u32>,
    /// `--entry NAME`: add the exported C entry points of this algorithm (`abi`).
    pub entry: Option<String>,
    /// Whether the entries are for a GPU (`--target nvptx64`: kernels too).
    pub entry_target: EntryTarget,
}

impl From<&Options> for PassOptions {
    fn from(o: &Options) -> PassOptions {
        PassOptions {
            print_after_all: o.print_after_all,
            print_before_all: o.print_before_all,
            stop_after: o.stop_after.clone(),
            time_passes: o.time_passes,
            layout: o.layout.clone(),
            stack_size: o.stack_size,
            entry: o.entry.clone(),
            entry_target: match (o.target, o.emit) {
                (Some(Target::Nvptx64), _) | (_, Emit::Ptx) => EntryTarget::Gpu,
                _ => EntryTarget::Host,
            },
        }
    }
}

/// What a compilation produced.
#[derive(Debug, Default)]
pub struct CompileResult {
    /// Errors and warnings, in the order found.
    pub diagnostics: Diagnostics,
    /// A compiler bug, if one happened.
    pub internal_error: Option<InternalError>,
    /// The requested output (none for `--emit=check` or on error).
    pub output: Option<String>,
    /// For `--emit=llvm|asm|obj|ptx`: the `lo` module the LLVM backend compiles (the driver
    /// runs the backend with its target options; `output` stays empty).
    pub lo_module: Option<Module>,
    /// With `--entry`: the C signature of the exported entry points (their records and the
    /// layout's buffers, as `--emit=header` describes them), once the pipeline has run.
    pub entry: Option<EntrySig>,
    /// With `--layout`: the logical tree its constructor reads (`layout::logical`), when the
    /// runtime can fill it (otherwise `constructor-specialize` reports why).
    pub logical: Option<scion_runtime::bvh::schema::Schema>,
    /// IR dumps and timing reports asked for by the pass options (for standard error).
    pub dumps: String,
}

/// Parses, checks, lowers and transforms; see the module docs.
pub fn compile(
    fe: &Frontend<'_>,
    emit: Emit,
    pipeline: &[String],
    popts: &PassOptions,
) -> CompileResult {
    let mut out = CompileResult::default();
    if let Some(d) = entry_request_error(emit, popts) {
        out.diagnostics.push(d);
        return out;
    }
    let files: Vec<FileId> = fe.prelude.iter().chain(fe.inputs).copied().collect();
    let (program, diags) = syntax::parse_program(fe.sources, &files);
    let parse_failed = diags.has_errors();
    out.diagnostics.extend(diags);
    if parse_failed {
        return out;
    }
    if emit == Emit::Ast {
        out.output = Some(syntax::print::print_program(&user_items(
            &program, fe.inputs,
        )));
        return out;
    }

    let (typed, diags) = sema::check_program(&program);
    out.diagnostics.extend(diags);
    // One model per layout, realizing the type sema chose; the structural checks of paper §6
    // read it.
    let models = Models::of(&program, &typed);
    out.diagnostics
        .extend(check_layout::check_layouts(&program, &models));
    out.diagnostics
        .extend(check_build::check_builds(&program, &models));
    if out.diagnostics.has_errors() || emit == Emit::Check {
        return out;
    }

    let mut module = match irgen::generate(&program, &typed) {
        Ok(m) => m,
        Err(e) => {
            out.internal_error = Some(e);
            return out;
        }
    };
    module.layouts = crate::layout::carried::layout_sources(&program, &models);
    if emit == Emit::Mem && popts.layout.is_none() {
        out.diagnostics.push(
            Diagnostic::error("E0908", "`--emit=mem` needs a layout").with_note(format!(
                "choose one with `--layout NAME`{}",
                known_layouts(&program)
            )),
        );
        return out;
    }
    let mut cx = PassCx::new();
    let mut entry: Option<EntrySig> = None;
    if let Some(name) = &popts.layout {
        let decl = program.items.iter().find_map(|it| match it {
            Item::Layout(d) if d.name.name == *name => Some(d),
            _ => None,
        });
        let Some(decl) = decl else {
            out.diagnostics.push(
                Diagnostic::error(
                    "E0908",
                    format!("`--layout {name}`: no layout of that name"),
                )
                .with_note(format!("the inputs declare{}", known_layouts(&program))),
            );
            return out;
        };
        let Some(model) = models.get(&decl.name.name).cloned() else {
            return out;
        };
        let logical = model
            .adt
            .as_ref()
            .map(|a| crate::layout::logical::LogicalAbi::derive(&module, a));
        out.logical = logical
            .as_ref()
            .and_then(|l| l.as_ref().ok())
            .map(|l| l.schema.clone());
        let spec = LayoutSpec::new(model);
        if let Some(algorithm) = &popts.entry {
            match abi::signature(&program, &module, algorithm, &spec, logical.as_ref()) {
                Ok(sig) => entry = Some(sig),
                Err(d) => {
                    out.diagnostics.push(d);
                    return out;
                }
            }
        }
        cx.insert_ext(spec);
    }
    // One pipeline to the requested output: the given passes, then pruning, the lowering and
    // the entries as the output needs them (driver::lower).
    let pipeline = lower::complete(pipeline.to_vec(), emit, entry.is_some());
    cx.insert_ext(UserFiles(fe.inputs.to_vec()));
    if let Some(sig) = &entry {
        cx.insert_ext(EntryRequest {
            sig: sig.clone(),
            target: popts.entry_target,
        });
    }
    if let Err(d) = lower::lowering_options(&mut cx, &pipeline, popts.stack_size) {
        out.diagnostics.push(d);
        return out;
    }
    let stopped = match run_pipeline(&mut module, &pipeline, popts, &mut cx, &mut out) {
        Ok(stopped) => stopped,
        Err(e) => {
            match e {
                PassError::Diagnostics(d) => out.diagnostics.extend(d),
                PassError::Internal(i) => out.internal_error = Some(i),
            }
            return out;
        }
    };
    out.entry = entry.clone();
    if stopped {
        // `--stop-after`: the IR where the pipeline stopped, whatever the output asked for.
        out.output = Some(scion_ir::print::print_module(&module));
        return out;
    }
    if emit.is_llvm() {
        out.lo_module = Some(module);
        return out;
    }
    if lower::needs_lo(emit) {
        match lower::render_low(&module, emit, entry.as_ref()) {
            Ok(text) => out.output = Some(text),
            Err(PassError::Diagnostics(d)) => out.diagnostics.extend(d),
            Err(PassError::Internal(i)) => out.internal_error = Some(i),
        }
        return out;
    }
    out.output = Some(scion_ir::print::print_module(&module));
    out
}

/// The driver's checks of `--entry` and `--emit=header` that need no input (E0910, E0914,
/// E0915).
fn entry_request_error(emit: Emit, popts: &PassOptions) -> Option<Diagnostic> {
    match (&popts.entry, emit) {
        (None, Emit::Header) => Some(
            Diagnostic::error(
                "E0915",
                "`--emit=header` needs `--entry NAME` and `--layout NAME`",
            )
            .with_note("the header declares the entry points of one algorithm and one layout"),
        ),
        (Some(a), Emit::Ast | Emit::Tree | Emit::Mem | Emit::Check) => Some(
            Diagnostic::error(
                "E0914",
                format!(
                    "`--entry {a}` has no effect with `--emit={}`",
                    emit.as_str()
                ),
            )
            .with_note("entry points are added after lowering: use `--emit=lo|clif|header`"),
        ),
        (Some(a), _) if popts.layout.is_none() => Some(abi::needs_layout(a)),
        _ => None,
    }
}

/// Runs `pipeline` on `m`; returns whether `--stop-after` ended it early.
fn run_pipeline(
    m: &mut Module,
    pipeline: &[String],
    popts: &PassOptions,
    cx: &mut PassCx,
    out: &mut CompileResult,
) -> Result<bool, PassError> {
    let registry = passes::registry();
    let mut pm = PassManager::from_names(&registry, pipeline)
        .map_err(|d| PassError::Diagnostics(d.into()))?;
    pm.options.print_after_all = popts.print_after_all;
    if popts.print_before_all {
        pm.options.print_before = pipeline.to_vec();
    }
    pm.options.stop_after = popts.stop_after.clone();
    pm.options.time_passes = popts.time_passes;
    let result = pm.run(m, cx, &mut out.dumps);
    // Warnings of the passes that ran come out even when a later pass fails (W0970 explains
    // an E0916 of `add-entries`).
    out.diagnostics.extend(std::mem::take(&mut cx.diagnostics));
    let report = result?;
    if popts.time_passes {
        out.dumps.push_str(&report.timing_table());
    }
    Ok(report.stopped_early)
}

/// `: A, B` listing the layouts of `program` (or ` no layout`), for notes.
fn known_layouts(program: &Program) -> String {
    let names: Vec<&str> = program
        .items
        .iter()
        .filter_map(|it| match it {
            Item::Layout(d) => Some(d.name.name.as_str()),
            _ => None,
        })
        .collect();
    if names.is_empty() {
        " no layout".to_string()
    } else {
        format!(": {}", names.join(", "))
    }
}

/// The program restricted to the items written in `inputs` (for `--emit=ast`).
fn user_items(program: &Program, inputs: &[FileId]) -> Program {
    Program {
        items: program
            .items
            .iter()
            .filter(|it| inputs.contains(&it.span().file))
            .cloned()
            .collect(),
        node_count: program.node_count,
    }
}
