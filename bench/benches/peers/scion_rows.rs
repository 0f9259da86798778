//! Scion's own contenders: closest hit specialized to a library layout and compiled by
//! Cranelift or LLVM -O3 (packed once by the generated builder, traced through the batch
//! entry), and the hand-written Rust kernel over the same bytes as the `pbrt` layout's
//! generated code (`scion_bench::pbrt_kernel`), which measures what the abstraction costs on
//! identical data.

use scion_bench::pbrt_kernel::PbrtKernel;
use scion_bench::{Contender, Workload};
use scion_host::contract::{LayoutCode, Packed};
use scion_host::entries::Entries;
use scion_host::jit::{program_lo, Codegen, EntryTarget, JitClosestHit, LoOptions};
use scion_host::mem_interp::{library_layouts, Program};
use scion_runtime::batch::BatchDriver;
use scion_runtime::primitive::Primitive;
use scion_runtime::triangle4::{sah_block_tree, Triangle4};
use std::time::Instant;

fn progress(s: &str) {
    eprintln!("peers: {s}");
}

/// The library layout called `layout` (`pbrt`, `pbrt-q16`, ...): file stem and layout name.
fn library_layout(layout: &str) -> Result<(&'static str, &'static str), String> {
    let stem = layout.replace('-', "_");
    library_layouts()
        .iter()
        .find(|l| l.0 == stem)
        .map(|l| (l.0, l.1))
        .ok_or_else(|| format!("unknown library layout `{layout}`"))
}

/// What `--layouts` names: a library layout (`pbrt`, `pbrt-q16`, `hair-bvh`, ...) or a layout
/// file (`PATH.scion[:LAYOUT]`), each with the closest hit over its type
/// (`scion_host::library::resolve`), or a closest hit in files as
/// `PATH.scion[+PATH.scion...]:LAYOUT:ENTRY`
/// (`lit-tests/Inputs/bvh8_aos_layout.scion:Bvh8Aos:closest_hit8`,
/// `library/algorithms/closest_hit_dop14.scion+library/layouts/dop14_split.scion:DopSplit:closest_hit_dop14`).
fn program_of(layout: &str) -> Result<Program, String> {
    if let [paths, name, entry] = layout.split(':').collect::<Vec<_>>()[..] {
        let mut files = Vec::new();
        for path in paths.split('+') {
            let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
            files.push((path.to_string(), text));
        }
        return Ok(Program {
            files,
            layout: name.to_string(),
            algorithm: entry.to_string(),
        });
    }
    Ok(scion_host::library::resolve(layout, None)?.program)
}

/// A layout's generated code as a contender: packed once (the pack time is its setup), then
/// traced through the batch entry.
fn layout_contender<'a>(
    name: String,
    code: Box<dyn LayoutCode>,
    w: &'a Workload,
    driver: &'a BatchDriver,
) -> Result<Contender<'a>, String> {
    let packed = Packed::new(code.as_ref(), &w.tree)?;
    Ok(Contender {
        name,
        bytes: Some(packed.bytes()),
        setup: packed.pack_time,
        subset: None,
        trace: Box::new(move |rays| {
            packed
                .trace(code.as_ref(), rays, driver)
                .map_err(|f| f.to_string())
        }),
    })
}

/// The primitive the leaves of `program`'s layout hold (`Triangle`, `Triangle4`, ...).
fn primitive_of(program: &Program) -> Result<String, String> {
    let lo = program_lo(
        program,
        &LoOptions {
            stack_size: None,
            opt_level: 0,
            dsl_opt: false,
            target: EntryTarget::Host,
        },
    )?;
    Ok(lo.entry.logical.primitive.clone())
}

/// A layout over blocks of four triangles (`Triangle4`, `bvh8-tri4`) as a contender: the
/// binned SAH tree over the workload's triangles with leaves of at most two blocks
/// (`sah_block_tree`), packed once by the generated builder (building and packing are
/// its setup), traced through the batch entry.
fn block_contender<'a>(
    name: String,
    entries: Entries,
    w: &'a Workload,
    driver: &'a BatchDriver,
) -> Result<Contender<'a>, String> {
    let start = Instant::now();
    let own;
    let tree = match &w.blocks {
        Some(t) => t,
        None => {
            own = sah_block_tree(&w.triangles);
            &own
        }
    };
    let packed = entries.pack(tree)?;
    Ok(Contender {
        name,
        bytes: Some(packed.bytes()),
        setup: start.elapsed(),
        subset: None,
        trace: Box::new(move |rays| {
            entries
                .closest_hits(&packed, rays, driver)
                .map_err(|f| f.to_string())
        }),
    })
}

/// `cranelift L` and `llvm-O3 L` for the library layout `layout`.
pub fn generated<'a>(
    layout: &str,
    w: &'a Workload,
    driver: &'a BatchDriver,
) -> Result<Vec<Contender<'a>>, String> {
    let program = program_of(layout)?;
    let blocks = primitive_of(&program)? == Triangle4::TYPE_NAME;
    let mut out = Vec::new();
    for (codegen, label) in [
        (Codegen::Cranelift, "cranelift"),
        (Codegen::Llvm(3), "llvm-O3"),
    ] {
        progress(&format!("compiling and packing {layout} ({label})"));
        let t = Instant::now();
        let name = format!("{label} {layout}");
        if blocks {
            let entries = Entries::compile(&program, codegen, None)?;
            progress(&format!("  compiled in {:.3} s", t.elapsed().as_secs_f64()));
            out.push(block_contender(name, entries, w, driver)?);
            continue;
        }
        let code = JitClosestHit::compile_program(&program, None, 3, true, codegen)?;
        progress(&format!("  compiled in {:.3} s", t.elapsed().as_secs_f64()));
        out.push(layout_contender(name, Box::new(code), w, driver)?);
    }
    Ok(out)
}

/// The tree packed into the `pbrt` layout by its generated builder (for [`hand_pbrt`]).
pub fn pack_pbrt(w: &Workload) -> Result<Packed, String> {
    let (stem, lname) = library_layout("pbrt")?;
    let code = JitClosestHit::compile(stem, lname, None)?;
    Packed::new(&code, &w.tree)
}

/// The hand-written kernel over `packed`, the `pbrt` layout's buffers (its pack time is the
/// setup).
pub fn hand_pbrt<'a>(packed: &'a Packed, driver: &'a BatchDriver) -> Result<Contender<'a>, String> {
    let kernel = PbrtKernel::new(&packed.buffers())?;
    Ok(Contender {
        name: "hand-written pbrt".into(),
        bytes: Some(kernel.bytes()),
        setup: packed.pack_time,
        subset: None,
        trace: Box::new(move |rays| kernel.trace(rays, driver)),
    })
}
