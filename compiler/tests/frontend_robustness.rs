//! No input makes the front end panic: a campaign of mutated library sources (and token soups)
//! through parse, sema, layout/build checks, irgen and the tree passes.
//!
//! 20,000 inputs in release builds (the suite runs `cargo test --release`), 2,000 in debug;
//! `SCION_FUZZ_INPUTS` overrides. Long campaigns: `cargo run --release --example
//! fuzz_frontend -- --inputs 1000000` (docs/testing.md records the last one).

use scion_compiler::fuzz::{compile_once, library_seeds, Campaign, Mutator};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;

#[test]
fn mutated_sources_never_panic() {
    let library = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../library");
    let seeds = library_seeds(&library).expect("reading library/");
    let default = if cfg!(debug_assertions) {
        2_000
    } else {
        20_000
    };
    let n: u64 = std::env::var("SCION_FUZZ_INPUTS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default);
    let mut mutator = Mutator::new(seeds.clone(), 0x5C10_2026);
    let mut campaign = Campaign::default();
    // The unmutated seeds themselves must compile without internal errors.
    for s in &seeds {
        assert_eq!(compile_once(s, &mut campaign), None);
    }
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let mut failure = None;
    for i in 0..n {
        let input = mutator.next_input();
        let outcome = catch_unwind(AssertUnwindSafe(|| compile_once(&input, &mut campaign)));
        match outcome {
            Ok(None) => {}
            Ok(Some(ice)) => {
                failure = Some((i, input, format!("internal compiler error: {ice}")));
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
        let path = std::env::temp_dir().join(format!("scion-fuzz-failure-{i}.scion"));
        let _ = std::fs::write(&path, &input);
        panic!("input #{i} ({}): {what}", path.display());
    }
    println!(
        "front-end robustness: {} inputs, {} accepted, {} rejected with diagnostics, 0 panics",
        campaign.inputs, campaign.accepted, campaign.rejected
    );
    assert!(
        campaign.rejected > 0 && campaign.accepted > 0,
        "the campaign must reach both outcomes"
    );
}
