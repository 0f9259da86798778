//! Frame homes for the vectors a loop reads but does not change.
//!
//! Cranelift's egraph hoists every loop-invariant computation out of its loop: the splats of
//! the ray that a traversal's leaf tests with, the ray's slab vectors its interior step tests
//! boxes with, their constants. Live across the whole loop, they outnumber x86-64's sixteen
//! vector registers, and register allocation (regalloc2) splits them around the loop's blocks:
//! each interior step of the binary closest hit reloaded eight such vectors at its top and
//! stored every one back on each exit, although none had changed, since the allocator does not
//! know that a spill slot still holds the value it spilled (docs/performance.md, "Twenty-sixth"
//! to "Twenty-eighth session").
//!
//! This pass runs on a function after Cranelift's optimizations and before its code
//! generation (which then runs without the egraph, so nothing is hoisted again). Each vector
//! value defined outside a loop and used inside it is stored once, right after its definition,
//! to a slot of the function's frame, and each block of the loop that uses it loads it from
//! there just before its first use (one address of the slot per block); a vector constant is
//! made again in the block instead (a load from the constant pool). No such value is then live
//! across a loop's blocks, and none is stored back.

use cranelift_codegen::cursor::{Cursor, FuncCursor};
use cranelift_codegen::dominator_tree::DominatorTree;
use cranelift_codegen::flowgraph::ControlFlowGraph;
use cranelift_codegen::ir::{
    self, types, InstBuilder, MemFlags, Opcode, StackSlotData, StackSlotKind, ValueDef,
};
use cranelift_codegen::loop_analysis::LoopAnalysis;
use std::collections::{BTreeMap, BTreeSet};

/// At most this many vectors get a home (16 bytes of frame each).
const MAX_HOMES: usize = 64;

/// Blocks of more Cranelift instructions than this make the pass leave the function alone.
const LONG_BLOCK: usize = 300;

/// Gives the loop-invariant vectors of `func` frame homes (see the module documentation).
/// Returns how many values got one.
pub fn rematerialize(func: &mut ir::Function) -> usize {
    if func.layout.entry_block().is_none() {
        return 0;
    }
    let cfg = ControlFlowGraph::with_function(func);
    let domtree = DominatorTree::with_function(func, &cfg);
    let mut loops = LoopAnalysis::new();
    loops.compute(func, &cfg, &domtree);
    if loops.loops().next().is_none() {
        return 0;
    }
    // For each candidate, the blocks that reload it (in layout order, for determinism).
    let mut reloads: BTreeMap<ir::Value, BTreeSet<ir::Block>> = BTreeMap::new();
    let blocks: Vec<ir::Block> = func.layout.blocks().collect();
    for &b in &blocks {
        if !domtree.is_reachable(b) || loops.innermost_loop(b).is_none() {
            continue;
        }
        for inst in func.layout.block_insts(b) {
            for v in func.dfg.inst_values(inst) {
                if !homed_type(func.dfg.value_type(v)) {
                    continue;
                }
                let def_block = match func.dfg.value_def(v) {
                    ValueDef::Result(i, _) => func.layout.inst_block(i),
                    ValueDef::Param(blk, _) => Some(blk),
                    _ => None,
                };
                let Some(d) = def_block else { continue };
                // Used in a loop that does not contain its definition.
                let mut lp = loops.innermost_loop(b);
                let mut outside = false;
                while let Some(l) = lp {
                    if !loops.is_in_loop(d, l) {
                        outside = true;
                        break;
                    }
                    lp = loops.loop_parent(l);
                }
                if outside {
                    reloads.entry(v).or_default().insert(b);
                }
            }
        }
    }
    if reloads.is_empty() {
        return 0;
    }
    // A long block of the loop runs out of registers by itself (the eight-wide closest hit's
    // interior step spills a third of its instructions' worth): a vector loaded there before
    // its first use is spilled again within it, where it was only reloaded before. Such
    // functions are left to register allocation.
    let long = reloads
        .values()
        .flatten()
        .any(|&b| func.layout.block_insts(b).count() > LONG_BLOCK);
    if long {
        return 0;
    }
    let is_const = |func: &ir::Function, v: ir::Value| match func.dfg.value_def(v) {
        ValueDef::Result(i, _) => func.dfg.insts[i].opcode() == Opcode::Vconst,
        _ => false,
    };
    let homed: Vec<ir::Value> = reloads
        .keys()
        .copied()
        .filter(|&v| !is_const(func, v))
        .take(MAX_HOMES)
        .collect();
    let offset: BTreeMap<ir::Value, i32> = homed
        .iter()
        .enumerate()
        .map(|(k, &v)| (v, 16 * k as i32))
        .collect();
    let flags = MemFlags::trusted();
    let slot = (!offset.is_empty()).then(|| {
        func.create_sized_stack_slot(StackSlotData::new(
            StackSlotKind::ExplicitSlot,
            16 * offset.len() as u32,
            4,
        ))
    });
    // Each homed value stored once, after its definition (a block parameter at its block's
    // first instruction).
    for (&v, &off) in &offset {
        let slot = slot.expect("a slot for the homed values");
        let mut pos = FuncCursor::new(func);
        match pos.func.dfg.value_def(v) {
            ValueDef::Result(i, _) => pos.goto_after_inst(i),
            ValueDef::Param(b, _) => pos.goto_first_insertion_point(b),
            _ => continue,
        }
        pos.ins().stack_store(v, slot, off);
    }
    // Each reloading block: each value loaded (or the constant made again) just before the
    // block's first instruction that uses it, from one address of the slot taken before the
    // first of them.
    let mut by_block: BTreeMap<ir::Block, Vec<ir::Value>> = BTreeMap::new();
    for (&v, bs) in &reloads {
        if offset.contains_key(&v) || is_const(func, v) {
            for &b in bs {
                by_block.entry(b).or_default().push(v);
            }
        }
    }
    for (b, vs) in by_block {
        let order: Vec<ir::Inst> = func.layout.block_insts(b).collect();
        // Each value just before its own first use; the slot's address once, before the first.
        let mut firsts: Vec<(ir::Inst, ir::Value)> = vs
            .iter()
            .filter_map(|&v| {
                order
                    .iter()
                    .copied()
                    .find(|&i| func.dfg.inst_values(i).any(|x| x == v))
                    .map(|i| (i, v))
            })
            .collect();
        firsts.sort_by_key(|&(i, v)| (order.iter().position(|&x| x == i), v));
        let mut base = None;
        let mut fresh = BTreeMap::new();
        for (first, v) in firsts {
            let mut pos = FuncCursor::new(func).at_inst(first);
            let ty = pos.func.dfg.value_type(v);
            let new = if let Some(&off) = offset.get(&v) {
                let slot = slot.expect("a slot for the homed values");
                let a = *base.get_or_insert_with(|| pos.ins().stack_addr(types::I64, slot, 0));
                pos.ins().load(ty, flags, a, off)
            } else {
                let ValueDef::Result(i, _) = pos.func.dfg.value_def(v) else {
                    continue;
                };
                let ir::InstructionData::UnaryConst {
                    constant_handle, ..
                } = pos.func.dfg.insts[i]
                else {
                    continue;
                };
                pos.ins().vconst(ty, constant_handle)
            };
            fresh.insert(v, new);
        }
        let insts: Vec<ir::Inst> = func.layout.block_insts(b).collect();
        for i in insts {
            func.dfg
                .map_inst_values(i, |x| fresh.get(&x).copied().unwrap_or(x));
        }
    }
    reloads.len()
}

/// Whether values of type `ty` get homes: 128-bit vectors. (Giving the loop-invariant pointers
/// homes too, loaded once per block, made the binary closest hit's code longer: 504.4 -> 519.9
/// instructions per ray on sponza's primary rays.)
fn homed_type(ty: ir::Type) -> bool {
    ty.bits() == 128 && ty.is_vector()
}

#[cfg(test)]
mod tests {
    use super::*;
    use cranelift_codegen::ir::condcodes::IntCC;
    use cranelift_codegen::ir::{AbiParam, Function, Signature, UserFuncName};
    use cranelift_codegen::isa::CallConv;
    use cranelift_frontend::{FunctionBuilder, FunctionBuilderContext};

    /// An empty function `name(f32x4) -> f32x4`.
    fn vector_function(name: &str) -> Function {
        let mut sig = Signature::new(CallConv::SystemV);
        sig.params.push(AbiParam::new(types::F32X4));
        sig.returns.push(AbiParam::new(types::F32X4));
        Function::with_name_signature(UserFuncName::testcase(name), sig)
    }

    /// `f(v: f32x4) -> f32x4`: ten times `acc += v` in a loop, `v` (a parameter) and a vector
    /// constant read by the loop and defined outside it.
    fn looped() -> Function {
        let mut func = vector_function("looped");
        let mut fctx = FunctionBuilderContext::new();
        let mut b = FunctionBuilder::new(&mut func, &mut fctx);
        let (entry, head, exit) = (b.create_block(), b.create_block(), b.create_block());
        b.append_block_params_for_function_params(entry);
        b.append_block_param(head, types::I32);
        b.append_block_param(head, types::F32X4);
        b.switch_to_block(entry);
        let v = b.block_params(entry)[0];
        let zero = b.ins().iconst(types::I32, 0);
        let c = b.func.dfg.constants.insert(vec![0u8; 16].into());
        let acc0 = b.ins().vconst(types::F32X4, c);
        let one = b.ins().vconst(types::F32X4, c);
        b.ins().jump(head, &[zero.into(), acc0.into()]);
        b.switch_to_block(head);
        let (i, acc) = (b.block_params(head)[0], b.block_params(head)[1]);
        let sum = b.ins().fadd(acc, v);
        let sum = b.ins().fadd(sum, one);
        let next = b.ins().iadd_imm(i, 1);
        let more = b.ins().icmp_imm(IntCC::UnsignedLessThan, next, 10);
        b.ins()
            .brif(more, head, &[next.into(), sum.into()], exit, &[]);
        b.switch_to_block(exit);
        b.ins().return_(&[sum]);
        b.seal_all_blocks();
        b.finalize();
        func
    }

    #[test]
    fn a_loop_reads_its_invariant_vectors_from_their_homes() {
        let mut func = looped();
        assert_eq!(rematerialize(&mut func), 2);
        let flags = cranelift_codegen::settings::Flags::new(cranelift_codegen::settings::builder());
        cranelift_codegen::verify_function(&func, &flags).expect("valid after the pass");
        let text = func.display().to_string();
        // The parameter stored once in the entry, loaded in the loop; the constant made again.
        let (entry, rest) = text.split_once("block1").expect("the loop block");
        assert_eq!(entry.matches("stack_store").count(), 1, "{text}");
        let (body, _) = rest.split_once("block2").expect("the exit block");
        assert_eq!(body.matches("load.f32x4").count(), 1, "{text}");
        assert_eq!(body.matches("vconst.f32x4").count(), 1, "{text}");
        let v = func.dfg.block_params(func.layout.entry_block().unwrap())[0];
        let head = func.layout.blocks().nth(1).unwrap();
        assert!(
            func.layout
                .block_insts(head)
                .all(|i| func.dfg.inst_values(i).all(|x| x != v)),
            "{text}"
        );
    }

    #[test]
    fn functions_without_loops_are_left_alone() {
        let mut func = vector_function("flat");
        let mut fctx = FunctionBuilderContext::new();
        let mut b = FunctionBuilder::new(&mut func, &mut fctx);
        let entry = b.create_block();
        b.append_block_params_for_function_params(entry);
        b.switch_to_block(entry);
        let v = b.block_params(entry)[0];
        let w = b.ins().fadd(v, v);
        b.ins().return_(&[w]);
        b.seal_all_blocks();
        b.finalize();
        let before = func.display().to_string();
        assert_eq!(rematerialize(&mut func), 0);
        assert_eq!(func.display().to_string(), before);
    }
}
