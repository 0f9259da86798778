//! If-conversion: a conditional branch whose two sides are short, side-effect-free blocks that
//! meet again at one join becomes straight-line code, both sides computed and the join's
//! arguments chosen by `select`, so that no branch is left to mispredict. LLVM's SimplifyCFG
//! does this before instruction selection; Cranelift does not, and the `lo` it gets has a branch
//! wherever the source returns early from a small function: the prelude's `distmin`
//! (`if tmax < enter { return inf; } if enter <= exit { return enter; } return inf`), inlined
//! at every box test of a traversal, was three branches per box on Cranelift and branch-free
//! code on LLVM (twice the mispredictions per ray on fzk_haus's primary rays; docs/performance.md,
//! "Eighteenth session").
//!
//! The general form of [`crate::flatten`], which turns boolean short-circuit diamonds into `bor`
//! and `band` before translation; this takes any join arguments (floats, integers, several).
//! A side qualifies when its block has this branch as its only predecessor, holds only pure ops
//! that cannot trap (arithmetic, compares, selects, casts, min/max and the like; not divisions
//! and remainders, which `flatten` keeps behind their branches too: a division by a zero the
//! branch guards, and their cost), at most [`BUDGET`] of them over the whole
//! conversion, and ends in a branch to the join or in another such conditional branch (nested
//! sides, converted the same way). A side may also be the join itself (a triangle). A join all
//! of whose edges come from the converted branches (the value an inner `if` chose) is passed
//! through the same way when it qualifies as a side. A final join with vector parameters
//! ([`crate::lanes::vector_params`]) is left alone. The converted blocks,
//! unreachable now, are not translated again.

use crate::translate::Fx;
use cranelift_codegen::ir::{self, InstBuilder};
use scion_ir::entity::{BlockId, FuncId, OpId, ValueId};
use scion_ir::lo::Op as L;
use scion_ir::op::OpKind;
use scion_ir::Module;
use std::collections::HashMap;

/// Most pure ops an if-conversion computes on both sides together.
pub const BUDGET: usize = 16;

/// A join argument: a value, or a choice by a condition between two.
enum Arg {
    Val(ValueId),
    Sel(ValueId, Box<Arg>, Box<Arg>),
}

/// A step of a converted region: a side block entered with these arguments, or a join of
/// the region (all of whose edges come from it) entered with these choices.
enum Step {
    Side(BlockId, Vec<ValueId>),
    Join(BlockId, Vec<Arg>),
}

/// How control reaches the join from one edge: the blocks to compute on the way, the join, its
/// arguments, and how many of the join's incoming edges the path stands for.
struct Path {
    emit: Vec<Step>,
    join: BlockId,
    args: Vec<Arg>,
    edges: usize,
}

/// The number of branch edges into each block of `f` ([`crate::flatten::predecessors`]).
pub(crate) fn predecessors(m: &Module, f: FuncId) -> HashMap<BlockId, usize> {
    crate::flatten::predecessors(m, f)
        .into_iter()
        .map(|(b, edges)| (b, edges.len()))
        .collect()
}

/// What a side may compute: what [`crate::flatten`] may run unconditionally, less divisions
/// and remainders (their cost).
fn pure(m: &Module, op: OpId) -> bool {
    crate::flatten::speculatable(m, op) && !matches!(m.ops[op].kind, OpKind::Lo(L::Div | L::Rem))
}

impl Fx<'_, '_> {
    /// Where the edge to `s` with arguments `xs` leads, computing side blocks on the way.
    fn path(&self, s: BlockId, xs: &[ValueId], budget: &mut usize, depth: usize) -> Option<Path> {
        if self.preds.get(&s) != Some(&1) || depth > 8 || !self.charge(s, budget) {
            return Some(Path {
                emit: Vec::new(),
                join: s,
                args: xs.iter().map(|&x| Arg::Val(x)).collect(),
                edges: 1,
            });
        }
        let mut p = self.through(s, budget, depth)?;
        p.emit.insert(0, Step::Side(s, xs.to_vec()));
        Some(p)
    }

    /// Whether block `s` holds only pure ops before its branch, within `budget` (then charged).
    fn charge(&self, s: BlockId, budget: &mut usize) -> bool {
        let m = self.m;
        let Some((_, body)) = m.blocks[s].ops.split_last() else {
            return false;
        };
        if body.len() > *budget || !body.iter().all(|&o| pure(m, o)) {
            return false;
        }
        *budget -= body.len();
        true
    }

    /// Where control goes from the end of block `s` (its body computed).
    fn through(&self, s: BlockId, budget: &mut usize, depth: usize) -> Option<Path> {
        let m = self.m;
        let t = &m.ops[*m.blocks[s].ops.last()?];
        match t.kind {
            OpKind::Lo(L::Br) => {
                let n = &t.successors[0];
                self.path(n.block, &n.args, budget, depth + 1)
            }
            OpKind::Lo(L::CondBr) => {
                let (a, b) = (&t.successors[0], &t.successors[1]);
                let pa = self.path(a.block, &a.args, budget, depth + 1)?;
                let pb = self.path(b.block, &b.args, budget, depth + 1)?;
                self.past_joins(merge(t.operands[0], pa, pb)?, budget, depth + 1)
            }
            _ => None,
        }
    }

    /// `p` continued through its join while every edge into the join is one of `p`'s and the
    /// join qualifies as a side (a value chosen in nested branches, then used).
    fn past_joins(&self, mut p: Path, budget: &mut usize, depth: usize) -> Option<Path> {
        while self.preds.get(&p.join) == Some(&p.edges) && depth <= 8 {
            let mut trial = *budget;
            if !self.charge(p.join, &mut trial) {
                break;
            }
            let Some(rest) = self.through(p.join, &mut trial, depth + 1) else {
                break;
            };
            *budget = trial;
            p.emit.push(Step::Join(p.join, p.args));
            p.emit.extend(rest.emit);
            p = Path {
                emit: p.emit,
                join: rest.join,
                args: rest.args,
                edges: rest.edges,
            };
        }
        Some(p)
    }

    /// Translates the conditional branch `op` as straight-line code and a jump when both of
    /// its sides qualify (see the module documentation); `false` when they do not (nothing was
    /// emitted then).
    pub(crate) fn if_convert<M: cranelift_module::Module>(
        &mut self,
        cl: &mut M,
        syms: &crate::translate::Symbols,
        op: OpId,
        blocks: &HashMap<BlockId, ir::Block>,
    ) -> Result<bool, String> {
        let m = self.m;
        let o = &m.ops[op];
        let (a, b) = (&o.successors[0], &o.successors[1]);
        let mut budget = BUDGET;
        let (Some(pa), Some(pb)) = (
            self.path(a.block, &a.args, &mut budget, 0),
            self.path(b.block, &b.args, &mut budget, 0),
        ) else {
            return Ok(false);
        };
        let Some(p) = merge(o.operands[0], pa, pb) else {
            return Ok(false);
        };
        let Some(p) = self.past_joins(p, &mut budget, 0) else {
            return Ok(false);
        };
        if p.emit.is_empty() || self.has_vector_params(p.join) {
            return Ok(false);
        }
        for step in &p.emit {
            let (blk, vs) = match step {
                Step::Side(blk, xs) => {
                    let vs: Vec<ir::Value> =
                        xs.iter().map(|&x| self.v(x)).collect::<Result<_, _>>()?;
                    (*blk, vs)
                }
                Step::Join(blk, args) => {
                    let mut vs = Vec::with_capacity(args.len());
                    for a in args {
                        vs.push(self.arg(a)?);
                    }
                    (*blk, vs)
                }
            };
            self.converted.insert(blk);
            for (&param, v) in m.blocks[blk].args.iter().zip(vs) {
                self.vals.insert(param, v);
                self.lane_vecs.remove(&param);
            }
            let body = &m.blocks[blk].ops;
            for &x in &body[..body.len() - 1] {
                self.op(cl, syms, x, blocks)?;
            }
        }
        let mut args = Vec::with_capacity(p.args.len());
        for arg in &p.args {
            args.push(self.arg(arg)?);
        }
        let join = *blocks.get(&p.join).ok_or("branch to a missing block")?;
        if self.is_direct(p.join) {
            for (k, (&param, v)) in m.blocks[p.join].args.iter().zip(args).enumerate() {
                let x = match &p.args[k] {
                    Arg::Val(x) => Some(*x),
                    Arg::Sel(..) => None,
                };
                self.bind_direct(param, v, x);
            }
            self.b.ins().jump(join, &[]);
        } else {
            let args: Vec<ir::BlockArg> = args.into_iter().map(ir::BlockArg::Value).collect();
            self.b.ins().jump(join, &args);
        }
        Ok(true)
    }

    fn arg(&mut self, a: &Arg) -> Result<ir::Value, String> {
        match a {
            Arg::Val(x) => self.v(*x),
            Arg::Sel(c, x, y) => {
                let (cv, x, y) = (self.v(*c)?, self.arg(x)?, self.arg(y)?);
                if x == y {
                    Ok(x)
                } else {
                    self.select(*c, cv, x, y)
                }
            }
        }
    }
}

/// The two sides of a branch on `c` as one path, when they reach the same join.
fn merge(c: ValueId, a: Path, b: Path) -> Option<Path> {
    if a.join != b.join || a.args.len() != b.args.len() {
        return None;
    }
    let mut emit = a.emit;
    emit.extend(b.emit);
    let args = a
        .args
        .into_iter()
        .zip(b.args)
        .map(|(x, y)| match (&x, &y) {
            (Arg::Val(p), Arg::Val(q)) if p == q => x,
            _ => Arg::Sel(c, Box::new(x), Box::new(y)),
        })
        .collect();
    Some(Path {
        emit,
        join: a.join,
        args,
        edges: a.edges + b.edges,
    })
}
