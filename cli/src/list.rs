//! `scion layouts`: the library's layouts as the registry (`scion_host::library`) finds them,
//! one line each: the name `--layout` takes, the layout's name in its source, the sum type it
//! realizes, the primitives its leaves hold, the closest hit `scion trace` compiles for it, and
//! how it stores boxes. `--names` prints only the names (for scripts), `--gpu` only the layouts
//! `scion trace --device gpu` runs, `--kit` only those a PTX kit holds, `--primitive
//! Triangle|Segment` only those over that primitive.

use crate::io::outln;
use crate::CliError;
use scion_host::library;

/// Runs `scion layouts`.
pub fn run(args: &crate::LayoutsArgs) -> Result<(), CliError> {
    let kit: Vec<&str> = scion_host::mem_interp::library_layouts()
        .iter()
        .map(|l| l.0)
        .collect();
    if !args.names {
        outln!(
            "{:<20} {:<18} {:<8} {:<9} {:<20} boxes",
            "name",
            "layout",
            "type",
            "leaves",
            "closest hit"
        );
    }
    for &(stem, _) in library::LAYOUT_FILES {
        if args.kit && !kit.contains(&stem) {
            continue;
        }
        let name = library::layout_name(stem);
        let resolved = library::resolve(stem, None);
        let on_gpu = |r: &library::Resolved| {
            r.primitive == "Triangle" || r.primitive == crate::trace_blocks::PRIMITIVE
        };
        if args.gpu && !resolved.as_ref().is_ok_and(on_gpu) {
            continue;
        }
        if let Some(p) = &args.primitive {
            if !resolved
                .as_ref()
                .is_ok_and(|r| r.primitive.eq_ignore_ascii_case(p))
            {
                continue;
            }
        }
        if args.names {
            outln!("{name}");
            continue;
        }
        match resolved {
            Ok(r) => {
                outln!(
                    "{name:<20} {:<18} {:<8} {:<9} {:<20} {}",
                    r.program.layout,
                    r.tree_type,
                    r.primitive,
                    r.program.algorithm,
                    r.boxes.name()
                );
            }
            Err(e) => outln!(
                "{name:<20} (does not compile: {})",
                e.lines().next().unwrap_or("")
            ),
        }
    }
    Ok(())
}
