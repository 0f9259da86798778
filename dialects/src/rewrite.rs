//! Changing IR in place: erasing ops, and replace-all-uses through the module's alias map.
//!
//! There are no use-lists. [`replace_all_uses`] records `old → new` in [`Module::aliases`];
//! [`resolve_aliases`] rewrites every operand and successor argument at once, following
//! chains, and clears the map. The pass manager resolves after each pass, so a pass may record
//! aliases freely while it iterates (Cranelift's `change_to_alias` / `resolve_all_aliases`).
//! Erasing detaches an op from its block; the arena slot stays, unreachable (`la-arena` has no
//! removal), and nothing walks it again. [`inline_region_before`] moves a structured region's
//! ops into the enclosing block (folding an `if`), and [`clone_region`] deep-copies a region
//! with a value map (what an inliner needs).

use crate::builder::{Builder, OpSpec};
use crate::entity::{BlockId, OpId, RegionId, TypeId, ValueId};
use crate::module::Module;
use rustc_hash::FxHashMap;

/// Records that every use of `old` is to read `new` instead.
pub fn replace_all_uses(m: &mut Module, old: ValueId, new: ValueId) {
    if old != new {
        m.aliases.insert(old, new);
    }
}

/// The value `v` stands for after following the alias chain (stops on a cycle).
pub fn resolve_value(m: &Module, v: ValueId) -> ValueId {
    let mut cur = v;
    let mut steps = 0;
    while let Some(&next) = m.aliases.get(&cur) {
        cur = next;
        steps += 1;
        if steps > m.aliases.len() {
            break;
        }
    }
    cur
}

/// Rewrites every use of an aliased value in the live functions and empties the alias map.
/// Returns whether anything changed.
pub fn resolve_aliases(m: &mut Module) -> bool {
    if m.aliases.is_empty() {
        return false;
    }
    let funcs = m.func_order.clone();
    let mut ops = Vec::new();
    for f in funcs {
        crate::walk::walk_region(m, m.funcs[f].body, crate::walk::Order::Pre, &mut |op| {
            ops.push(op)
        });
    }
    for op in ops {
        let operands = m.ops[op].operands.clone();
        for (i, v) in operands.into_iter().enumerate() {
            let r = resolve_value(m, v);
            m.ops[op].operands[i] = r;
        }
        for s in 0..m.ops[op].successors.len() {
            for a in 0..m.ops[op].successors[s].args.len() {
                let v = m.ops[op].successors[s].args[a];
                let r = resolve_value(m, v);
                m.ops[op].successors[s].args[a] = r;
            }
        }
    }
    m.aliases.clear();
    true
}

/// Detaches `op` from its block. Its results must have no remaining uses (or be aliased).
pub fn erase_op(m: &mut Module, op: OpId) {
    if let Some(b) = m.ops[op].parent.take() {
        m.blocks[b].ops.retain(|&o| o != op);
    }
}

/// Replaces `old`'s results by `new_values` (alias) and erases `old`.
pub fn replace_op(m: &mut Module, old: OpId, new_values: &[ValueId]) {
    let results = m.ops[old].results.clone();
    for (r, &n) in results.iter().zip(new_values) {
        replace_all_uses(m, *r, n);
    }
    erase_op(m, old);
}

/// Moves the ops of `region`'s single block, all but its terminator, to just before `before`
/// (in `before`'s block), and returns the terminator, which stays behind in the emptied region.
/// The block's arguments are replaced by `args` (through aliases) and removed from the block.
/// `None` (and nothing changed) when the region does not have exactly one block, `args` does
/// not match the block's arguments in number, the block has no terminator, or `before` is
/// detached. Folding an `if` passes no arguments; inlining a call passes the call's operands.
pub fn inline_region_before(
    m: &mut Module,
    region: RegionId,
    before: OpId,
    args: &[ValueId],
) -> Option<OpId> {
    let [block] = m.regions[region].blocks[..] else {
        return None;
    };
    let target = m.ops[before].parent?;
    if m.blocks[block].args.len() != args.len() {
        return None;
    }
    let &term = m.blocks[block].ops.last()?;
    if !m.ops[term].kind.is_terminator() {
        return None;
    }
    let pos = m.blocks[target].ops.iter().position(|&o| o == before)?;
    for (old, &new) in m.blocks[block].args.clone().into_iter().zip(args) {
        replace_all_uses(m, old, new);
    }
    m.blocks[block].args.clear();
    let moved: Vec<OpId> = m.blocks[block]
        .ops
        .drain(..)
        .filter(|&o| o != term)
        .collect();
    m.blocks[block].ops.push(term);
    for (i, &op) in moved.iter().enumerate() {
        m.ops[op].parent = Some(target);
        m.blocks[target].ops.insert(pos + i, op);
    }
    Some(term)
}

/// Deep-copies `region` (blocks, arguments, ops, nested regions, spans) into a new detached
/// region. Uses of values defined outside the region are rewritten through `map` when it has
/// them (e.g. an inlined function's parameters mapped to the call's arguments) and kept
/// otherwise; on return `map` also maps every value defined inside to its copy.
pub fn clone_region(
    m: &mut Module,
    region: RegionId,
    map: &mut FxHashMap<ValueId, ValueId>,
) -> RegionId {
    let mut new_ops = Vec::new();
    let r = clone_region_raw(m, region, map, &mut new_ops);
    // Operands are remapped once everything is copied, so uses that precede their definition
    // in block order (possible in CFG regions) find their copies too.
    for op in new_ops {
        for i in 0..m.ops[op].operands.len() {
            let v = m.ops[op].operands[i];
            if let Some(&n) = map.get(&v) {
                m.ops[op].operands[i] = n;
            }
        }
        for s in 0..m.ops[op].successors.len() {
            for a in 0..m.ops[op].successors[s].args.len() {
                let v = m.ops[op].successors[s].args[a];
                if let Some(&n) = map.get(&v) {
                    m.ops[op].successors[s].args[a] = n;
                }
            }
        }
    }
    r
}

fn clone_region_raw(
    m: &mut Module,
    region: RegionId,
    map: &mut FxHashMap<ValueId, ValueId>,
    new_ops: &mut Vec<OpId>,
) -> RegionId {
    let new_region = m.new_region();
    let blocks = m.regions[region].blocks.clone();
    let mut block_map: FxHashMap<BlockId, BlockId> = FxHashMap::default();
    for &b in &blocks {
        let arg_types: Vec<TypeId> = m.blocks[b].args.iter().map(|&a| m.values[a].ty).collect();
        let nb = m.add_block(new_region, &arg_types);
        for (&old, &new) in m.blocks[b]
            .args
            .clone()
            .iter()
            .zip(m.blocks[nb].args.clone().iter())
        {
            map.insert(old, new);
        }
        block_map.insert(b, nb);
    }
    for &b in &blocks {
        for op in m.blocks[b].ops.clone() {
            let o = m.ops[op].clone();
            let regions: Vec<RegionId> = o
                .regions
                .iter()
                .map(|&r| clone_region_raw(m, r, map, new_ops))
                .collect();
            let result_types: Vec<TypeId> = o.results.iter().map(|&v| m.values[v].ty).collect();
            let mut spec = OpSpec::new(o.kind)
                .operands(&o.operands)
                .results(&result_types);
            spec.attrs = o.attrs.clone();
            for r in regions {
                spec = spec.region(r);
            }
            for s in &o.successors {
                spec = spec.successor(block_map.get(&s.block).copied().unwrap_or(s.block), &s.args);
            }
            let span = m.span(op);
            let mut builder = Builder::at_end(m, block_map[&b]);
            builder.set_span(span);
            let new = builder.insert(spec);
            for (&old, &newv) in o.results.iter().zip(m.ops[new].results.clone().iter()) {
                map.insert(old, newv);
            }
            new_ops.push(new);
        }
    }
    new_region
}
