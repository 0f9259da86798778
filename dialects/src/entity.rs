//! Typed ids of the IR's entities: every function, region, block, operation, value and type
//! lives in an arena of the [`Module`](crate::module::Module) and is named by a typed index.
//!
//! Typed indices (rather than `Rc<RefCell<_>>` graphs or raw `usize`s) make the IR cheap to build,
//! copy and walk, and let the type checker catch a block id passed where an op id was expected.
//! Ids are meaningful only inside the module that created them. They never appear in the text
//! form: the printer renumbers values and blocks per function (`%0`, `^bb0`), so a pass that
//! allocates and drops temporaries does not change the printed numbers of what it left alone.

use crate::module::{Block, Func, Region, ValueData};
use crate::op::Operation;
use crate::types::Type;

/// A function of a module.
pub type FuncId = la_arena::Idx<Func>;
/// A region: a list of blocks owned by an operation or a function.
pub type RegionId = la_arena::Idx<Region>;
/// A basic block: arguments and a list of operations, the last one a terminator.
pub type BlockId = la_arena::Idx<Block>;
/// An operation.
pub type OpId = la_arena::Idx<Operation>;
/// An SSA value: an operation's result or a block's argument.
pub type ValueId = la_arena::Idx<ValueData>;
/// An interned type; two `TypeId`s of one module are equal exactly when the types are.
pub type TypeId = la_arena::Idx<Type>;

/// The arena position of an id, for diagnostics of internal errors and for dense side tables.
pub fn raw_index<T>(id: la_arena::Idx<T>) -> u32 {
    u32::from(id.into_raw())
}
