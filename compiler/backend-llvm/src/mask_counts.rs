//! Counts of a vector compare's true lanes as one `llvm.ctpop`, after LLVM's optimizations.
//!
//! An eight-wide traversal counts the children a ray enters as a sum of eight 0/1 values
//! (library/algorithms/closest_hit8.scion, `hit1`). The SLP vectorizer turns the eight compares
//! into one `<8 x i1>` compare, and for AVX2 it also turns the sum into `ctpop` of the mask's
//! bits (`vmovmskps` and `popcnt`). For AVX-512 its cost model leaves the sum scalar: eight
//! `extractelement`s of the mask, each `zext`ed and added, which the code generator lowers to
//! eight shifts and moves out of the mask register and an add chain (about 40 instructions
//! where 3 do). Once the vectorizers are done, such a sum, every lane of one `<N x i1>` counted
//! once and nothing else, is replaced by `zext(ctpop(bitcast mask to iN))`: the same number.
//! Likewise each remaining `extractelement` of a constant lane of such a mask becomes a test
//! of that bit of the mask's bits ([`mask_lanes_as_bits`]). Both run on x86-64 only, where
//! the mask's bits are one `vmovmskps` or `kmovb` (NEON has no such move).

use inkwell::intrinsics::Intrinsic;
use inkwell::module::Module as LModule;
use inkwell::values::{
    BasicValue, BasicValueEnum, InstructionOpcode, InstructionValue, IntValue, VectorValue,
};

/// The mask and the lane that `v` counts: `zext i1 (extractelement <N x i1> mask, lane)`.
fn counted_lane<'ctx>(v: IntValue<'ctx>) -> Option<(VectorValue<'ctx>, u32)> {
    let zext = v.as_instruction_value()?;
    if zext.get_opcode() != InstructionOpcode::ZExt {
        return None;
    }
    let bit = match zext.get_operand(0)?.value()? {
        BasicValueEnum::IntValue(b) if b.get_type().get_bit_width() == 1 => b,
        _ => return None,
    };
    let extract = bit.as_instruction_value()?;
    if extract.get_opcode() != InstructionOpcode::ExtractElement {
        return None;
    }
    let mask = match extract.get_operand(0)?.value()? {
        BasicValueEnum::VectorValue(m) => m,
        _ => return None,
    };
    let lane = match extract.get_operand(1)?.value()? {
        BasicValueEnum::IntValue(i) => i.get_zero_extended_constant()?,
        _ => return None,
    };
    u32::try_from(lane).ok().map(|lane| (mask, lane))
}

/// The leaves of the `add` tree rooted at `inst` (at most `limit` of them), or `None` when a
/// leaf is not a counted lane.
fn leaves<'ctx>(
    inst: InstructionValue<'ctx>,
    limit: usize,
    out: &mut Vec<(VectorValue<'ctx>, u32)>,
) -> Option<()> {
    for k in 0..2 {
        let v = match inst.get_operand(k)?.value()? {
            BasicValueEnum::IntValue(v) => v,
            _ => return None,
        };
        match v.as_instruction_value() {
            Some(i) if i.get_opcode() == InstructionOpcode::Add => leaves(i, limit, out)?,
            _ => out.push(counted_lane(v)?),
        }
        if out.len() > limit {
            return None;
        }
    }
    Some(())
}

/// Rewrites every `add` tree that sums each lane of one `<N x i1>` mask exactly once into
/// `ctpop` of the mask's bits.
pub(crate) fn mask_counts_as_ctpop(lm: &LModule) {
    let ctx = lm.get_context();
    let b = ctx.create_builder();
    let Some(ctpop) = Intrinsic::find("llvm.ctpop") else {
        return;
    };
    for f in lm.get_functions() {
        for bb in f.get_basic_blocks() {
            let mut next = bb.get_first_instruction();
            while let Some(inst) = next {
                next = inst.get_next_instruction();
                if inst.get_opcode() != InstructionOpcode::Add {
                    continue;
                }
                let mut found = Vec::new();
                if leaves(inst, 64, &mut found).is_none() || found.is_empty() {
                    continue;
                }
                let mask = found[0].0;
                let n = mask.get_type().get_size();
                let mut lanes: Vec<u32> = found
                    .iter()
                    .filter(|(m, _)| *m == mask)
                    .map(|&(_, l)| l)
                    .collect();
                lanes.sort_unstable();
                if found.len() != n as usize || lanes != (0..n).collect::<Vec<u32>>() {
                    continue;
                }
                let result_ty = match inst.get_type() {
                    inkwell::types::AnyTypeEnum::IntType(t) => t,
                    _ => continue,
                };
                let Some(width) = std::num::NonZeroU32::new(n) else {
                    continue;
                };
                let Ok(bits_ty) = ctx.custom_width_int_type(width) else {
                    continue;
                };
                let Some(decl) = ctpop.get_declaration(lm, &[bits_ty.into()]) else {
                    continue;
                };
                b.position_before(&inst);
                let Ok(bits) = b.build_bit_cast(mask, bits_ty, "") else {
                    continue;
                };
                let Ok(call) = b.build_call(decl, &[bits.into()], "") else {
                    continue;
                };
                let inkwell::values::ValueKind::Basic(BasicValueEnum::IntValue(count)) =
                    call.try_as_basic_value()
                else {
                    continue;
                };
                let Ok(count) = b.build_int_z_extend_or_bit_cast(count, result_ty, "") else {
                    continue;
                };
                let Some(new) = count.as_instruction_value() else {
                    continue;
                };
                inst.replace_all_uses_with(&new);
                inst.erase_from_basic_block();
            }
        }
    }
}

/// Rewrites every `extractelement <N x i1> %mask, i` (a constant lane, `N` of 4, 8 or 16) into
/// a test of bit `i` of the mask's bits (`bitcast %mask to iN`, one per mask): for AVX-512 the
/// code generator otherwise moves each lane out of the mask register on its own (`kshiftrb`
/// and `kmovd` per lane, for the conditional visits of an eight-wide node), where one `kmovb`
/// and bit tests do.
pub(crate) fn mask_lanes_as_bits(lm: &LModule) {
    let ctx = lm.get_context();
    let b = ctx.create_builder();
    for f in lm.get_functions() {
        let mut bits_of: Vec<(VectorValue, IntValue)> = Vec::new();
        for bb in f.get_basic_blocks() {
            let mut next = bb.get_first_instruction();
            while let Some(inst) = next {
                next = inst.get_next_instruction();
                if inst.get_opcode() != InstructionOpcode::ExtractElement {
                    continue;
                }
                let Some(BasicValueEnum::VectorValue(mask)) =
                    inst.get_operand(0).and_then(|o| o.value())
                else {
                    continue;
                };
                let n = mask.get_type().get_size();
                let is_bool = matches!(mask.get_type().get_element_type(),
                    inkwell::types::BasicTypeEnum::IntType(t) if t.get_bit_width() == 1);
                if !is_bool || ![4, 8, 16].contains(&n) {
                    continue;
                }
                let Some(lane) = (match inst.get_operand(1).and_then(|o| o.value()) {
                    Some(BasicValueEnum::IntValue(i)) => i.get_zero_extended_constant(),
                    _ => None,
                }) else {
                    continue;
                };
                let Some(def) = mask.as_instruction_value() else {
                    continue;
                };
                if def.get_opcode() == InstructionOpcode::Phi || lane >= u64::from(n) {
                    continue;
                }
                let bits = match bits_of.iter().find(|(m, _)| *m == mask) {
                    Some(&(_, bits)) => bits,
                    None => {
                        let Some(after) = def.get_next_instruction() else {
                            continue;
                        };
                        let Some(width) = std::num::NonZeroU32::new(n) else {
                            continue;
                        };
                        let Ok(ty) = ctx.custom_width_int_type(width) else {
                            continue;
                        };
                        b.position_before(&after);
                        let Ok(BasicValueEnum::IntValue(bits)) = b.build_bit_cast(mask, ty, "")
                        else {
                            continue;
                        };
                        bits_of.push((mask, bits));
                        bits
                    }
                };
                b.position_before(&inst);
                let one = bits.get_type().const_int(1 << lane, false);
                let zero = bits.get_type().const_zero();
                let Ok(set) = b.build_and(bits, one, "") else {
                    continue;
                };
                let Ok(test) = b.build_int_compare(inkwell::IntPredicate::NE, set, zero, "") else {
                    continue;
                };
                let Some(new) = test.as_instruction_value() else {
                    continue;
                };
                inst.replace_all_uses_with(&new);
                inst.erase_from_basic_block();
            }
        }
    }
}
