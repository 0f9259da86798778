//! `cargo bench -p scion-bench --bench compile`: criterion micro-benchmarks of compile time, from
//! source to machine code, of the library's closest hit specialized to one layout (pbrt):
//! Cranelift at the JIT's level and at -O0 of the DSL pipeline.

use criterion::{criterion_group, criterion_main, Criterion};
use scion_tests::jit::JitClosestHit;

fn compile_time(c: &mut Criterion) {
    let mut g = c.benchmark_group("compile closest_hit + pbrt");
    g.sample_size(20);
    g.bench_function("cranelift, DSL -O0", |b| {
        b.iter(|| JitClosestHit::compile_at("pbrt", "LinearBVH", None, 0).expect("compiles"))
    });
    g.bench_function("cranelift, DSL -O2", |b| {
        b.iter(|| JitClosestHit::compile("pbrt", "LinearBVH", None).expect("compiles"))
    });
    g.finish();
}

criterion_group!(benches, compile_time);
criterion_main!(benches);
