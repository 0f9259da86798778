//! Interned types: each distinct type is stored once per module, so [`TypeId`] equality is type
//! equality and types are cheap to copy and compare.
//!
//! The type system is the traversal language's (paper §3), seen by every level: booleans (`i1`),
//! integers whose signedness is part of the type (`i8`..`i64`, `u8`..`u64`), floats, vectors
//! (`vector<3xf32>`), tuples (`tuple<f32, u32>`, with `tuple<>` the unit type), fixed arrays
//! (`array<8 x T>`), dynamic arrays or slices (`array<? x T>`), `set<T>`, `option<T>`, the
//! algebraic data types declared in the module (`!tree.adt<"BVH">`), references for `mut`
//! parameters and local cells (`!tree.ref<T>`) and an opaque pointer (`ptr`). The `mem` and `lo`
//! dialects add their own variants here, next to the tree ones.

use crate::entity::TypeId;
use la_arena::Arena;
use rustc_hash::FxHashMap;
use std::fmt;

/// An integer type: width and signedness. `i1` (the boolean) is [`Type::Bool`], not an `IntTy`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum IntTy {
    /// `i8`
    I8,
    /// `i16`
    I16,
    /// `i32`
    I32,
    /// `i64`
    I64,
    /// `u8`
    U8,
    /// `u16`
    U16,
    /// `u32`
    U32,
    /// `u64`
    U64,
}

impl IntTy {
    /// Every integer type, signed first.
    pub const ALL: [IntTy; 8] = [
        IntTy::I8,
        IntTy::I16,
        IntTy::I32,
        IntTy::I64,
        IntTy::U8,
        IntTy::U16,
        IntTy::U32,
        IntTy::U64,
    ];

    /// Width in bits.
    pub fn bits(self) -> u32 {
        match self {
            IntTy::I8 | IntTy::U8 => 8,
            IntTy::I16 | IntTy::U16 => 16,
            IntTy::I32 | IntTy::U32 => 32,
            IntTy::I64 | IntTy::U64 => 64,
        }
    }

    /// True for `i8`..`i64`.
    pub fn is_signed(self) -> bool {
        matches!(self, IntTy::I8 | IntTy::I16 | IntTy::I32 | IntTy::I64)
    }

    /// The text name (`i32`, `u8`, ...).
    pub fn name(self) -> &'static str {
        match self {
            IntTy::I8 => "i8",
            IntTy::I16 => "i16",
            IntTy::I32 => "i32",
            IntTy::I64 => "i64",
            IntTy::U8 => "u8",
            IntTy::U16 => "u16",
            IntTy::U32 => "u32",
            IntTy::U64 => "u64",
        }
    }

    /// Wraps `v` to this type's width and signedness (two's complement), the semantics of every
    /// integer operation of the IR.
    pub fn wrap(self, v: i128) -> i128 {
        let bits = self.bits();
        let mask = (1i128 << bits) - 1;
        let low = v & mask;
        if self.is_signed() && low >> (bits - 1) & 1 == 1 {
            low - (1i128 << bits)
        } else {
            low
        }
    }

    /// The smallest and largest value of the type.
    pub fn range(self) -> (i128, i128) {
        let bits = self.bits();
        if self.is_signed() {
            (-(1i128 << (bits - 1)), (1i128 << (bits - 1)) - 1)
        } else {
            (0, (1i128 << bits) - 1)
        }
    }
}

/// A floating-point type.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum FloatTy {
    /// IEEE binary16.
    F16,
    /// IEEE binary32.
    F32,
    /// IEEE binary64.
    F64,
}

impl FloatTy {
    /// Width in bits.
    pub fn bits(self) -> u32 {
        match self {
            FloatTy::F16 => 16,
            FloatTy::F32 => 32,
            FloatTy::F64 => 64,
        }
    }

    /// The text name.
    pub fn name(self) -> &'static str {
        match self {
            FloatTy::F16 => "f16",
            FloatTy::F32 => "f32",
            FloatTy::F64 => "f64",
        }
    }
}

/// One type. Build them through [`TypeTable::intern`] (or [`crate::Module::ty`]).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Type {
    /// `i1`, the boolean.
    Bool,
    /// `i8`..`i64`, `u8`..`u64`.
    Int(IntTy),
    /// `f16`, `f32`, `f64`.
    Float(FloatTy),
    /// `vector<NxT>` of a scalar element type.
    Vector {
        /// Element type (a scalar).
        elem: TypeId,
        /// Number of lanes (at least 1).
        lanes: u32,
    },
    /// `tuple<A, B, ...>`; `tuple<>` is the unit type.
    Tuple(Vec<TypeId>),
    /// `array<N x T>` when `len` is known, `array<? x T>` (a slice) when not.
    Array {
        /// Element type.
        elem: TypeId,
        /// Number of elements, `None` for a slice whose length is a run-time value.
        len: Option<u64>,
    },
    /// `set<T>`.
    Set(TypeId),
    /// `option<T>`.
    Option(TypeId),
    /// `!tree.adt<"Name">`: a record or sum declared in the module's ADT table.
    Adt(String),
    /// `!tree.ref<T>`: a reference to a mutable `T` (a `mut` parameter or a local cell).
    Ref(TypeId),
    /// `ptr`: an opaque address.
    Ptr,
    /// `!mem.view<T>`: a run-time length window of `T`s in a layout's buffer (`mem.view`).
    View(TypeId),
}

/// The type arena of one module with its hash-consing map.
#[derive(Clone, Debug, Default)]
pub struct TypeTable {
    arena: Arena<Type>,
    map: FxHashMap<Type, TypeId>,
}

impl TypeTable {
    /// An empty table.
    pub fn new() -> TypeTable {
        TypeTable::default()
    }

    /// The id of `ty`, adding it when new.
    pub fn intern(&mut self, ty: Type) -> TypeId {
        if let Some(&id) = self.map.get(&ty) {
            return id;
        }
        let id = self.arena.alloc(ty.clone());
        self.map.insert(ty, id);
        id
    }

    /// The id of `ty` when it was interned already.
    pub fn lookup(&self, ty: &Type) -> Option<TypeId> {
        self.map.get(ty).copied()
    }

    /// The type behind `id`.
    pub fn get(&self, id: TypeId) -> &Type {
        &self.arena[id]
    }

    /// True when `id` was handed out by this table.
    pub fn contains(&self, id: TypeId) -> bool {
        (crate::entity::raw_index(id) as usize) < self.arena.len()
    }

    /// Number of distinct types.
    pub fn len(&self) -> usize {
        self.arena.len()
    }

    /// True when no type was interned.
    pub fn is_empty(&self) -> bool {
        self.arena.is_empty()
    }

    /// `i1`.
    pub fn bool(&mut self) -> TypeId {
        self.intern(Type::Bool)
    }
    /// An integer type.
    pub fn int(&mut self, t: IntTy) -> TypeId {
        self.intern(Type::Int(t))
    }
    /// A float type.
    pub fn float(&mut self, t: FloatTy) -> TypeId {
        self.intern(Type::Float(t))
    }
    /// `f32`.
    pub fn f32(&mut self) -> TypeId {
        self.float(FloatTy::F32)
    }
    /// `u32`.
    pub fn u32(&mut self) -> TypeId {
        self.int(IntTy::U32)
    }
    /// `i32`.
    pub fn i32(&mut self) -> TypeId {
        self.int(IntTy::I32)
    }
    /// `vector<lanes x elem>`.
    pub fn vector(&mut self, elem: TypeId, lanes: u32) -> TypeId {
        self.intern(Type::Vector { elem, lanes })
    }
    /// `tuple<...>`.
    pub fn tuple(&mut self, elems: Vec<TypeId>) -> TypeId {
        self.intern(Type::Tuple(elems))
    }
    /// `tuple<>`.
    pub fn unit(&mut self) -> TypeId {
        self.intern(Type::Tuple(Vec::new()))
    }
    /// `array<len x elem>` or `array<? x elem>`.
    pub fn array(&mut self, elem: TypeId, len: Option<u64>) -> TypeId {
        self.intern(Type::Array { elem, len })
    }
    /// `!tree.adt<"name">`.
    pub fn adt(&mut self, name: &str) -> TypeId {
        self.intern(Type::Adt(name.to_string()))
    }
    /// `!tree.ref<T>`.
    pub fn reference(&mut self, pointee: TypeId) -> TypeId {
        self.intern(Type::Ref(pointee))
    }

    /// True for `i1` and the integer types.
    pub fn is_integer_like(&self, id: TypeId) -> bool {
        matches!(self.get(id), Type::Bool | Type::Int(_))
    }

    /// The integer type of `id`, if it is one (not `i1`).
    pub fn as_int(&self, id: TypeId) -> Option<IntTy> {
        match self.get(id) {
            Type::Int(t) => Some(*t),
            _ => None,
        }
    }

    /// The float type of `id`, if it is one.
    pub fn as_float(&self, id: TypeId) -> Option<FloatTy> {
        match self.get(id) {
            Type::Float(t) => Some(*t),
            _ => None,
        }
    }

    /// True for `i1`, integers and floats.
    pub fn is_scalar(&self, id: TypeId) -> bool {
        matches!(self.get(id), Type::Bool | Type::Int(_) | Type::Float(_))
    }

    /// The element type of a vector, or the type itself for a scalar.
    pub fn scalar_of(&self, id: TypeId) -> TypeId {
        match self.get(id) {
            Type::Vector { elem, .. } => *elem,
            _ => id,
        }
    }

    /// Lanes of a vector, `None` for anything else.
    pub fn lanes(&self, id: TypeId) -> Option<u32> {
        match self.get(id) {
            Type::Vector { lanes, .. } => Some(*lanes),
            _ => None,
        }
    }

    /// Size in bits of a scalar or vector (lanes × element), `None` for other types.
    pub fn bit_width(&self, id: TypeId) -> Option<u32> {
        match self.get(id) {
            Type::Bool => Some(1),
            Type::Int(t) => Some(t.bits()),
            Type::Float(t) => Some(t.bits()),
            Type::Vector { elem, lanes } => self.bit_width(*elem).map(|w| w * lanes),
            _ => None,
        }
    }

    /// A displayable form of `id` in the text syntax.
    pub fn display(&self, id: TypeId) -> TypeDisplay<'_> {
        TypeDisplay { table: self, id }
    }
}

/// Prints a type in the text syntax; see [`TypeTable::display`].
pub struct TypeDisplay<'a> {
    table: &'a TypeTable,
    id: TypeId,
}

impl fmt::Display for TypeDisplay<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let t = self.table;
        // Printing must not panic even on broken IR (the verifier prints what it rejects).
        if !t.contains(self.id) {
            return write!(f, "<<invalid type {}>>", crate::entity::raw_index(self.id));
        }
        match t.get(self.id) {
            Type::Bool => write!(f, "i1"),
            Type::Int(i) => write!(f, "{}", i.name()),
            Type::Float(x) => write!(f, "{}", x.name()),
            Type::Vector { elem, lanes } => write!(f, "vector<{}x{}>", lanes, t.display(*elem)),
            Type::Tuple(elems) => {
                write!(f, "tuple<")?;
                for (i, e) in elems.iter().enumerate() {
                    if i > 0 {
                        write!(f, ", ")?;
                    }
                    write!(f, "{}", t.display(*e))?;
                }
                write!(f, ">")
            }
            Type::Array { elem, len: Some(n) } => write!(f, "array<{} x {}>", n, t.display(*elem)),
            Type::Array { elem, len: None } => write!(f, "array<? x {}>", t.display(*elem)),
            Type::Set(e) => write!(f, "set<{}>", t.display(*e)),
            Type::Option(e) => write!(f, "option<{}>", t.display(*e)),
            Type::Adt(name) => write!(f, "!tree.adt<{}>", crate::attr::quote(name)),
            Type::Ref(e) => write!(f, "!tree.ref<{}>", t.display(*e)),
            Type::Ptr => write!(f, "ptr"),
            Type::View(e) => write!(f, "!mem.view<{}>", t.display(*e)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interning_makes_equal_types_equal_ids() {
        let mut t = TypeTable::new();
        let f = t.f32();
        let v1 = t.vector(f, 3);
        let v2 = t.intern(Type::Vector { elem: f, lanes: 3 });
        assert_eq!(v1, v2);
        let u = t.u32();
        let tup = t.tuple(vec![f, u]);
        assert_ne!(tup, t.tuple(vec![u, f]));
        assert_eq!(t.display(tup).to_string(), "tuple<f32, u32>");
        let a = t.adt("BVH");
        let s = t.array(a, None);
        assert_eq!(t.display(s).to_string(), "array<? x !tree.adt<\"BVH\">>");
        assert_eq!(t.display(v1).to_string(), "vector<3xf32>");
    }

    #[test]
    fn wrap_is_twos_complement() {
        assert_eq!(IntTy::I8.wrap(128), -128);
        assert_eq!(IntTy::U8.wrap(-1), 255);
        assert_eq!(IntTy::U64.wrap(-1), u64::MAX as i128);
        assert_eq!(IntTy::I64.wrap(i64::MAX as i128 + 1), i64::MIN as i128);
        assert_eq!(IntTy::U16.range(), (0, 65535));
    }
}
