//! No input makes the back half panic: mutated library sources that the front end accepts go
//! through `mem-to-lo` (partial), `recursion-to-stack` and the Cranelift translation
//! (`--emit=clif`), and `--emit=lo` output parses back; failures must be diagnostics, never
//! panics or internal errors.

use scion_compiler::driver::cli::Emit;
use scion_compiler::frontend::{compile, Frontend, PassOptions};
use scion_compiler::fuzz::{library_seeds, Mutator};
use scion_ir::diag::SourceMap;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;

fn lower_once(text: &str, emit: Emit) -> Result<bool, String> {
    let mut sources = SourceMap::new();
    let file = sources.add("fuzz.scion", text.to_string());
    let fe = Frontend {
        sources: &sources,
        prelude: &[],
        inputs: &[file],
    };
    let pipeline = vec!["const-fold".to_string(), "dce".to_string()];
    let r = compile(&fe, emit, &pipeline, &PassOptions::default());
    let _ = r.diagnostics.render(&sources);
    if let Some(ice) = r.internal_error {
        return Err(format!("internal compiler error: {ice}"));
    }
    if let (Emit::Lo, Some(out)) = (emit, &r.output) {
        let m = scion_ir::parse_module(out, scion_ir::diag::FileId(0))
            .map_err(|d| format!("--emit=lo output does not parse: {d:?}"))?;
        scion_ir::verify(&m).map_err(|e| format!("--emit=lo output does not verify: {e:?}"))?;
    }
    Ok(r.output.is_some())
}

#[test]
fn mutated_sources_never_panic_below_the_tree_level() {
    let library = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../library");
    let seeds = library_seeds(&library).expect("reading library/");
    let n: u64 = std::env::var("SCION_LOWER_FUZZ_INPUTS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(if cfg!(debug_assertions) { 1000 } else { 6000 });
    for s in &seeds {
        lower_once(s, Emit::Clif).unwrap_or_else(|e| panic!("seed: {e}"));
    }
    let mut mutator = Mutator::new(seeds, 0x10_2026);
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let mut lowered = 0;
    let mut failure = None;
    for i in 0..n {
        let input = mutator.next_input();
        let emit = if i % 2 == 0 { Emit::Lo } else { Emit::Clif };
        match catch_unwind(AssertUnwindSafe(|| lower_once(&input, emit))) {
            Ok(Ok(true)) => lowered += 1,
            Ok(Ok(false)) => {}
            Ok(Err(e)) => {
                failure = Some((i, input, e));
                break;
            }
            Err(p) => {
                let msg = p
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                failure = Some((i, input, format!("panic: {msg}")));
                break;
            }
        }
    }
    std::panic::set_hook(hook);
    if let Some((i, input, what)) = failure {
        let path = std::env::temp_dir().join(format!("scion-lower-fuzz-{i}.scion"));
        let _ = std::fs::write(&path, &input);
        panic!("input #{i} ({}): {what}", path.display());
    }
    assert!(lowered > 0, "no mutated input reached the backend");
    println!("{lowered} of {n} mutated inputs lowered");
}
