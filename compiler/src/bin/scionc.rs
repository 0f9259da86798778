//! `scionc`: the Scion compiler driver. See `scionc --help`.

use clap::Parser;
use scion_compiler::driver::{run, Options};

fn main() {
    let opts = Options::parse();
    std::process::exit(run(&opts));
}
