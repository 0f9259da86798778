//! The `lo` dialect: a scalar SSA control-flow graph, the last level before a backend (design
//! note §5, paper §7.3).
//!
//! A function body is a CFG region: blocks with arguments (SSA φ's), ended by `lo.br`,
//! `lo.cond_br` or `lo.return`. Values are scalars (`i1`, `i8`..`u64`, `f32`, `f64`) or `ptr`;
//! vectors, tuples and records were scalarized by `mem-to-lo`. Memory is reached only through
//! `lo.load`/`lo.store` at `ptr + offset`, with `lo.ptr_add` for computed addresses and
//! `lo.stack_slot` for frame memory (explicit traversal stacks, `mut` cells). Each op maps to
//! one or a few Cranelift instructions (`scion-clif`) and later LLVM instructions. Scalar
//! semantics are `tree`'s ([`crate::tree::scalar`]); `min`/`max` are IEEE `minNum`/`maxNum`;
//! directed rounding (`add_rd` .. `mul_ru`, `f32`) is exact ([`crate::tree::directed`]), kept
//! as ops for NVPTX and expanded into round-to-nearest ops for CPUs ([`directed`]).

pub mod backend;
pub mod directed;
pub mod lanes;
pub mod layout_reads;
pub mod nan;
pub mod ops;
pub mod verify;

pub use ops::Op;

use crate::attr::Attr;
use crate::builder::{Builder, OpSpec};
use crate::entity::{BlockId, OpId, TypeId, ValueId};
use crate::tree::CmpPred;

/// `lo` shorthands on the builder.
impl Builder<'_> {
    /// `lo.const` of an integer (or `ptr`) type.
    pub fn lo_int(&mut self, ty: TypeId, v: i128) -> ValueId {
        let op = self.insert(
            OpSpec::new(Op::Const)
                .results(&[ty])
                .attr("value", Attr::Int(v)),
        );
        self.result(op, 0)
    }

    /// `lo.const` of a float type (an `f32` value is given widened to `f64`).
    pub fn lo_float(&mut self, ty: TypeId, v: f64) -> ValueId {
        let op = self.insert(
            OpSpec::new(Op::Const)
                .results(&[ty])
                .attr("value", Attr::float(v)),
        );
        self.result(op, 0)
    }

    /// `lo.const` of `i1`.
    pub fn lo_bool(&mut self, v: bool) -> ValueId {
        let ty = self.m.types.bool();
        let op = self.insert(
            OpSpec::new(Op::Const)
                .results(&[ty])
                .attr("value", Attr::Bool(v)),
        );
        self.result(op, 0)
    }

    /// A `lo` op with one result.
    pub fn lo1(&mut self, op: Op, operands: &[ValueId], ty: TypeId) -> ValueId {
        self.build1(op, operands, ty)
    }

    /// `lo.cmp {pred}`.
    pub fn lo_cmp(&mut self, pred: CmpPred, a: ValueId, b: ValueId) -> ValueId {
        let ty = self.m.types.bool();
        let op = self.insert(
            OpSpec::new(Op::Cmp)
                .operands(&[a, b])
                .results(&[ty])
                .attr("pred", Attr::str(pred.name())),
        );
        self.result(op, 0)
    }

    /// `lo.load {offset}`.
    pub fn lo_load(&mut self, ptr: ValueId, offset: i64, ty: TypeId) -> ValueId {
        let op = self.insert(
            OpSpec::new(Op::Load)
                .operands(&[ptr])
                .results(&[ty])
                .attr("offset", Attr::Int(offset as i128)),
        );
        self.result(op, 0)
    }

    /// `lo.store {offset}`.
    pub fn lo_store(&mut self, ptr: ValueId, offset: i64, value: ValueId) -> OpId {
        self.insert(
            OpSpec::new(Op::Store)
                .operands(&[ptr, value])
                .attr("offset", Attr::Int(offset as i128)),
        )
    }

    /// `lo.stack_slot {size, align}`.
    pub fn lo_stack_slot(&mut self, size: u64, align: u64) -> ValueId {
        let ty = self.m.ty(crate::types::Type::Ptr);
        let op = self.insert(
            OpSpec::new(Op::StackSlot)
                .results(&[ty])
                .attr("size", Attr::Int(size as i128))
                .attr("align", Attr::Int(align as i128)),
        );
        self.result(op, 0)
    }

    /// `lo.call {callee}`.
    pub fn lo_call(&mut self, callee: &str, args: &[ValueId], results: &[TypeId]) -> OpId {
        self.insert(
            OpSpec::new(Op::Call)
                .operands(args)
                .results(results)
                .attr("callee", Attr::Sym(callee.to_string())),
        )
    }

    /// `lo.br ^target(args)`.
    pub fn lo_br(&mut self, target: BlockId, args: &[ValueId]) -> OpId {
        self.insert(OpSpec::new(Op::Br).successor(target, args))
    }

    /// `lo.cond_br %c, ^t(targs), ^f(fargs)`.
    pub fn lo_cond_br(
        &mut self,
        cond: ValueId,
        then: (BlockId, &[ValueId]),
        else_: (BlockId, &[ValueId]),
    ) -> OpId {
        self.insert(
            OpSpec::new(Op::CondBr)
                .operands(&[cond])
                .successor(then.0, then.1)
                .successor(else_.0, else_.1),
        )
    }

    /// `lo.return`.
    pub fn lo_ret(&mut self, values: &[ValueId]) -> OpId {
        self.insert(OpSpec::new(Op::Return).operands(values))
    }
}

impl From<Op> for crate::op::OpKind {
    fn from(op: Op) -> crate::op::OpKind {
        crate::op::OpKind::Lo(op)
    }
}
