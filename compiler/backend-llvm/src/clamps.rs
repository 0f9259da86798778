//! Two-lane clamps back to compare-and-select, after LLVM's optimizations, on x86-64.
//!
//! The translation emits `min`/`max` of an arithmetic result against a constant neither NaN
//! nor zero (the slab test's NaN clamps, `max((lo - o) * inv, -inf)`) as `llvm.minnum` /
//! `llvm.maxnum`, which is exactly minNum/maxNum there and, unlike a compare-and-select, keeps
//! one shape through InstCombine and the SLP vectorizer (an eight-wide node's six clamps become
//! one `vmaxps`/`vminps` each). But LLVM 22 lowers a `<2 x float>` `llvm.maxnum` on x86 (the
//! binary traversal's `[left, right]` pairs) by widening it to four lanes, two of them
//! undefined, which hides that the constant is never NaN: it adds a NaN fix-up (`vcmpunordps`
//! and a masked move) to each. Once the vectorizers are done, such a call is turned back into
//! `x > c ? x : c` (`x < c ? x : c` for `minnum`): the same value (a NaN `x` gives `c`, and a tie
//! gives `c`, whose bits are `x`'s since `c` is not zero), and one `maxps`/`minps` on x86.

use inkwell::module::Module as LModule;
use inkwell::values::{BasicValue, BasicValueEnum, CallSiteValue, InstructionOpcode};
use inkwell::FloatPredicate;

/// Rewrites every two-lane `f32` `llvm.minnum`/`llvm.maxnum` with a constant operand whose
/// lanes are neither NaN nor zero into a compare-and-select.
pub(crate) fn two_lane_clamps_as_selects(lm: &LModule) {
    let b = lm.get_context().create_builder();
    for f in lm.get_functions() {
        for bb in f.get_basic_blocks() {
            let mut next = bb.get_first_instruction();
            while let Some(inst) = next {
                next = inst.get_next_instruction();
                if inst.get_opcode() != InstructionOpcode::Call {
                    continue;
                }
                let Ok(call) = CallSiteValue::try_from(inst) else {
                    continue;
                };
                let Some(callee) = call.get_called_fn_value() else {
                    continue;
                };
                let name = callee.get_name().to_string_lossy();
                let pred = match name.as_ref() {
                    "llvm.maxnum.v2f32" => FloatPredicate::OGT,
                    "llvm.minnum.v2f32" => FloatPredicate::OLT,
                    _ => continue,
                };
                let operand = |i: u32| match inst.get_operand(i) {
                    Some(inkwell::values::Operand::Value(BasicValueEnum::VectorValue(v))) => {
                        Some(v)
                    }
                    _ => None,
                };
                let (Some(p), Some(q)) = (operand(0), operand(1)) else {
                    continue;
                };
                let clean = |v: inkwell::values::VectorValue| {
                    v.is_const()
                        && (0..v.get_type().get_size()).all(|k| {
                            match v.get_element_as_constant(k) {
                                BasicValueEnum::FloatValue(c) => c
                                    .get_constant()
                                    .is_some_and(|(c, _)| !c.is_nan() && c != 0.0),
                                _ => false,
                            }
                        })
                };
                // minnum/maxnum are commutative: the constant may be either operand.
                let (x, c) = if clean(q) {
                    (p, q)
                } else if clean(p) {
                    (q, p)
                } else {
                    continue;
                };
                b.position_before(&inst);
                let Ok(better) = b.build_float_compare(pred, x, c, "") else {
                    continue;
                };
                let Ok(sel) = b.build_select(better, x, c, "") else {
                    continue;
                };
                let Some(new) = sel.as_instruction_value() else {
                    continue;
                };
                inst.replace_all_uses_with(&new);
                inst.erase_from_basic_block();
            }
        }
    }
}
