//! The containers: [`Module`] → [`Func`] → [`Region`] → [`Block`] → operation → value, all in
//! the module's arenas, plus the table of algebraic data types and the spans side table.
//!
//! Invariants (checked by [`crate::verify::verify`]):
//! - every op, block and region listed somewhere is listed exactly once, and its `parent` field
//!   names the block, region or owner that lists it;
//! - every value is defined exactly once, by the op result or block argument its
//!   [`ValueDef`] names;
//! - spans are never part of an entity: they live in [`Module::spans`], so equality, hashing
//!   and CSE never see positions.
//!
//! Arenas never shrink: erasing an op only detaches it from its block (see [`crate::rewrite`]).

use crate::attr::{Attr, Attrs};
use crate::diag::Span;
use crate::entity::{BlockId, FuncId, OpId, RegionId, TypeId, ValueId};
use crate::op::Operation;
use crate::types::{Type, TypeTable};
use la_arena::{Arena, ArenaMap};
use rustc_hash::FxHashMap;
use smallvec::SmallVec;

/// Where a value comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ValueDef {
    /// Result number `1` of op `0`.
    Result(OpId, u32),
    /// Argument number `1` of block `0`.
    BlockArg(BlockId, u32),
    /// A value used before its definition while parsing; never present in a parsed module.
    Forward,
}

/// An SSA value: its type and its definition.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ValueData {
    /// The value's type.
    pub ty: TypeId,
    /// Where it is defined.
    pub def: ValueDef,
}

/// A basic block.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Block {
    /// Its arguments (the function's parameters for a function's entry block, the destructed
    /// fields for a `tree.match` arm, the element for a `tree.foreach` body).
    pub args: SmallVec<[ValueId; 4]>,
    /// Its operations in order; the last is the terminator.
    pub ops: Vec<OpId>,
    /// The region listing the block.
    pub parent: Option<RegionId>,
}

/// Who owns a region.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RegionParent {
    /// The body of a function.
    Func(FuncId),
    /// Region of an operation.
    Op(OpId),
}

/// A list of blocks; the first is the entry.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Region {
    /// Blocks in order; the first is the entry block.
    pub blocks: Vec<BlockId>,
    /// The owner, `None` while the region is being built.
    pub parent: Option<RegionParent>,
}

/// A function: a symbol, a signature and a body.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Func {
    /// The symbol (`@name` in text); unique in the module.
    pub name: String,
    /// Parameter types; the entry block's arguments have exactly these types.
    pub params: Vec<TypeId>,
    /// Result types (empty for none).
    pub results: Vec<TypeId>,
    /// The body; its entry block's arguments are the parameters.
    pub body: RegionId,
    /// Function-level facts for later levels (e.g. an entry point's ABI name), printed as
    /// `attributes {...}` after the signature.
    pub attrs: Attrs,
}

/// The function attribute of a best-first function (source `order by k`): the index of the
/// parameter whose value orders its queued recursive calls, smallest first (docs/ir.md,
/// "Best-first functions"). Passes that change a function's parameters keep it pointing at the
/// same parameter (its first leaf once `mem-to-lo` scalarizes).
pub const ORDER_BY: &str = "order_by";

impl Func {
    /// The ordering parameter of a best-first function ([`ORDER_BY`]).
    pub fn order_by(&self) -> Option<usize> {
        self.attrs
            .get(ORDER_BY)
            .and_then(Attr::as_int)
            .and_then(|i| usize::try_from(i).ok())
    }

    /// Sets (or moves) the ordering parameter ([`ORDER_BY`]).
    pub fn set_order_by(&mut self, index: usize) {
        self.attrs.set(ORDER_BY, Attr::Int(index as i128));
    }
}

/// A named, typed field of an ADT.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Field {
    /// The field's name.
    pub name: String,
    /// Its type.
    pub ty: TypeId,
}

/// One variant of a sum type.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Variant {
    /// The variant's name (`Leaf`).
    pub name: String,
    /// Its own fields, after the shared ones.
    pub fields: Vec<Field>,
}

/// An algebraic data type: a record (no variants; all fields shared) or a sum whose variants
/// all carry the shared fields first (`type BVH(bounds: AABB) = Interior(...) | Leaf(...)`).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct AdtDef {
    /// The type's name, as in `!tree.adt<"BVH">`.
    pub name: String,
    /// Fields every value has (for a record: all of them).
    pub shared: Vec<Field>,
    /// Variants of a sum; empty for a record.
    pub variants: Vec<Variant>,
}

impl AdtDef {
    /// True for a record.
    pub fn is_record(&self) -> bool {
        self.variants.is_empty()
    }

    /// The variant called `name` with its position.
    pub fn variant(&self, name: &str) -> Option<(usize, &Variant)> {
        self.variants
            .iter()
            .enumerate()
            .find(|(_, v)| v.name == name)
    }

    /// The shared field called `name` with its position.
    pub fn shared_field(&self, name: &str) -> Option<(usize, &Field)> {
        self.shared.iter().enumerate().find(|(_, f)| f.name == name)
    }

    /// All fields of a value of `variant` (shared first), or of the record when `None`.
    pub fn fields_of(&self, variant: Option<&str>) -> Option<Vec<&Field>> {
        let mut fields: Vec<&Field> = self.shared.iter().collect();
        match variant {
            None if self.is_record() => Some(fields),
            None => None,
            Some(v) => {
                let (_, var) = self.variant(v)?;
                fields.extend(var.fields.iter());
                Some(fields)
            }
        }
    }
}

/// A layout declaration carried by a `tree`-level module, so that the specializations can run
/// on text IR (`scion-opt --layout NAME --passes=destructor-specialize`): its source in the
/// layout language (the `layout` declaration and the `type` declarations it may read) and the
/// type the checker decided it realizes. Printed `tree.layout @Name for @Type "source"`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LayoutSource {
    /// The layout's name.
    pub name: String,
    /// The sum type it realizes, as the type checker chose it (`None`: undecided).
    pub adt: Option<String>,
    /// The declarations, as source text.
    pub source: String,
}

/// A compilation unit of IR: functions, ADT declarations and every arena.
#[derive(Clone, Debug, Default)]
pub struct Module {
    /// Every function ever added; [`Module::func_order`] says which are live and in what order.
    pub funcs: Arena<Func>,
    /// The live functions in print order.
    pub func_order: Vec<FuncId>,
    /// ADT declarations in print order.
    pub adts: Vec<AdtDef>,
    /// Layouts carried for the specializations, in print order.
    pub layouts: Vec<LayoutSource>,
    adt_index: FxHashMap<String, usize>,
    /// All regions.
    pub regions: Arena<Region>,
    /// All blocks.
    pub blocks: Arena<Block>,
    /// All operations.
    pub ops: Arena<Operation>,
    /// All values.
    pub values: Arena<ValueData>,
    /// The interned types.
    pub types: TypeTable,
    /// Source positions of ops (side table: never part of op equality).
    pub spans: ArenaMap<OpId, Span>,
    /// Source positions of functions.
    pub func_spans: ArenaMap<FuncId, Span>,
    /// Pending replace-all-uses: uses of a key are to read the value instead. Resolved by
    /// [`crate::rewrite::resolve_aliases`], which the pass manager calls after every pass.
    pub aliases: FxHashMap<ValueId, ValueId>,
}

impl Module {
    /// An empty module.
    pub fn new() -> Module {
        Module::default()
    }

    /// Interns a type.
    pub fn ty(&mut self, ty: Type) -> TypeId {
        self.types.intern(ty)
    }

    /// The type of a value.
    pub fn value_type(&self, v: ValueId) -> TypeId {
        self.values[v].ty
    }

    /// Declares an ADT. Returns `Err` with the earlier declaration's position when the name is
    /// taken.
    pub fn declare_adt(&mut self, def: AdtDef) -> Result<TypeId, usize> {
        if let Some(&i) = self.adt_index.get(&def.name) {
            return Err(i);
        }
        let ty = self.types.adt(&def.name);
        self.adt_index.insert(def.name.clone(), self.adts.len());
        self.adts.push(def);
        Ok(ty)
    }

    /// The ADT called `name`.
    pub fn adt(&self, name: &str) -> Option<&AdtDef> {
        self.adt_index.get(name).map(|&i| &self.adts[i])
    }

    /// The ADT a type names, when it is `!tree.adt<"...">` of a declared type.
    pub fn adt_of_type(&self, ty: TypeId) -> Option<&AdtDef> {
        match self.types.get(ty) {
            Type::Adt(name) => self.adt(name),
            _ => None,
        }
    }

    /// Adds a function with an empty body region holding one entry block whose arguments are
    /// the parameters. Returns the function and its entry block.
    pub fn add_func(
        &mut self,
        name: &str,
        params: &[TypeId],
        results: &[TypeId],
    ) -> (FuncId, BlockId) {
        let body = self.regions.alloc(Region::default());
        let fid = self.funcs.alloc(Func {
            name: name.to_string(),
            params: params.to_vec(),
            results: results.to_vec(),
            body,
            attrs: Attrs::new(),
        });
        self.regions[body].parent = Some(RegionParent::Func(fid));
        self.func_order.push(fid);
        let entry = self.add_block(body, params);
        (fid, entry)
    }

    /// Adds a function declaration: a signature whose body region has no block (defined
    /// elsewhere, e.g. by the runtime). It prints as `func @name(T, ...) -> (R, ...)`.
    pub fn declare_func(&mut self, name: &str, params: &[TypeId], results: &[TypeId]) -> FuncId {
        let (f, _) = self.add_func(name, params, results);
        let body = self.funcs[f].body;
        self.regions[body].blocks.clear();
        f
    }

    /// True when `f` has no body (see [`Module::declare_func`]).
    pub fn is_declaration(&self, f: FuncId) -> bool {
        self.regions[self.funcs[f].body].blocks.is_empty()
    }

    /// The live function called `name`.
    pub fn func_by_name(&self, name: &str) -> Option<FuncId> {
        self.func_order
            .iter()
            .copied()
            .find(|&f| self.funcs[f].name == name)
    }

    /// Removes a function from the module (its arena entries stay, unreachable).
    pub fn remove_func(&mut self, f: FuncId) {
        self.func_order.retain(|&g| g != f);
    }

    /// The entry block of a function.
    pub fn entry_block(&self, f: FuncId) -> Option<BlockId> {
        self.regions[self.funcs[f].body].blocks.first().copied()
    }

    /// A new detached region (give it to an op through the builder).
    pub fn new_region(&mut self) -> RegionId {
        self.regions.alloc(Region::default())
    }

    /// Appends a new block with arguments of `arg_types` to `region`.
    pub fn add_block(&mut self, region: RegionId, arg_types: &[TypeId]) -> BlockId {
        let block = self.blocks.alloc(Block {
            parent: Some(region),
            ..Block::default()
        });
        for (i, &ty) in arg_types.iter().enumerate() {
            let v = self.values.alloc(ValueData {
                ty,
                def: ValueDef::BlockArg(block, i as u32),
            });
            self.blocks[block].args.push(v);
        }
        self.regions[region].blocks.push(block);
        block
    }

    /// Adds one more argument to `block`.
    pub fn add_block_arg(&mut self, block: BlockId, ty: TypeId) -> ValueId {
        let i = self.blocks[block].args.len() as u32;
        let v = self.values.alloc(ValueData {
            ty,
            def: ValueDef::BlockArg(block, i),
        });
        self.blocks[block].args.push(v);
        v
    }

    /// Result `i` of `op`.
    pub fn result(&self, op: OpId, i: usize) -> ValueId {
        self.ops[op].results[i]
    }

    /// The op defining `v`, if `v` is a result.
    pub fn def_op(&self, v: ValueId) -> Option<OpId> {
        match self.values[v].def {
            ValueDef::Result(op, _) => Some(op),
            _ => None,
        }
    }

    /// The span recorded for `op`.
    pub fn span(&self, op: OpId) -> Option<Span> {
        self.spans.get(op).copied()
    }

    /// Records the span of `op`.
    pub fn set_span(&mut self, op: OpId, span: Span) {
        self.spans.insert(op, span);
    }

    /// The function whose body (transitively) contains `op`, following parent links (`None`
    /// for a detached op, or parent links that loop, which only broken IR has).
    pub fn func_of_op(&self, op: OpId) -> Option<FuncId> {
        let mut op = op;
        for _ in 0..=self.ops.len() {
            let block = self.ops[op].parent?;
            let region = self.blocks[block].parent?;
            match self.regions[region].parent? {
                RegionParent::Func(f) => return Some(f),
                RegionParent::Op(o) => op = o,
            }
        }
        None
    }
}
