//! Sizes and alignments of physical types (docs/design/layout-catalog.md §2.3, rule 1).
//!
//! Input: a written [`TypeExpr`] and the program's `type` declarations; output: its byte size
//! and natural alignment. Primitives have their own size as alignment (`u8` 1, `u16` 2,
//! `u32`/`f32` 4, `u64`/`ptr` 8); a vector or a statically sized array has its element's
//! alignment; a record lays its fields out in order, each at its natural alignment, and is as
//! aligned as its most aligned field, its size rounded up to that alignment (so `AABB` is 24
//! bytes and `Triangle` 40). The ADT a layout realizes is stored as the layout's reference.

use crate::syntax::ast::{ArrayLen, Program, TypeDecl, TypeExpr, TypeExprKind};
use rustc_hash::FxHashMap;

/// Byte size and alignment of a type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shape {
    /// Size in bytes.
    pub size: u64,
    /// Natural alignment in bytes (a power of two).
    pub align: u64,
}

/// Why a type has no static size.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ShapeError {
    /// An array whose length is a name (`Triangle[P]`): only a global may have it.
    Dynamic(String),
    /// A name that is neither a primitive nor a declared record type.
    Unknown(String),
    /// `set[T]`, `option[T]`, a sum type or a recursive record: no physical representation.
    NotStorable(String),
}

impl ShapeError {
    /// A one-line explanation.
    pub fn message(&self) -> String {
        match self {
            ShapeError::Dynamic(n) => {
                format!("an array sized by `{n}` has no static size; only a global array may be sized by a name")
            }
            ShapeError::Unknown(n) => format!("unknown type `{n}`"),
            ShapeError::NotStorable(why) => format!("type cannot be stored: {why}"),
        }
    }
}

/// Size and alignment of a primitive type name, if it is one.
pub fn primitive(name: &str) -> Option<Shape> {
    let size = match name {
        "bool" | "u8" | "i8" => 1,
        "u16" | "i16" | "f16" => 2,
        "u32" | "i32" | "f32" => 4,
        "u64" | "i64" | "f64" | "ptr" => 8,
        _ => return None,
    };
    Some(Shape { size, align: size })
}

/// The value range of an integer type name (`bool` counts as `0..=1`), for split coverage.
pub fn integer_domain(name: &str) -> Option<(i128, i128)> {
    let bits: u32 = match name {
        "bool" => return Some((0, 1)),
        "u8" | "i8" => 8,
        "u16" | "i16" => 16,
        "u32" | "i32" => 32,
        "u64" | "i64" => 64,
        _ => return None,
    };
    if name.starts_with('u') {
        Some((0, (1i128 << bits) - 1))
    } else {
        Some((-(1i128 << (bits - 1)), (1i128 << (bits - 1)) - 1))
    }
}

/// Rounds `x` up to a multiple of `align` (`align` ≥ 1).
pub fn round_up(x: u64, align: u64) -> u64 {
    let a = align.max(1);
    x.div_ceil(a).saturating_mul(a)
}

/// The record types of a program, for sizing stored fields.
#[derive(Clone, Debug, Default)]
pub struct TypeEnv<'p> {
    records: FxHashMap<&'p str, &'p TypeDecl>,
    sums: FxHashMap<&'p str, &'p TypeDecl>,
    /// The realized ADT's name and the shape of the layout's reference, so that a stored field
    /// of the ADT type (a child reference) has the reference's size.
    pub reference: Option<(String, Shape)>,
}

impl<'p> TypeEnv<'p> {
    /// Collects the `type` declarations of `program`.
    pub fn new(program: &'p Program) -> TypeEnv<'p> {
        let mut env = TypeEnv::default();
        for item in &program.items {
            if let crate::syntax::ast::Item::Type(t) = item {
                if t.variants.is_some() {
                    env.sums.entry(t.name.name.as_str()).or_insert(t);
                } else {
                    env.records.entry(t.name.name.as_str()).or_insert(t);
                }
            }
        }
        env
    }

    /// Size and alignment of `ty`.
    pub fn shape(&self, ty: &TypeExpr) -> Result<Shape, ShapeError> {
        self.shape_at(ty, 0)
    }

    fn shape_at(&self, ty: &TypeExpr, depth: u32) -> Result<Shape, ShapeError> {
        if depth > 64 {
            return Err(ShapeError::NotStorable("the type contains itself".into()));
        }
        match &ty.kind {
            TypeExprKind::Named(id) => self.named(&id.name, depth),
            TypeExprKind::Vector { elem, lanes } => {
                let e =
                    primitive(&elem.name).ok_or_else(|| ShapeError::Unknown(elem.name.clone()))?;
                Ok(Shape {
                    size: e.size.saturating_mul(u64::from(*lanes)),
                    align: e.align,
                })
            }
            TypeExprKind::Array { elem, len } => match len {
                ArrayLen::Const(n, _) => {
                    let e = self.shape_at(elem, depth + 1)?;
                    Ok(Shape {
                        size: round_up(e.size, e.align).saturating_mul(*n),
                        align: e.align,
                    })
                }
                ArrayLen::Name(n) => Err(ShapeError::Dynamic(n.name.clone())),
            },
            TypeExprKind::Tuple(parts) => {
                let mut shapes = Vec::new();
                for p in parts {
                    shapes.push(self.shape_at(p, depth + 1)?);
                }
                Ok(record_shape(&shapes))
            }
            TypeExprKind::Set(_) => Err(ShapeError::NotStorable("`set` has no fixed size".into())),
            TypeExprKind::Option(_) => {
                Err(ShapeError::NotStorable("`option` has no fixed size".into()))
            }
        }
    }

    fn named(&self, name: &str, depth: u32) -> Result<Shape, ShapeError> {
        if let Some(p) = primitive(name) {
            return Ok(p);
        }
        if let Some((adt, shape)) = &self.reference {
            if adt == name {
                return Ok(*shape);
            }
        }
        if let Some(decl) = self.records.get(name) {
            let mut shapes = Vec::new();
            for f in &decl.fields {
                shapes.push(self.shape_at(&f.ty, depth + 1)?);
            }
            return Ok(record_shape(&shapes));
        }
        if self.sums.contains_key(name) {
            return Err(ShapeError::NotStorable(format!(
                "`{name}` is a sum type; store a reference or an encoding of it instead"
            )));
        }
        Err(ShapeError::Unknown(name.to_string()))
    }

    /// The sum type declarations, by name.
    pub fn sum(&self, name: &str) -> Option<&'p TypeDecl> {
        self.sums.get(name).copied()
    }

    /// Every sum type declaration (unordered).
    pub fn sums(&self) -> impl Iterator<Item = &'p TypeDecl> + '_ {
        self.sums.values().copied()
    }
}

/// The shape of fields laid out in order, each at its natural alignment, the whole rounded up to
/// the largest alignment.
pub fn record_shape(fields: &[Shape]) -> Shape {
    let mut off = 0u64;
    let mut align = 1u64;
    for f in fields {
        off = round_up(off, f.align).saturating_add(f.size);
        align = align.max(f.align);
    }
    Shape {
        size: round_up(off, align),
        align,
    }
}

/// Structural equality of written types, ignoring spans.
pub fn same_type(a: &TypeExpr, b: &TypeExpr) -> bool {
    match (&a.kind, &b.kind) {
        (TypeExprKind::Named(x), TypeExprKind::Named(y)) => x.name == y.name,
        (
            TypeExprKind::Vector {
                elem: e1,
                lanes: l1,
            },
            TypeExprKind::Vector {
                elem: e2,
                lanes: l2,
            },
        ) => e1.name == e2.name && l1 == l2,
        (TypeExprKind::Array { elem: e1, len: n1 }, TypeExprKind::Array { elem: e2, len: n2 }) => {
            same_type(e1, e2)
                && match (n1, n2) {
                    (ArrayLen::Const(x, _), ArrayLen::Const(y, _)) => x == y,
                    (ArrayLen::Name(x), ArrayLen::Name(y)) => x.name == y.name,
                    _ => false,
                }
        }
        (TypeExprKind::Tuple(x), TypeExprKind::Tuple(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(a, b)| same_type(a, b))
        }
        (TypeExprKind::Set(x), TypeExprKind::Set(y))
        | (TypeExprKind::Option(x), TypeExprKind::Option(y)) => same_type(x, y),
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shape_of(src: &str, ty: &str) -> Shape {
        let prog = crate::layout::fixtures::program(&[&format!("{src}\ntype Probe(x: {ty});")]);
        let env = TypeEnv::new(&prog);
        let probe = prog
            .items
            .iter()
            .find_map(|i| match i {
                crate::syntax::ast::Item::Type(t) if t.name.name == "Probe" => Some(t),
                _ => None,
            })
            .expect("probe");
        env.shape(&probe.fields[0].ty).expect("sized")
    }

    #[test]
    fn prelude_records_have_catalog_sizes() {
        let prelude = include_str!("../../../library/prelude.scion");
        assert_eq!(shape_of(prelude, "AABB"), Shape { size: 24, align: 4 });
        assert_eq!(shape_of(prelude, "Triangle"), Shape { size: 40, align: 4 });
        assert_eq!(shape_of(prelude, "u8[8]"), Shape { size: 8, align: 1 });
        assert_eq!(shape_of(prelude, "u16x3"), Shape { size: 6, align: 2 });
        assert_eq!(
            shape_of("type Mix(a: u8, b: u64, c: u16);", "Mix"),
            Shape { size: 24, align: 8 }
        );
    }

    #[test]
    fn domains_and_rounding() {
        assert_eq!(integer_domain("u16"), Some((0, 65535)));
        assert_eq!(integer_domain("i8"), Some((-128, 127)));
        assert_eq!(integer_domain("f32"), None);
        assert_eq!(round_up(30, 32), 32);
        assert_eq!(round_up(136, 16), 144);
    }
}
