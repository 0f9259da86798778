//! Times loading and building (binned SAH twice, median once) for one OBJ scene:
//! `cargo run --release -p scion-runtime --example build_time -- SCENE.obj`.

use scion_runtime::bvh::{build_median, build_sah_binned, SahOptions};
use scion_runtime::scene::load_obj;
use std::time::Instant;
fn main() {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: build_time SCENE.obj");
        std::process::exit(2);
    };
    let t = Instant::now();
    let s = match load_obj(&path) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    println!("load {:?}", t.elapsed());
    for _ in 0..2 {
        let t = Instant::now();
        let tree = build_sah_binned(&s.triangles, &SahOptions::default());
        println!("sah {:?} {:?}", t.elapsed(), tree.stats());
    }
    let t = Instant::now();
    let tree = build_median(&s.triangles);
    println!("median {:?} nodes {}", t.elapsed(), tree.nodes.len());
}
