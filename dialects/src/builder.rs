//! Building IR: an insertion cursor (MLIR's `OpBuilder`, Cranelift's `FuncCursor`) that creates
//! operations, blocks and regions at a point of a module, stamping each new op with the current
//! span.
//!
//! An op is described by an [`OpSpec`] (kind, operands, result types, attributes, regions,
//! successors) and inserted by [`Builder::insert`], which allocates its result values. Nested
//! code is built with [`Builder::region`], which moves the cursor into a fresh single-block
//! region for the duration of a closure. `tree`-specific shorthands live in [`crate::tree`].

use crate::attr::{Attr, Attrs};
use crate::diag::Span;
use crate::entity::{BlockId, OpId, RegionId, TypeId, ValueId};
use crate::module::{Module, RegionParent, ValueData, ValueDef};
use crate::op::{OpKind, Operation, Successor};
use smallvec::SmallVec;

/// Everything needed to create one operation.
#[derive(Clone, Debug)]
pub struct OpSpec {
    /// The kind.
    pub kind: OpKind,
    /// Operands in order.
    pub operands: SmallVec<[ValueId; 4]>,
    /// One type per result.
    pub result_types: SmallVec<[TypeId; 2]>,
    /// Attributes.
    pub attrs: Attrs,
    /// Regions (detached, built beforehand); the op becomes their owner.
    pub regions: SmallVec<[RegionId; 2]>,
    /// Branch targets.
    pub successors: SmallVec<[Successor; 2]>,
}

impl OpSpec {
    /// An op of `kind` with nothing else yet.
    pub fn new(kind: impl Into<OpKind>) -> OpSpec {
        OpSpec {
            kind: kind.into(),
            operands: SmallVec::new(),
            result_types: SmallVec::new(),
            attrs: Attrs::new(),
            regions: SmallVec::new(),
            successors: SmallVec::new(),
        }
    }

    /// Sets the operands.
    pub fn operands(mut self, vals: &[ValueId]) -> OpSpec {
        self.operands = vals.iter().copied().collect();
        self
    }

    /// Sets the result types.
    pub fn results(mut self, tys: &[TypeId]) -> OpSpec {
        self.result_types = tys.iter().copied().collect();
        self
    }

    /// Sets one attribute.
    pub fn attr(mut self, name: &str, value: Attr) -> OpSpec {
        self.attrs.set(name, value);
        self
    }

    /// Appends a region.
    pub fn region(mut self, r: RegionId) -> OpSpec {
        self.regions.push(r);
        self
    }

    /// Appends a successor.
    pub fn successor(mut self, block: BlockId, args: &[ValueId]) -> OpSpec {
        self.successors.push(Successor {
            block,
            args: args.iter().copied().collect(),
        });
        self
    }
}

/// Where the builder inserts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InsertPoint {
    /// Nowhere: ops are created detached.
    Detached,
    /// At the end of a block.
    End(BlockId),
    /// Just before an op (which must be in a block).
    Before(OpId),
    /// Just after an op (which must be in a block).
    After(OpId),
}

/// An insertion cursor over a module.
pub struct Builder<'m> {
    /// The module being built.
    pub m: &'m mut Module,
    point: InsertPoint,
    span: Option<Span>,
}

impl<'m> Builder<'m> {
    /// A cursor that inserts nowhere yet.
    pub fn new(m: &'m mut Module) -> Builder<'m> {
        Builder {
            m,
            point: InsertPoint::Detached,
            span: None,
        }
    }

    /// A cursor at the end of `block`.
    pub fn at_end(m: &'m mut Module, block: BlockId) -> Builder<'m> {
        Builder {
            m,
            point: InsertPoint::End(block),
            span: None,
        }
    }

    /// Moves the cursor.
    pub fn set_insertion_point(&mut self, p: InsertPoint) {
        self.point = p;
    }

    /// Moves the cursor to the end of `block`.
    pub fn set_insertion_point_to_end(&mut self, block: BlockId) {
        self.point = InsertPoint::End(block);
    }

    /// The cursor.
    pub fn insertion_point(&self) -> InsertPoint {
        self.point
    }

    /// The block ops are inserted into, if any.
    pub fn insertion_block(&self) -> Option<BlockId> {
        match self.point {
            InsertPoint::Detached => None,
            InsertPoint::End(b) => Some(b),
            InsertPoint::Before(op) | InsertPoint::After(op) => self.m.ops[op].parent,
        }
    }

    /// The span given to every op created from now on (`None`: no span).
    pub fn set_span(&mut self, span: Option<Span>) {
        self.span = span;
    }

    /// The current span.
    pub fn span(&self) -> Option<Span> {
        self.span
    }

    /// Creates the op without inserting it; its results are allocated and its regions adopted.
    pub fn create(&mut self, spec: OpSpec) -> OpId {
        let op = self.m.ops.alloc(Operation {
            kind: spec.kind,
            operands: spec.operands,
            results: SmallVec::new(),
            attrs: spec.attrs,
            regions: spec.regions,
            successors: spec.successors,
            parent: None,
        });
        for (i, &ty) in spec.result_types.iter().enumerate() {
            let v = self.m.values.alloc(ValueData {
                ty,
                def: ValueDef::Result(op, i as u32),
            });
            self.m.ops[op].results.push(v);
        }
        for i in 0..self.m.ops[op].regions.len() {
            let r = self.m.ops[op].regions[i];
            self.m.regions[r].parent = Some(RegionParent::Op(op));
        }
        if let Some(span) = self.span {
            self.m.spans.insert(op, span);
        }
        op
    }

    /// Creates the op and inserts it at the cursor (it stays detached when the cursor is
    /// [`InsertPoint::Detached`]). After `After(x)`, the cursor moves past the new op so that
    /// successive inserts keep their order.
    pub fn insert(&mut self, spec: OpSpec) -> OpId {
        let op = self.create(spec);
        self.place(op);
        op
    }

    /// Inserts an existing detached op at the cursor.
    pub fn place(&mut self, op: OpId) {
        match self.point {
            InsertPoint::Detached => {}
            InsertPoint::End(b) => {
                self.m.blocks[b].ops.push(op);
                self.m.ops[op].parent = Some(b);
            }
            InsertPoint::Before(at) | InsertPoint::After(at) => {
                let Some(b) = self.m.ops[at].parent else {
                    return;
                };
                let pos = self.m.blocks[b]
                    .ops
                    .iter()
                    .position(|&o| o == at)
                    .unwrap_or(0);
                let pos = if matches!(self.point, InsertPoint::After(_)) {
                    pos + 1
                } else {
                    pos
                };
                self.m.blocks[b].ops.insert(pos, op);
                self.m.ops[op].parent = Some(b);
                if matches!(self.point, InsertPoint::After(_)) {
                    self.point = InsertPoint::After(op);
                }
            }
        }
    }

    /// Inserts an op with the given operands and result types and no attributes or regions.
    pub fn build(
        &mut self,
        kind: impl Into<OpKind>,
        operands: &[ValueId],
        result_types: &[TypeId],
    ) -> OpId {
        self.insert(OpSpec::new(kind).operands(operands).results(result_types))
    }

    /// Like [`Builder::build`] for an op with exactly one result; returns the result.
    pub fn build1(
        &mut self,
        kind: impl Into<OpKind>,
        operands: &[ValueId],
        result_type: TypeId,
    ) -> ValueId {
        let op = self.build(kind, operands, &[result_type]);
        self.m.ops[op].results[0]
    }

    /// Result `i` of `op`.
    pub fn result(&self, op: OpId, i: usize) -> ValueId {
        self.m.ops[op].results[i]
    }

    /// The type of `v`.
    pub fn value_type(&self, v: ValueId) -> TypeId {
        self.m.values[v].ty
    }

    /// Appends a block with arguments to a region.
    pub fn create_block(&mut self, region: RegionId, arg_types: &[TypeId]) -> BlockId {
        self.m.add_block(region, arg_types)
    }

    /// Builds a detached single-block region: creates it with a block of `arg_types`, points
    /// the cursor at the block's end, runs `body` with the block's arguments and puts the cursor
    /// back. The region is then handed to an op through [`OpSpec::region`].
    pub fn region(
        &mut self,
        arg_types: &[TypeId],
        body: impl FnOnce(&mut Builder<'_>, &[ValueId]),
    ) -> RegionId {
        let region = self.m.new_region();
        let block = self.m.add_block(region, arg_types);
        let args: SmallVec<[ValueId; 4]> = self.m.blocks[block].args.clone();
        let saved = self.point;
        self.point = InsertPoint::End(block);
        body(self, &args);
        self.point = saved;
        region
    }
}
