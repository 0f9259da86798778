//! Semantic types of the three Scion languages and the table of declared algebraic data types
//! (paper §3, Figure 3 `T`).
//!
//! Input: nothing (these are the values `resolve` and `infer` produce). Output: [`Ty`], the
//! type every expression, binding and field has after inference, and [`AdtTable`], the
//! declared records and sums. Inference variables ([`Ty::Var`]) exist only while a program is
//! being checked; a finished [`super::TypedProgram`] holds none.

use std::fmt;

/// A primitive scalar type.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Prim {
    /// `bool` (an `i1`).
    Bool,
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
    /// `f16`
    F16,
    /// `f32`
    F32,
    /// `f64`
    F64,
}

impl Prim {
    /// Every primitive, for lookups by name.
    pub const ALL: [Prim; 12] = [
        Prim::Bool,
        Prim::I8,
        Prim::I16,
        Prim::I32,
        Prim::I64,
        Prim::U8,
        Prim::U16,
        Prim::U32,
        Prim::U64,
        Prim::F16,
        Prim::F32,
        Prim::F64,
    ];

    /// The primitive spelled `name` (`i1` is a synonym of `bool`).
    pub fn from_name(name: &str) -> Option<Prim> {
        if name == "i1" {
            return Some(Prim::Bool);
        }
        Prim::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The spelling.
    pub fn name(self) -> &'static str {
        match self {
            Prim::Bool => "bool",
            Prim::I8 => "i8",
            Prim::I16 => "i16",
            Prim::I32 => "i32",
            Prim::I64 => "i64",
            Prim::U8 => "u8",
            Prim::U16 => "u16",
            Prim::U32 => "u32",
            Prim::U64 => "u64",
            Prim::F16 => "f16",
            Prim::F32 => "f32",
            Prim::F64 => "f64",
        }
    }

    /// Size in bits (`bool` counts as 1).
    pub fn bits(self) -> u32 {
        match self {
            Prim::Bool => 1,
            Prim::I8 | Prim::U8 => 8,
            Prim::I16 | Prim::U16 | Prim::F16 => 16,
            Prim::I32 | Prim::U32 | Prim::F32 => 32,
            Prim::I64 | Prim::U64 | Prim::F64 => 64,
        }
    }

    /// Signed or unsigned integer.
    pub fn is_int(self) -> bool {
        self.is_signed_int() || self.is_unsigned_int()
    }

    /// `i8` .. `i64`.
    pub fn is_signed_int(self) -> bool {
        matches!(self, Prim::I8 | Prim::I16 | Prim::I32 | Prim::I64)
    }

    /// `u8` .. `u64`.
    pub fn is_unsigned_int(self) -> bool {
        matches!(self, Prim::U8 | Prim::U16 | Prim::U32 | Prim::U64)
    }

    /// `f16`, `f32`, `f64`.
    pub fn is_float(self) -> bool {
        matches!(self, Prim::F16 | Prim::F32 | Prim::F64)
    }

    /// Integer or float.
    pub fn is_numeric(self) -> bool {
        self.is_int() || self.is_float()
    }

    /// The largest integer literal this integer type holds (signed types also accept the
    /// magnitude of their minimum, `2^(n-1)`, so that `-128` fits `i8`).
    pub fn int_literal_max(self) -> Option<u128> {
        if self.is_unsigned_int() {
            Some((1u128 << self.bits()) - 1)
        } else if self.is_signed_int() {
            Some(1u128 << (self.bits() - 1))
        } else {
            None
        }
    }
}

/// Identifies a declared `type` in the [`AdtTable`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct AdtId(pub u32);

/// An inference variable (exists only during checking).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TyVar(pub u32);

/// A semantic type.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Ty {
    /// A scalar.
    Prim(Prim),
    /// A vector `f32x3`: element and lane count.
    Vector(Prim, u32),
    /// `(T1, ..., Tn)`; `()` (no components) is the unit type.
    Tuple(Vec<Ty>),
    /// `T[n]`, a statically sized array.
    Array(Box<Ty>, u64),
    /// A slice: a dependent-length array `T[x]` (its length is a field or global) or the result
    /// of slicing an array.
    Slice(Box<Ty>),
    /// `set[T]`
    Set(Box<Ty>),
    /// `option[T]`
    Option(Box<Ty>),
    /// A declared record or sum type.
    Adt(AdtId),
    /// A raw address (`ptr`).
    Ptr,
    /// An inference variable (never in a finished [`super::TypedProgram`]).
    Var(TyVar),
    /// The type of an expression that already had an error; compatible with everything so one
    /// mistake is reported once.
    Error,
}

impl Ty {
    /// The unit type `()`.
    pub fn unit() -> Ty {
        Ty::Tuple(Vec::new())
    }

    /// `bool`.
    pub fn bool() -> Ty {
        Ty::Prim(Prim::Bool)
    }

    /// True for `()`.
    pub fn is_unit(&self) -> bool {
        matches!(self, Ty::Tuple(v) if v.is_empty())
    }

    /// The primitive when this is a scalar integer type.
    pub fn as_int(&self) -> Option<Prim> {
        match self {
            Ty::Prim(p) if p.is_int() => Some(*p),
            _ => None,
        }
    }

    /// True when the type mentions an inference variable.
    pub fn has_vars(&self) -> bool {
        match self {
            Ty::Var(_) => true,
            Ty::Tuple(ts) => ts.iter().any(Ty::has_vars),
            Ty::Array(t, _) | Ty::Slice(t) | Ty::Set(t) | Ty::Option(t) => t.has_vars(),
            _ => false,
        }
    }

    /// True when the type mentions [`Ty::Error`].
    pub fn has_error(&self) -> bool {
        match self {
            Ty::Error => true,
            Ty::Tuple(ts) => ts.iter().any(Ty::has_error),
            Ty::Array(t, _) | Ty::Slice(t) | Ty::Set(t) | Ty::Option(t) => t.has_error(),
            _ => false,
        }
    }

    /// Size in bits of a scalar, vector or pointer (for `to`); `None` for aggregates.
    pub fn bit_size(&self) -> Option<u64> {
        match self {
            Ty::Prim(p) => Some(p.bits() as u64),
            Ty::Vector(p, n) => Some(p.bits() as u64 * *n as u64),
            Ty::Ptr => Some(64),
            _ => None,
        }
    }

    /// Renders the type with ADT names taken from `adts`.
    pub fn display<'a>(&'a self, adts: &'a AdtTable) -> TyDisplay<'a> {
        TyDisplay { ty: self, adts }
    }
}

/// [`Ty`] printed in source syntax.
pub struct TyDisplay<'a> {
    ty: &'a Ty,
    adts: &'a AdtTable,
}

impl fmt::Display for TyDisplay<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let adts = self.adts;
        match self.ty {
            Ty::Prim(p) => write!(f, "{}", p.name()),
            Ty::Vector(p, n) => write!(f, "{}x{}", p.name(), n),
            Ty::Tuple(ts) => {
                write!(f, "(")?;
                for (i, t) in ts.iter().enumerate() {
                    if i > 0 {
                        write!(f, ", ")?;
                    }
                    write!(f, "{}", t.display(adts))?;
                }
                write!(f, ")")
            }
            Ty::Array(t, n) => write!(f, "{}[{}]", t.display(adts), n),
            Ty::Slice(t) => write!(f, "{}[..]", t.display(adts)),
            Ty::Set(t) => write!(f, "set[{}]", t.display(adts)),
            Ty::Option(t) => write!(f, "option[{}]", t.display(adts)),
            Ty::Adt(id) => match adts.get(*id) {
                Some(a) => write!(f, "{}", a.name),
                None => write!(f, "<type {}>", id.0),
            },
            Ty::Ptr => write!(f, "ptr"),
            Ty::Var(_) => write!(f, "_"),
            Ty::Error => write!(f, "{{error}}"),
        }
    }
}

/// A field of a record, the shared prefix of a sum, or a variant.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldDef {
    /// Field name.
    pub name: String,
    /// Field type (dependent-length arrays are [`Ty::Slice`]).
    pub ty: Ty,
    /// For a dependent-length array `T[x]`: the name `x` of the field giving its length.
    pub len_field: Option<String>,
    /// Whether the declaration gives a default value (the expression is in the AST, typed in the
    /// side tables).
    pub has_default: bool,
}

/// One variant of a sum type.
#[derive(Clone, Debug, PartialEq)]
pub struct VariantDef {
    /// Variant name.
    pub name: String,
    /// The variant's own fields (after the shared ones).
    pub fields: Vec<FieldDef>,
}

/// Record or sum.
#[derive(Clone, Debug, PartialEq)]
pub enum AdtKind {
    /// `type R(fields);`
    Record,
    /// `type S(shared) = A(...) | B(...);`
    Sum(Vec<VariantDef>),
}

/// A declared `type`.
#[derive(Clone, Debug, PartialEq)]
pub struct AdtDef {
    /// Type name.
    pub name: String,
    /// Index of the declaring item in `Program::items`.
    pub item: usize,
    /// Record fields, or the fields shared by every variant of a sum.
    pub fields: Vec<FieldDef>,
    /// Record or sum.
    pub kind: AdtKind,
}

impl AdtDef {
    /// The variants of a sum (empty for a record).
    pub fn variants(&self) -> &[VariantDef] {
        match &self.kind {
            AdtKind::Record => &[],
            AdtKind::Sum(vs) => vs,
        }
    }

    /// True for a sum type.
    pub fn is_sum(&self) -> bool {
        matches!(self.kind, AdtKind::Sum(_))
    }

    /// All logical fields of variant `v`: the shared ones first, then the variant's own.
    pub fn variant_fields(&self, v: usize) -> Vec<&FieldDef> {
        let own = self
            .variants()
            .get(v)
            .map(|v| v.fields.as_slice())
            .unwrap_or(&[]);
        self.fields.iter().chain(own.iter()).collect()
    }

    /// Index of the variant named `name`.
    pub fn variant_index(&self, name: &str) -> Option<usize> {
        self.variants().iter().position(|v| v.name == name)
    }
}

/// All declared types, indexed by [`AdtId`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AdtTable {
    /// In declaration order.
    pub adts: Vec<AdtDef>,
}

impl AdtTable {
    /// The type with id `id`.
    pub fn get(&self, id: AdtId) -> Option<&AdtDef> {
        self.adts.get(id.0 as usize)
    }

    /// The type named `name`.
    pub fn by_name(&self, name: &str) -> Option<AdtId> {
        self.adts
            .iter()
            .position(|a| a.name == name)
            .map(|i| AdtId(i as u32))
    }

    /// Every `(type, variant index)` whose variant is named `name`.
    pub fn variants_named(&self, name: &str) -> Vec<(AdtId, usize)> {
        let mut out = Vec::new();
        for (i, a) in self.adts.iter().enumerate() {
            if let Some(v) = a.variant_index(name) {
                out.push((AdtId(i as u32), v));
            }
        }
        out
    }

    /// True when values of `ty` (transitively) contain the type `adt`.
    pub fn mentions(&self, ty: &Ty, adt: AdtId) -> bool {
        match ty {
            Ty::Adt(a) => *a == adt,
            Ty::Tuple(ts) => ts.iter().any(|t| self.mentions(t, adt)),
            Ty::Array(t, _) | Ty::Slice(t) | Ty::Set(t) | Ty::Option(t) => self.mentions(t, adt),
            _ => false,
        }
    }
}

/// Parses a vector type name such as `f32x3` into its element and lane count.
pub fn vector_from_name(name: &str) -> Option<(Prim, u32)> {
    let x = name.rfind('x')?;
    let (elem, lanes) = (&name[..x], &name[x + 1..]);
    let prim = Prim::from_name(elem)?;
    if prim == Prim::Bool || lanes.is_empty() || !lanes.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let n: u32 = lanes.parse().ok()?;
    (1..=64).contains(&n).then_some((prim, n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prim_names_round_trip() {
        for p in Prim::ALL {
            assert_eq!(Prim::from_name(p.name()), Some(p));
        }
        assert_eq!(Prim::from_name("i1"), Some(Prim::Bool));
        assert_eq!(Prim::from_name("f128"), None);
    }

    #[test]
    fn vector_names() {
        assert_eq!(vector_from_name("f32x3"), Some((Prim::F32, 3)));
        assert_eq!(vector_from_name("u8x8"), Some((Prim::U8, 8)));
        assert_eq!(vector_from_name("boolx2"), None);
        assert_eq!(vector_from_name("f32x"), None);
        assert_eq!(vector_from_name("f32x0"), None);
        assert_eq!(vector_from_name("Ray"), None);
    }

    #[test]
    fn literal_ranges() {
        assert_eq!(Prim::U8.int_literal_max(), Some(255));
        assert_eq!(Prim::I8.int_literal_max(), Some(128));
        assert_eq!(Prim::F32.int_literal_max(), None);
        assert_eq!(Ty::Vector(Prim::F32, 3).bit_size(), Some(96));
    }
}
