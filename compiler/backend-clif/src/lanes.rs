//! The source's four-lane vector operations as Cranelift vector instructions.
//!
//! `mem-to-lo` lowers a four- or eight-lane operation (`a - b` on two `f32x4`) as one scalar op
//! per lane and marks the run (`scion_ir::lo::lanes`). Cranelift has no SLP vectorizer, so
//! without this every lane is its own instruction (the prelude's four-triangle test, `hit_lanes`,
//! four times over). Here a group of four 32-bit lanes (`f32`, 32-bit integers, and booleans
//! that are masks of such compares) becomes one 128-bit instruction (`F32X4`, `I32X4`; a
//! boolean lane is `0` or `-1` in an `I32X4` mask): float `add sub mul div neg`, integer `add
//! sub and or xor bitnot`, boolean `and or xor not`, `cmp`, `select` (`bitselect` on the mask)
//! and `bitcast`. An operand is the vector of an earlier group when its lanes are exactly that
//! group's lanes in order, a splat when the four are one value, else built from the scalars
//! (`scalar_to_vector`, `insertlane`). The lanes are then the `lo` values (`extractlane`, a
//! boolean lane compared with zero), which Cranelift drops where nothing reads them.
//!
//! Every lane computes exactly what its scalar op computes: the same IEEE operation lane by
//! lane, a NaN made canonical where any lane's must be (harmless for the others, whose NaN
//! cannot be seen), compares with the scalar translation's condition codes. Groups of other
//! kinds or widths (`min`/`max`, shifts, casts, eight lanes, 64-bit lanes) stay scalar.

use crate::translate::{float_cc, int_cc, Fx};
use cranelift_codegen::ir::condcodes::{FloatCC, IntCC};
use cranelift_codegen::ir::immediates::Ieee32;
use cranelift_codegen::ir::{self, types, Endianness, InstBuilder, MemFlags};
use scion_ir::entity::{BlockId, OpId, ValueId};
use scion_ir::lo::lanes::lane_groups;
use scion_ir::lo::Op as L;
use scion_ir::op::OpKind;
use scion_ir::types::{FloatTy, Type};
use scion_ir::Module;
use std::collections::HashMap;

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
    if lanes != Some(4) {
        return false;
    }
    let Some(r) = lane32(m, m.values[o.results[0]].ty) else {
        return false;
    };
    let operand = |j: usize| o.operands.get(j).and_then(|&x| lane32(m, m.values[x].ty));
    match kind {
        L::Add | L::Sub => matches!(r, Lane::F32 | Lane::I32),
        L::Mul | L::Div | L::Neg => r == Lane::F32,
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

/// The groups of the blocks `blocks` Cranelift emits as vector instructions.
pub(crate) fn groups(m: &Module, blocks: &[BlockId]) -> HashMap<OpId, Vec<OpId>> {
    lane_groups(m, blocks, vector_kind)
}

/// Little-endian lanes, which a bitcast between vector types must name.
fn lanes_flags() -> MemFlags {
    MemFlags::new().with_endianness(Endianness::Little)
}

impl Fx<'_, '_> {
    /// The vector whose lanes are the values `xs`, all of lane type `lane`.
    fn lane_vector(&mut self, xs: &[ValueId], lane: Lane) -> Result<ir::Value, String> {
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
