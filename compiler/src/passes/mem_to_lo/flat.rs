//! Scalarization of types for `mem-to-lo`: every `tree` value becomes a list of scalar *leaves*
//! (`i1`, integers, `f32`/`f64`, `ptr`), and every type that lives in memory (a `mut` cell, a
//! record loaded from a buffer) gets a byte layout.
//!
//! Leaves, in order: a scalar is itself; `vector<NxT>` is its N lanes; a tuple, or a record
//! (an ADT without variants), is its elements or fields in order; `array<N x T>` (fixed) is N
//! copies of `T`'s leaves; `!tree.ref<T>` is one `ptr` to a cell holding a `T`. The unit tuple
//! has no leaves. Sum ADTs, slices, sets and options have no scalar form here.
//!
//! Memory layout (the layout model's rule for plain data): members in order, each at its
//! natural alignment; a scalar's alignment is its size (`i1` one byte), a vector's is its
//! element's (so `vector<3xf32>` is 12 bytes, align 4), an aggregate's is its largest member's
//! and its size is rounded up to it. `AABB` is 24 bytes and `Triangle(p0, p1, p2, id)` 40.

use scion_ir::entity::TypeId;
use scion_ir::types::{FloatTy, Type};
use scion_ir::Module;

/// The scalar leaf types of `ty` (a type of the source module `m`).
pub fn leaves(m: &Module, ty: TypeId) -> Result<Vec<Type>, String> {
    let mut out = Vec::new();
    push_leaves(m, ty, &mut out)?;
    Ok(out)
}

fn push_leaves(m: &Module, ty: TypeId, out: &mut Vec<Type>) -> Result<(), String> {
    match m.types.get(ty) {
        Type::Bool | Type::Int(_) | Type::Float(FloatTy::F32 | FloatTy::F64) | Type::Ptr => {
            out.push(m.types.get(ty).clone())
        }
        Type::Vector { elem, lanes } => {
            for _ in 0..*lanes {
                push_leaves(m, *elem, out)?;
            }
        }
        Type::Tuple(elems) => {
            for &e in elems {
                push_leaves(m, e, out)?;
            }
        }
        Type::Array { elem, len: Some(n) } => {
            for _ in 0..*n {
                push_leaves(m, *elem, out)?;
            }
        }
        Type::Ref(_) => out.push(Type::Ptr),
        Type::View(_) => {
            let u64t = Type::Int(scion_ir::types::IntTy::U64);
            out.extend([Type::Ptr, u64t.clone(), u64t]);
        }
        Type::Adt(name) => {
            let def = m
                .adt(name)
                .ok_or_else(|| format!("unknown type `{name}`"))?;
            if !def.is_record() {
                return Err(format!(
                    "`{name}` is a sum type; it needs a layout (destructor specialization) first"
                ));
            }
            for f in &def.shared {
                push_leaves(m, f.ty, out)?;
            }
        }
        _ => {
            return Err(format!(
                "values of type {} have no scalar form",
                m.types.display(ty)
            ))
        }
    }
    Ok(())
}

/// Size and alignment in bytes of a scalar leaf type.
pub fn scalar_size(m: &Module, ty: TypeId) -> Option<u64> {
    Some(match m.types.get(ty) {
        Type::Bool => 1,
        Type::Int(t) => u64::from(t.bits() / 8),
        Type::Float(FloatTy::F32) => 4,
        Type::Float(FloatTy::F64) | Type::Ptr | Type::Ref(_) => 8,
        _ => return None,
    })
}

/// The memory layout of `ty`: size, alignment, and the byte offset of each leaf (in the order
/// of [`leaves`]).
pub fn layout(m: &Module, ty: TypeId) -> Result<(u64, u64, Vec<u64>), String> {
    let mut offs = Vec::new();
    let (size, align) = place(m, ty, 0, &mut offs)?;
    Ok((size, align, offs))
}

fn place(m: &Module, ty: TypeId, base: u64, offs: &mut Vec<u64>) -> Result<(u64, u64), String> {
    if let Some(s) = scalar_size(m, ty) {
        offs.push(base);
        return Ok((s, s));
    }
    let members: Vec<TypeId> = match m.types.get(ty) {
        Type::Vector { elem, lanes } => vec![*elem; *lanes as usize],
        Type::Tuple(elems) => elems.clone(),
        Type::Array { elem, len: Some(n) } => vec![*elem; *n as usize],
        Type::Adt(name) => match m.adt(name) {
            Some(def) if def.is_record() => def.shared.iter().map(|f| f.ty).collect(),
            _ => return Err(format!("`{name}` has no plain-data layout")),
        },
        Type::View(_) => {
            // Three 8-byte leaves: first element, length, stride.
            for k in 0..3 {
                offs.push(base + 8 * k);
            }
            return Ok((24, 8));
        }
        _ => {
            return Err(format!(
                "values of type {} have no memory layout",
                m.types.display(ty)
            ))
        }
    };
    let (mut size, mut align) = (0u64, 1u64);
    for t in members {
        let mark = offs.len();
        let (s, a) = place(m, t, 0, offs)?;
        size = size.div_ceil(a) * a;
        for o in &mut offs[mark..] {
            *o += base + size;
        }
        size += s;
        align = align.max(a);
    }
    Ok((size.div_ceil(align) * align, align))
}

#[cfg(test)]
mod tests {
    use super::*;
    use scion_ir::module::{AdtDef, Field};

    #[test]
    fn record_layouts_follow_natural_alignment() {
        let mut m = Module::new();
        let f32t = m.types.f32();
        let u32t = m.types.u32();
        let v3 = m.types.vector(f32t, 3);
        let f = |n: &str, ty| Field { name: n.into(), ty };
        let aabb = m
            .declare_adt(AdtDef {
                name: "AABB".into(),
                shared: vec![f("low", v3), f("high", v3)],
                variants: vec![],
            })
            .unwrap();
        let tri = m
            .declare_adt(AdtDef {
                name: "Triangle".into(),
                shared: vec![f("p0", v3), f("p1", v3), f("p2", v3), f("id", u32t)],
                variants: vec![],
            })
            .unwrap();
        assert_eq!(layout(&m, aabb).unwrap().0, 24);
        let (size, align, offs) = layout(&m, tri).unwrap();
        assert_eq!((size, align), (40, 4));
        assert_eq!(offs[9], 36);
        let u8t = m.types.int(scion_ir::types::IntTy::U8);
        let f64t = m.types.float(FloatTy::F64);
        let t = m.types.tuple(vec![u8t, f64t, u8t]);
        assert_eq!(layout(&m, t).unwrap(), (24, 8, vec![0, 8, 16]));
        assert_eq!(leaves(&m, tri).unwrap().len(), 10);
    }
}
