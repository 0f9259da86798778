//! `mem-split-loads`: a layout array that is read whole only to be indexed becomes one load per
//! index (level: any → same).
//!
//! Destructor specialization reads an array field where the traversal names it, all of it at
//! once: `ch` of an eight-wide node is `mem.load ... : array<8 x u64>`, eight loads once lowered.
//! When the traversal then takes one element by a run-time index (`ch[slot]`, the child a
//! sorted key names), `mem-to-lo` has the eight values at hand and picks one with a chain of
//! seven selects, and the eight loads happen at every visit whatever the visit needs. This pass
//! replaces each `tree.index` of such a load by a load of that element alone, at the index:
//!
//! * a constant index `c` (in range) reads at the array's offset plus `c` times the element
//!   size;
//! * a run-time index `k` reads at `mem.addr` of the array plus `k'` times the element size,
//!   with `k' = k < n ? k : 0` on `k` as `u64` (an index outside the array reads element 0, as
//!   the select chain does, so nothing outside the array is ever read).
//!
//! Then `mem-sink` moves each element load into the region that uses it. It applies to a
//! `mem.load` of an array of scalars whose every use is a `tree.index` of it, in a function that
//! writes no layout (`mem-cse`'s writers), where reading later reads the same bytes.

use super::cse::layout_writers;
use rustc_hash::FxHashMap;
use scion_ir::attr::Attr;
use scion_ir::builder::OpSpec;
use scion_ir::data_layout::size_align;
use scion_ir::op::OpKind;
use scion_ir::pass::{Pass, PassCx, PassError};
use scion_ir::tree::CmpPred;
use scion_ir::types::{IntTy, Type};
use scion_ir::{mem, rewrite, tree, walk, Builder, FuncId, InsertPoint, Module, OpId, ValueId};

/// The `mem-split-loads` pass.
#[derive(Default)]
pub struct MemSplitLoads;

impl Pass for MemSplitLoads {
    fn name(&self) -> &'static str {
        "mem-split-loads"
    }

    fn summary(&self) -> &'static str {
        "read an indexed layout array one element at a time instead of whole"
    }

    fn run(&mut self, m: &mut Module, _cx: &mut PassCx) -> Result<bool, PassError> {
        let writers = layout_writers(m);
        let mut changed = false;
        for f in m.func_order.clone() {
            if m.is_declaration(f) || writers.contains(&f) {
                continue;
            }
            changed |= split_func(m, f);
        }
        Ok(changed)
    }
}

/// A whole-array load worth splitting: its element type, length and element size.
fn candidate(m: &Module, op: OpId) -> Option<(scion_ir::TypeId, u64, u64)> {
    let o = &m.ops[op];
    if o.kind != OpKind::Mem(mem::Op::Load) || o.results.len() != 1 {
        return None;
    }
    let Type::Array { elem, len: Some(n) } = *m.types.get(m.values[o.results[0]].ty) else {
        return None;
    };
    if n == 0 || !matches!(m.types.get(elem), Type::Int(_) | Type::Float(_)) {
        return None;
    }
    let (size, _) = size_align(m, elem)?;
    Some((elem, n, size))
}

fn split_func(m: &mut Module, f: FuncId) -> bool {
    let mut users: FxHashMap<ValueId, Vec<OpId>> = FxHashMap::default();
    let mut loads = Vec::new();
    walk::walk_region(m, m.funcs[f].body, walk::Order::Pre, &mut |op| {
        for &v in &m.ops[op].operands {
            users.entry(v).or_default().push(op);
        }
        if candidate(m, op).is_some() {
            loads.push(op);
        }
    });
    let mut changed = false;
    for load in loads {
        let Some((elem, n, size)) = candidate(m, load) else {
            continue;
        };
        let array = m.ops[load].results[0];
        let uses = users.get(&array).cloned().unwrap_or_default();
        let indexes_only = !uses.is_empty()
            && uses.iter().all(|&u| {
                let o = &m.ops[u];
                o.kind == OpKind::Tree(tree::Op::Index)
                    && o.operands.first() == Some(&array)
                    && o.results.len() == 1
                    && constant(m, o.operands[1]).is_none_or(|c| (0..n as i128).contains(&c))
            });
        if !indexes_only {
            continue;
        }
        let base = m.ops[load].operands.clone();
        let offset = m.ops[load].int_attr("offset").unwrap_or(0);
        let stride = m.ops[load].int_attr("stride").unwrap_or(0);
        let span = m.span(load);
        for u in uses {
            let k = m.ops[u].operands[1];
            let mut b = Builder::new(m);
            b.set_insertion_point(InsertPoint::Before(u));
            b.set_span(span);
            let value = match constant(b.m, k) {
                Some(c) => {
                    let op = b.insert(
                        OpSpec::new(mem::Op::Load)
                            .operands(&base)
                            .results(&[elem])
                            .attr("offset", Attr::Int(offset + c * i128::from(size)))
                            .attr("stride", Attr::Int(stride)),
                    );
                    b.result(op, 0)
                }
                None => {
                    let ptr = b.m.ty(Type::Ptr);
                    let addr = b.insert(
                        OpSpec::new(mem::Op::Addr)
                            .operands(&base)
                            .results(&[ptr])
                            .attr("offset", Attr::Int(offset))
                            .attr("stride", Attr::Int(stride)),
                    );
                    let addr = b.result(addr, 0);
                    let u64t = b.m.types.int(IntTy::U64);
                    let k64 = if b.value_type(k) == u64t {
                        k
                    } else {
                        b.cast(k, u64t)
                    };
                    let len = b.const_int(u64t, i128::from(n));
                    let inside = b.cmp(CmpPred::Lt, k64, len);
                    let zero = b.const_int(u64t, 0);
                    let at = b.select(inside, k64, zero);
                    let op = b.insert(
                        OpSpec::new(mem::Op::Load)
                            .operands(&[addr, at])
                            .results(&[elem])
                            .attr("offset", Attr::Int(0))
                            .attr("stride", Attr::Int(i128::from(size))),
                    );
                    b.result(op, 0)
                }
            };
            let old = m.ops[u].results[0];
            rewrite::replace_all_uses(m, old, value);
            rewrite::erase_op(m, u);
        }
        rewrite::erase_op(m, load);
        changed = true;
    }
    changed
}

/// The value of an integer `tree.const`.
fn constant(m: &Module, v: ValueId) -> Option<i128> {
    let d = m.def_op(v)?;
    (m.ops[d].kind == OpKind::Tree(tree::Op::Const))
        .then(|| m.ops[d].int_attr("value"))
        .flatten()
}
