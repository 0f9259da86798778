//! The C records of an entry point: the query record (the algorithm's non-tree, non-`mut`
//! parameters) and the result record (its `mut` parameters), each a flat list of named scalar
//! fields with byte offsets.
//!
//! Input: the `tree`-level types of the parameters. Output: [`Record`]s. Each parameter is laid
//! out as `mem-to-lo` lays out a value in memory ([`flat::layout`]: members in order, each at its
//! natural alignment), and the parameters follow each other in order, each at its own alignment;
//! for scalars, vectors and records of scalars (a `Ray`, a `(f32, u32)`) this is every scalar at
//! its natural alignment. A `mut` parameter's part of the result record is exactly the cell the
//! algorithm reads and writes through its pointer.

use crate::passes::mem_to_lo as flat;
use scion_ir::entity::TypeId;
use scion_ir::types::{FloatTy, IntTy, Type};
use scion_ir::Module;

/// One scalar field of a record.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    /// A C identifier: the parameter's name and the path to the scalar (`ray_origin_x`).
    pub name: String,
    /// The scalar `lo` type.
    pub ty: Type,
    /// Byte offset in the record.
    pub offset: u64,
}

/// A C struct of scalars.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Record {
    /// The fields, in order of offset.
    pub fields: Vec<Field>,
    /// Size in bytes (a multiple of `align`; 0 for no field).
    pub size: u64,
    /// Alignment in bytes (1 for no field).
    pub align: u64,
}

impl Record {
    /// An empty record.
    pub fn new() -> Record {
        Record {
            fields: Vec::new(),
            size: 0,
            align: 1,
        }
    }

    /// Appends the value of type `ty` named `name` at its alignment; returns its byte offset
    /// and the range of its fields.
    pub fn push(
        &mut self,
        m: &Module,
        name: &str,
        ty: TypeId,
    ) -> Result<(u64, std::ops::Range<usize>), String> {
        let mut named = Vec::new();
        push_named(m, ty, name.to_string(), &mut named)?;
        let (size, align, offs) = flat::layout(m, ty)?;
        if offs.len() != named.len() {
            return Err(format!(
                "the layout of {} has {} scalars, expected {}",
                m.types.display(ty),
                offs.len(),
                named.len()
            ));
        }
        let base = self.size.div_ceil(align) * align;
        let first = self.fields.len();
        for ((name, ty), off) in named.into_iter().zip(offs) {
            self.fields.push(Field {
                name,
                ty,
                offset: base + off,
            });
        }
        self.align = self.align.max(align);
        self.size = (base + size).div_ceil(self.align) * self.align;
        Ok((base, first..self.fields.len()))
    }
}

/// The scalar leaves of `ty` with C names, in the order of `flat::leaves`.
fn push_named(
    m: &Module,
    ty: TypeId,
    name: String,
    out: &mut Vec<(String, Type)>,
) -> Result<(), String> {
    match m.types.get(ty) {
        t @ (Type::Bool | Type::Int(_) | Type::Float(FloatTy::F32 | FloatTy::F64) | Type::Ptr) => {
            out.push((name, t.clone()))
        }
        Type::Vector { elem, lanes } => {
            for k in 0..*lanes {
                let lane = match (lanes, k) {
                    (2..=4, 0) => "x".to_string(),
                    (2..=4, 1) => "y".to_string(),
                    (3..=4, 2) => "z".to_string(),
                    (4, 3) => "w".to_string(),
                    _ => k.to_string(),
                };
                push_named(m, *elem, format!("{name}_{lane}"), out)?;
            }
        }
        Type::Tuple(elems) => {
            for (k, &e) in elems.iter().enumerate() {
                push_named(m, e, format!("{name}_{k}"), out)?;
            }
        }
        Type::Array { elem, len: Some(n) } => {
            for k in 0..*n {
                push_named(m, *elem, format!("{name}_{k}"), out)?;
            }
        }
        Type::Set(_) => {
            // A sink (docs/c-abi.md): the caller's array, its capacity, the insertions made.
            let u64t = Type::Int(IntTy::U64);
            out.push((format!("{name}_data"), Type::Ptr));
            out.push((format!("{name}_capacity"), u64t.clone()));
            out.push((format!("{name}_count"), u64t));
        }
        Type::Adt(adt) => {
            let def = m.adt(adt).ok_or_else(|| format!("unknown type `{adt}`"))?;
            if !def.is_record() {
                return Err(format!("`{adt}` is a sum type"));
            }
            for f in &def.shared {
                push_named(m, f.ty, format!("{name}_{}", f.name), out)?;
            }
        }
        _ => {
            return Err(format!(
                "values of type {} have no C representation",
                m.types.display(ty)
            ))
        }
    }
    Ok(())
}

/// The C type of a scalar `lo` type (`i1` is one byte, 0 or 1).
pub fn c_type(ty: &Type) -> &'static str {
    match ty {
        Type::Bool => "uint8_t",
        Type::Int(t) => match t {
            IntTy::I8 => "int8_t",
            IntTy::I16 => "int16_t",
            IntTy::I32 => "int32_t",
            IntTy::I64 => "int64_t",
            IntTy::U8 => "uint8_t",
            IntTy::U16 => "uint16_t",
            IntTy::U32 => "uint32_t",
            IntTy::U64 => "uint64_t",
        },
        Type::Float(FloatTy::F32) => "float",
        Type::Float(_) => "double",
        _ => "void *",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameters_follow_each_other_at_their_alignment() {
        let mut m = Module::new();
        let b = m.types.bool();
        let f64t = m.types.float(FloatTy::F64);
        let f32t = m.types.f32();
        let v3 = m.types.vector(f32t, 3);
        let u8t = m.types.int(IntTy::U8);
        let pair = m.types.tuple(vec![u8t, f64t]);
        let mut r = Record::new();
        assert_eq!(r.push(&m, "flag", b).unwrap(), (0, 0..1));
        assert_eq!(r.push(&m, "w", f64t).unwrap(), (8, 1..2));
        assert_eq!(r.push(&m, "v", v3).unwrap(), (16, 2..5));
        // A tuple is laid out as a whole (16 bytes, align 8), after the vector's 12 bytes.
        assert_eq!(r.push(&m, "p", pair).unwrap(), (32, 5..7));
        let names: Vec<(&str, u64)> = r
            .fields
            .iter()
            .map(|f| (f.name.as_str(), f.offset))
            .collect();
        assert_eq!(
            names,
            [
                ("flag", 0),
                ("w", 8),
                ("v_x", 16),
                ("v_y", 20),
                ("v_z", 24),
                ("p_0", 32),
                ("p_1", 40)
            ]
        );
        assert_eq!((r.size, r.align), (48, 8));
        assert_eq!(c_type(&r.fields[0].ty), "uint8_t");
        assert_eq!(c_type(&r.fields[1].ty), "double");
        assert_eq!(c_type(&r.fields[2].ty), "float");
    }

    #[test]
    fn a_set_is_a_sink_of_data_capacity_and_count() {
        let mut m = Module::new();
        let u32t = m.types.u32();
        let pair = m.types.tuple(vec![u32t, u32t]);
        let set = m.types.intern(Type::Set(pair));
        let mut r = Record::new();
        assert_eq!(r.push(&m, "pairs", set).unwrap(), (0, 0..3));
        let names: Vec<(&str, u64)> = r
            .fields
            .iter()
            .map(|f| (f.name.as_str(), f.offset))
            .collect();
        assert_eq!(
            names,
            [
                ("pairs_data", 0),
                ("pairs_capacity", 8),
                ("pairs_count", 16)
            ]
        );
        assert_eq!((r.size, r.align), (24, 8));
    }

    #[test]
    fn values_without_a_c_form_are_refused() {
        let mut m = Module::new();
        let f32t = m.types.f32();
        let opt = m.types.intern(Type::Option(f32t));
        let mut r = Record::new();
        assert!(r.push(&m, "s", opt).is_err());
        assert!(r.fields.is_empty());
    }
}
