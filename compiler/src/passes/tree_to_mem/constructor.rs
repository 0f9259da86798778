//! `constructor-specialize` (paper §7.2): the packer of a layout, from its `build`.
//!
//! Input: the build functions irgen made for the chosen layout (`@L.build.<Variant>`,
//! `@L.build.root`, attribute `build_of = "L"`) and the [`LayoutSpec`]. Output:
//! * the build functions rewritten to `mem`: extra first parameters `(%tree: ptr, %B: ptr,
//!   %counter: !tree.ref<u32>, %cursor: !tree.ref<u32>, %status: !tree.ref<i32>)`; `tree.this`
//!   becomes the node's placement index (the counter, taken on entry for `order=pre`, after the
//!   last child is built for `order=post`), or its address `mem.addr` for pointer references;
//!   `tree.build_child` of an array of children calls `@L.node` for each slot in order and
//!   gives the array of their references (`tree.array`);
//!   `tree.build_store` a `mem.store` at the field's resolved path; `tree.build_child` a call of
//!   `@L.node`; `tree.append` a copy loop into the global array at the running cursor;
//! * `@L.node(%tree, %B, %i: u32, %counter, %cursor, %status) -> (R)`: reads logical node `%i`
//!   and calls the build function of its variant;
//! * `@L.sizes(%tree: ptr, %sizes: ptr)`: the byte size of every buffer (`u64` each, plan order);
//! * `@L.build(%tree: ptr, %B: ptr) -> (i32)`: writes the globals that size arrays, runs
//!   `build root`, builds the tree from its root and returns the status (0 = ok).
//!
//! `%tree` points to the C-ABI view of the logical tree (`docs/design/specialization.md` §3):
//! `LogicalTreeView { nodes: ptr @0, node_count: u32 @8, root: u32 @12, prims: ptr @16,
//! prim_count: u32 @24 }` (32 bytes); `LogicalNode` is 44 bytes (`kind` @0, `bounds` @4,
//! `child[2]` @28, `prim_offset` @36, `prim_count` @40), primitives are 40-byte `Triangle`s.
//! `this[a:b] = e` updates the returned reference and sets `%status` to 1 when the value does
//! not fit. Build functions of other layouts are removed. The logical tree is a binary BVH; an
//! ADT of another shape is reported (E0380).

use super::counters::{counter_slots, counter_type, CounterSlots, COUNTERS_ATTR};
use super::logical_nodes::{dispatch, load, Arm, Dispatch};
use super::reader::Reader;
use super::{spec_of, unsupported, LayoutSpec};
use crate::layout::logical::{LogicalAbi, LogicalField, Slot};
use crate::layout::model::GroupKind;
use crate::layout::plan::BufferKind;
use crate::layout::plan::Count;
use scion_ir::attr::Attr;
use scion_ir::diag::{Diagnostic, Diagnostics};
use scion_ir::module::ValueDef;
use scion_ir::rewrite::{erase_op, replace_all_uses};
use scion_ir::tree::{CmpPred, Op};
use scion_ir::types::Type;
use scion_ir::walk::{func_ops, Order};
use scion_ir::{
    mem, Builder, FuncId, InsertPoint, Module, OpKind, OpSpec, Pass, PassCx, PassError, TypeId,
    ValueId,
};

/// Byte offsets of `ScionTreeView`, the header `%tree` points to.
pub mod view {
    pub const NODES: u64 = 0;
    pub const NODE_COUNT: u64 = 8;
    pub const ROOT: u64 = 12;
    pub const PRIMS: u64 = 16;
    pub const PRIM_COUNT: u64 = 24;
}

/// The pass object.
#[derive(Default)]
pub struct ConstructorSpecialize;

impl Pass for ConstructorSpecialize {
    fn name(&self) -> &'static str {
        "constructor-specialize"
    }

    fn summary(&self) -> &'static str {
        "generate @L.sizes and @L.build, the packer of the layout, from its build (needs --layout)"
    }

    fn run(&mut self, m: &mut Module, cx: &mut PassCx) -> Result<bool, PassError> {
        let spec = spec_of(m, cx, self.name())?;
        specialize(m, spec).map_err(PassError::Diagnostics)
    }
}

/// The values every rewritten build function receives first.
#[derive(Clone, Copy)]
struct Ctx {
    tree: ValueId,
    b: ValueId,
    counter: ValueId,
    cursor: ValueId,
    status: ValueId,
}

/// Generates the packer of `spec`'s layout. Returns whether anything changed.
pub fn specialize(m: &mut Module, spec: &LayoutSpec) -> Result<bool, Diagnostics> {
    let lname = spec.model.name.name.clone();
    let mut ours = Vec::new();
    let mut changed = false;
    for f in m.func_order.clone() {
        match m.funcs[f].attrs.get("build_of").and_then(Attr::as_str) {
            Some(l) if l == lname => ours.push(f),
            Some(_) => {
                m.remove_func(f);
                changed = true;
            }
            None => {}
        }
    }
    if ours.is_empty() {
        return Ok(changed);
    }
    let mut diags = Diagnostics::default();
    for &f in &ours {
        if let Some(why) = m.funcs[f].attrs.get("unsupported").and_then(Attr::as_str) {
            let msg = format!(
                "the build of `{lname}` for `{}` uses what build functions cannot express: {why}",
                attr(m, f, "variant")
            );
            diags.push(unsupported(m.func_spans.get(f).copied(), msg));
        }
    }
    if diags.has_errors() {
        return Err(diags);
    }
    if let Err(d) = generate(m, spec, &ours) {
        diags.push(d);
        return Err(diags);
    }
    Ok(true)
}

fn attr(m: &Module, f: FuncId, key: &str) -> String {
    m.funcs[f]
        .attrs
        .get(key)
        .and_then(Attr::as_str)
        .unwrap_or_default()
        .to_string()
}

fn generate(m: &mut Module, spec: &LayoutSpec, ours: &[FuncId]) -> Result<(), Diagnostic> {
    let lname = spec.model.name.name.clone();
    let span = Some(spec.model.span);
    let model_adt = spec
        .model
        .adt
        .as_ref()
        .ok_or_else(|| unsupported(span, "a layout whose tree type is unknown"))?;
    let logical = LogicalAbi::derive(m, model_adt).map_err(|e| unsupported(span, e))?;
    let find = |v: &str| ours.iter().copied().find(|&f| attr(m, f, "variant") == v);
    // The variants a logical node can be: every interior one (the axis-aligned first), then
    // the leaf; each has its build function.
    let mut kinds: Vec<usize> = logical.interiors.clone();
    kinds.sort_by_key(|&k| k != logical.interior);
    kinds.push(logical.leaf);
    let mut arms_fns: Vec<(usize, FuncId)> = Vec::new();
    for &k in &kinds {
        let v = &logical.variants[k].0;
        let Some(f) = find(v) else {
            return Err(unsupported(
                span,
                format!("the build of `{lname}` has no function for `{v}` (a construct irgen cannot lower)"),
            ));
        };
        arms_fns.push((k, f));
    }
    let fi = arms_fns[0].1;
    let root_fn = find("root");
    let shared: Vec<LogicalField> = logical.variants[logical.interior].1[..logical.shared].to_vec();
    let stride = logical.node_size;
    let post = attr(m, fi, "order") == "post";
    let ref_ty = m.funcs[fi]
        .results
        .first()
        .copied()
        .ok_or_else(|| unsupported(span, "a variant build without a result"))?;
    let ptr = m.ty(Type::Ptr);
    let u32t = m.types.u32();
    let i32t = m.types.i32();
    let ru32 = m.types.reference(u32t);
    let ri32 = m.types.reference(i32t);
    let slots = counter_slots(spec);
    let rcounter = match counter_type(m, &slots) {
        Some(t) => m.types.reference(t),
        None => ru32,
    };
    let extra = [ptr, ptr, rcounter, ru32, ri32];
    // Declare @L.node first so that build functions can call it.
    let node_name = format!("{lname}.node");
    let node_params = [ptr, ptr, u32t, rcounter, ru32, ri32];
    let (node_fn, node_entry) = m.add_func(&node_name, &node_params, &[ref_ty]);
    m.func_spans.insert(node_fn, spec.model.span);
    m.funcs[node_fn]
        .attrs
        .set(COUNTERS_ATTR, Attr::Int(slots.count.max(1) as i128));
    // The variants whose builds place a node (take the next index of the shared counter):
    // every placement index stays below their count.
    let placing: Vec<String> = ours
        .iter()
        .map(|&f| (f, attr(m, f, "variant")))
        .filter(|(f, v)| v != "root" && places(m, spec, *f, v))
        .map(|(_, v)| v)
        .collect();
    for &f in ours {
        let variant = attr(m, f, "variant");
        let b = BuildShape {
            extra: &extra,
            node_name: &node_name,
            ref_ty,
            post,
            shared: &shared,
            stride,
            slots: &slots,
        };
        rewrite_build(m, spec, f, &variant, &b)?;
    }
    // @L.node: dispatch on the logical node's kind.
    {
        let args = m.blocks[node_entry].args.to_vec();
        let (tree, i) = (args[0], args[2]);
        let pass = [args[0], args[1], args[3], args[4], args[5]];
        let mut bd = Builder::at_end(m, node_entry);
        let nodes = load(&mut bd, tree, None, view::NODES, 0, ptr);
        let kind = load(&mut bd, nodes, Some(i), 0, stride, u32t);
        let prims = load(&mut bd, tree, None, view::PRIMS, 0, ptr);
        let arms: Vec<Arm> = arms_fns
            .iter()
            .map(|&(k, f)| Arm {
                kind: k as u32,
                name: bd.m.funcs[f].name.clone(),
                params: bd.m.funcs[f].params[5..].to_vec(),
                fields: logical.variants[k].1.clone(),
            })
            .collect();
        let cx = Dispatch {
            pass,
            nodes,
            prims,
            i,
            kind,
            stride,
            ref_ty,
        };
        let r = match dispatch(&mut bd, &cx, &arms) {
            Ok(r) => r,
            Err(e) => return Err(unsupported(span, e)),
        };
        bd.ret(&[r]);
    }
    // With a counter per indirect group a group's records are exactly its variants' nodes;
    // with one counter for all, any placing variant's node takes an index.
    let placing = if slots.count > 1 { Vec::new() } else { placing };
    super::entries::sizes_fn(m, spec, &lname, &logical, &placing)?;
    super::entries::build_fn(
        m, spec, &lname, &node_name, root_fn, ref_ty, &shared, stride,
    )?;
    if spec.model.components.len() > 1 {
        let full = super::destructor::reference_type(m, spec)
            .map_err(|e| unsupported(span, e.to_string()))?;
        super::entries::root_ref_fn(m, spec, &lname, full)?;
    }
    Ok(())
}

/// Whether build function `f` (of variant `variant`) places its node, taking the next index of
/// the counter: its variant has a record (every variant does in a layout with a group indexed
/// by the reference; in one with indirect groups, the variants whose split arms reach one), or
/// its build reads or writes its record. A variant realized by its reference alone (an
/// eight-wide leaf) places nothing: its `this` starts at 0 for `this[a:b] = e`.
fn places(m: &Module, spec: &LayoutSpec, f: FuncId, variant: &str) -> bool {
    let has_record = spec.plan.buffers.iter().any(|b| match &b.count {
        Count::Nodes { .. } => true,
        Count::VariantNodes { variants } => variants.iter().any(|v| v == variant),
        _ => false,
    });
    has_record
        || func_ops(m, f, Order::Pre)
            .iter()
            .any(|&o| matches!(m.ops[o].kind, OpKind::Tree(Op::BuildStore | Op::BuildLoad)))
}

/// What every build function of a layout shares.
struct BuildShape<'a> {
    /// The extra first parameters (`%tree`, `%B`, the counter, cursor and status cells).
    extra: &'a [TypeId],
    /// `@L.node`.
    node_name: &'a str,
    /// The placed reference's type.
    ref_ty: TypeId,
    /// `order=post`.
    post: bool,
    /// The logical node's shared fields (a child's `bounds`, read by `tree.child_field`).
    shared: &'a [LogicalField],
    /// Bytes per logical node.
    stride: u64,
    /// Which placement counter each variant takes its index from.
    slots: &'a CounterSlots,
}

/// Rewrites one build function in place (see the module docs).
fn rewrite_build(
    m: &mut Module,
    spec: &LayoutSpec,
    f: FuncId,
    variant: &str,
    shape: &BuildShape<'_>,
) -> Result<(), Diagnostic> {
    let (extra, node_name, ref_ty, post) = (shape.extra, shape.node_name, shape.ref_ty, shape.post);
    let span = m.func_spans.get(f).copied();
    let entry = m.entry_block(f).expect("build functions have bodies");
    // Extra parameters first; array parameters become views of the logical primitives.
    let mut new_args = Vec::new();
    for &t in extra {
        new_args.push(m.add_block_arg(entry, t));
    }
    let n = extra.len();
    let args = &mut m.blocks[entry].args;
    args.rotate_right(n);
    let args = args.clone();
    for (k, &a) in args.iter().enumerate() {
        m.values[a].def = ValueDef::BlockArg(entry, k as u32);
        if let Type::Array { elem, len: None } = m.types.get(m.values[a].ty).clone() {
            m.values[a].ty = m.ty(Type::View(elem));
        }
    }
    m.funcs[f].params = args.iter().map(|&a| m.values[a].ty).collect();
    let cx = Ctx {
        tree: args[0],
        b: args[1],
        counter: args[2],
        cursor: args[3],
        status: args[4],
    };
    let is_root = variant == "root";
    let variant = if is_root {
        spec.first_variant()
    } else {
        variant.to_string()
    };
    let ops = func_ops(m, f, Order::Pre);
    // Where `this` is taken: on entry (pre-order), or after the last top-level op that builds
    // a child (post-order).
    let body_ops = m.blocks[entry].ops.clone();
    let mut at = InsertPoint::Before(body_ops[0]);
    if post {
        for &o in &body_ops {
            let mut builds = false;
            if m.ops[o].kind == OpKind::Tree(Op::BuildChild) {
                builds = true;
            }
            for &r in &m.ops[o].regions {
                scion_ir::walk::walk_region(m, r, Order::Pre, &mut |x| {
                    if m.ops[x].kind == OpKind::Tree(Op::BuildChild) {
                        builds = true;
                    }
                });
            }
            if builds {
                at = InsertPoint::After(o);
            }
        }
        // Stores written before the children are built need `this`, known only after them:
        // they move (in order) to just after the last child build.
        if let InsertPoint::After(anchor) = at {
            let pos = body_ops.iter().position(|&o| o == anchor).unwrap_or(0);
            let mut early = Vec::new();
            for &o in &body_ops[..pos] {
                let needs_this = |k: OpKind| {
                    matches!(
                        k,
                        OpKind::Tree(Op::BuildStore | Op::BuildStoreBits | Op::This)
                    )
                };
                if needs_this(m.ops[o].kind) {
                    early.push(o);
                    continue;
                }
                let mut nested = false;
                for &r in &m.ops[o].regions {
                    scion_ir::walk::walk_region(m, r, Order::Pre, &mut |x| {
                        nested |= needs_this(m.ops[x].kind);
                    });
                }
                if nested {
                    return Err(unsupported(
                        m.span(o).or(span),
                        "in an `order=post` build, a store inside a branch before the last child is built",
                    ));
                }
            }
            if early
                .iter()
                .any(|&o| m.ops[o].kind == OpKind::Tree(Op::This))
            {
                return Err(unsupported(
                    span,
                    "in an `order=post` build, `this` used before the children are built",
                ));
            }
            for &o in early.iter().rev() {
                erase_op(m, o);
                let mut bd = Builder::new(m);
                bd.set_insertion_point(InsertPoint::After(anchor));
                bd.place(o);
            }
        }
    }
    // A node is placed (takes the next index of the counter) when it has a record (see
    // `places`); a variant realized by its reference alone places nothing, so indirect groups
    // hold exactly the records placed, and its `this` is 0 (what `this[a:b] = e` fills in).
    let this = if is_root {
        None
    } else if places(m, spec, f, &variant) {
        Some(take_this(
            m,
            spec,
            cx,
            at,
            ref_ty,
            shape.slots.slot_of(&variant),
        )?)
    } else if m.types.as_int(ref_ty).is_some() {
        let mut bd = Builder::new(m);
        bd.set_insertion_point(at);
        Some(bd.const_int(ref_ty, 0))
    } else {
        None
    };
    // With `this[a:b] = e` the reference is a cell starting as the placement value: `tree.this`
    // reads it, the bit stores update it. Stores into the node still use the placement value.
    let has_bits = ops
        .iter()
        .any(|&o| m.ops[o].kind == OpKind::Tree(Op::BuildStoreBits));
    let cell = match (this, has_bits) {
        (Some(t), true) => {
            if m.types.as_int(ref_ty).is_none() {
                return Err(unsupported(
                    span,
                    "`this[a:b] = e` with a reference that is not an integer",
                ));
            }
            let def = m.def_op(t).expect("`this` is computed by an op");
            let mut bd = Builder::new(m);
            bd.set_insertion_point(InsertPoint::After(def));
            Some(bd.var(t))
        }
        _ => None,
    };
    for op in ops {
        let kind = m.ops[op].kind;
        let field = m.ops[op].str_attr("field").unwrap_or_default().to_string();
        match kind {
            OpKind::Tree(Op::This) => {
                let Some(t) = this else {
                    return Err(unsupported(span, "`this` in `build root`"));
                };
                let r = m.ops[op].results[0];
                let t = match cell {
                    Some(c) => {
                        let mut bd = Builder::new(m);
                        bd.set_insertion_point(InsertPoint::Before(op));
                        bd.load(c).expect("a cell")
                    }
                    None => t,
                };
                replace_all_uses(m, r, t);
                erase_op(m, op);
            }
            OpKind::Tree(Op::BuildStoreBits) => {
                let Some(c) = cell else {
                    return Err(unsupported(
                        m.span(op).or(span),
                        "`this[a:b] = e` in `build root`",
                    ));
                };
                let lo = m.ops[op].int_attr("lo").unwrap_or(0);
                let hi = m.ops[op].int_attr("hi").unwrap_or(0);
                let v = m.ops[op].operands[0];
                store_bits(m, op, c, cx.status, v, lo, hi, ref_ty);
                erase_op(m, op);
            }
            OpKind::Tree(Op::BuildStore) => {
                let v = m.ops[op].operands[0];
                let mut rd = Reader::placing(spec, cx.b, this, InsertPoint::Before(op));
                rd.store_field(m, &variant, &field, v)?;
                erase_op(m, op);
            }
            OpKind::Tree(Op::BuildLoad) => {
                let mut rd = Reader::placing(spec, cx.b, this, InsertPoint::Before(op));
                let v = rd.field(m, &variant, &field)?;
                let old = m.ops[op].results[0];
                if m.values[old].ty != m.values[v].ty {
                    return Err(unsupported(
                        m.span(op).or(span),
                        format!("`{field}` read in a build with a type other than its stored one"),
                    ));
                }
                replace_all_uses(m, old, v);
                erase_op(m, op);
            }
            OpKind::Tree(Op::ChildField) => {
                let idx = m.ops[op].operands[0];
                let old = m.ops[op].results[0];
                let want = m.values[old].ty;
                let at = shape.shared.iter().find_map(|x| match x.slot {
                    Slot::Value { offset } if x.name == field && x.ty == want => Some(offset),
                    _ => None,
                });
                let Some(offset) = at else {
                    return Err(unsupported(
                        m.span(op).or(span),
                        format!(
                            "a child's field `{field}` in a build (a child's shared fields, such \
                             as its bounds, can be read)"
                        ),
                    ));
                };
                let ptr = m.ty(Type::Ptr);
                let u32t = m.types.u32();
                let mut bd = Builder::new(m);
                bd.set_insertion_point(InsertPoint::Before(op));
                let i = if bd.value_type(idx) == u32t {
                    idx
                } else {
                    bd.cast(idx, u32t)
                };
                let nodes = load(&mut bd, cx.tree, None, view::NODES, 0, ptr);
                let v = load(&mut bd, nodes, Some(i), offset, shape.stride, want);
                replace_all_uses(m, old, v);
                erase_op(m, op);
            }
            OpKind::Tree(Op::BuildChild) => {
                let idx = m.ops[op].operands[0];
                let mut bd = Builder::new(m);
                bd.set_insertion_point(InsertPoint::Before(op));
                let node = |bd: &mut Builder<'_>, i: ValueId| {
                    let c = bd.call(
                        node_name,
                        &[cx.tree, cx.b, i, cx.counter, cx.cursor, cx.status],
                        &[ref_ty],
                    );
                    bd.result(c, 0)
                };
                // An array of children: each built in slot order, their references an array.
                let r = match bd.m.types.get(bd.value_type(idx)).clone() {
                    Type::Array { elem, len: Some(n) } => {
                        let refs: Vec<ValueId> = (0..n)
                            .map(|k| {
                                let kv = bd.const_int(elem, k as i128);
                                let i = bd.build1(Op::Index, &[idx, kv], elem);
                                node(&mut bd, i)
                            })
                            .collect();
                        let t = bd.m.ty(Type::Array {
                            elem: ref_ty,
                            len: Some(n),
                        });
                        bd.build1(Op::Array, &refs, t)
                    }
                    _ => node(&mut bd, idx),
                };
                let old = m.ops[op].results[0];
                replace_all_uses(m, old, r);
                erase_op(m, op);
            }
            OpKind::Tree(Op::Append) => {
                let (data, count) = (m.ops[op].operands[0], m.ops[op].operands[1]);
                let rt = m.values[m.ops[op].results[0]].ty;
                let mut rd = Reader::placing(spec, cx.b, this, InsertPoint::Before(op));
                let (gbuf, stride, elem) = rd.array_of_field(m, &variant, &field)?;
                let u32t = m.types.u32();
                let mut bd = Builder::new(m);
                bd.set_insertion_point(InsertPoint::Before(op));
                let start = bd.load(cx.cursor).expect("cursor is a cell");
                let n = if bd.value_type(count) == u32t {
                    count
                } else {
                    bd.cast(count, u32t)
                };
                let next = bd.binary(Op::Add, start, n);
                bd.store(cx.cursor, next);
                let body = bd.region(&[elem, u32t], |bd, a| {
                    let at = bd.binary(Op::Add, start, a[1]);
                    bd.insert(
                        OpSpec::new(mem::Op::Store)
                            .operands(&[gbuf, at, a[0]])
                            .attr("offset", Attr::Int(0))
                            .attr("stride", Attr::Int(stride as i128)),
                    );
                    bd.yield_(&[]);
                });
                bd.insert(OpSpec::new(Op::Foreach).operands(&[data]).region(body));
                let r = if rt == u32t {
                    start
                } else {
                    bd.cast(start, rt)
                };
                let old = m.ops[op].results[0];
                replace_all_uses(m, old, r);
                erase_op(m, op);
            }
            _ => {}
        }
    }
    m.funcs[f]
        .attrs
        .set("build_of", Attr::str(spec.model.name.name.clone()));
    Ok(())
}

/// `this[lo:hi] = v` on the reference cell `c`: the bits are replaced by `v`'s low bits, and
/// `%status` becomes 1 when `v` does not fit in `hi - lo` bits.
#[allow(clippy::too_many_arguments)]
fn store_bits(
    m: &mut Module,
    at: scion_ir::OpId,
    c: ValueId,
    status: ValueId,
    v: ValueId,
    lo: i128,
    hi: i128,
    ref_ty: TypeId,
) {
    let i32t = m.types.i32();
    let bits = m.types.as_int(ref_ty).map_or(64, |t| t.bits() as i128);
    let all = if bits >= 127 { -1 } else { (1i128 << bits) - 1 };
    let width = hi - lo;
    let mut bd = Builder::new(m);
    bd.set_insertion_point(InsertPoint::Before(at));
    let v = if bd.value_type(v) == ref_ty {
        v
    } else {
        bd.cast(v, ref_ty)
    };
    let low_mask = if width >= bits {
        all
    } else {
        (1i128 << width) - 1
    };
    let low = bd.const_int(ref_ty, low_mask);
    let kept = bd.binary(Op::And, v, low);
    let fits = bd.cmp(CmpPred::Eq, kept, v);
    let old_status = bd.load(status).expect("status is a cell");
    let one = bd.const_int(i32t, 1);
    let new_status = bd.select(fits, old_status, one);
    bd.store(status, new_status);
    let old = bd.load(c).expect("a cell");
    let mask = bd.const_int(ref_ty, ((low_mask << lo) & all) ^ all);
    let cleared = bd.binary(Op::And, old, mask);
    let shift = bd.const_int(ref_ty, lo);
    let placed = bd.binary(Op::Shl, kept, shift);
    let new = bd.binary(Op::Or, cleared, placed);
    bd.store(c, new);
}

/// Takes the next placement index at `at`: `this` is the index, or the node's address for a
/// pointer-referenced group.
fn take_this(
    m: &mut Module,
    spec: &LayoutSpec,
    cx: Ctx,
    at: InsertPoint,
    ref_ty: TypeId,
    slot: Option<usize>,
) -> Result<ValueId, Diagnostic> {
    let u32t = m.types.u32();
    let mut bd = Builder::new(m);
    bd.set_insertion_point(at);
    let cell = bd.load(cx.counter).expect("counter is a cell");
    let one = bd.const_int(u32t, 1);
    let c = match slot {
        None => {
            let next = bd.binary(Op::Add, cell, one);
            bd.store(cx.counter, next);
            cell
        }
        // One counter per indirect group: component `k` of the counters' tuple.
        Some(k) => {
            let op = bd.insert(
                OpSpec::new(Op::Extract)
                    .operands(&[cell])
                    .attr("index", Attr::Int(k as i128))
                    .results(&[u32t]),
            );
            let c = bd.result(op, 0);
            let next = bd.binary(Op::Add, c, one);
            let tuple_ty = bd.value_type(cell);
            let op = bd.insert(
                OpSpec::new(Op::Insert)
                    .operands(&[cell, next])
                    .attr("index", Attr::Int(k as i128))
                    .results(&[tuple_ty]),
            );
            let new = bd.result(op, 0);
            bd.store(cx.counter, new);
            c
        }
    };
    if ref_ty == u32t {
        return Ok(c);
    }
    // Another integer reference (`R: u64` of the eight-wide L64 links): the placement index
    // converted.
    if m.types.as_int(ref_ty).is_some() {
        let mut bd = Builder::new(m);
        bd.set_insertion_point(at);
        return Ok(bd.cast(c, ref_ty));
    }
    if matches!(m.types.get(ref_ty), Type::Ptr) {
        let model = &spec.model;
        let Some(g) = model
            .groups
            .iter()
            .position(|g| g.kind == GroupKind::Pointer)
        else {
            return Err(unsupported(
                Some(model.span),
                "a pointer reference without a group indexed by it",
            ));
        };
        let kind = BufferKind::GroupArray { group: g, array: 0 };
        let mut rd = Reader::new(spec, cx.b, vec![], at);
        let (base, stride) = rd.buffer_base(m, &kind)?;
        let mut bd = Builder::new(m);
        bd.set_insertion_point(at);
        let ptr = bd.m.ty(Type::Ptr);
        let op = bd.insert(
            OpSpec::new(mem::Op::Addr)
                .operands(&[base, c])
                .results(&[ptr])
                .attr("offset", Attr::Int(0))
                .attr("stride", Attr::Int(stride as i128)),
        );
        return Ok(bd.result(op, 0));
    }
    Err(unsupported(
        Some(spec.model.span),
        "a reference type other than an integer or `ptr` in a build",
    ))
}
