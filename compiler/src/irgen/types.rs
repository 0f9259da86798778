//! Semantic types ([`Ty`]) to IR types ([`Type`]) and the module's ADT table.

use crate::sema::{Prim, Ty, TypedProgram};
use rustc_hash::FxHashMap;
use scion_ir::diag::InternalError;
use scion_ir::entity::TypeId;
use scion_ir::module::{AdtDef, Field, Variant};
use scion_ir::types::{FloatTy, IntTy, Type};
use scion_ir::Module;

/// Memoized lowering of semantic types.
#[derive(Default)]
pub(super) struct TypeMap {
    cache: FxHashMap<Ty, TypeId>,
}

impl TypeMap {
    /// The IR type of `t`.
    pub(super) fn lower(
        &mut self,
        m: &mut Module,
        typed: &TypedProgram,
        t: &Ty,
    ) -> Result<TypeId, InternalError> {
        if let Some(&id) = self.cache.get(t) {
            return Ok(id);
        }
        let ir = match t {
            Ty::Prim(p) => prim(*p),
            Ty::Vector(p, n) => {
                let elem = m.ty(prim(*p));
                Type::Vector { elem, lanes: *n }
            }
            Ty::Tuple(ts) => {
                let mut elems = Vec::with_capacity(ts.len());
                for e in ts {
                    elems.push(self.lower(m, typed, e)?);
                }
                Type::Tuple(elems)
            }
            Ty::Array(e, n) => Type::Array {
                elem: self.lower(m, typed, e)?,
                len: Some(*n),
            },
            Ty::Slice(e) => Type::Array {
                elem: self.lower(m, typed, e)?,
                len: None,
            },
            Ty::Set(e) => Type::Set(self.lower(m, typed, e)?),
            Ty::Option(e) => Type::Option(self.lower(m, typed, e)?),
            Ty::Adt(id) => match typed.adts.get(*id) {
                Some(def) => Type::Adt(def.name.clone()),
                None => return Err(InternalError::new(format!("unknown ADT id {}", id.0))),
            },
            Ty::Ptr => Type::Ptr,
            Ty::Var(_) | Ty::Error => {
                return Err(InternalError::new(format!(
                    "type `{}` reached IR generation unresolved",
                    t.display(&typed.adts)
                )))
            }
        };
        let id = m.ty(ir);
        self.cache.insert(t.clone(), id);
        Ok(id)
    }

    /// The result list of a function returning `t`: empty for the unit type.
    pub(super) fn lower_results(
        &mut self,
        m: &mut Module,
        typed: &TypedProgram,
        t: &Ty,
    ) -> Result<Vec<TypeId>, InternalError> {
        if t.is_unit() {
            Ok(Vec::new())
        } else {
            Ok(vec![self.lower(m, typed, t)?])
        }
    }
}

/// The IR scalar of a primitive.
pub(super) fn prim(p: Prim) -> Type {
    match p {
        Prim::Bool => Type::Bool,
        Prim::I8 => Type::Int(IntTy::I8),
        Prim::I16 => Type::Int(IntTy::I16),
        Prim::I32 => Type::Int(IntTy::I32),
        Prim::I64 => Type::Int(IntTy::I64),
        Prim::U8 => Type::Int(IntTy::U8),
        Prim::U16 => Type::Int(IntTy::U16),
        Prim::U32 => Type::Int(IntTy::U32),
        Prim::U64 => Type::Int(IntTy::U64),
        Prim::F16 => Type::Float(FloatTy::F16),
        Prim::F32 => Type::Float(FloatTy::F32),
        Prim::F64 => Type::Float(FloatTy::F64),
    }
}

/// Declares every ADT of the program in the module, in declaration order.
pub(super) fn declare_adts(
    m: &mut Module,
    tys: &mut TypeMap,
    typed: &TypedProgram,
) -> Result<(), InternalError> {
    for def in &typed.adts.adts {
        let mut shared = Vec::new();
        for f in &def.fields {
            shared.push(Field {
                name: f.name.clone(),
                ty: tys.lower(m, typed, &f.ty)?,
            });
        }
        let mut variants = Vec::new();
        for v in def.variants() {
            let mut fields = Vec::new();
            for f in &v.fields {
                fields.push(Field {
                    name: f.name.clone(),
                    ty: tys.lower(m, typed, &f.ty)?,
                });
            }
            variants.push(Variant {
                name: v.name.clone(),
                fields,
            });
        }
        m.declare_adt(AdtDef {
            name: def.name.clone(),
            shared,
            variants,
        })
        .map_err(|_| InternalError::new(format!("type `{}` declared twice", def.name)))?;
    }
    Ok(())
}
