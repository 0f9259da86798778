//! Operations: the one generic instruction shape of every level, and [`OpKind`], the closed
//! union of the dialects' op enums.
//!
//! An [`Operation`] has a kind, operands (values), results (values it defines), an attribute
//! dictionary, regions (nested code, owned by the op) and successors (blocks of the same region
//! it may branch to, with the values passed to their arguments). Which of these an op kind uses
//! is written on its variant and checked by the verifier. Kinds are plain Rust enums, one per
//! dialect: adding an op makes `rustc` point at every `match` (printer, verifier, interpreter,
//! lowering) that must learn it. The `mem` and `lo` dialects slot in as `OpKind::Mem(..)` and
//! `OpKind::Lo(..)`; `lo` will use multi-block regions and successors, `tree` and `mem` use
//! single-block structured regions.

use crate::attr::{Attr, Attrs};
use crate::entity::{BlockId, RegionId, ValueId};
use crate::{mem, tree};
use smallvec::SmallVec;

/// The dialects, for checks such as "no `tree` op survives this pass".
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Dialect {
    /// The layout-agnostic traversal level.
    Tree,
    /// The scalar SSA control-flow graph level.
    Lo,
    /// Reads and writes of a physical layout's buffers (added to `tree`).
    Mem,
}

impl Dialect {
    /// The text prefix (`tree`).
    pub fn name(self) -> &'static str {
        match self {
            Dialect::Tree => "tree",
            Dialect::Lo => "lo",
            Dialect::Mem => "mem",
        }
    }
}

/// What an operation does: one dialect's op enum.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum OpKind {
    /// An op of the `tree` dialect.
    Tree(tree::Op),
    /// An op of the `lo` dialect.
    Lo(crate::lo::Op),
    /// An op of the `mem` dialect.
    Mem(mem::Op),
}

impl From<mem::Op> for OpKind {
    fn from(op: mem::Op) -> OpKind {
        OpKind::Mem(op)
    }
}

impl From<tree::Op> for OpKind {
    fn from(op: tree::Op) -> OpKind {
        OpKind::Tree(op)
    }
}

impl OpKind {
    /// The dialect the op belongs to.
    pub fn dialect(self) -> Dialect {
        match self {
            OpKind::Tree(_) => Dialect::Tree,
            OpKind::Lo(_) => Dialect::Lo,
            OpKind::Mem(_) => Dialect::Mem,
        }
    }

    /// The name without the dialect prefix.
    pub fn mnemonic(self) -> &'static str {
        match self {
            OpKind::Tree(op) => op.mnemonic(),
            OpKind::Lo(op) => op.mnemonic(),
            OpKind::Mem(op) => op.mnemonic(),
        }
    }

    /// The full name as printed, `dialect.mnemonic` (`tree.add`).
    pub fn name(self) -> String {
        format!("{}.{}", self.dialect().name(), self.mnemonic())
    }

    /// The kind named `name` (`tree.add`), if any.
    pub fn from_name(name: &str) -> Option<OpKind> {
        let (dialect, mnemonic) = name.split_once('.')?;
        match dialect {
            "tree" => tree::Op::from_mnemonic(mnemonic).map(OpKind::Tree),
            "lo" => crate::lo::Op::from_mnemonic(mnemonic).map(OpKind::Lo),
            "mem" => mem::Op::from_mnemonic(mnemonic).map(OpKind::Mem),
            _ => None,
        }
    }

    /// True for ops that must end a block and may appear nowhere else.
    pub fn is_terminator(self) -> bool {
        match self {
            OpKind::Tree(op) => op.is_terminator(),
            OpKind::Lo(op) => op.is_terminator(),
            OpKind::Mem(_) => false,
        }
    }

    /// True for ops without side effects apart from their results (regions not considered).
    pub fn is_pure(self) -> bool {
        match self {
            OpKind::Tree(op) => op.is_pure(),
            OpKind::Lo(op) => op.is_pure(),
            OpKind::Mem(op) => op.is_pure(),
        }
    }

    /// True when the op's regions are structured: exactly one block, no successors inside, left
    /// only through the block's terminator. Every `tree` region is; `lo` regions will be CFGs.
    pub fn has_structured_regions(self) -> bool {
        match self {
            OpKind::Tree(_) | OpKind::Mem(_) => true,
            OpKind::Lo(_) => false,
        }
    }

    /// True when this is the kind `mem::Op::X` given.
    pub fn is_mem(self, op: mem::Op) -> bool {
        self == OpKind::Mem(op)
    }

    /// True when this is the kind `tree::Op::X` given.
    pub fn is_tree(self, op: tree::Op) -> bool {
        self == OpKind::Tree(op)
    }
}

/// A branch target: a block of the same region and the values for its arguments.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Successor {
    /// The target block.
    pub block: BlockId,
    /// One value per block argument.
    pub args: SmallVec<[ValueId; 4]>,
}

/// One operation. Stored in [`crate::Module::ops`]; its position is the block that lists it.
#[derive(Clone, Debug, PartialEq)]
pub struct Operation {
    /// What it does.
    pub kind: OpKind,
    /// The values it reads, in the order its kind documents.
    pub operands: SmallVec<[ValueId; 4]>,
    /// The values it defines.
    pub results: SmallVec<[ValueId; 2]>,
    /// Compile-time data, sorted by name.
    pub attrs: Attrs,
    /// Nested code owned by the op.
    pub regions: SmallVec<[RegionId; 2]>,
    /// Branch targets (CFG terminators only).
    pub successors: SmallVec<[Successor; 2]>,
    /// The block listing this op, `None` while detached (built but not inserted, or erased).
    pub parent: Option<BlockId>,
}

impl Operation {
    /// The attribute `name`.
    pub fn attr(&self, name: &str) -> Option<&Attr> {
        self.attrs.get(name)
    }

    /// The integer attribute `name`.
    pub fn int_attr(&self, name: &str) -> Option<i128> {
        self.attrs.get(name).and_then(Attr::as_int)
    }

    /// The string attribute `name`.
    pub fn str_attr(&self, name: &str) -> Option<&str> {
        self.attrs.get(name).and_then(Attr::as_str)
    }

    /// The function a `tree.call` or `lo.call` names (its `callee` symbol).
    pub fn callee(&self) -> Option<&str> {
        self.attrs.get("callee").and_then(Attr::as_sym)
    }

    /// The predicate of a `tree.cmp` or `lo.cmp` (`pred`), when it is a known one.
    pub fn pred(&self) -> Option<tree::CmpPred> {
        self.str_attr("pred").and_then(tree::CmpPred::from_name)
    }

    /// The `tree` op kind, if this is a `tree` op.
    pub fn tree_op(&self) -> Option<tree::Op> {
        match self.kind {
            OpKind::Tree(op) => Some(op),
            OpKind::Lo(_) | OpKind::Mem(_) => None,
        }
    }

    /// The `lo` op kind, if this is a `lo` op.
    pub fn lo_op(&self) -> Option<crate::lo::Op> {
        match self.kind {
            OpKind::Lo(op) => Some(op),
            OpKind::Tree(_) | OpKind::Mem(_) => None,
        }
    }
}
