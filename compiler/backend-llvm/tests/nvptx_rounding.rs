//! The NVPTX translation of directed rounding, checked without a GPU.
//!
//! On NVPTX, `lo.add_rd`, `lo.add_ru`, `lo.mul_rd` and `lo.mul_ru` become single NVVM
//! intrinsics (`llvm.nvvm.add.rm.f`, ... : PTX's `add.rm.f32`, non-ftz) instead of the
//! round-to-nearest expansion that CPUs run (`scion_ir::lo::directed`), so neither the JIT
//! tests nor the emulated GPU pipeline execute them. LLVM 22 constant-folds these intrinsics
//! with PTX's semantics (IEEE 754 arithmetic in the named rounding direction) where operands
//! and result are finite and normal or zero. This test translates the ops for `nvptx64`, calls
//! them with constant operands, lets LLVM's `-O2` pipeline (with the NVPTX target machine) fold
//! the calls, and compares each folded result bit for bit with the `lo` interpreter: it checks
//! that each op maps to the intrinsic of the right operation and direction, the operand order
//! and the NaN canonicalization around it. Cases LLVM does not fold (NaN, infinite or
//! subnormal operands or results) are counted, not compared: the GPU run checks them.

use inkwell::context::Context;
use inkwell::memory_buffer::MemoryBuffer;
use inkwell::passes::PassBuilderOptions;
use inkwell::values::{AnyValue, BasicValueEnum};
use proptest::prelude::*;
use proptest::strategy::ValueTree;
use proptest::test_runner::{Config, TestRunner};
use scion_ir::interp::lo::LoInterp;
use scion_ir::interp::Val;
use scion_llvm::Target;

const OPS: [&str; 4] = ["add_rd", "add_ru", "mul_rd", "mul_ru"];

fn module() -> scion_ir::Module {
    let text: String = OPS
        .iter()
        .map(|op| {
            format!(
                "func @{op}(%a: f32, %b: f32) -> (f32) attributes {{export}} {{\n  \
                 %r = \"lo.{op}\"(%a, %b) : (f32, f32) -> f32\n  \
                 \"lo.return\"(%r) : (f32) -> ()\n}}\n"
            )
        })
        .collect();
    let m = scion_ir::parse_module(&text, scion_ir::diag::FileId(0))
        .unwrap_or_else(|e| panic!("{e:?}"));
    scion_ir::verify(&m).unwrap_or_else(|e| panic!("{e:?}"));
    m
}

/// Operand pairs that make rounding do something: mantissas at random with nearby exponents
/// (sums and products that are inexact), far-apart exponents (one operand below the other's
/// ulp), exact cancellations (the sign of a zero result depends on the direction), products
/// near the ends of the normal range, and special values.
fn pairs() -> impl Strategy<Value = (u32, u32)> {
    let near = (any::<u32>(), any::<u32>(), 0u32..8, 100u32..150).prop_map(|(a, b, d, e)| {
        let a = (a & 0x807f_ffff) | (e << 23);
        let b = (b & 0x807f_ffff) | ((e - d) << 23);
        (a, b)
    });
    let far = (any::<u32>(), any::<u32>(), 20u32..40).prop_map(|(a, b, d)| {
        let a = (a & 0x807f_ffff) | (127 << 23);
        let b = (b & 0x807f_ffff) | ((127 - d) << 23);
        (a, b)
    });
    let cancel = any::<u32>().prop_map(|a| (a, a ^ 0x8000_0000));
    let edge = (any::<u32>(), any::<u32>(), 0u32..2).prop_map(|(a, b, hi)| {
        // Exponents that put products near the top (overflow) or bottom (subnormal) of f32.
        let (ea, eb) = if hi == 1 { (250, 130) } else { (5, 122) };
        (
            (a & 0x807f_ffff) | (ea << 23),
            (b & 0x807f_ffff) | (eb << 23),
        )
    });
    let special = prop_oneof![
        Just(0u32),
        Just(0x8000_0000),
        Just(1),
        Just(0x8000_0001),
        Just(f32::MIN_POSITIVE.to_bits()),
        Just(f32::MAX.to_bits()),
        Just(f32::INFINITY.to_bits()),
        Just(f32::NEG_INFINITY.to_bits()),
        Just(0x7fa0_1234),
        Just(1.0f32.to_bits()),
        any::<u32>(),
    ];
    prop_oneof![
        4 => near,
        2 => far,
        1 => cancel,
        1 => edge,
        1 => (special.clone(), special),
    ]
}

/// An `f32` constant in LLVM IR: the hexadecimal bits of the same value as a double.
fn llvm_f32(bits: u32) -> String {
    format!("0x{:016X}", f64::from(f32::from_bits(bits)).to_bits())
}

fn normal_or_zero(x: f32) -> bool {
    x == 0.0 || x.is_normal()
}

/// The unrounded result is zero or within f32's normal range (an `f32` sum is exact in `f64`
/// up to a relative 2^-53, a product exactly).
fn exact_in_range(op: &str, a: f32, b: f32) -> bool {
    let (a, b) = (f64::from(a), f64::from(b));
    let r = if op.starts_with("add") { a + b } else { a * b };
    r == 0.0 || (r.abs() >= f64::from(f32::MIN_POSITIVE) && r.abs() <= f64::from(f32::MAX))
}

#[test]
fn nvptx_directed_rounding_folds_to_the_interpreters_results() {
    let m = module();
    let ir = scion_llvm::translate_to_ir(&m, Target::Nvptx64).unwrap_or_else(|e| panic!("{e}"));
    for op in OPS {
        let rm = if op.ends_with("rd") { "rm" } else { "rp" };
        let intr = format!("@llvm.nvvm.{}.{rm}.f(", &op[..3]);
        assert!(ir.contains(&intr), "{op} does not call {intr}:\n{ir}");
    }

    let n = if cfg!(debug_assertions) { 400 } else { 2000 };
    let mut runner = TestRunner::new(Config::default());
    let inputs = proptest::collection::vec(pairs(), n)
        .new_tree(&mut runner)
        .unwrap()
        .current();

    // One function per (op, pair) that calls the op on constants.
    let mut text = ir.clone();
    let mut cases = Vec::new();
    for (i, &(a, b)) in inputs.iter().enumerate() {
        for op in OPS {
            text.push_str(&format!(
                "\ndefine float @case_{op}_{i}() {{\n  %r = call float @{op}(float {}, float {})\n  \
                 ret float %r\n}}\n",
                llvm_f32(a),
                llvm_f32(b)
            ));
            cases.push((op, i, a, b));
        }
    }
    let cx = Context::create();
    let buf = MemoryBuffer::create_from_memory_range_copy(text.as_bytes(), "cases");
    let lm = cx
        .create_module_from_ir(buf)
        .unwrap_or_else(|e| panic!("{e}"));
    let tm = scion_llvm::target::target_machine(Target::Nvptx64, None, 2).unwrap();
    lm.set_triple(&tm.get_triple());
    lm.set_data_layout(&tm.get_target_data().get_data_layout());
    lm.run_passes("default<O2>", &tm, PassBuilderOptions::create())
        .unwrap_or_else(|e| panic!("{e}"));

    let (mut folded, mut in_domain) = (0usize, 0usize);
    for (op, i, a, b) in cases {
        let (fa, fb) = (f32::from_bits(a), f32::from_bits(b));
        let want = match LoInterp::new(&m).call(op, vec![Val::F32(fa), Val::F32(fb)]) {
            Ok(v) => match v[..] {
                [Val::F32(x)] => x,
                _ => panic!("{op}: {v:?}"),
            },
            Err(e) => panic!("interpreter: {op}({fa:e}, {fb:e}): {e:?}"),
        };
        let f = lm.get_function(&format!("case_{op}_{i}")).unwrap();
        let ret = f
            .get_first_basic_block()
            .and_then(|bb| bb.get_terminator())
            .unwrap();
        let got = match ret.get_operand(0).and_then(|o| o.value()) {
            Some(BasicValueEnum::FloatValue(v)) if v.is_const() => v.get_constant().map(|c| c.0),
            _ => None,
        };
        // LLVM folds where the operands and the result are finite, normal or zero and the
        // exact result did not underflow.
        let domain = [fa, fb, want].into_iter().all(normal_or_zero) && exact_in_range(op, fa, fb);
        in_domain += usize::from(domain);
        match got {
            Some(g) => {
                folded += 1;
                let g = g as f32;
                assert_eq!(
                    g.to_bits(),
                    want.to_bits(),
                    "{op}({fa:e} [{a:#010x}], {fb:e} [{b:#010x}]): NVPTX folds to {g:e} \
                     [{:#010x}], the interpreter gives {want:e} [{:#010x}]",
                    g.to_bits(),
                    want.to_bits()
                );
            }
            None => assert!(
                !domain,
                "LLVM did not fold {op}({fa:e}, {fb:e}) (in its folding domain): {}",
                f.print_to_string().to_string()
            ),
        }
    }
    println!(
        "nvptx directed rounding: {folded} folded results equal to the interpreter's, \
         {in_domain} cases in the folding domain, of {}",
        inputs.len() * OPS.len()
    );
    assert!(
        folded >= inputs.len() * OPS.len() / 2,
        "only {folded} cases folded: the test checks too little"
    );
}
