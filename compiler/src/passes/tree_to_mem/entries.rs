//! The entry points constructor specialization generates besides the build functions:
//! `@L.sizes(%tree, %sizes)` (the byte size of every buffer) and `@L.build(%tree, %B) -> (i32)`
//! (globals, `build root`, then the tree from its root). See `constructor.rs` for the whole
//! contract and `docs/design/specialization.md` §3.1 for the C ABI.

use super::constructor::view;
use super::logical_nodes::{load, logical_fields, store};
use super::reader::Reader;
use super::{unsupported, LayoutSpec};
use crate::layout::logical::{LogicalAbi, LogicalField};
use crate::layout::plan::Count;
use scion_ir::attr::Attr;
use scion_ir::diag::Diagnostic;
use scion_ir::rewrite::erase_op;
use scion_ir::tree::{CmpPred, Op};
use scion_ir::types::{IntTy, Type};
use scion_ir::{Builder, FuncId, InsertPoint, Module, TypeId, ValueId};

/// `@L.sizes(%tree, %sizes)`. An indirect group holds a record per node whose build places one
/// (`placing`: the variants whose builds take a placement index, which numbers the records):
/// their count is taken from the logical nodes' kinds (`logical` gives each variant's kind and
/// the node stride).
pub(super) fn sizes_fn(
    m: &mut Module,
    spec: &LayoutSpec,
    lname: &str,
    logical: &LogicalAbi,
    placing: &[String],
) -> Result<(), Diagnostic> {
    let ptr = m.ty(Type::Ptr);
    let u32t = m.types.u32();
    let u64t = m.types.int(IntTy::U64);
    let (f, entry) = m.add_func(&format!("{lname}.sizes"), &[ptr, ptr], &[]);
    m.func_spans.insert(f, spec.model.span);
    let args = m.blocks[entry].args.to_vec();
    let mut bd = Builder::at_end(m, entry);
    let nc = load(&mut bd, args[0], None, view::NODE_COUNT, 0, u32t);
    let pc = load(&mut bd, args[0], None, view::PRIM_COUNT, 0, u32t);
    for (i, buf) in spec.plan.buffers.iter().enumerate() {
        let count = match &buf.count {
            Count::One => bd.const_int(u32t, 1),
            Count::Nodes { per_element: 1, .. } => nc,
            Count::Nodes { per_element, .. } => {
                let k = bd.const_int(u32t, *per_element as i128 - 1);
                let d = bd.const_int(u32t, *per_element as i128);
                let s = bd.binary(Op::Add, nc, k);
                bd.binary(Op::Div, s, d)
            }
            Count::VariantNodes { variants } => {
                // The variants reaching the group and every variant that takes an index: a
                // record's index never passes the count.
                let kinds: Vec<usize> = logical
                    .variants
                    .iter()
                    .enumerate()
                    .filter(|(_, (n, _))| variants.contains(n) || placing.contains(n))
                    .map(|(k, _)| k)
                    .collect();
                count_kinds(&mut bd, args[0], nc, &kinds, logical.node_size)
            }
            Count::LogicalLength { .. } => pc,
            Count::Global(g) => {
                return Err(unsupported(
                    Some(spec.model.span),
                    format!(
                        "buffer `{}` sized by global `{g}`, which the logical tree does not give",
                        buf.name
                    ),
                ))
            }
        };
        let c = bd.cast(count, u64t);
        let stride = bd.const_int(u64t, buf.stride as i128);
        let bytes = bd.binary(Op::Mul, c, stride);
        store(&mut bd, args[1], 8 * i as u64, bytes);
    }
    bd.ret(&[]);
    Ok(())
}

/// The number of logical nodes whose kind is one of `kinds`: a loop over the nodes' kind words
/// (a view of `nc` `u32`s, `stride` bytes apart).
fn count_kinds(
    bd: &mut Builder<'_>,
    tree: ValueId,
    nc: ValueId,
    kinds: &[usize],
    stride: u64,
) -> ValueId {
    let u32t = bd.m.types.u32();
    let ptr = bd.m.ty(Type::Ptr);
    let nodes = load(bd, tree, None, view::NODES, 0, ptr);
    let zero = bd.const_int(u32t, 0);
    let cell = bd.var(zero);
    let vt = bd.m.ty(Type::View(u32t));
    let op = bd.insert(
        scion_ir::OpSpec::new(scion_ir::mem::Op::View)
            .operands(&[nodes, zero, nc])
            .results(&[vt])
            .attr("stride", scion_ir::attr::Attr::Int(stride as i128)),
    );
    let kinds_view = bd.result(op, 0);
    let body = bd.region(&[u32t], |bd, a| {
        let mut hit: Option<ValueId> = None;
        for &k in kinds {
            let kv = bd.const_int(u32t, k as i128);
            let is = bd.cmp(CmpPred::Eq, a[0], kv);
            hit = Some(match hit {
                None => is,
                Some(h) => bd.binary(Op::Or, h, is),
            });
        }
        let one = bd.const_int(u32t, 1);
        let zero = bd.const_int(u32t, 0);
        let add = match hit {
            Some(h) => bd.select(h, one, zero),
            None => zero,
        };
        let old = bd.load(cell).expect("a cell");
        let new = bd.binary(Op::Add, old, add);
        bd.store(cell, new);
        bd.yield_(&[]);
    });
    bd.insert(
        scion_ir::OpSpec::new(Op::Foreach)
            .operands(&[kinds_view])
            .region(body),
    );
    bd.load(cell).expect("a cell")
}

/// `@L.build(%tree, %B) -> (i32)`.
#[allow(clippy::too_many_arguments)]
pub(super) fn build_fn(
    m: &mut Module,
    spec: &LayoutSpec,
    lname: &str,
    node_name: &str,
    root_fn: Option<FuncId>,
    ref_ty: TypeId,
    shared: &[LogicalField],
    stride: u64,
) -> Result<(), Diagnostic> {
    let ptr = m.ty(Type::Ptr);
    let u32t = m.types.u32();
    let i32t = m.types.i32();
    let (f, entry) = m.add_func(&format!("{lname}.build"), &[ptr, ptr], &[i32t]);
    m.func_spans.insert(f, spec.model.span);
    let args = m.blocks[entry].args.to_vec();
    let (tree, b) = (args[0], args[1]);
    let mut bd = Builder::at_end(m, entry);
    let zero = bd.const_int(u32t, 0);
    let counters =
        bd.m.func_by_name(node_name)
            .and_then(|f| bd.m.funcs[f].attrs.get(super::counters::COUNTERS_ATTR))
            .and_then(Attr::as_int)
            .unwrap_or(1) as usize;
    let first_counts = super::counters::zero_counters(&mut bd, counters);
    let counter = bd.var(first_counts);
    let cursor = bd.var(zero);
    let szero = bd.const_int(i32t, 0);
    let status = bd.var(szero);
    let nc = load(&mut bd, tree, None, view::NODE_COUNT, 0, u32t);
    let root = load(&mut bd, tree, None, view::ROOT, 0, u32t);
    let pc = load(&mut bd, tree, None, view::PRIM_COUNT, 0, u32t);
    // The globals that size arrays: node and primitive counts.
    let first = bd.ret(&[szero]);
    let mut rd = Reader::new(spec, b, vec![], InsertPoint::Before(first));
    let variant = spec.first_variant();
    for buf in &spec.plan.buffers {
        let (global, v) = match &buf.count {
            Count::Nodes {
                size_global: Some(g),
                ..
            } => (g, nc),
            Count::LogicalLength { len_global, .. } => (len_global, pc),
            _ => continue,
        };
        rd.store_field(m, &variant, global, v)?;
    }
    erase_op(m, first);
    let mut bd = Builder::at_end(m, entry);
    let pass = [tree, b, counter, cursor, status];
    // An empty tree (`root = NO_NODE`) only gets its globals.
    let no_node = bd.const_int(u32t, u32::MAX as i128);
    let nonempty = bd.cmp(CmpPred::Ne, root, no_node);
    let root_call = match root_fn {
        Some(rf) => {
            let name = bd.m.funcs[rf].name.clone();
            let params = bd.m.funcs[rf].params[5..].to_vec();
            Some((name, params))
        }
        None => None,
    };
    let failed = std::cell::RefCell::new(None);
    bd.if_(
        nonempty,
        &[],
        |bd| {
            if let Some((name, params)) = &root_call {
                let nodes = load(bd, tree, None, view::NODES, 0, ptr);
                let prims = load(bd, tree, None, view::PRIMS, 0, ptr);
                match logical_fields(bd, params, shared, nodes, prims, root, stride) {
                    Ok(vals) => {
                        let all: Vec<ValueId> = pass.iter().copied().chain(vals).collect();
                        bd.call(name, &all, &[]);
                    }
                    Err(e) => *failed.borrow_mut() = Some(e),
                }
            }
            bd.call(
                node_name,
                &[tree, b, root, counter, cursor, status],
                &[ref_ty],
            );
            bd.yield_(&[]);
        },
        |bd| {
            bd.yield_(&[]);
        },
    );
    if let Some(e) = failed.into_inner() {
        return Err(unsupported(
            Some(spec.model.span),
            format!("`build root` reads {e}"),
        ));
    }
    let s = bd.load(status).expect("status is a cell");
    bd.ret(&[s]);
    Ok(())
}

/// The name of the function that gives the whole reference of the root from its placed
/// component, for a layout whose reference has several components.
pub fn root_ref_name(lname: &str) -> String {
    format!("{lname}.root_ref")
}

/// `@L.root_ref(%B: ptr, %i) -> (R)` for a reference of several components: the root's
/// reference, its first component `%i` (what `@L.build` placed) and every other component's
/// default, a layout expression over the globals (`lo: f32x3 = scene.low`): the traversal takes
/// the others from the parent (`left = (I + 1, lo, with_axis(hi, axis, pl))`), so only the
/// root's need a value of their own. A component without a default is reported (E0380).
pub(super) fn root_ref_fn(
    m: &mut Module,
    spec: &LayoutSpec,
    lname: &str,
    ref_ty: TypeId,
) -> Result<(), Diagnostic> {
    let comps = &spec.model.components;
    let ptr = m.ty(Type::Ptr);
    let Type::Tuple(tys) = m.types.get(ref_ty).clone() else {
        return Err(unsupported(
            Some(spec.model.span),
            "a reference of several components that is not a tuple",
        ));
    };
    let (f, entry) = m.add_func(&root_ref_name(lname), &[ptr, tys[0]], &[ref_ty]);
    m.func_spans.insert(f, spec.model.span);
    let args = m.blocks[entry].args.to_vec();
    // A placeholder to insert before; the tuple's return replaces it.
    let first = Builder::at_end(m, entry).ret(&[]);
    let variant = spec.first_variant();
    let mut rd = Reader::new(spec, args[0], vec![args[1]], InsertPoint::Before(first));
    let mut vals = vec![args[1]];
    for (k, c) in comps.iter().enumerate().skip(1) {
        if c.carried.is_some() {
            // The root has no parent: its carried components are zero.
            let mut bd = Builder::new(m);
            bd.set_insertion_point(InsertPoint::Before(first));
            let z = zero(&mut bd, tys[k]).ok_or_else(|| {
                unsupported(
                    Some(c.name.span),
                    "a tree-carried component of a type without a zero value",
                )
            })?;
            vals.push(z);
            continue;
        }
        let Some(e) = &c.default else {
            return Err(Diagnostic::error(
                "E0380",
                format!(
                    "reference component `{}` without a default (its value at the root, an \
                     expression over the globals)",
                    c.name.name
                ),
            )
            .with_primary(c.name.span, "no default")
            .with_note(
                "a build places the first component; a child's others come from the layout's \
                 expression for the child, the root's from their defaults (`lo: f32x3 = scene.low`)",
            ));
        };
        let v = rd.expr(m, &variant, e, Some(tys[k]))?;
        if m.values[v].ty != tys[k] {
            return Err(unsupported(
                Some(c.name.span),
                format!(
                    "the default of reference component `{}` has another type",
                    c.name.name
                ),
            ));
        }
        vals.push(v);
    }
    let mut bd = Builder::new(m);
    bd.set_insertion_point(InsertPoint::Before(first));
    let tuple = bd.tuple(&vals);
    bd.ret(&[tuple]);
    erase_op(m, first);
    Ok(())
}

/// The zero value of `ty` (numbers 0, `false`, records, tuples, vectors and arrays of zeros).
fn zero(bd: &mut Builder<'_>, ty: TypeId) -> Option<ValueId> {
    Some(match bd.m.types.get(ty).clone() {
        Type::Bool => bd.const_bool(false),
        Type::Int(_) => bd.const_int(ty, 0),
        Type::Float(_) => bd.const_float(ty, 0.0),
        Type::Vector { elem, lanes } => {
            let z = zero(bd, elem)?;
            bd.vector(&vec![z; lanes as usize])?
        }
        Type::Tuple(es) => {
            let vals = es
                .iter()
                .map(|&e| zero(bd, e))
                .collect::<Option<Vec<_>>>()?;
            bd.tuple(&vals)
        }
        Type::Adt(name) => {
            let adt = bd.m.adt(&name)?;
            if !adt.is_record() {
                return None;
            }
            let tys: Vec<TypeId> = adt.shared.iter().map(|f| f.ty).collect();
            let vals = tys
                .iter()
                .map(|&e| zero(bd, e))
                .collect::<Option<Vec<_>>>()?;
            bd.ctor(ty, None, &vals)
        }
        _ => return None,
    })
}
