//! Reading the logical tree in the generated packer: `@L.node`'s dispatch on a logical node's
//! kind to its variant's build function, and the loads of that node's logical fields
//! (`layout::logical` says where each sits) that the build functions take.

use crate::layout::logical::{LogicalField, Slot};
use scion_ir::attr::Attr;
use scion_ir::data_layout::size_align;
use scion_ir::tree::CmpPred;
use scion_ir::types::Type;
use scion_ir::{mem, Builder, OpSpec, TypeId, ValueId};

/// One variant's arm of `@L.node`: its kind, build function and logical fields.
pub(super) struct Arm {
    pub(super) kind: u32,
    pub(super) name: String,
    pub(super) params: Vec<TypeId>,
    pub(super) fields: Vec<LogicalField>,
}

/// What every arm of `@L.node` reads.
pub(super) struct Dispatch {
    /// `%tree, %out, %next, %count, %status` passed on to the build functions.
    pub(super) pass: [ValueId; 5],
    pub(super) nodes: ValueId,
    pub(super) prims: ValueId,
    pub(super) i: ValueId,
    pub(super) kind: ValueId,
    pub(super) stride: u64,
    pub(super) ref_ty: TypeId,
}

/// `if kind == k0 { build k0 } else if ... else { build the last }`: the call of the build
/// function of node `i`'s variant with its logical fields.
pub(super) fn dispatch(
    bd: &mut Builder<'_>,
    cx: &Dispatch,
    arms: &[Arm],
) -> Result<ValueId, String> {
    let call = |bd: &mut Builder<'_>, a: &Arm| -> Result<ValueId, String> {
        let vals = logical_fields(
            bd, &a.params, &a.fields, cx.nodes, cx.prims, cx.i, cx.stride,
        )?;
        let all: Vec<ValueId> = cx.pass.iter().copied().chain(vals).collect();
        let c = bd.call(&a.name, &all, &[cx.ref_ty]);
        Ok(bd.result(c, 0))
    };
    let [first, rest @ ..] = arms else {
        return Err("a tree type without variants".into());
    };
    if rest.is_empty() {
        return call(bd, first);
    }
    let u32t = bd.m.types.u32();
    let want = bd.const_int(u32t, i128::from(first.kind));
    let test = bd.cmp(CmpPred::Eq, cx.kind, want);
    let failed = std::cell::RefCell::new(None);
    let arm = |bd: &mut Builder<'_>, r: Result<ValueId, String>| match r {
        Ok(v) => {
            bd.yield_(&[v]);
        }
        Err(e) => {
            *failed.borrow_mut() = Some(e);
            let z = bd.const_int(u32t, 0);
            bd.yield_(&[z]);
        }
    };
    let if_op = bd.if_(
        test,
        &[cx.ref_ty],
        |bd| {
            let r = call(bd, first);
            arm(bd, r)
        },
        |bd| {
            let r = dispatch(bd, cx, rest);
            arm(bd, r)
        },
    );
    if let Some(e) = failed.into_inner() {
        return Err(e);
    }
    Ok(bd.result(if_op, 0))
}

pub(super) fn load(
    bd: &mut Builder<'_>,
    base: ValueId,
    index: Option<ValueId>,
    offset: u64,
    stride: u64,
    t: TypeId,
) -> ValueId {
    let mut spec = OpSpec::new(mem::Op::Load)
        .results(&[t])
        .attr("offset", Attr::Int(offset as i128));
    spec = match index {
        Some(i) => spec
            .operands(&[base, i])
            .attr("stride", Attr::Int(stride as i128)),
        None => spec.operands(&[base]),
    };
    let op = bd.insert(spec);
    bd.result(op, 0)
}

pub(super) fn store(bd: &mut Builder<'_>, base: ValueId, offset: u64, v: ValueId) {
    bd.insert(
        OpSpec::new(mem::Op::Store)
            .operands(&[base, v])
            .attr("offset", Attr::Int(offset as i128)),
    );
}

/// The logical fields of node `i` for a build function's parameter types (after `%tree`..):
/// `fields` says where each sits in the node (`layout::logical`).
pub(super) fn logical_fields(
    bd: &mut Builder<'_>,
    params: &[TypeId],
    fields: &[LogicalField],
    nodes: ValueId,
    prims: ValueId,
    i: ValueId,
    stride: u64,
) -> Result<Vec<ValueId>, String> {
    let u32t = bd.m.types.u32();
    let mut out = Vec::new();
    for (&p, f) in params.iter().zip(fields) {
        let v = match &f.slot {
            Slot::Value { offset } => {
                let v = load(bd, nodes, Some(i), *offset, stride, f.ty);
                if p == f.ty {
                    v
                } else if matches!(bd.m.types.get(p), Type::Int(_)) {
                    bd.cast(v, p)
                } else {
                    return Err(format!(
                        "`{}` as {} (the logical tree holds {})",
                        f.name,
                        bd.m.types.display(p),
                        bd.m.types.display(f.ty)
                    ));
                }
            }
            Slot::Children { offset, count: 1 } if p == u32t => {
                load(bd, nodes, Some(i), *offset, stride, u32t)
            }
            Slot::Children { offset, count } => match bd.m.types.get(p).clone() {
                Type::Array { elem, len: Some(n) } if elem == u32t && n == *count => {
                    load(bd, nodes, Some(i), *offset, stride, p)
                }
                _ => {
                    return Err(format!(
                        "the children `{}` as {} ({count} logical node indices)",
                        f.name,
                        bd.m.types.display(p)
                    ))
                }
            },
            Slot::Prims { offset, count } => {
                let start = load(bd, nodes, Some(i), *offset, stride, u32t);
                let (Some(cf), Type::View(elem)) = (fields.get(*count), bd.m.types.get(p)) else {
                    return Err(format!(
                        "the primitives `{}` as {}",
                        f.name,
                        bd.m.types.display(p)
                    ));
                };
                // The primitive record's size (the runtime's: the layout model checked it).
                let Some((prim_stride, _)) = size_align(bd.m, *elem) else {
                    return Err(format!("the primitives `{}` have no size", f.name));
                };
                let Slot::Value { offset: co } = cf.slot else {
                    return Err(format!("the length of `{}`", f.name));
                };
                let len = load(bd, nodes, Some(i), co, stride, cf.ty);
                let len = if cf.ty == u32t {
                    len
                } else {
                    bd.cast(len, u32t)
                };
                let op = bd.insert(
                    OpSpec::new(mem::Op::View)
                        .operands(&[prims, start, len])
                        .results(&[p])
                        .attr("stride", Attr::Int(prim_stride as i128)),
                );
                bd.result(op, 0)
            }
        };
        out.push(v);
    }
    Ok(out)
}
