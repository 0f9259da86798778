//! A long robustness campaign over the front end (see compiler/tests/frontend_robustness.rs).
//!
//! `cargo run --release -p scion-compiler --example fuzz_frontend -- --inputs 1000000 --seed 1`
//! Saves the first failing input to `fuzz-failure.scion` and exits with status 1.

use scion_compiler::fuzz::{compile_once, library_seeds, Campaign, Mutator};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;
use std::time::Instant;

fn main() {
    let mut inputs: u64 = 1_000_000;
    let mut seed: u64 = 1;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let v = args.next().and_then(|s| s.parse().ok());
        match (a.as_str(), v) {
            ("--inputs", Some(n)) => inputs = n,
            ("--seed", Some(s)) => seed = s,
            _ => {
                eprintln!("usage: fuzz_frontend [--inputs N] [--seed S]");
                std::process::exit(2);
            }
        }
    }
    let library = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../library");
    let seeds = library_seeds(&library).expect("reading library/");
    let mut mutator = Mutator::new(seeds, seed);
    let mut campaign = Campaign::default();
    std::panic::set_hook(Box::new(|_| {}));
    let start = Instant::now();
    for i in 0..inputs {
        let input = mutator.next_input();
        let r = catch_unwind(AssertUnwindSafe(|| compile_once(&input, &mut campaign)));
        let bad = match r {
            Ok(None) => None,
            Ok(Some(ice)) => Some(ice),
            Err(_) => Some("panic".to_string()),
        };
        if let Some(what) = bad {
            let _ = std::fs::write("fuzz-failure.scion", &input);
            eprintln!("input #{i} (seed {seed}): {what}; saved to fuzz-failure.scion");
            std::process::exit(1);
        }
        if (i + 1) % 50_000 == 0 {
            eprintln!("{} inputs, {:.0} s", i + 1, start.elapsed().as_secs_f64());
        }
    }
    println!(
        "{} inputs (seed {seed}) in {:.0} s: {} accepted, {} rejected with diagnostics, {} internal errors, 0 panics",
        campaign.inputs,
        start.elapsed().as_secs_f64(),
        campaign.accepted,
        campaign.rejected,
        campaign.internal_errors
    );
}
