//! Where a `lo` load goes in the Cranelift function, and how many loads it becomes.
//!
//! `lo` orders a block's loads as the source reads them, often all before the arithmetic that
//! takes them; Cranelift keeps loads in their order and its egraph places pure values where
//! they are first needed, so loads gathered into vector lanes would all be live at once and
//! spilled. Here: which loads wait for the lane group that takes them ([`deferrable_loads`]),
//! which may be treated as pure values ([`pure_loads`]), emitting a waiting load
//! ([`Fx::emit_deferred`]), and four loads of consecutive words that a group takes as one
//! vector load ([`Fx::vector_load`]).

use crate::translate::{Fx, Symbols};
use cranelift_codegen::ir::{self, types, InstBuilder, MemFlags};
use cranelift_module::Module as ClModule;
use scion_ir::entity::{BlockId, OpId, ValueId};
use scion_ir::lo::layout_reads;
use scion_ir::lo::Op as L;
use scion_ir::op::OpKind;
use scion_ir::types::{FloatTy, Type};
use scion_ir::Module;
use std::collections::{HashMap, HashSet};

/// The flags of a load: a pure value Cranelift may move (`notrap readonly can_move`), or an
/// ordinary load that keeps its place.
pub(crate) fn flags(pure: bool) -> MemFlags {
    if pure {
        MemFlags::new()
            .with_notrap()
            .with_readonly()
            .with_can_move()
    } else {
        MemFlags::new()
    }
}

/// The loads of `blocks` to emit where their value is put in a vector, not where `lo` has them:
/// a load whose every use is an operand of a group Cranelift emits as a vector. A leaf's
/// four triangles are loaded field by field and then gathered into lanes (`block_of`); loaded
/// all first, as `lo` orders them, the 36 floats outlive the registers and are spilled and
/// reloaded before each insertion. [`Fx::op`] emits a deferred load just before its group, or
/// before anything else in the block that reads it, writes memory or branches, so that no load
/// moves past a store. The load's one use may also be an argument of a jump into a block that
/// only that jump enters (`direct`), whose parameter is used so, and so on: the loads of an
/// inlined call's arguments (`block_of`'s triangles) reach its lanes through such blocks, and
/// `Fx::op` carries them over the jumps.
pub(crate) fn deferrable_loads(
    m: &Module,
    f: scion_ir::FuncId,
    groups: &HashMap<OpId, Vec<OpId>>,
    direct: &HashSet<BlockId>,
    dead: &HashSet<ValueId>,
) -> std::collections::HashSet<OpId> {
    // Uses, less those that pass a value to a dead parameter (never materialized).
    let mut uses = scion_ir::walk::use_counts(m, f);
    let blocks = &m.regions[m.funcs[f].body].blocks;
    for &b in blocks {
        for &op in &m.blocks[b].ops {
            for s in &m.ops[op].successors {
                for (x, p) in s.args.iter().zip(&m.blocks[s.block].args) {
                    if dead.contains(p) {
                        if let Some(n) = uses.get_mut(x) {
                            *n -= 1;
                        }
                    }
                }
            }
        }
    }
    // How often each value is an operand of a group's op.
    let mut in_groups: HashMap<ValueId, u32> = HashMap::new();
    for &o in groups.values().flatten() {
        for &x in &m.ops[o].operands {
            *in_groups.entry(x).or_insert(0) += 1;
        }
    }
    // The parameter each argument of a jump into a direct block becomes.
    let mut forward: HashMap<ValueId, ValueId> = HashMap::new();
    for &b in blocks {
        for &op in &m.blocks[b].ops {
            let o = &m.ops[op];
            if o.kind == OpKind::Lo(L::Br) && direct.contains(&o.successors[0].block) {
                let s = &o.successors[0];
                for (&x, &p) in s.args.iter().zip(&m.blocks[s.block].args) {
                    if !dead.contains(&p) {
                        forward.insert(x, p);
                    }
                }
            }
        }
    }
    let once = |v: &ValueId| uses.get(v) == Some(&1);
    let mut out = std::collections::HashSet::new();
    for &b in blocks {
        for &op in &m.blocks[b].ops {
            let o = &m.ops[op];
            if o.kind != OpKind::Lo(L::Load) || o.results.len() != 1 {
                continue;
            }
            let mut v = o.results[0];
            for _ in 0..blocks.len() {
                match forward.get(&v) {
                    Some(p) if !in_groups.contains_key(&v) && once(&v) => v = *p,
                    _ => break,
                }
            }
            // Every use (at the end of the chain) a group's operand.
            if in_groups.get(&v).is_some_and(|n| uses.get(&v) == Some(n)) {
                out.insert(op);
            }
        }
    }
    out
}

/// The deferrable loads Cranelift may treat as pure values (`notrap readonly can_move`): those
/// that read a layout buffer, in a function that writes none. Cranelift's egraph places pure
/// values where they are first needed, so each load then comes just before the lane insertion
/// that takes it (and may fold into it); as ordinary loads they keep their place, all of them
/// before the first insertion, and the insertions' pure values are placed after them all.
pub(crate) fn pure_loads(
    m: &Module,
    f: scion_ir::FuncId,
    deferrable: &HashSet<OpId>,
) -> HashSet<OpId> {
    if layout_reads::writes_layout(m, f) {
        return HashSet::new();
    }
    deferrable
        .iter()
        .copied()
        .filter(|&op| layout_reads::in_layout(m, m.ops[op].operands[0]))
        .collect()
}

impl Fx<'_, '_> {
    /// The deferred `load`, known here as `name` (its result, or the parameter of a direct
    /// block it was passed as).
    pub(crate) fn emit_deferred<M: ClModule>(
        &mut self,
        cl: &mut M,
        syms: &Symbols,
        name: ValueId,
        load: OpId,
        blocks: &HashMap<BlockId, ir::Block>,
    ) -> Result<(), String> {
        self.scalar_op(cl, syms, load, blocks)?;
        self.load_of.insert(name, load);
        let r = self.m.ops[load].results[0];
        if name != r {
            let v = self.v(r)?;
            self.bind_direct(name, v, Some(r));
        }
        Ok(())
    }

    /// When the four lanes `xs` are loads of 32-bit words at consecutive offsets from one
    /// address (a box's low corner and the high corner's x, in a layout that stores them
    /// together), one 16-byte load of them all, its lanes bound to them. Each load is either
    /// deferred (not emitted yet: this is its place) or pure (a layout buffer that nothing
    /// writes while the function runs, [`pure_loads`], so reading it again gives
    /// the same word); the loads keep their flags (all four must agree) and the vector reads
    /// only the words they name.
    pub(crate) fn vector_load(&mut self, xs: &[ValueId]) -> Result<(), String> {
        let m = self.m;
        if xs.len() != 4 {
            return Ok(());
        }
        // Each lane's load op, and its place among the deferred loads if it is one.
        let mut lanes: Vec<(OpId, Option<usize>)> = Vec::with_capacity(4);
        for x in xs {
            if let Some(i) = self.deferred.iter().position(|d| d.0 == *x) {
                lanes.push((self.deferred[i].1, Some(i)));
                continue;
            }
            let Some(op) = m.def_op(*x).or_else(|| self.load_of.get(x).copied()) else {
                return Ok(());
            };
            if !(self.pure_loads.contains(&op) && self.vals.contains_key(x)) {
                return Ok(());
            }
            lanes.push((op, None));
        }
        if lanes.iter().all(|l| l.1.is_none()) {
            return Ok(());
        }
        let load = |k: usize| &m.ops[lanes[k].0];
        let ty = m.values[load(0).results[0]].ty;
        let vt = match m.types.get(ty) {
            Type::Float(FloatTy::F32) => types::F32X4,
            Type::Int(t) if t.bits() == 32 => types::I32X4,
            _ => return Ok(()),
        };
        let addr = load(0).operands[0];
        let off0 = load(0).int_attr("offset").unwrap_or(0);
        let pure = self.pure_loads.contains(&lanes[0].0);
        for (k, &(op, _)) in lanes.iter().enumerate() {
            let o = &m.ops[op];
            if o.kind != OpKind::Lo(L::Load)
                || o.operands[0] != addr
                || m.values[o.results[0]].ty != ty
                || o.int_attr("offset").unwrap_or(0) != off0 + 4 * k as i128
                || o.attr("global").is_some()
                || self.pure_loads.contains(&op) != pure
            {
                return Ok(());
            }
        }
        let flags = flags(pure);
        let base = self.v(addr)?;
        let v = self.b.ins().load(vt, flags, base, off0 as i32);
        // The deferred lanes are emitted now, as lanes of `v`; a pure lane already emitted
        // keeps its value (the same word) for its other uses, and this operand takes `v`.
        let mut idx: Vec<usize> = lanes.iter().filter_map(|l| l.1).collect();
        idx.sort_unstable();
        let taken: Vec<(usize, ValueId, OpId)> = lanes
            .iter()
            .enumerate()
            .filter_map(|(k, l)| l.1.map(|i| (k, self.deferred[i].0, self.deferred[i].1)))
            .collect();
        for i in idx.into_iter().rev() {
            self.deferred.remove(i);
        }
        for (k, name, op) in taken {
            let lane = self.b.ins().extractlane(v, k as u8);
            self.bind_lane(name, op, v, k as u8, lane);
        }
        self.loaded_vectors.insert(xs.to_vec(), v);
        Ok(())
    }

    /// The deferred load `op`, known here as `name`, read as lane `k` of the vector `v` (the
    /// lane's value `lane`): no longer pending, and its value that lane for every use.
    pub(crate) fn bind_lane(
        &mut self,
        name: ValueId,
        op: OpId,
        v: ir::Value,
        k: u8,
        lane: ir::Value,
    ) {
        if let Some(p) = self.deferred.iter().position(|d| d.0 == name) {
            self.deferred.remove(p);
        }
        self.load_of.insert(name, op);
        for r in [name, self.m.ops[op].results[0]] {
            self.vals.insert(r, lane);
            self.lane_vecs.insert(r, (v, k));
            self.lane_sets.remove(&r);
        }
    }
}
