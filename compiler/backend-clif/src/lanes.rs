//! The source's four-lane vector operations as Cranelift vector instructions.
//!
//! `mem-to-lo` lowers a four- or eight-lane operation (`a - b` on two `f32x4`) as one scalar op
//! per lane and marks the run (`scion_ir::lo::lanes`). Cranelift has no SLP vectorizer, so
//! without this every lane is its own instruction (the prelude's four-triangle test, `hit_lanes`,
//! four times over). Here a group of four 32-bit lanes (`f32`, 32-bit integers, and booleans
//! that are masks of such compares; an eight-lane group is two of four, its lanes 0-3 and 4-7)
//! becomes one 128-bit instruction (`F32X4`, `I32X4`; a
//! boolean lane is `0` or `-1` in an `I32X4` mask): float `add sub mul div neg`, integer `add
//! sub and or xor bitnot`, boolean `and or xor not`, `cmp`, `select` (`bitselect` on the mask),
//! `bitcast`, and float `min`/`max` where every lane takes one select form
//! ([`MinMaxForm`]: `minps`/`maxps`). An operand is the vector of an earlier group when its
//! lanes are exactly that group's lanes in order, one shuffle of it when they are its lanes in
//! another order, a splat when the four are one value, one 16-byte load when they are loads of
//! consecutive words from one address (`Fx::vector_load`), a column of four records' rows
//! transposed when they are loads of one word of four records whose next words the block also
//! reads (`Fx::transposed_load`, [`crate::transpose`]), else built from the scalars
//! (`scalar_to_vector`, `insertlane`). The lanes are then the `lo` values (`extractlane`, a
//! boolean lane compared with zero), which Cranelift drops where nothing reads them.
//!
//! Reductions: the `and` (`or`) of the four lanes of one mask, however the scalar `and`s
//! (`or`s) group them (the prelude's `any`, or `hit_lanes`' test that every lane misses, reach
//! `lo` as such chains), is one `vall_true` (`vany_true`) of the mask: `ptest` or `movmsk` and a
//! compare, not four lane extractions. The partial chains stay scalar (unused, they are
//! dropped).
//!
//! Every lane computes exactly what its scalar op computes: the same IEEE operation lane by
//! lane, a NaN made canonical where any lane's must be (harmless for the others, whose NaN
//! cannot be seen), compares with the scalar translation's condition codes, `min`/`max` with its
//! select form. Groups of other kinds or widths (`min`/`max` that may meet a NaN, shifts, casts,
//! 64-bit lanes) stay scalar.

use crate::translate::{float_cc, int_cc, Fx};
use cranelift_codegen::ir::condcodes::{FloatCC, IntCC};
use cranelift_codegen::ir::immediates::Ieee32;
use cranelift_codegen::ir::{self, types, Endianness, InstBuilder, MemFlags};
use scion_ir::entity::{BlockId, OpId, ValueId};
use scion_ir::lo::lanes::lane_groups;
use scion_ir::lo::nan::MinMaxForm;
use scion_ir::lo::Op as L;
use scion_ir::op::OpKind;
use scion_ir::types::{FloatTy, Type};
use scion_ir::Module;
use std::collections::{HashMap, HashSet};

/// The lane type of `ty` when four of it fill a 128-bit register: `f32`, a 32-bit integer, or a
/// boolean (a mask lane).
fn lane32(m: &Module, ty: scion_ir::TypeId) -> Option<Lane> {
    match m.types.get(ty) {
        Type::Float(FloatTy::F32) => Some(Lane::F32),
        Type::Int(t) if t.bits() == 32 => Some(Lane::I32),
        Type::Bool => Some(Lane::Bool),
        _ => None,
    }
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Lane {
    F32,
    I32,
    Bool,
}

impl Lane {
    fn vector(self) -> ir::Type {
        match self {
            Lane::F32 => types::F32X4,
            Lane::I32 | Lane::Bool => types::I32X4,
        }
    }
}

/// Whether the group whose first op is `op` becomes one Cranelift vector instruction.
fn vector_kind(m: &Module, op: OpId) -> bool {
    let o = &m.ops[op];
    let OpKind::Lo(kind) = o.kind else {
        return false;
    };
    let lanes = scion_ir::lo::lanes::lane_mark(m, op).map(|(_, _, n)| n);
    if !matches!(lanes, Some(4 | 8)) {
        return false;
    }
    let Some(r) = lane32(m, m.values[o.results[0]].ty) else {
        return false;
    };
    let operand = |j: usize| o.operands.get(j).and_then(|&x| lane32(m, m.values[x].ty));
    match kind {
        L::Add | L::Sub => matches!(r, Lane::F32 | Lane::I32),
        L::Mul | L::Div | L::Neg => r == Lane::F32,
        // `minps`/`maxps` where every lane's NaN facts allow a select ([`Fx::group`]).
        L::Min | L::Max => r == Lane::F32,
        L::And | L::Or | L::Xor => matches!(r, Lane::I32 | Lane::Bool),
        L::BitNot => r == Lane::I32,
        L::Not => r == Lane::Bool,
        L::Cmp => matches!(operand(0), Some(Lane::F32 | Lane::I32)),
        L::Select => operand(0) == Some(Lane::Bool) && matches!(r, Lane::F32 | Lane::I32),
        L::Bitcast => matches!(
            (operand(0), r),
            (Some(Lane::F32), Lane::I32) | (Some(Lane::I32), Lane::F32)
        ),
        _ => false,
    }
}

/// The groups of the blocks `blocks` Cranelift emits as vector instructions, each of four
/// lanes: an eight-lane group is two, its lanes 0-3 and 4-7 (Cranelift's x86-64 and AArch64
/// vectors are 128 bits), each translated as its own group and keyed by its first op.
pub(crate) fn groups(m: &Module, blocks: &[BlockId]) -> HashMap<OpId, Vec<OpId>> {
    let mut out = HashMap::new();
    for (first, ops) in lane_groups(m, blocks, vector_kind) {
        if ops.len() == 8 {
            out.insert(ops[4], ops[4..].to_vec());
            out.insert(first, ops[..4].to_vec());
        } else {
            out.insert(first, ops);
        }
    }
    out
}

/// The parameters of the `direct` blocks (entered by one branch, their parameters bound at
/// it) that nothing reads: the branch binds nothing for them. An inlined `nearest_lane` takes
/// a leaf's whole block of four triangles and reads only their ids.
pub(crate) fn dead_direct_params(
    m: &Module,
    f: scion_ir::FuncId,
    direct: &HashSet<BlockId>,
) -> HashSet<ValueId> {
    let uses = scion_ir::walk::use_counts(m, f);
    direct
        .iter()
        .flat_map(|&b| m.blocks[b].args.iter().copied())
        .filter(|p| !uses.contains_key(p))
        .collect()
}

/// Where a vector comes from: a group (its first op) or a run of block arguments.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Source {
    Group(OpId),
    Params(BlockId, usize),
}

/// The block arguments of `blocks` passed as one vector: for each block, the first argument of
/// each run of four (`f32` or 32-bit integers) that every branch to it passes either as the
/// lanes of one vector, in order (a group's results, or another such run), or as one value four
/// times (a splat), at least one branch the former. A value computed in four lanes and merged
/// at a join (`hit_lanes`' early return of `inf` in every lane, inlined) then stays in one
/// register instead of four extractions and four insertions. The entry block keeps its
/// parameters.
pub(crate) fn vector_params(
    m: &Module,
    blocks: &[BlockId],
    groups: &HashMap<OpId, Vec<OpId>>,
) -> HashMap<BlockId, Vec<usize>> {
    let mut lane_of: HashMap<ValueId, (Source, usize)> = HashMap::new();
    for (&first, ops) in groups {
        for (k, &o) in ops.iter().enumerate() {
            lane_of.insert(m.ops[o].results[0], (Source::Group(first), k));
        }
    }
    let mut edges: HashMap<BlockId, Vec<&[ValueId]>> = HashMap::new();
    for &b in blocks {
        for &op in &m.blocks[b].ops {
            for s in &m.ops[op].successors {
                edges.entry(s.block).or_default().push(&s.args);
            }
        }
    }
    let mut out: HashMap<BlockId, Vec<usize>> = HashMap::new();
    // Runs feed runs (a join of joins): repeat until nothing changes.
    loop {
        let mut changed = false;
        for &b in blocks.iter().skip(1) {
            let args = &m.blocks[b].args;
            let Some(ins) = edges.get(&b) else {
                continue;
            };
            let mut i = 0;
            while i + 4 <= args.len() {
                let known = out.get(&b).is_some_and(|r| r.contains(&i));
                let ty = m.values[args[i]].ty;
                let fits = known
                    || (matches!(lane32(m, ty), Some(Lane::F32 | Lane::I32))
                        && args[i..i + 4].iter().all(|&a| m.values[a].ty == ty)
                        && {
                            let mut vector = false;
                            ins.iter().all(|xs| {
                                let xs = &xs[i..i + 4];
                                if xs.iter().all(|&x| x == xs[0]) {
                                    return true;
                                }
                                let Some(&(src, 0)) = lane_of.get(&xs[0]) else {
                                    return false;
                                };
                                let lanes = xs
                                    .iter()
                                    .enumerate()
                                    .all(|(k, x)| lane_of.get(x) == Some(&(src, k)));
                                vector |= lanes;
                                lanes
                            }) && vector
                        });
                if !fits {
                    i += 1;
                    continue;
                }
                if !known {
                    out.entry(b).or_default().push(i);
                    for k in 0..4 {
                        lane_of.insert(args[i + k], (Source::Params(b, i), k));
                    }
                    changed = true;
                }
                i += 4;
            }
        }
        if !changed {
            return out;
        }
    }
}

/// The vector type of a run of block arguments of type `ty` ([`vector_params`]).
pub(crate) fn param_vector_type(m: &Module, ty: scion_ir::TypeId) -> Option<ir::Type> {
    lane32(m, ty).map(Lane::vector)
}

/// Little-endian lanes, which a bitcast between vector types must name.
pub(crate) fn lanes_flags() -> MemFlags {
    MemFlags::new().with_endianness(Endianness::Little)
}

impl Fx<'_, '_> {
    /// The lanes `xs` of one vector in another order, as one shuffle of it (`pshufd` on x64):
    /// a box's far planes loaded one lane apart from its near planes and aligned with them.
    fn permuted(&mut self, xs: &[ValueId], vt: ir::Type) -> Option<ir::Value> {
        let &(v, _) = self.lane_vecs.get(&xs[0])?;
        if self.b.func.dfg.value_type(v) != vt {
            return None;
        }
        let mut mask = [0u8; 16];
        for (k, x) in xs.iter().enumerate() {
            let &(w, lane) = self.lane_vecs.get(x)?;
            if w != v {
                return None;
            }
            for i in 0..4 {
                mask[4 * k + i] = 4 * lane + i as u8;
            }
        }
        let bytes = self.b.ins().bitcast(types::I8X16, lanes_flags(), v);
        let imm = self
            .b
            .func
            .dfg
            .immediates
            .push(ir::ConstantData::from(mask.to_vec()));
        let shuffled = self.b.ins().shuffle(bytes, bytes, imm);
        Some(self.b.ins().bitcast(vt, lanes_flags(), shuffled))
    }

    /// The vector whose lanes are the values `xs`, all of lane type `lane`.
    fn lane_vector(&mut self, xs: &[ValueId], lane: Lane) -> Result<ir::Value, String> {
        if let Some(&v) = self.loaded_vectors.get(xs) {
            return Ok(v);
        }
        if let Some(&(v, 0)) = self.lane_vecs.get(&xs[0]) {
            if xs
                .iter()
                .enumerate()
                .all(|(k, x)| self.lane_vecs.get(x) == Some(&(v, k as u8)))
            {
                return Ok(v);
            }
        }
        let vt = lane.vector();
        if let Some(v) = self.permuted(xs, vt) {
            return Ok(v);
        }
        let mut scalars = Vec::with_capacity(xs.len());
        for &x in xs {
            let s = self.v(x)?;
            scalars.push(if lane == Lane::Bool {
                // 0 or 1 as a mask lane, 0 or -1.
                let w = self.b.ins().uextend(types::I32, s);
                self.b.ins().ineg(w)
            } else {
                s
            });
        }
        if scalars.iter().all(|&s| s == scalars[0]) {
            return Ok(self.b.ins().splat(vt, scalars[0]));
        }
        let mut acc = self.b.ins().scalar_to_vector(vt, scalars[0]);
        for (k, &s) in scalars.iter().enumerate().skip(1) {
            acc = self.b.ins().insertlane(acc, s, k as u8);
        }
        Ok(acc)
    }

    /// The block arguments `args` of `block` bound to its Cranelift parameters `params`, a run
    /// of [`vector_params`] to the lanes of its one vector parameter.
    pub(crate) fn bind_params(
        &mut self,
        args: &[ValueId],
        runs: &[usize],
        params: &[ir::Value],
    ) -> Result<(), String> {
        let mut p = params.iter();
        let mut i = 0;
        while i < args.len() {
            let v = *p.next().ok_or("fewer block parameters than arguments")?;
            if runs.contains(&i) {
                for k in 0..4 {
                    let lane = self.b.ins().extractlane(v, k as u8);
                    self.vals.insert(args[i + k], lane);
                    self.lane_vecs.insert(args[i + k], (v, k as u8));
                }
                i += 4;
            } else {
                self.vals.insert(args[i], v);
                i += 1;
            }
        }
        Ok(())
    }

    /// The Cranelift arguments of a branch passing `xs` to a block whose runs of vector
    /// parameters start at `runs`.
    pub(crate) fn jump_args(
        &mut self,
        xs: &[ValueId],
        runs: &[usize],
    ) -> Result<Vec<ir::Value>, String> {
        let mut out = Vec::with_capacity(xs.len());
        let mut i = 0;
        while i < xs.len() {
            if runs.contains(&i) {
                let lane = lane32(self.m, self.m.values[xs[i]].ty)
                    .ok_or("a vector run of another type")?;
                out.push(self.lane_vector(&xs[i..i + 4], lane)?);
                i += 4;
            } else {
                out.push(self.v(xs[i])?);
                i += 1;
            }
        }
        Ok(out)
    }

    /// `select(c, x, y)` of the boolean `cond` (Cranelift value `c`). A float choice is made in
    /// the low lane of a vector register, a compare's mask and a bit select, because
    /// Cranelift's x86-64 backend lowers a `select` of floats to a branch around a move (a
    /// misprediction where the condition is data: a box test's hit or miss); the mask is the
    /// compare itself when `cond` is a float compare, else `c` widened to a lane mask. Other
    /// types use `select` (a conditional move).
    pub(crate) fn select(
        &mut self,
        cond: ValueId,
        c: ir::Value,
        x: ir::Value,
        y: ir::Value,
    ) -> Result<ir::Value, String> {
        let t = self.b.func.dfg.value_type(x);
        let (vt, mt, wide) = match t {
            types::F32 => (types::F32X4, types::I32X4, types::I32),
            types::F64 => (types::F64X2, types::I64X2, types::I64),
            _ => return Ok(self.b.ins().select(c, x, y)),
        };
        let m = self.m;
        let compare = match m.values[cond].def {
            scion_ir::module::ValueDef::Result(op, 0) => {
                let o = &m.ops[op];
                let float_operands = o.operands.len() == 2
                    && matches!(m.types.get(m.values[o.operands[0]].ty), Type::Float(_))
                    && self.b.func.dfg.value_type(self.v(o.operands[0])?) == t;
                match (o.kind, o.pred()) {
                    (OpKind::Lo(L::Cmp), Some(pred)) if float_operands => {
                        Some((pred, o.operands[0], o.operands[1]))
                    }
                    _ => None,
                }
            }
            _ => None,
        };
        let mask = match compare {
            Some((pred, a, b)) => {
                let (a, b) = (self.v(a)?, self.v(b)?);
                let va = self.b.ins().scalar_to_vector(vt, a);
                let vb = self.b.ins().scalar_to_vector(vt, b);
                let mask = self.b.ins().fcmp(float_cc(pred), va, vb);
                self.b.ins().bitcast(vt, lanes_flags(), mask)
            }
            None => {
                let w = self.b.ins().uextend(wide, c);
                let w = self.b.ins().ineg(w);
                let mask = self.b.ins().splat(mt, w);
                self.b.ins().bitcast(vt, lanes_flags(), mask)
            }
        };
        let vx = self.b.ins().scalar_to_vector(vt, x);
        let vy = self.b.ins().scalar_to_vector(vt, y);
        let r = self.b.ins().bitselect(mask, vx, vy);
        Ok(self.b.ins().extractlane(r, 0))
    }

    /// The boolean `op` (an `and` or an `or` of two booleans) when it completes the reduction of
    /// the four lanes of one mask (see the module documentation); `None` otherwise, after noting
    /// which lanes it covers.
    pub(crate) fn lane_reduction(&mut self, op: OpId) -> Result<Option<ir::Value>, String> {
        let m = self.m;
        let o = &m.ops[op];
        let is_and = match o.kind {
            OpKind::Lo(L::And) => true,
            OpKind::Lo(L::Or) => false,
            _ => return Ok(None),
        };
        let r = o.results[0];
        if o.operands.len() != 2 || lane32(m, m.values[r].ty) != Some(Lane::Bool) {
            return Ok(None);
        }
        // (mask, lanes, and/or if already a reduction) of an operand.
        let set = |x: ValueId| {
            if let Some(&(v, k)) = self.lane_vecs.get(&x) {
                Some((v, 1u8 << k, None))
            } else {
                self.lane_sets
                    .get(&x)
                    .map(|&(v, bits, and)| (v, bits, Some(and)))
            }
        };
        let (Some(a), Some(b)) = (set(o.operands[0]), set(o.operands[1])) else {
            return Ok(None);
        };
        let same_kind = |k: Option<bool>| k.is_none_or(|k| k == is_and);
        if a.0 != b.0 || a.1 & b.1 != 0 || !same_kind(a.2) || !same_kind(b.2) {
            return Ok(None);
        }
        let bits = a.1 | b.1;
        self.lane_sets.insert(r, (a.0, bits, is_and));
        if bits != 0b1111 {
            return Ok(None);
        }
        Ok(Some(if is_and {
            self.b.ins().vall_true(a.0)
        } else {
            self.b.ins().vany_true(a.0)
        }))
    }

    /// Translates the group `ops` as one vector instruction and binds its lanes; `false` when
    /// an operand cannot be a vector here (the caller then translates the ops one by one).
    pub(crate) fn group(&mut self, ops: &[OpId]) -> Result<bool, String> {
        let m = self.m;
        let first = &m.ops[ops[0]];
        let OpKind::Lo(kind) = first.kind else {
            return Ok(false);
        };
        let Some(rl) = lane32(m, m.values[first.results[0]].ty) else {
            return Ok(false);
        };
        // A float min/max is one instruction only when every lane takes the same select form.
        let form = if matches!(kind, L::Min | L::Max) {
            match self.nan.lanes_min_max_form(m, ops) {
                None | Some(MinMaxForm::General) => return Ok(false),
                form => form,
            }
        } else {
            None
        };
        let mut args = Vec::with_capacity(first.operands.len());
        for j in 0..first.operands.len() {
            let xs: Vec<ValueId> = ops.iter().map(|&o| m.ops[o].operands[j]).collect();
            let Some(lane) = lane32(m, m.values[xs[0]].ty) else {
                return Ok(false);
            };
            args.push((self.lane_vector(&xs, lane)?, lane));
        }
        let signed = first
            .operands
            .first()
            .and_then(|&x| m.types.as_int(m.values[x].ty))
            .is_some_and(|t| t.is_signed());
        let a = |j: usize| args[j].0;
        let b = &mut self.b;
        let v = match kind {
            L::Add if rl == Lane::F32 => b.ins().fadd(a(0), a(1)),
            L::Sub if rl == Lane::F32 => b.ins().fsub(a(0), a(1)),
            L::Mul => b.ins().fmul(a(0), a(1)),
            L::Div => b.ins().fdiv(a(0), a(1)),
            L::Neg => b.ins().fneg(a(0)),
            L::Add => b.ins().iadd(a(0), a(1)),
            L::Sub => b.ins().isub(a(0), a(1)),
            L::And => b.ins().band(a(0), a(1)),
            L::Or => b.ins().bor(a(0), a(1)),
            L::Xor => b.ins().bxor(a(0), a(1)),
            L::BitNot | L::Not => b.ins().bnot(a(0)),
            L::Cmp => {
                let pred = first.pred().ok_or("bad predicate")?;
                if args[0].1 == Lane::F32 {
                    b.ins().fcmp(float_cc(pred), a(0), a(1))
                } else {
                    b.ins().icmp(int_cc(pred, signed), a(0), a(1))
                }
            }
            L::Select => {
                let vt = rl.vector();
                let mask = if vt == types::I32X4 {
                    a(0)
                } else {
                    b.ins().bitcast(vt, lanes_flags(), a(0))
                };
                b.ins().bitselect(mask, a(1), a(2))
            }
            L::Bitcast => b.ins().bitcast(rl.vector(), lanes_flags(), a(0)),
            L::Min | L::Max => {
                // The scalar forms (`Fx::min_max`) lane by lane: `select(fcmp lt x y, x, y)`
                // (min; max with the compare swapped), with (x, y) = (q, p), or (p, q) when
                // swapped: Cranelift's `minps`/`maxps` patterns.
                let (x, y) = if form == Some(MinMaxForm::SelectSwapped) {
                    (a(0), a(1))
                } else {
                    (a(1), a(0))
                };
                let c = if kind == L::Max {
                    b.ins().fcmp(FloatCC::LessThan, y, x)
                } else {
                    b.ins().fcmp(FloatCC::LessThan, x, y)
                };
                let c = b.ins().bitcast(types::F32X4, lanes_flags(), c);
                b.ins().bitselect(c, x, y)
            }
            _ => return Ok(false),
        };
        // A NaN made canonical where some lane's can be seen, lane by lane.
        let v = if rl == Lane::F32
            && matches!(kind, L::Add | L::Sub | L::Mul | L::Div)
            && ops
                .iter()
                .any(|&o| self.nan.canonicalize(m.ops[o].results[0]))
        {
            let uno = self.b.ins().fcmp(FloatCC::Unordered, v, v);
            let uno = self.b.ins().bitcast(types::F32X4, lanes_flags(), uno);
            let c = self.b.ins().f32const(Ieee32::with_bits(0x7fc0_0000));
            let nan = self.b.ins().splat(types::F32X4, c);
            self.b.ins().bitselect(uno, nan, v)
        } else {
            v
        };
        for (k, &o) in ops.iter().enumerate() {
            let lane = self.b.ins().extractlane(v, k as u8);
            let lane = if rl == Lane::Bool {
                self.b.ins().icmp_imm(IntCC::NotEqual, lane, 0)
            } else {
                lane
            };
            let r = m.ops[o].results[0];
            self.vals.insert(r, lane);
            self.lane_vecs.insert(r, (v, k as u8));
        }
        Ok(true)
    }
}
