//! `cargo bench -p scion-bench --bench compile`: criterion micro-benchmarks of compile time, from
//! source to machine code, of the library's closest hit specialized to one layout (pbrt):
//! Cranelift with the DSL pipeline at -O0 and at -O3 (the JIT's level), and LLVM at -O3 (DSL and LLVM
//! pipelines both at -O3).

use criterion::{criterion_group, criterion_main, Criterion};
use scion_host::jit::{Codegen, JitClosestHit};

fn compile_time(c: &mut Criterion) {
    let mut g = c.benchmark_group("compile closest_hit + pbrt");
    g.sample_size(20);
    g.bench_function("cranelift, DSL -O0", |b| {
        b.iter(|| JitClosestHit::compile_at("pbrt", "LinearBVH", None, 0).expect("compiles"))
    });
    g.bench_function("cranelift, DSL -O3", |b| {
        b.iter(|| JitClosestHit::compile("pbrt", "LinearBVH", None).expect("compiles"))
    });
    g.bench_function("llvm -O3", |b| {
        b.iter(|| {
            JitClosestHit::compile_with("pbrt", "LinearBVH", None, 3, Codegen::Llvm(3))
                .expect("compiles")
        })
    });
    g.finish();
}

criterion_group!(benches, compile_time);
criterion_main!(benches);
