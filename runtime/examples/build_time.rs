use scion_runtime::bvh::{build_median, build_sah_binned, SahOptions};
use scion_runtime::scene::load_obj;
use std::time::Instant;
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let t = Instant::now();
    let s = load_obj(&path).unwrap();
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
