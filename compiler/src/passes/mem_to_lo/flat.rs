//! Scalarization of types for `mem-to-lo`: every `tree` value becomes a list of scalar *leaves*
//! (`i1`, integers, `f32`/`f64`, `ptr`), and every type that lives in memory (a `mut` cell, a
//! record loaded from a buffer) gets a byte layout.
//!
//! Leaves, in order: a scalar is itself; `vector<NxT>` is its N lanes; a tuple, or a record
//! (an ADT without variants), is its elements or fields in order; `array<N x T>` (fixed) is N
//! copies of `T`'s leaves; `!tree.ref<T>` is one `ptr` to a cell holding a `T`; a view, and a
//! set (a sink, `sets.rs`), is three: an address and two `u64`s. The unit tuple has no leaves.
//! Sum ADTs, slices and options have no scalar form here.
//!
//! Memory layout: [`scion_ir::data_layout`] (one model for `mem-to-lo`, the interpreter and the C
//! ABI), re-exported here as [`layout`].

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
        Type::View(_) | Type::Set(_) => {
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

pub use scion_ir::data_layout::layout;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aggregates_have_one_leaf_per_scalar_in_memory_order() {
        let mut m = Module::new();
        let f32t = m.types.f32();
        let u32t = m.types.u32();
        let v3 = m.types.vector(f32t, 3);
        let t = m.types.tuple(vec![v3, u32t, v3]);
        assert_eq!(leaves(&m, t).unwrap().len(), 7);
        assert_eq!(layout(&m, t).unwrap().2, vec![0, 4, 8, 12, 16, 20, 24]);
    }
}
