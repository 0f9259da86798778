//! The memory layout of plain data: byte size, alignment and the offset of every scalar leaf of
//! a type, in one place. `mem-to-lo` lays out `mut` cells and records read from buffers with it,
//! the interpreter's `mem.load`/`mem.store` decode bytes with it, and the C ABI's record structs
//! (`scionc --emit=header`) follow it.
//!
//! Rules (the layout model's for plain data; layout catalog §2.3 rule 1): members in order, each
//! at its natural alignment; a scalar's alignment is its size (`i1` one byte, `f16` two, a `ptr`
//! and a `!tree.ref<T>` eight); a vector's and a fixed array's are their element's (so
//! `vector<3xf32>` is 12 bytes, align 4, and an array's stride is its element's size rounded up to
//! its alignment); a tuple's or record's is its largest member's, and its size is rounded up to
//! it. A `!mem.view<T>` is three 8-byte leaves (first element, length, stride). `AABB` is 24
//! bytes, `Triangle(p0, p1, p2, id)` 40. Sum types, slices, sets and options have no plain-data
//! layout.

use crate::entity::TypeId;
use crate::module::Module;
use crate::types::Type;

/// Size and alignment in bytes of a scalar leaf type (`None` for aggregates).
pub fn scalar_size(m: &Module, ty: TypeId) -> Option<u64> {
    scalar_type_size(m.types.get(ty))
}

/// [`scalar_size`] of a type itself.
pub fn scalar_type_size(ty: &Type) -> Option<u64> {
    Some(match ty {
        Type::Bool => 1,
        Type::Int(t) => u64::from(t.bits() / 8),
        Type::Float(f) => u64::from(f.bits() / 8),
        Type::Ptr | Type::Ref(_) => 8,
        _ => return None,
    })
}

/// Size, alignment, and the byte offset of each scalar leaf of `ty` in leaf order (lanes,
/// elements and fields in order, depth first).
pub fn layout(m: &Module, ty: TypeId) -> Result<(u64, u64, Vec<u64>), String> {
    let mut offs = Vec::new();
    let (size, align) = place(m, ty, 0, Some(&mut offs))?;
    Ok((size, align, offs))
}

/// Size and alignment of `ty`, when it is plain data.
pub fn size_align(m: &Module, ty: TypeId) -> Option<(u64, u64)> {
    place(m, ty, 0, None).ok()
}

fn place(
    m: &Module,
    ty: TypeId,
    base: u64,
    mut offs: Option<&mut Vec<u64>>,
) -> Result<(u64, u64), String> {
    if let Some(s) = scalar_size(m, ty) {
        if let Some(o) = offs {
            o.push(base);
        }
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
        Type::View(_) | Type::Set(_) => {
            if let Some(o) = offs {
                o.extend([base, base + 8, base + 16]);
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
        let mark = offs.as_ref().map_or(0, |o| o.len());
        let (s, a) = place(m, t, 0, offs.as_deref_mut())?;
        size = size.div_ceil(a) * a;
        if let Some(o) = offs.as_deref_mut() {
            for x in &mut o[mark..] {
                *x += base + size;
            }
        }
        size += s;
        align = align.max(a);
    }
    Ok((size.div_ceil(align) * align, align))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::module::{AdtDef, Field};
    use crate::types::{FloatTy, IntTy};

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
        assert_eq!(size_align(&m, tri), Some((40, 4)));
        let u8t = m.types.int(IntTy::U8);
        let f64t = m.types.float(FloatTy::F64);
        let t = m.types.tuple(vec![u8t, f64t, u8t]);
        assert_eq!(layout(&m, t).unwrap(), (24, 8, vec![0, 8, 16]));
        // An array's stride is its element's size rounded up to its alignment.
        let arr = m.types.array(t, Some(3));
        assert_eq!(size_align(&m, arr), Some((72, 8)));
        let f16t = m.types.float(FloatTy::F16);
        let h = m.types.tuple(vec![f16t, u8t]);
        assert_eq!(layout(&m, h).unwrap(), (4, 2, vec![0, 2]));
    }

    #[test]
    fn sums_have_no_plain_data_layout() {
        let mut m = Module::new();
        let u32t = m.types.u32();
        let t = m
            .declare_adt(AdtDef {
                name: "T".into(),
                shared: vec![],
                variants: vec![crate::module::Variant {
                    name: "A".into(),
                    fields: vec![Field {
                        name: "x".into(),
                        ty: u32t,
                    }],
                }],
            })
            .unwrap();
        assert!(layout(&m, t).is_err());
        assert_eq!(size_align(&m, t), None);
    }
}
