//! Layouts carried in the module (`scion_ir::module::LayoutSource`), so that the
//! specializations run on text IR as they do after the front end: `scionc` records every layout
//! of the program with the type sema chose for it, and `destructor-specialize` /
//! `constructor-specialize` rebuild the layout's model from that record when the pass context
//! has none (`scion-opt --layout NAME`).
//!
//! A record's source is the `layout` declaration and every `type` declaration of the program
//! (prelude included), printed by `syntax::print`: what building the model reads (the realized
//! type's variants with their array lengths, the sizes of records).

use crate::layout::model::{AdtChoice, LayoutModel, Models};
use crate::syntax::ast::{Item, Program};
use scion_ir::diag::{Diagnostic, Diagnostics, SourceMap};
use scion_ir::module::LayoutSource;

/// The records of `program`'s layouts (the first declaration of each name).
pub fn layout_sources(program: &Program, models: &Models) -> Vec<LayoutSource> {
    let types: Vec<Item> = program
        .items
        .iter()
        .filter(|i| matches!(i, Item::Type(_)))
        .cloned()
        .collect();
    let mut out: Vec<LayoutSource> = Vec::new();
    for item in &program.items {
        let Item::Layout(decl) = item else { continue };
        if out.iter().any(|l| l.name == decl.name.name) {
            continue;
        }
        // The declaration the model was built from: with the components the checker's types
        // let the compiler declare.
        let decl = models.decl(&decl.name.name).unwrap_or(decl);
        let mut items = types.clone();
        items.push(Item::Layout(decl.clone()));
        let source = crate::syntax::print::print_program(&Program {
            items,
            node_count: program.node_count,
        });
        out.push(LayoutSource {
            name: decl.name.name.clone(),
            adt: models
                .get(&decl.name.name)
                .and_then(|m| m.adt.as_ref())
                .map(|a| a.name.clone()),
            source,
        });
    }
    out
}

/// The model of the layout `name` carried by a module (`None` picks the only one), parsed
/// from its record: errors name a missing or ambiguous layout, or source that does not parse
/// (spans point into the record's source, file `<layout NAME>`).
pub fn model_of(records: &[LayoutSource], name: Option<&str>) -> Result<LayoutModel, Diagnostics> {
    let one = |d: Diagnostic| {
        let mut ds = Diagnostics::new();
        ds.push(d);
        ds
    };
    let names = || {
        records
            .iter()
            .map(|l| format!("`{}`", l.name))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let record = match name {
        Some(n) => records.iter().find(|l| l.name == n).ok_or_else(|| {
            one(Diagnostic::error("E0908", format!("`--layout {n}`: the module carries no layout of that name"))
                .with_note(if records.is_empty() {
                    "the module carries no `tree.layout` records (scionc --emit=tree writes them)".to_string()
                } else {
                    format!("it carries {}", names())
                }))
        })?,
        None => match records {
            [one_record] => one_record,
            [] => {
                return Err(one(
                    Diagnostic::error("E0907", "the specialization needs a layout")
                        .with_note("the module carries no `tree.layout` records: produce it with `scionc --emit=tree`, or run the pass through `scionc --layout NAME`"),
                ))
            }
            _ => {
                return Err(one(
                    Diagnostic::error("E0907", "the module carries several layouts")
                        .with_note(format!("choose one with `--layout NAME`: {}", names())),
                ))
            }
        },
    };
    let mut sources = SourceMap::new();
    let file = sources.add(format!("<layout {}>", record.name), record.source.clone());
    // Problems in the record are rendered against its own source, not the module's text.
    let broken = |d: &Diagnostics| {
        one(Diagnostic::error(
            "E0917",
            format!(
                "the module's record of layout `{}` does not build",
                record.name
            ),
        )
        .with_note(d.render(&sources)))
    };
    let (program, diags) = crate::syntax::parse_program(&sources, &[file]);
    if diags.has_errors() {
        return Err(broken(&diags));
    }
    let decl = program
        .items
        .iter()
        .find_map(|i| match i {
            Item::Layout(d) if d.name.name == record.name => Some(d),
            _ => None,
        })
        .ok_or_else(|| {
            one(Diagnostic::error(
                "E0908",
                format!(
                    "the record of layout `{}` declares no such layout",
                    record.name
                ),
            ))
        })?;
    let choice = record
        .adt
        .as_deref()
        .map_or(AdtChoice::Undecided, AdtChoice::Chosen);
    let model = LayoutModel::of(decl, &program, choice);
    if model.diagnostics.has_errors() {
        return Err(broken(&model.diagnostics));
    }
    Ok(model)
}
