//! `destructor-specialize` (paper §7.1, Algorithm 1): traversals over a layout's references.
//!
//! Input: `tree` functions whose parameters include the layout's tree type (`!tree.adt<"BVH">`)
//! and the [`LayoutSpec`] of the pass context. Output, for each such function:
//! * a first parameter `%B: ptr` (the layout instance: a table of buffer addresses), and every
//!   tree parameter retyped to the layout's reference type (`u32` for `LinearBVH(I: u32)`,
//!   `ptr` for `PtrBVH(R: ptr)`, a tuple for several components);
//! * each `tree.match` on a tree value becomes a chain of `tree.if` on the variant tests (the
//!   split predicates, first matching arm wins), and each arm's bound fields the values the
//!   reader (`reader.rs`) computes for them: `mem.load` at the resolved path, derived expressions (inlined,
//!   each at most once per destruction), `mem.view` for slices of global arrays; recursive fields
//!   are references;
//! * `tree.field` of a shared field and `tree.is` on a tree value are read the same way;
//! * an array of children (`children: BVH8[8]`) is read as the array of the children's
//!   references, so `foreach c in children` and `children[k]` give references;
//! * calls to specialized functions pass `%B` along.
//!
//! A function over several trees of the layout (a collision traversal over `a: BVH, b: BVH`)
//! gets one table per tree parameter, `%B0, %B1, ...` first, in the order of the tree
//! parameters: every tree value inside the function descends from one of its tree parameters
//! (a match's bound children, a child array's elements), and its reads use that parameter's
//! table; a call passes, for each tree argument in order, the table of the tree it descends from.
//!
//! * a `tree.if` yielding tree values (`let near: BVH = if swap { right } else { left }`)
//!   yields their references.
//!
//! Tree values used any other way (built with `tree.ctor`, returned, stored in a cell, put in a
//! tuple) are reported (E0380), never miscompiled.

use super::reader::{Layer, Reader};
use super::{ir_type, spec_of, unsupported, LayoutSpec};
use rustc_hash::{FxHashMap, FxHashSet};
use scion_ir::attr::Attr;
use scion_ir::diag::{Diagnostic, Diagnostics};
use scion_ir::module::ValueDef;
use scion_ir::rewrite::{erase_op, inline_region_before, replace_all_uses, replace_op};
use scion_ir::tree::Op;
use scion_ir::types::Type;
use scion_ir::walk::{func_ops, Order};
use scion_ir::{
    Builder, FuncId, InsertPoint, Module, OpKind, OpSpec, Pass, PassCx, PassError, TypeId, ValueId,
};

/// The pass object.
#[derive(Default)]
pub struct DestructorSpecialize;

impl Pass for DestructorSpecialize {
    fn name(&self) -> &'static str {
        "destructor-specialize"
    }

    fn summary(&self) -> &'static str {
        "rewrite traversals of the layout's tree type into reads of the layout (needs --layout)"
    }

    fn run(&mut self, m: &mut Module, cx: &mut PassCx) -> Result<bool, PassError> {
        let spec = spec_of(m, cx, self.name())?;
        specialize(m, spec)
    }
}

/// Specializes every function of `m` that takes the layout's tree type. Returns whether
/// anything changed.
pub fn specialize(m: &mut Module, spec: &LayoutSpec) -> Result<bool, PassError> {
    let Some(adt) = spec.model.adt.as_ref().map(|a| a.name.clone()) else {
        return Err(
            unsupported(Some(spec.model.span), "a layout whose tree type is unknown").into(),
        );
    };
    let Some(tree_ty) = m.types.lookup(&Type::Adt(adt.clone())) else {
        return Ok(false);
    };
    let ref_ty = reference_type(m, spec)?;
    let ptr = m.ty(Type::Ptr);
    let targets: Vec<FuncId> = m
        .func_order
        .iter()
        .copied()
        .filter(|&f| m.funcs[f].params.iter().any(|&p| mentions(m, p, tree_ty)))
        .collect();
    if targets.is_empty() {
        return Ok(false);
    }
    let mut diags = Diagnostics::default();
    let names: FxHashSet<String> = targets.iter().map(|&f| m.funcs[f].name.clone()).collect();
    for &f in &targets {
        let func = &m.funcs[f];
        let span = m.func_spans.get(f).copied();
        if m.is_declaration(f) {
            diags.push(unsupported(
                span,
                format!("declared function `@{}` takes a tree value", func.name),
            ));
            continue;
        }
        if func
            .params
            .iter()
            .any(|&p| p != tree_ty && mentions(m, p, tree_ty))
            || func.results.iter().any(|&r| mentions(m, r, tree_ty))
        {
            diags.push(unsupported(
                span,
                format!(
                    "`@{}` passes tree values other than as plain parameters",
                    func.name
                ),
            ));
        }
    }
    if diags.has_errors() {
        return Err(diags.into());
    }
    for &f in &targets {
        if let Err(d) = specialize_func(m, spec, f, tree_ty, ref_ty, ptr, &names) {
            diags.push(d);
        }
    }
    if diags.has_errors() {
        return Err(diags.into());
    }
    slices_to_views(m)?;
    Ok(true)
}

/// A function that takes a leaf's primitives (`data: Triangle[nprims]`, an `array<? x T>`
/// parameter) is passed the layout's `mem.view<T>` of them once the traversal that calls it
/// is specialized: such a parameter becomes a view (`tree.index`, `tree.foreach` and `len`
/// read either), and so on down the functions it passes it to. A function passed both a view
/// and a tree array is reported.
fn slices_to_views(m: &mut Module) -> Result<(), PassError> {
    // The arms' bound values read the layout through aliases until these are resolved.
    scion_ir::rewrite::resolve_aliases(m);
    loop {
        let args = call_arguments(m);
        let is_view = |t: TypeId| matches!(m.types.get(t), Type::View(_));
        let slice_of = |t: TypeId| match m.types.get(t) {
            Type::Array { elem, len: None } => Some(*elem),
            _ => None,
        };
        // A tree array passed where a view is now expected.
        if let Some(&(op, f, ..)) = args
            .iter()
            .find(|&&(_, f, i, a)| is_view(m.funcs[f].params[i]) && slice_of(a).is_some())
        {
            return Err(unsupported(
                m.span(op),
                format!(
                    "`@{}` is passed both a layout's primitives and a tree array",
                    m.funcs[f].name
                ),
            )
            .into());
        }
        let retype: Vec<(FuncId, usize, TypeId)> = args
            .iter()
            .filter(|&&(_, f, i, a)| {
                matches!(m.types.get(a), Type::View(e) if slice_of(m.funcs[f].params[i]) == Some(*e))
            })
            .map(|&(_, f, i, a)| (f, i, a))
            .collect();
        if retype.is_empty() {
            return Ok(());
        }
        for (f, i, view) in retype {
            m.funcs[f].params[i] = view;
            if let Some(entry) = m.entry_block(f) {
                let arg = m.blocks[entry].args[i];
                m.values[arg].ty = view;
            }
        }
    }
}

/// Every argument of a call of a defined function: (call, callee, parameter index, the
/// argument's type).
fn call_arguments(m: &Module) -> Vec<(scion_ir::OpId, FuncId, usize, TypeId)> {
    let mut out = Vec::new();
    for &f in &m.func_order {
        if m.is_declaration(f) {
            continue;
        }
        for op in func_ops(m, f, Order::Pre) {
            let o = &m.ops[op];
            if o.kind != OpKind::Tree(Op::Call) {
                continue;
            }
            let Some(callee) = o.callee().and_then(|c| m.func_by_name(c)) else {
                continue;
            };
            let n = m.funcs[callee].params.len();
            for (i, &a) in o.operands.iter().enumerate().take(n) {
                out.push((op, callee, i, m.values[a].ty));
            }
        }
    }
    out
}

/// The IR type of the layout's reference: its one component, or a tuple of them.
pub(super) fn reference_type(m: &mut Module, spec: &LayoutSpec) -> Result<TypeId, PassError> {
    let mut comps = Vec::new();
    for c in &spec.model.components {
        match ir_type(m, &c.ty) {
            Some(t) => comps.push(t),
            None => {
                return Err(
                    unsupported(Some(c.name.span), "a reference component of this type").into(),
                )
            }
        }
    }
    Ok(match comps.as_slice() {
        [one] => *one,
        _ => m.types.tuple(comps),
    })
}

fn mentions(m: &Module, ty: TypeId, tree: TypeId) -> bool {
    if ty == tree {
        return true;
    }
    match m.types.get(ty) {
        Type::Vector { .. }
        | Type::Bool
        | Type::Int(_)
        | Type::Float(_)
        | Type::Ptr
        | Type::Adt(_) => false,
        Type::Tuple(es) => es.iter().any(|&e| mentions(m, e, tree)),
        Type::Array { elem, .. }
        | Type::Set(elem)
        | Type::Option(elem)
        | Type::Ref(elem)
        | Type::View(elem) => mentions(m, *elem, tree),
    }
}

fn specialize_func(
    m: &mut Module,
    spec: &LayoutSpec,
    f: FuncId,
    tree_ty: TypeId,
    ref_ty: TypeId,
    ptr: TypeId,
    specialized: &FxHashSet<String>,
) -> Result<(), Diagnostic> {
    let entry = m
        .entry_block(f)
        .expect("a function with a body has an entry block");
    // Collect the work before changing types: ops reading tree values.
    let ops = func_ops(m, f, Order::Pre);
    let tree_of = tree_provenance(m, f, &ops, tree_ty);
    let ntrees = m.funcs[f].params.iter().filter(|&&p| p == tree_ty).count();
    let unknown = |m: &Module, op: scion_ir::OpId| {
        unsupported(
            m.span(op),
            format!(
                "a tree value in `@{}` that descends from none of its tree parameters",
                m.funcs[f].name
            ),
        )
    };
    let mut matches = Vec::new();
    let mut reads = Vec::new();
    let mut calls = Vec::new();
    for &op in &ops {
        let o = &m.ops[op];
        let on_tree = o
            .operands
            .first()
            .is_some_and(|&v| m.values[v].ty == tree_ty);
        // With one tree parameter every tree value is of that tree (a use this pass does not
        // know is reported below, by what it is).
        let tree = |v: ValueId| {
            let t = tree_of
                .get(&scion_ir::rewrite::resolve_value(m, v))
                .copied();
            t.or((ntrees == 1).then_some(0))
        };
        match o.kind {
            OpKind::Tree(Op::Match) if on_tree => {
                matches.push((op, tree(o.operands[0]).ok_or_else(|| unknown(m, op))?))
            }
            OpKind::Tree(Op::Field | Op::Is) if on_tree => {
                reads.push((op, tree(o.operands[0]).ok_or_else(|| unknown(m, op))?))
            }
            OpKind::Tree(Op::Call) => {
                if let Some(s) = o.callee() {
                    if specialized.contains(s) {
                        let mut trees = Vec::new();
                        for &v in o.operands.iter().filter(|&&v| m.values[v].ty == tree_ty) {
                            trees.push(tree(v).ok_or_else(|| unknown(m, op))?);
                        }
                        calls.push((op, trees));
                    }
                }
            }
            _ => {}
        }
    }
    // One `%B` per tree parameter first, tree parameters retyped to references.
    let tables: Vec<ValueId> = (0..ntrees).map(|_| m.add_block_arg(entry, ptr)).collect();
    let args = &mut m.blocks[entry].args;
    args.rotate_right(ntrees);
    let args = args.clone();
    for (i, &a) in args.iter().enumerate() {
        m.values[a].def = ValueDef::BlockArg(entry, i as u32);
        if m.values[a].ty == tree_ty {
            m.values[a].ty = ref_ty;
        }
    }
    let params: Vec<TypeId> = args.iter().map(|&a| m.values[a].ty).collect();
    m.funcs[f].params = params;
    // The tables come first now: the ordering parameter moved up.
    if let Some(k) = m.funcs[f].order_by() {
        m.funcs[f].set_order_by(k + ntrees);
    }
    for (op, trees) in calls {
        let bs: Vec<ValueId> = trees.iter().map(|&t| tables[t]).collect();
        m.ops[op].operands.insert_many(0, bs);
    }
    // Outer matches first (pre-order), so an inner match's operand is already aliased; then
    // the field reads, whose operands (children bound by the matches) are references by then,
    // so the components of a tuple reference can be taken apart.
    for (op, t) in matches {
        destruct(m, spec, op, tables[t], tree_ty, ref_ty)?;
        retype_children(m, f, tree_ty);
        retype_tree_ifs(m, f, tree_ty, ref_ty);
    }
    for (op, t) in reads {
        read_op(m, spec, op, tables[t])?;
    }
    // Whatever still carries a tree value is a use this pass does not know.
    for op in func_ops(m, f, Order::Pre) {
        let o = &m.ops[op];
        let bad = o.operands.iter().chain(o.results.iter()).any(|&v| {
            let v = scion_ir::rewrite::resolve_value(m, v);
            mentions(m, m.values[v].ty, tree_ty)
        });
        if bad {
            return Err(unsupported(
                m.span(op),
                format!(
                    "`{}` on a tree value in `@{}`",
                    o.kind.name(),
                    m.funcs[f].name
                ),
            )
            .with_note(
                "traversals may match on tree values, read their fields and pass them to calls",
            ));
        }
    }
    Ok(())
}

/// Which tree parameter (0 for the first parameter of the tree type, 1 for the second, ...)
/// each tree value of `f` descends from: a parameter is its own tree; the fields a `tree.match`
/// on a tree value binds, the elements a `tree.foreach` over its children binds and a
/// `tree.index` reads descend from the tree of the value they come from. `ops` in pre-order.
fn tree_provenance(
    m: &Module,
    f: FuncId,
    ops: &[scion_ir::OpId],
    tree_ty: TypeId,
) -> FxHashMap<ValueId, usize> {
    let mut tree_of = FxHashMap::default();
    let entry = m.entry_block(f).expect("a function with a body");
    let params = m.blocks[entry].args.iter();
    for (k, &a) in params.filter(|&&a| m.values[a].ty == tree_ty).enumerate() {
        tree_of.insert(a, k);
    }
    for &op in ops {
        let o = &m.ops[op];
        let Some(&first) = o.operands.first() else {
            continue;
        };
        let Some(&t) = tree_of.get(&scion_ir::rewrite::resolve_value(m, first)) else {
            continue;
        };
        match o.kind {
            OpKind::Tree(Op::Match | Op::Foreach) => {
                for &r in &o.regions {
                    if let Some(&block) = m.regions[r].blocks.first() {
                        for &a in &m.blocks[block].args {
                            if mentions(m, m.values[a].ty, tree_ty) {
                                tree_of.insert(a, t);
                            }
                        }
                    }
                }
            }
            OpKind::Tree(Op::Index | Op::Field) => {
                for &r in &o.results {
                    if mentions(m, m.values[r].ty, tree_ty) {
                        tree_of.insert(r, t);
                    }
                }
            }
            _ => {}
        }
    }
    // A `tree.if`'s tree result descends from the tree its arms' values descend from (post-
    // order: an inner if's result is known before the outer one yields it).
    for &op in ops.iter().rev() {
        let o = &m.ops[op];
        if !matches!(o.kind, OpKind::Tree(Op::If)) {
            continue;
        }
        for (i, &r) in o.results.iter().enumerate() {
            if m.values[r].ty != tree_ty {
                continue;
            }
            let mut from = None;
            let mut agree = true;
            for &region in &o.regions {
                let term = m.regions[region]
                    .blocks
                    .last()
                    .and_then(|&b| m.blocks[b].ops.last().copied());
                let Some(term) = term else { continue };
                if !matches!(m.ops[term].kind, OpKind::Tree(Op::Yield)) {
                    continue;
                }
                let v = m.ops[term].operands.get(i).copied();
                let t = v.and_then(|v| tree_of.get(&scion_ir::rewrite::resolve_value(m, v)));
                match (from, t) {
                    (_, None) => agree = false,
                    (None, Some(&t)) => from = Some(t),
                    (Some(a), Some(&t)) => agree &= a == t,
                }
            }
            if let (true, Some(t)) = (agree, from) {
                tree_of.insert(r, t);
            }
        }
    }
    tree_of
}

/// An array of children read from the layout is an array of references: the element a
/// `tree.foreach` binds and a `tree.index` reads from it are references too.
fn retype_children(m: &mut Module, f: FuncId, tree_ty: TypeId) {
    for op in func_ops(m, f, Order::Pre) {
        let o = &m.ops[op];
        let Some(&arr) = o.operands.first() else {
            continue;
        };
        let arr = scion_ir::rewrite::resolve_value(m, arr);
        let Type::Array { elem, .. } = *m.types.get(m.values[arr].ty) else {
            continue;
        };
        if elem == tree_ty {
            continue;
        }
        match o.kind {
            OpKind::Tree(Op::Foreach) => {
                let block = m.regions[o.regions[0]].blocks[0];
                if let Some(&a) = m.blocks[block].args.first() {
                    if m.values[a].ty == tree_ty {
                        m.values[a].ty = elem;
                    }
                }
            }
            OpKind::Tree(Op::Index) => {
                let r = o.results[0];
                if m.values[r].ty == tree_ty {
                    m.values[r].ty = elem;
                }
            }
            _ => {}
        }
    }
}

/// A `tree.if` choosing between tree values (`let near: BVH = if swap { right } else { left }`)
/// chooses between their references once every value it yields is one: its result is retyped
/// to the reference type (a select of node references after lowering). Arms that return
/// instead of yielding do not constrain it.
fn retype_tree_ifs(m: &mut Module, f: FuncId, tree_ty: TypeId, ref_ty: TypeId) {
    for op in func_ops(m, f, Order::Pre) {
        if !matches!(m.ops[op].kind, OpKind::Tree(Op::If)) {
            continue;
        }
        let results = m.ops[op].results.clone();
        for (i, &r) in results.iter().enumerate() {
            if m.values[r].ty != tree_ty {
                continue;
            }
            let all_refs = m.ops[op].regions.iter().all(|&region| {
                let Some(&block) = m.regions[region].blocks.last() else {
                    return false;
                };
                let Some(&term) = m.blocks[block].ops.last() else {
                    return false;
                };
                let t = &m.ops[term];
                match t.kind {
                    OpKind::Tree(Op::Yield) => t.operands.get(i).is_some_and(|&v| {
                        m.values[scion_ir::rewrite::resolve_value(m, v)].ty == ref_ty
                    }),
                    OpKind::Tree(Op::Return) => true,
                    _ => false,
                }
            });
            if all_refs {
                m.values[r].ty = ref_ty;
            }
        }
    }
}

/// The reference components of a (possibly aliased) reference value, for a reader inserting
/// before `at`.
fn components(m: &mut Module, spec: &LayoutSpec, r: ValueId, at: scion_ir::OpId) -> Vec<ValueId> {
    let n = spec.model.components.len();
    if n == 1 {
        return vec![r];
    }
    let mut bd = Builder::new(m);
    bd.set_insertion_point(InsertPoint::Before(at));
    (0..n).filter_map(|i| bd.extract(r, i)).collect()
}

/// `tree.field` of a shared field or `tree.is` on a tree value.
fn read_op(
    m: &mut Module,
    spec: &LayoutSpec,
    op: scion_ir::OpId,
    b: ValueId,
) -> Result<(), Diagnostic> {
    let r = scion_ir::rewrite::resolve_value(m, m.ops[op].operands[0]);
    let comps = components(m, spec, r, op);
    let mut rd = Reader::new(spec, b, comps, InsertPoint::Before(op));
    let o = &m.ops[op];
    let v = if o.kind == OpKind::Tree(Op::Field) {
        let name = o.str_attr("name").unwrap_or_default().to_string();
        let variant = first_variant(spec)?;
        rd.field(m, &variant, &name)?
    } else {
        let variant = o.str_attr("variant").unwrap_or_default().to_string();
        rd.variant_test(m, &variant)?
    };
    replace_op(m, op, &[v]);
    Ok(())
}

fn first_variant(spec: &LayoutSpec) -> Result<String, Diagnostic> {
    Some(spec.first_variant())
        .filter(|v| !v.is_empty())
        .ok_or_else(|| {
            unsupported(
                Some(spec.model.span),
                "a layout whose tree type has no variants",
            )
        })
}

/// Rewrites one `tree.match` on a tree value into a chain of `tree.if`.
fn destruct(
    m: &mut Module,
    spec: &LayoutSpec,
    op: scion_ir::OpId,
    b: ValueId,
    tree_ty: TypeId,
    ref_ty: TypeId,
) -> Result<(), Diagnostic> {
    let r = scion_ir::rewrite::resolve_value(m, m.ops[op].operands[0]);
    let adt_name = match m.types.get(tree_ty) {
        Type::Adt(n) => n.clone(),
        _ => unreachable!("the tree type is an ADT"),
    };
    let arms: Vec<String> = m.ops[op]
        .attr("arms")
        .and_then(Attr::as_list)
        .map(|l| {
            l.iter()
                .filter_map(|a| a.as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default();
    let regions = m.ops[op].regions.clone();
    let result_tys: Vec<TypeId> = m.ops[op].results.iter().map(|&v| m.values[v].ty).collect();
    let comps = components(m, spec, r, op);
    let mut rd = Reader::new(spec, b, comps, InsertPoint::Before(op));
    let default_variant = first_variant(spec)?;
    // Variant tests, in layer 0; a wildcard arm is unconditional and ends the chain.
    let mut chain: Vec<(Option<ValueId>, scion_ir::RegionId, String)> = Vec::new();
    for (i, (name, &region)) in arms.iter().zip(&regions).enumerate() {
        let last = i + 1 == arms.len();
        let test = if name == "_" || last {
            None
        } else {
            Some(rd.variant_test(m, name)?)
        };
        chain.push((test, region, name.clone()));
        if name == "_" {
            break;
        }
    }
    // Each arm's bound fields, computed at the start of its block.
    let field_names: FxHashMap<String, Vec<String>> = m
        .adt(&adt_name)
        .map(|a| {
            let mut map = FxHashMap::default();
            for v in &a.variants {
                let names = a
                    .fields_of(Some(&v.name))
                    .unwrap_or_default()
                    .iter()
                    .map(|f| f.name.clone())
                    .collect();
                map.insert(v.name.clone(), names);
            }
            map.insert(
                "_".to_string(),
                a.shared.iter().map(|f| f.name.clone()).collect(),
            );
            map
        })
        .unwrap_or_default();
    let uses = use_set(m, op);
    for (_, region, name) in &chain {
        let block = m.regions[*region].blocks[0];
        let first = m.blocks[block].ops[0];
        rd.layers.push(Layer::new(InsertPoint::Before(first)));
        let variant = if name == "_" {
            default_variant.clone()
        } else {
            name.clone()
        };
        let args = m.blocks[block].args.clone();
        let fields = field_names.get(name.as_str()).cloned().unwrap_or_default();
        for (a, field) in args.iter().zip(&fields) {
            if !uses.contains(a) {
                continue;
            }
            let v = if m.values[*a].ty == tree_ty {
                rd.child_ref(m, &variant, field)?
            } else {
                rd.field(m, &variant, field)?
            };
            if m.values[*a].ty == tree_ty && m.values[v].ty != ref_ty {
                return Err(unsupported(
                    m.span(op),
                    format!(
                        "recursive field `{field}` of `{variant}` is not a reference of the layout"
                    ),
                ));
            }
            replace_all_uses(m, *a, v);
        }
        m.blocks[block].args.clear();
        rd.layers.pop();
    }
    // The chain: if t1 { A1 } else { if t2 { A2 } else { ... } }.
    if chain.len() == 1 {
        let region = chain[0].1;
        let term = inline_region_before(m, region, op, &[]).expect("a structured arm");
        let t = &m.ops[term];
        if t.kind == OpKind::Tree(Op::Yield) {
            let vals: Vec<ValueId> = t.operands.to_vec();
            replace_op(m, op, &vals);
        } else {
            // The arm returns: it becomes the end of the enclosing block.
            let parent = m.ops[op].parent.expect("the match is placed");
            let pos = m.blocks[parent]
                .ops
                .iter()
                .position(|&o| o == op)
                .expect("listed");
            let dead: Vec<_> = m.blocks[parent].ops[pos..].to_vec();
            erase_op(m, term);
            for d in dead {
                erase_op(m, d);
            }
            m.ops[term].parent = Some(parent);
            m.blocks[parent].ops.push(term);
        }
        return Ok(());
    }
    let outer = build_chain(m, &chain, &result_tys);
    let mut bd = Builder::new(m);
    bd.set_insertion_point(InsertPoint::Before(op));
    bd.place(outer);
    let vals: Vec<ValueId> = m.ops[outer].results.to_vec();
    replace_op(m, op, &vals);
    Ok(())
}

/// A detached `tree.if` chain over `chain[..]` (at least two arms; the last is the final else).
fn build_chain(
    m: &mut Module,
    chain: &[(Option<ValueId>, scion_ir::RegionId, String)],
    results: &[TypeId],
) -> scion_ir::OpId {
    let (test, then, _) = chain[0];
    let else_region = if chain.len() == 2 {
        chain[1].1
    } else {
        let inner = build_chain(m, &chain[1..], results);
        let region = m.new_region();
        let block = m.add_block(region, &[]);
        let mut bd = Builder::at_end(m, block);
        bd.place(inner);
        let vals: Vec<ValueId> = bd.m.ops[inner].results.to_vec();
        bd.yield_(&vals);
        region
    };
    let cond = test.expect("every arm but the last has a test");
    let mut bd = Builder::new(m);
    bd.create(
        OpSpec::new(Op::If)
            .operands(&[cond])
            .results(results)
            .region(then)
            .region(else_region),
    )
}

/// Values used anywhere inside `op`'s regions (after aliases).
fn use_set(m: &Module, op: scion_ir::OpId) -> FxHashSet<ValueId> {
    let mut used = FxHashSet::default();
    for &r in &m.ops[op].regions {
        scion_ir::walk::walk_region(m, r, Order::Pre, &mut |o| {
            used.extend(m.ops[o].operands.iter().copied());
        });
    }
    used
}
