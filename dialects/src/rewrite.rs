//! Changing IR in place: erasing ops, and replace-all-uses through the module's alias map.
//!
//! There are no use-lists. [`replace_all_uses`] records `old → new` in [`Module::aliases`];
//! [`resolve_aliases`] rewrites every operand and successor argument at once, following
//! chains, and clears the map. The pass manager resolves after each pass, so a pass may record
//! aliases freely while it iterates (Cranelift's `change_to_alias` / `resolve_all_aliases`).
//! Erasing detaches an op from its block; the arena slot stays, unreachable (`la-arena` has no
//! removal), and nothing walks it again.

use crate::entity::{OpId, ValueId};
use crate::module::Module;

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
