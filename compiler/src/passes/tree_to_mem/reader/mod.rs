//! Reading one node of a layout: the values of its fields (loads at resolved paths, derived
//! expressions, views of global arrays) and its variant tests (split predicates).
//!
//! A [`Reader`] serves one *destruction* (one `match` on a reference, or one field read). It
//! keeps a stack of [`Layer`]s: layer 0 sits just before the destructing op (buffer bases,
//! discriminants and shared fields go there), each further layer at the start of one arm. A name
//! is computed at most once per layer chain: every value is cached in the layer it was emitted
//! in and found again from any inner layer. The variant tests are in `predicates.rs`.

use super::{ir_type, unsupported, LayoutSpec};
use crate::layout::model::Storage;
use crate::layout::plan::BufferKind;
use crate::layout::resolve::{Dep, FieldPath, Index, ResolveError, Resolver, Step};
use crate::syntax::ast::ExprKind;
use rustc_hash::FxHashMap;
use scion_ir::attr::Attr;
use scion_ir::diag::Diagnostic;
use scion_ir::tree::Op;
use scion_ir::types::Type;
use scion_ir::{mem, Builder, InsertPoint, Module, OpSpec, TypeId, ValueId};

type R<T> = Result<T, Diagnostic>;

mod exprs;
pub(in crate::passes::tree_to_mem) use exprs::const_int;

/// One place values are emitted, with the values already emitted there.
pub(super) struct Layer {
    /// Where new ops go.
    pub point: InsertPoint,
    names: FxHashMap<String, ValueId>,
}

impl Layer {
    /// An empty layer inserting at `point`.
    pub fn new(point: InsertPoint) -> Layer {
        Layer {
            point,
            names: FxHashMap::default(),
        }
    }
}

/// Reads fields of the node a reference denotes.
pub(super) struct Reader<'a> {
    pub(super) spec: &'a LayoutSpec,
    resolver: Resolver<'a>,
    /// The layout instance `%B`.
    b: ValueId,
    /// The reference's components, in declaration order.
    components: Vec<ValueId>,
    /// Innermost last.
    pub layers: Vec<Layer>,
    /// Reading or writing the record a build places: its first component is the placed
    /// index itself (see [`Reader::placing`]).
    placing: bool,
}

impl<'a> Reader<'a> {
    /// A reader of the node `components` denotes, emitting its first values at `outer`.
    pub fn new(
        spec: &'a LayoutSpec,
        b: ValueId,
        components: Vec<ValueId>,
        outer: InsertPoint,
    ) -> Reader<'a> {
        Reader {
            spec,
            resolver: Resolver::new(&spec.model),
            b,
            components,
            layers: vec![Layer::new(outer)],
            placing: false,
        }
    }

    /// A reader of the node a build places, whose `this` is `this`. A record of an indirect
    /// group reached by a key over the reference (`AABBNode from aabb_nodes[I[5:64]]`) is the
    /// one at the placed index itself: the build returns a reference whose key gives that
    /// index (`this << 5`), which the compiler cannot invert.
    pub fn placing(
        spec: &'a LayoutSpec,
        b: ValueId,
        this: Option<ValueId>,
        outer: InsertPoint,
    ) -> Reader<'a> {
        let mut r = Reader::new(spec, b, this.into_iter().collect(), outer);
        r.placing = true;
        r
    }

    pub(super) fn lookup(&self, key: &str) -> Option<ValueId> {
        self.layers
            .iter()
            .rev()
            .find_map(|l| l.names.get(key).copied())
    }

    pub(super) fn remember(&mut self, key: String, v: ValueId, outer: bool) {
        let layer = if outer {
            self.layers.first_mut()
        } else {
            self.layers.last_mut()
        };
        if let Some(l) = layer {
            l.names.insert(key, v);
        }
    }

    pub(super) fn builder<'m>(&self, m: &'m mut Module, outer: bool) -> Builder<'m> {
        let layer = if outer {
            &self.layers[0]
        } else {
            &self.layers[self.layers.len() - 1]
        };
        let mut b = Builder::new(m);
        b.set_insertion_point(layer.point);
        b
    }

    /// The base address of buffer `kind` (emitted once, in layer 0).
    fn buffer(&mut self, m: &mut Module, kind: &BufferKind) -> R<(ValueId, u64)> {
        let Some(index) = self.spec.buffer_index(kind) else {
            return Err(unsupported(
                Some(self.spec.model.span),
                format!(
                    "layout `{}` has no buffer for {kind:?}",
                    self.spec.model.name.name
                ),
            ));
        };
        let buf = &self.spec.plan.buffers[index];
        let stride = buf.stride;
        let key = format!("#buffer{index}");
        if let Some(v) = self.lookup(&key) {
            return Ok((v, stride));
        }
        let name = buf.name.clone();
        let mut bd = self.builder(m, true);
        let p = bd.m.types.intern(Type::Ptr);
        let op = bd.insert(
            OpSpec::new(mem::Op::Buffer)
                .operands(&[self.b])
                .results(&[p])
                .attr("index", Attr::Int(index as i128))
                .attr("name", Attr::str(name)),
        );
        let v = bd.result(op, 0);
        self.remember(key, v, true);
        Ok((v, stride))
    }

    /// The value of logical field `name` of `variant` (a load, a derived value or a view).
    pub fn field(&mut self, m: &mut Module, variant: &str, name: &str) -> R<ValueId> {
        if let Some(v) = self.lookup(name) {
            return Ok(v);
        }
        let path = self
            .resolver
            .resolve(variant, name)
            .map_err(|e| resolve_error(self.spec, &e))?;
        let v = self.path_value(m, variant, name, &path)?;
        self.remember(name.to_string(), v, false);
        Ok(v)
    }

    /// The whole reference of recursive field `name` of `variant`. The layout's expression
    /// for it (`left = I + 1`) gives the components that are not tree-carried (one value, or
    /// a tuple of them in order); each carried component (`c = parent.x`) takes this node's
    /// value of `x`.
    pub fn child_ref(&mut self, m: &mut Module, variant: &str, name: &str) -> R<ValueId> {
        let v = self.field(m, variant, name)?;
        let comps = &self.spec.model.components;
        if comps.iter().all(|c| c.carried.is_none()) {
            return Ok(v);
        }
        let own = comps.iter().filter(|c| c.carried.is_none()).count();
        let span = Some(self.spec.model.span);
        if matches!(m.types.get(m.values[v].ty), Type::Array { .. }) {
            return Err(unsupported(
                span,
                format!("an array of children (`{name}`) in a layout with tree-carried components"),
            ));
        }
        let own_vals: Vec<ValueId> = if own == 1 {
            vec![v]
        } else {
            match m.types.get(m.values[v].ty) {
                Type::Tuple(es) if es.len() == own => {}
                _ => {
                    return Err(unsupported(
                        span,
                        format!(
                            "child `{name}` of `{variant}` gives no tuple of the {own} components \
                             that are not carried"
                        ),
                    ))
                }
            }
            let mut bd = self.builder(m, false);
            (0..own).filter_map(|k| bd.extract(v, k)).collect()
        };
        let carried: Vec<(usize, Option<String>)> = comps
            .iter()
            .enumerate()
            .map(|(k, c)| (k, c.carried.as_ref().map(|x| x.name.clone())))
            .collect();
        let mut own_iter = own_vals.into_iter();
        let mut vals = Vec::with_capacity(carried.len());
        for (_, x) in carried {
            let val = match x {
                None => own_iter.next().expect("one value per own component"),
                Some(x) => match self.spec.model.component(&x) {
                    Some(j) => self.components.get(j).copied().ok_or_else(|| {
                        unsupported(span, format!("component `{x}` unknown here"))
                    })?,
                    None => self.field(m, variant, &x)?,
                },
            };
            vals.push(val);
        }
        Ok(self.builder(m, false).tuple(&vals))
    }

    fn path_value(
        &mut self,
        m: &mut Module,
        variant: &str,
        name: &str,
        path: &FieldPath,
    ) -> R<ValueId> {
        let model = &self.spec.model;
        match path {
            FieldPath::Stored {
                member,
                steps,
                storage,
                ty,
                ..
            } => {
                let span = Some(model.members[*member].span);
                let Some(t) = ir_type(m, ty) else {
                    return Err(unsupported(
                        span,
                        format!("field `{name}` has a type the reader cannot load"),
                    ));
                };
                let (base, index, offset, stride) =
                    self.address(m, variant, steps, *storage, span)?;
                Ok(self.load(m, base, index, offset, stride, t))
            }
            FieldPath::Derived {
                member,
                value,
                deps,
                ..
            } => {
                for (id, dep) in deps {
                    let msg = match dep {
                        Dep::Unknown(_) => {
                            "a name of this derived field is on no route of the variant"
                        }
                        Dep::Ambiguous(_) => {
                            "a name of this derived field has several declarations"
                        }
                        _ => continue,
                    };
                    return Err(unsupported(Some(id.span), msg)
                        .with_note(format!("in derived field `{name}` of variant `{variant}`")));
                }
                let _ = member;
                // A literal takes the logical field's type (`nprims = 0` is a `u16`).
                let want = self.logical_scalar(m, variant, name);
                self.expr(m, variant, value, want)
            }
            FieldPath::Alternatives(cases) => {
                // The variant is realized by several arms that place the field differently:
                // read every placement (plain loads and pure expressions) and select by the
                // arms' tests, which are disjoint.
                let mut acc: Option<ValueId> = None;
                for (guards, path) in cases.iter().rev() {
                    if matches!(path, FieldPath::Alternatives(_)) {
                        return Err(unsupported(
                            None,
                            format!("field `{name}` of `{variant}`: nested alternatives"),
                        ));
                    }
                    let v = self.path_value(m, variant, name, path)?;
                    acc = Some(match acc {
                        None => v,
                        Some(other) => {
                            let mut test: Option<ValueId> = None;
                            for &(s, k) in guards {
                                let t = self.arm_test(m, s, k)?;
                                test = Some(match test {
                                    None => t,
                                    Some(a) => self.builder(m, true).binary(Op::And, a, t),
                                });
                            }
                            match test {
                                Some(t) => {
                                    if m.values[v].ty != m.values[other].ty {
                                        return Err(unsupported(
                                            None,
                                            format!("field `{name}` of `{variant}` has different types in different arms"),
                                        ));
                                    }
                                    self.builder(m, false).select(t, v, other)
                                }
                                None => v,
                            }
                        }
                    });
                }
                acc.ok_or_else(|| {
                    unsupported(
                        None,
                        format!("field `{name}` of `{variant}` has no placement"),
                    )
                })
            }
        }
    }

    fn load(
        &mut self,
        m: &mut Module,
        base: ValueId,
        index: Option<ValueId>,
        offset: u64,
        stride: u64,
        t: TypeId,
    ) -> ValueId {
        let mut bd = self.builder(m, false);
        let mut spec = OpSpec::new(mem::Op::Load)
            .results(&[t])
            .attr("offset", Attr::Int(offset as i128));
        match index {
            Some(i) => {
                spec = spec
                    .operands(&[base, i])
                    .attr("stride", Attr::Int(stride as i128));
            }
            None => spec = spec.operands(&[base]),
        }
        let op = bd.insert(spec);
        bd.result(op, 0)
    }

    /// Base, optional index, offset and stride of a stored field.
    fn address(
        &mut self,
        m: &mut Module,
        variant: &str,
        steps: &[Step],
        storage: Storage,
        span: Option<scion_ir::diag::Span>,
    ) -> R<(ValueId, Option<ValueId>, u64, u64)> {
        match storage {
            Storage::Globals { offset } => {
                let (base, _) = self.buffer(m, &BufferKind::Globals)?;
                Ok((base, None, offset, 0))
            }
            Storage::Element {
                group,
                array,
                offset,
            } => {
                let model = &self.spec.model;
                let n = steps.len();
                let Some(last) = steps.last().filter(|s| s.group == group) else {
                    return Err(unsupported(
                        span,
                        "a field path that does not end in its group",
                    ));
                };
                match &last.index {
                    Index::Key(e) if self.placing && self.over_components(e) => {
                        let idx = self.components.first().copied().ok_or_else(|| {
                            unsupported(span, "a placed record without its index")
                        })?;
                        let (base, stride) =
                            self.buffer(m, &BufferKind::GroupArray { group, array })?;
                        Ok((base, Some(idx), offset, stride))
                    }
                    Index::Value(e) | Index::Key(e) => {
                        let idx = self.expr(m, variant, e, None)?;
                        let (base, stride) =
                            self.buffer(m, &BufferKind::GroupArray { group, array })?;
                        Ok((base, Some(idx), offset, stride))
                    }
                    Index::Pointer(e) => {
                        if array != 0 {
                            return Err(unsupported(
                                span,
                                "`---` arrays of a pointer-indexed group",
                            ));
                        }
                        let p = self.expr(m, variant, e, None)?;
                        Ok((p, None, offset, 0))
                    }
                    Index::Tile { count } => {
                        let g = &model.groups[group];
                        let (Some((outer, outer_array, tile_off)), true) = (g.parent, n >= 2)
                        else {
                            return Err(unsupported(
                                span,
                                "a nested group without its outer group",
                            ));
                        };
                        let inner_stride = g.arrays[array].stride;
                        let key = format!("#tile{group}.{array}");
                        let slot_key = format!("#slot{group}");
                        if let (Some(a), Some(slot)) = (self.lookup(&key), self.lookup(&slot_key)) {
                            return Ok((a, Some(slot), offset, inner_stride));
                        }
                        let block_off = g.arrays[array].offset;
                        let count = *count;
                        let prev = steps[n - 2].clone();
                        let idx = match &prev.index {
                            Index::Value(e) | Index::Key(e) | Index::Pointer(e) => {
                                self.expr(m, variant, e, None)?
                            }
                            _ => {
                                return Err(unsupported(span, "groups nested more than one level"))
                            }
                        };
                        let it = m.values[idx].ty;
                        let c = self.builder(m, false).const_int(it, count as i128);
                        let (elem, slot) = {
                            let mut bd = self.builder(m, false);
                            (bd.binary(Op::Div, idx, c), bd.binary(Op::Rem, idx, c))
                        };
                        let addr_off = (tile_off + block_off) as i128;
                        let (obase, ostride) = if matches!(prev.index, Index::Pointer(_)) {
                            (idx, 0)
                        } else {
                            self.buffer(
                                m,
                                &BufferKind::GroupArray {
                                    group: outer,
                                    array: outer_array,
                                },
                            )?
                        };
                        let mut bd = self.builder(m, false);
                        let p = bd.m.types.intern(Type::Ptr);
                        let spec = if matches!(prev.index, Index::Pointer(_)) {
                            OpSpec::new(mem::Op::Addr).operands(&[obase])
                        } else {
                            OpSpec::new(mem::Op::Addr)
                                .operands(&[obase, elem])
                                .attr("stride", Attr::Int(ostride as i128))
                        };
                        let op = bd.insert(spec.results(&[p]).attr("offset", Attr::Int(addr_off)));
                        let a = bd.result(op, 0);
                        self.remember(key, a, false);
                        self.remember(slot_key, slot, false);
                        Ok((a, Some(slot), offset, inner_stride))
                    }
                    Index::Missing => Err(unsupported(span, "a group without `by`")),
                }
            }
            Storage::GlobalArray(_) => Err(unsupported(
                span,
                "a global array read whole (slice it, `a[lo : hi]`, or index it, `a[i]`)",
            )),
            Storage::None => Err(unsupported(span, "a field without storage")),
        }
    }

    /// Whether `e` reads only reference components (a key over the reference, `I[5:64]`).
    fn over_components(&self, e: &crate::syntax::ast::Expr) -> bool {
        crate::layout::resolve::names_in(e)
            .iter()
            .all(|id| self.spec.model.component(&id.name).is_some())
    }

    /// Stores `value` into stored field `name` of the node (constructor specialization).
    pub fn store_field(
        &mut self,
        m: &mut Module,
        variant: &str,
        name: &str,
        value: ValueId,
    ) -> R<()> {
        let path = self
            .resolver
            .resolve(variant, name)
            .map_err(|e| resolve_error(self.spec, &e))?;
        let FieldPath::Stored {
            member,
            steps,
            storage,
            ty,
            ..
        } = path
        else {
            return Err(unsupported(
                Some(self.spec.model.span),
                format!("`build {name}` of `{variant}` targets no single stored field"),
            ));
        };
        let span = Some(self.spec.model.members[member].span);
        let want = ir_type(m, &ty);
        let value = match want {
            Some(t) if t != m.values[value].ty => {
                if m.types.as_int(t).is_some() && m.types.as_int(m.values[value].ty).is_some() {
                    self.convert(m, value, t)
                } else {
                    return Err(unsupported(
                        span,
                        format!("`build {name}`: the value's type differs from the stored type"),
                    ));
                }
            }
            _ => value,
        };
        let (base, index, offset, stride) = self.address(m, variant, &steps, storage, span)?;
        let mut bd = self.builder(m, false);
        let mut spec = OpSpec::new(mem::Op::Store).attr("offset", Attr::Int(offset as i128));
        spec = match index {
            Some(i) => spec
                .operands(&[base, i, value])
                .attr("stride", Attr::Int(stride as i128)),
            None => spec.operands(&[base, value]),
        };
        bd.insert(spec);
        Ok(())
    }

    /// The global array behind logical array field `name` of `variant` (`data = primitives[..]`):
    /// its buffer base, stride and element type.
    pub fn array_of_field(
        &mut self,
        m: &mut Module,
        variant: &str,
        name: &str,
    ) -> R<(ValueId, u64, TypeId)> {
        let path = self
            .resolver
            .resolve(variant, name)
            .map_err(|e| resolve_error(self.spec, &e))?;
        // The global array the field slices; when several arms place the field (an empty
        // leaf's `primitives[0 : 0]` and the others), they must all slice the same one.
        let mut arrays: Vec<&str> = Vec::new();
        let paths: Vec<&FieldPath> = match &path {
            FieldPath::Alternatives(cases) => cases.iter().map(|(_, p)| p).collect(),
            p => vec![p],
        };
        for p in paths {
            if let FieldPath::Derived { value, .. } = p {
                if let ExprKind::Slice { base, .. } = &value.kind {
                    if let ExprKind::Name(id) = &base.kind {
                        arrays.push(&id.name);
                        continue;
                    }
                }
            }
            arrays.clear();
            break;
        }
        arrays.dedup();
        if let [array] = arrays[..] {
            let array = array.to_string();
            if let Some((kind, elem)) = self.global_array(m, variant, &array) {
                let (b, stride) = self.buffer(m, &kind)?;
                return Ok((b, stride, elem));
            }
        }
        Err(unsupported(
            Some(self.spec.model.span),
            format!("`append` to `{name}` of `{variant}`, which is no slice of a global array"),
        ))
    }

    /// The buffer base of `kind` (for `this` of pointer layouts and the globals).
    pub fn buffer_base(&mut self, m: &mut Module, kind: &BufferKind) -> R<(ValueId, u64)> {
        self.buffer(m, kind)
    }

    /// The global array a name denotes, if it does: its buffer kind and element type.
    fn global_array(
        &mut self,
        m: &mut Module,
        variant: &str,
        name: &str,
    ) -> Option<(BufferKind, TypeId)> {
        let path = self.resolver.resolve(variant, name).ok()?;
        let FieldPath::Stored {
            member,
            storage: Storage::GlobalArray(n),
            ..
        } = path
        else {
            return None;
        };
        let elem = ir_type(m, &self.spec.model.global_arrays[n].elem)?;
        Some((BufferKind::GlobalArray { member }, elem))
    }

    /// The type of logical field `name` of `variant` when it is a number (what a literal
    /// defining it becomes).
    fn logical_scalar(&self, m: &mut Module, variant: &str, name: &str) -> Option<TypeId> {
        let adt = self.spec.model.adt.as_ref()?;
        let f = adt
            .variant(variant)?
            .fields
            .iter()
            .find(|f| f.name.name == name && !f.recursive)?;
        let t = ir_type(m, &f.ty)?;
        matches!(m.types.get(t), Type::Int(_) | Type::Float(_)).then_some(t)
    }
}

fn resolve_error(spec: &LayoutSpec, e: &ResolveError) -> Diagnostic {
    let msg = match e {
        ResolveError::UnknownVariant(v) => {
            format!("layout `{}` has no variant `{v}`", spec.model.name.name)
        }
        ResolveError::Unrealized(v) => format!(
            "no split arm of layout `{}` realizes `{v}`",
            spec.model.name.name
        ),
        other => format!("no unique physical path: {other:?}"),
    };
    Diagnostic::error("E0381", msg).with_primary(spec.model.span, "in this layout")
}
