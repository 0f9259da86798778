//! Per-op rules of the `mem` dialect, the ones documented on [`super::Op`]'s variants.

use super::Op;
use crate::attr::Attr;
use crate::entity::{OpId, TypeId};
use crate::module::Module;
use crate::types::Type;
use crate::verify::OpContext;

type VResult = Result<(), String>;

/// Checks one `mem` op.
pub fn verify_op(m: &Module, id: OpId, kind: Op, _cx: &OpContext<'_>) -> VResult {
    let o = &m.ops[id];
    let ot: Vec<TypeId> = o.operands.iter().map(|&v| m.values[v].ty).collect();
    let rt: Vec<TypeId> = o.results.iter().map(|&v| m.values[v].ty).collect();
    let t = &m.types;
    let show = |ty: TypeId| t.display(ty).to_string();
    let name = format!("mem.{}", kind.mnemonic());
    if !o.regions.is_empty() || !o.successors.is_empty() {
        return Err(format!("`{name}` takes no regions or successors"));
    }
    let is_ptr = |ty: TypeId| matches!(t.get(ty), Type::Ptr);
    let is_int = |ty: TypeId| t.as_int(ty).is_some();
    let nonneg = |key: &str| -> Result<Option<i128>, String> {
        match o.attr(key) {
            None => Ok(None),
            Some(Attr::Int(v)) if *v >= 0 => Ok(Some(*v)),
            Some(_) => Err(format!(
                "`{key}` of `{name}` must be a non-negative integer"
            )),
        }
    };
    // Address operands shared by load, store and addr: base, optional index.
    let address = |n_addr: usize| -> VResult {
        if !is_ptr(ot[0]) {
            return Err(format!("`{name}` base must be ptr, not {}", show(ot[0])));
        }
        if nonneg("offset")?.is_none() {
            return Err(format!("`{name}` needs an `offset`"));
        }
        let stride = nonneg("stride")?;
        if n_addr == 2 {
            if !is_int(ot[1]) {
                return Err(format!(
                    "`{name}` index must be an integer, not {}",
                    show(ot[1])
                ));
            }
            if stride.is_none() {
                return Err(format!("`{name}` with an index needs a `stride`"));
            }
        }
        Ok(())
    };
    match kind {
        Op::Buffer => {
            if ot.len() != 1 || rt.len() != 1 || !is_ptr(ot[0]) || !is_ptr(rt[0]) {
                return Err("`mem.buffer` takes the layout instance (ptr) and yields a ptr".into());
            }
            if nonneg("index")?.is_none() {
                return Err("`mem.buffer` needs an `index`".into());
            }
            match o.attr("name") {
                Some(Attr::Str(_)) => Ok(()),
                _ => Err("`mem.buffer` needs a string `name`".into()),
            }
        }
        Op::Load => {
            if !(1..=2).contains(&ot.len()) || rt.len() != 1 {
                return Err(
                    "`mem.load` takes a base and an optional index, and has one result".into(),
                );
            }
            address(ot.len())?;
            if !loadable(m, rt[0]) {
                return Err(format!("`mem.load` of {}, not plain data", show(rt[0])));
            }
            Ok(())
        }
        Op::Store => {
            if !(2..=3).contains(&ot.len()) || !rt.is_empty() {
                return Err("`mem.store` takes a base, an optional index and a value".into());
            }
            address(ot.len() - 1)?;
            let v = ot[ot.len() - 1];
            if !loadable(m, v) {
                return Err(format!("`mem.store` of {}, not plain data", show(v)));
            }
            Ok(())
        }
        Op::Addr => {
            if !(1..=2).contains(&ot.len()) || rt.len() != 1 || !is_ptr(rt[0]) {
                return Err(
                    "`mem.addr` takes a base and an optional index and yields a ptr".into(),
                );
            }
            address(ot.len())
        }
        Op::View => {
            if ot.len() != 3 || rt.len() != 1 {
                return Err("`mem.view` takes base, start and len, and has one result".into());
            }
            if !is_ptr(ot[0]) || !is_int(ot[1]) || !is_int(ot[2]) {
                return Err("`mem.view` operands are (ptr, integer, integer)".into());
            }
            let Type::View(elem) = t.get(rt[0]) else {
                return Err(format!(
                    "`mem.view` result must be !mem.view<T>, not {}",
                    show(rt[0])
                ));
            };
            if !loadable(m, *elem) {
                return Err(format!("view of {}, not plain data", show(*elem)));
            }
            match nonneg("stride")? {
                Some(s) if s > 0 => Ok(()),
                _ => Err("`mem.view` needs a positive `stride`".into()),
            }
        }
    }
}

/// True for the types `mem.load` may read: scalars, vectors, `ptr`, and records (ADTs without
/// variants) whose fields are all loadable.
pub fn loadable(m: &Module, ty: TypeId) -> bool {
    match m.types.get(ty) {
        Type::Bool | Type::Int(_) | Type::Float(_) | Type::Vector { .. } | Type::Ptr => true,
        Type::Tuple(elems) => elems.iter().all(|&e| loadable(m, e)),
        Type::Array { elem, len: Some(_) } => loadable(m, *elem),
        Type::Adt(name) => m
            .adt(name)
            .is_some_and(|a| a.variants.is_empty() && a.shared.iter().all(|f| loadable(m, f.ty))),
        _ => false,
    }
}
