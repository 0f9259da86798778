//! `mem-to-lo`: lowers structured `tree` (and `mem`) functions to the `lo` dialect, a scalar SSA
//! control-flow graph (design note §5, paper §7.3). Input: a module whose traversal values are
//! no longer tree ADTs; output: a module of `lo` functions only.
//!
//! * **Control flow.** A `tree.if` becomes a `lo.cond_br` to two blocks and, when at least one
//!   arm yields, a join block whose arguments are the results (short-circuit `&&`/`||` are such
//!   `if`s); `tree.return` from any depth is a `lo.return`; `tree.foreach` over a fixed array is
//!   unrolled (its element count is in the type); a `tree.match` on a record runs its one arm.
//! * **Scalarization** (`mem_to_lo/flat.rs`): vectors, tuples, records (`Ray`, `AABB`, `Triangle`) and
//!   fixed arrays become their scalar leaves, as separate SSA values; function parameters and
//!   results of aggregate type are flattened the same way (a `(Ray, AABB) -> (f32, f32)`
//!   function takes 12 scalars and returns 2).
//! * **Mutable state.** A `!tree.ref<T>` is one `ptr` to memory holding a `T` laid out by
//!   [`flat::layout`]: a `mut` parameter is an in/out pointer the caller owns, a `tree.var` is a
//!   `lo.stack_slot` of the callee's frame; `tree.load`/`tree.store` are one scalar load/store
//!   per leaf at its offset.
//! * **Calls** stay calls (`lo.call` with flattened arguments); intrinsics become scalar ops per
//!   lane (`mem_to_lo/intrinsics.rs`).
//!
//! A `set[T]` that is only inserted into is a sink (`mem_to_lo/sets.rs`).
//!
//! Functions that cannot be lowered (sum ADTs not yet specialized, sets read other than by
//! `insert`, slices, options, and intrinsics without a scalar form) are a user error (E0970) naming the function and the
//! reason; with the option `mem-to-lo:partial=true` (what `scionc --emit=lo` uses for inputs
//! without a layout) they are dropped instead, with the functions that call them.

mod control;
mod flat;
mod intrinsics;
mod mem_ops;
mod opmap;
mod quant;
mod sets;

use opmap::{lo_of, unsigned};

pub use flat::{layout, leaves};

use rustc_hash::{FxHashMap, FxHashSet};
use scion_ir::attr::Attr;
use scion_ir::diag::{Diagnostic, Diagnostics, Span};
use scion_ir::entity::{BlockId, FuncId, OpId, TypeId, ValueId};
use scion_ir::lo::Op as L;
use scion_ir::op::OpKind;
use scion_ir::tree::{CmpPred, Intrinsic, Op as T};
use scion_ir::types::Type;
use scion_ir::{Builder, Module, OpSpec, Pass, PassCx, PassError};

/// The pass object.
pub struct MemToLo;

impl Pass for MemToLo {
    fn name(&self) -> &'static str {
        "mem-to-lo"
    }

    fn summary(&self) -> &'static str {
        "structured tree/mem functions to the lo CFG: scalarize aggregates, lower control flow"
    }

    fn run(&mut self, m: &mut Module, cx: &mut PassCx) -> Result<bool, PassError> {
        let partial = cx
            .option("mem-to-lo", "partial")
            .is_some_and(|v| v == "true");
        match lower_module(m, partial) {
            Ok((lo, skipped)) => {
                for (name, why) in skipped {
                    cx.diagnostics.push(
                        Diagnostic::warning(
                            "W0970",
                            format!("`@{name}` is not lowered to lo: {why}"),
                        )
                        .with_note("mem-to-lo:partial=true leaves it out (with its callers)"),
                    );
                }
                *m = lo;
                Ok(true)
            }
            Err((func, why, span)) => {
                let mut d =
                    Diagnostic::error("E0970", format!("cannot lower `@{func}` to lo: {why}"));
                if let Some(s) = span {
                    d = d.with_primary(s, "here");
                }
                let mut ds = Diagnostics::new();
                ds.push(d.with_note(
                    "mem-to-lo needs scalar, vector, tuple, record and fixed-array values; \
                     sum ADTs need destructor specialization first",
                ));
                Err(PassError::Diagnostics(ds))
            }
        }
    }
}

/// A failure: function name, reason, where.
pub type LowerError = (String, String, Option<Span>);

/// Lowers every function of `src` to `lo`. With `partial`, functions that cannot be lowered
/// (and their callers) are left out and listed with the reason; without, the first one is the
/// error.
pub fn lower_module(
    src: &Module,
    partial: bool,
) -> Result<(Module, Vec<(String, String)>), LowerError> {
    let mut failed: Vec<(String, String)> = Vec::new();
    loop {
        let skip: FxHashSet<&str> = failed.iter().map(|(n, _)| n.as_str()).collect();
        let mut dst = Module::new();
        let mut todo: Vec<(FuncId, FuncId)> = Vec::new();
        let mut new_failure = None;
        for &f in &src.func_order {
            let func = &src.funcs[f];
            if skip.contains(func.name.as_str()) {
                continue;
            }
            let sig = |tys: &[TypeId]| -> Result<Vec<Type>, String> {
                let mut out = Vec::new();
                for &t in tys {
                    out.extend(leaves(src, t)?);
                }
                Ok(out)
            };
            let (params, results) = match (sig(&func.params), sig(&func.results)) {
                (Ok(p), Ok(r)) => (p, r),
                (Err(e), _) | (_, Err(e)) => {
                    new_failure = Some((func.name.clone(), e, src.func_spans.get(f).copied()));
                    break;
                }
            };
            let p: Vec<TypeId> = params.into_iter().map(|t| dst.ty(t)).collect();
            let r: Vec<TypeId> = results.into_iter().map(|t| dst.ty(t)).collect();
            let g = if src.is_declaration(f) {
                dst.declare_func(&func.name, &p, &r)
            } else {
                let (g, _) = dst.add_func(&func.name, &p, &r);
                todo.push((f, g));
                g
            };
            dst.funcs[g].attrs = func.attrs.clone();
            // The ordering parameter's first leaf (parameters before it may have several).
            if let Some(k) = func.order_by() {
                let before: Result<Vec<Type>, String> =
                    sig(&func.params[..k.min(func.params.len())]);
                if let Ok(before) = before {
                    dst.funcs[g].set_order_by(before.len());
                }
            }
            if let Some(s) = src.func_spans.get(f) {
                dst.func_spans.insert(g, *s);
            }
        }
        if new_failure.is_none() {
            for (f, g) in todo {
                if let Err((why, span)) = lower_func(src, &mut dst, f, g) {
                    new_failure = Some((src.funcs[f].name.clone(), why, span));
                    break;
                }
            }
        }
        match new_failure {
            None => return Ok((dst, failed)),
            Some(e) if !partial => return Err(e),
            Some((name, why, _)) => failed.push((name, why)),
        }
    }
}

type R<T> = Result<T, (String, Option<Span>)>;

/// What lowering an op did to the current block.
enum Step {
    /// Go on with the next op in this block.
    Next(BlockId),
    /// The region yielded these leaves from this block.
    Yield(BlockId, Vec<ValueId>),
    /// The block was terminated (a return): the rest of the region is unreachable.
    Dead,
}

struct FnLower<'a> {
    src: &'a Module,
    dst: &'a mut Module,
    vals: FxHashMap<ValueId, Vec<ValueId>>,
    span: Option<Span>,
    /// Vector operations marked so far ([`FnLower::tag_lanes`]).
    lane_groups: u64,
}

fn lower_func(src: &Module, dst: &mut Module, f: FuncId, g: FuncId) -> R<()> {
    let (Some(tentry), Some(lentry)) = (src.entry_block(f), dst.entry_block(g)) else {
        return Err(("function has no body".into(), None));
    };
    let mut cx = FnLower {
        src,
        dst,
        vals: FxHashMap::default(),
        span: src.func_spans.get(f).copied(),
        lane_groups: 0,
    };
    let mut flat_args = cx.dst.blocks[lentry].args.iter().copied();
    let mut args = Vec::new();
    for &p in &src.funcs[f].params {
        let n = leaves(src, p).map_err(|e| (e, None))?.len();
        args.push(flat_args.by_ref().take(n).collect());
    }
    match cx.lower_block(tentry, args, lentry)? {
        None => Ok(()),
        Some(_) => Err(("function body ends with a yield".into(), None)),
    }
}

impl FnLower<'_> {
    fn err<X>(&self, msg: impl Into<String>) -> R<X> {
        Err((msg.into(), self.span))
    }

    fn lo_ty(&mut self, src_ty: TypeId) -> R<Vec<TypeId>> {
        let ls = leaves(self.src, src_ty).map_err(|e| (e, self.span))?;
        Ok(ls.into_iter().map(|t| self.dst.ty(t)).collect())
    }

    fn get(&self, v: ValueId) -> R<Vec<ValueId>> {
        match self.vals.get(&v) {
            Some(l) => Ok(l.clone()),
            None => self.err("a value is used before it is lowered"),
        }
    }

    fn insert(&mut self, cur: BlockId, spec: OpSpec) -> OpId {
        let mut b = Builder::at_end(self.dst, cur);
        b.set_span(self.span);
        b.insert(spec)
    }

    /// One `lo` op with one result.
    fn e1(&mut self, cur: BlockId, op: L, operands: &[ValueId], ty: TypeId) -> ValueId {
        let o = self.insert(cur, OpSpec::new(op).operands(operands).results(&[ty]));
        self.dst.ops[o].results[0]
    }

    fn ty_of(&self, v: ValueId) -> TypeId {
        self.dst.values[v].ty
    }

    fn int_const(&mut self, cur: BlockId, ty: TypeId, v: i128) -> ValueId {
        let o = self.insert(
            cur,
            OpSpec::new(L::Const)
                .results(&[ty])
                .attr("value", Attr::Int(v)),
        );
        self.dst.ops[o].results[0]
    }

    fn cmp(&mut self, cur: BlockId, pred: CmpPred, a: ValueId, b: ValueId) -> ValueId {
        let bt = self.dst.types.bool();
        let o = self.insert(
            cur,
            OpSpec::new(L::Cmp)
                .operands(&[a, b])
                .results(&[bt])
                .attr("pred", Attr::str(pred.name())),
        );
        self.dst.ops[o].results[0]
    }

    /// Lowers the ops of the structured block `tb`, whose arguments are `args` (leaves each),
    /// starting in the `lo` block `cur`. Returns where and what it yielded, or `None` when every
    /// path returned.
    fn lower_block(
        &mut self,
        tb: BlockId,
        args: Vec<Vec<ValueId>>,
        mut cur: BlockId,
    ) -> R<Option<(BlockId, Vec<ValueId>)>> {
        let src = self.src;
        let block = &src.blocks[tb];
        if block.args.len() != args.len() {
            return self.err("block argument count mismatch");
        }
        for (&a, l) in block.args.iter().zip(args) {
            self.vals.insert(a, l);
        }
        for &op in &block.ops {
            if let Some(s) = src.span(op) {
                self.span = Some(s);
            }
            match self.lower_op(op, cur)? {
                Step::Next(b) => cur = b,
                Step::Yield(b, vals) => return Ok(Some((b, vals))),
                Step::Dead => return Ok(None),
            }
        }
        self.err("structured block without a terminator")
    }

    fn lower_op(&mut self, op: OpId, cur: BlockId) -> R<Step> {
        let src = self.src;
        let o = &src.ops[op];
        let mut ins: Vec<Vec<ValueId>> = Vec::with_capacity(o.operands.len());
        for &v in &o.operands {
            ins.push(self.get(v)?);
        }
        let kind = match o.kind {
            OpKind::Tree(k) => k,
            OpKind::Lo(k) => return self.copy_lo(op, k, cur),
            OpKind::Mem(k) => return self.lower_mem(op, k, &ins, cur),
        };
        let res_ty = o.results.first().map(|&r| src.values[r].ty);
        let out: Vec<ValueId> = match kind {
            T::Const => {
                let ty = self.lo_ty(res_ty.unwrap_or_default_ty(self)?)?;
                let (Some(&ty), Some(value)) = (ty.first(), o.attr("value")) else {
                    return self.err("bad constant");
                };
                let c = self.insert(
                    cur,
                    OpSpec::new(L::Const)
                        .results(&[ty])
                        .attr("value", value.clone()),
                );
                vec![self.dst.ops[c].results[0]]
            }
            T::Add
            | T::Sub
            | T::Mul
            | T::Div
            | T::Rem
            | T::And
            | T::Or
            | T::Xor
            | T::Shl
            | T::Shr => {
                let lop = lo_of(kind);
                let (a, b) = (&ins[0], &ins[1]);
                let mut out = Vec::new();
                for (i, &x) in a.iter().enumerate() {
                    let y = if b.len() == 1 { b[0] } else { b[i] };
                    let ty = self.ty_of(x);
                    out.push(self.e1(cur, lop, &[x, y], ty));
                }
                out
            }
            T::Neg | T::BitNot | T::Not => {
                let lop = lo_of(kind);
                ins[0]
                    .clone()
                    .into_iter()
                    .map(|x| {
                        let ty = self.ty_of(x);
                        self.e1(cur, lop, &[x], ty)
                    })
                    .collect()
            }
            T::Cmp => {
                let pred = o.pred().ok_or(("bad predicate".to_string(), self.span))?;
                let (a, b) = (ins[0].clone(), ins[1].clone());
                a.iter()
                    .zip(&b)
                    .map(|(&x, &y)| self.cmp(cur, pred, x, y))
                    .collect()
            }
            T::Select => {
                let (c, a, b) = (ins[0].clone(), ins[1].clone(), ins[2].clone());
                let mut out = Vec::new();
                for i in 0..a.len() {
                    let ci = if c.len() == 1 { c[0] } else { c[i] };
                    let ty = self.ty_of(a[i]);
                    out.push(self.e1(cur, L::Select, &[ci, a[i], b[i]], ty));
                }
                out
            }
            T::Cast | T::Bitcast => {
                let lop = if kind == T::Cast { L::Cast } else { L::Bitcast };
                let tys = self.lo_ty(res_ty.unwrap_or_default_ty(self)?)?;
                if tys.len() != ins[0].len() {
                    return self.err("a bitcast between different lane counts has no lo form");
                }
                let a = ins[0].clone();
                a.iter()
                    .zip(tys)
                    .map(|(&x, ty)| {
                        if self.ty_of(x) == ty {
                            x
                        } else {
                            self.e1(cur, lop, &[x], ty)
                        }
                    })
                    .collect()
            }
            T::Tuple | T::Array | T::Vector => ins.concat(),
            T::Ctor => {
                if o.attr("variant").is_some() {
                    return self.err("a variant constructor needs a layout");
                }
                ins.concat()
            }
            T::Extract | T::Field | T::Lane => {
                let index = o.int_attr("index").unwrap_or(0) as usize;
                let agg = src.values[o.operands[0]].ty;
                let (start, len) = self.member_range(agg, index)?;
                ins[0][start..start + len].to_vec()
            }
            T::Insert => {
                let index = o.int_attr("index").unwrap_or(0) as usize;
                let agg = src.values[o.operands[0]].ty;
                let (start, len) = self.member_range(agg, index)?;
                let mut out = ins[0].clone();
                out.splice(start..start + len, ins[1].iter().copied());
                out
            }
            T::Index => match src.types.get(src.values[o.operands[0]].ty) {
                Type::View(elem) => self.index_view(cur, &ins[0], ins[1][0], *elem)?,
                _ => self.index(cur, o.operands[0], &ins[0], o.operands[1], ins[1][0])?,
            },
            T::Bits => self.bits(cur, op, &ins)?,
            T::Is | T::Slice => {
                return self.err(format!("`tree.{}` needs a layout", kind.mnemonic()))
            }
            T::This
            | T::BuildStore
            | T::BuildStoreBits
            | T::BuildChild
            | T::BuildLoad
            | T::ChildField
            | T::Append => {
                return self.err(format!(
                    "`tree.{}` needs constructor specialization first",
                    kind.mnemonic()
                ))
            }
            T::Call => {
                let callee = o.callee().unwrap_or("");
                let Some(g) = self.dst.func_by_name(callee) else {
                    return self.err(format!("calls `@{callee}`, which cannot be lowered"));
                };
                let results = self.dst.funcs[g].results.clone();
                let c = self.insert(
                    cur,
                    OpSpec::new(L::Call)
                        .operands(&ins.concat())
                        .results(&results)
                        .attr("callee", Attr::Sym(callee.to_string())),
                );
                let flat = self.dst.ops[c].results.to_vec();
                return self.bind_results(op, flat, cur);
            }
            T::Intrinsic
                if o.str_attr("name") == Some(Intrinsic::Len.name())
                    && o.operands.first().is_some_and(|&v| {
                        matches!(src.types.get(src.values[v].ty), Type::View(_))
                    }) =>
            {
                let ty = self.lo_ty(res_ty.unwrap_or_default_ty(self)?)?[0];
                let n = ins[0][1];
                vec![if self.ty_of(n) == ty {
                    n
                } else {
                    self.e1(cur, L::Cast, &[n], ty)
                }]
            }
            T::Intrinsic if o.str_attr("name") == Some(Intrinsic::Sort.name()) => {
                let n = match src.types.get(src.values[o.operands[0]].ty) {
                    Type::Array { len: Some(n), .. } => *n as usize,
                    _ => return self.err("`sort` of something other than a fixed array"),
                };
                intrinsics::sort(self, cur, &ins[0], n)?
            }
            T::Intrinsic if o.str_attr("name") == Some(Intrinsic::SetInsert.name()) => {
                let Type::Set(elem) = *src.types.get(src.values[o.operands[0]].ty) else {
                    return self.err("`set_insert` into something other than a set");
                };
                let (next, sink) = self.sink_insert(cur, &ins[0], &ins[1], elem)?;
                return self.bind_results(op, sink, next);
            }
            T::Intrinsic => {
                let intrinsic = Intrinsic::of(o).map_err(|e| (e, self.span))?;
                let ty = res_ty.unwrap_or_default_ty(self)?;
                let tys = self.lo_ty(ty)?;
                intrinsics::lower(self, cur, intrinsic, &ins, &tys)?
            }
            T::Var => {
                let ty = src.values[o.operands[0]].ty;
                let (size, align, offs) = layout(src, ty).map_err(|e| (e, self.span))?;
                let ptr = self.dst.ty(Type::Ptr);
                let s = self.insert(
                    cur,
                    OpSpec::new(L::StackSlot)
                        .results(&[ptr])
                        .attr("size", Attr::Int(size.max(1) as i128))
                        .attr("align", Attr::Int(align as i128)),
                );
                let slot = self.dst.ops[s].results[0];
                self.store_leaves(cur, slot, &offs, &ins[0]);
                vec![slot]
            }
            T::Load => {
                let pointee = self.pointee(o.operands[0])?;
                let (_, _, offs) = layout(src, pointee).map_err(|e| (e, self.span))?;
                let tys = self.lo_ty(pointee)?;
                let p = ins[0][0];
                offs.iter()
                    .zip(tys)
                    .map(|(&off, ty)| {
                        let l = self.insert(
                            cur,
                            OpSpec::new(L::Load)
                                .operands(&[p])
                                .results(&[ty])
                                .attr("offset", Attr::Int(off as i128)),
                        );
                        self.dst.ops[l].results[0]
                    })
                    .collect()
            }
            T::Store => {
                let pointee = self.pointee(o.operands[0])?;
                let (_, _, offs) = layout(src, pointee).map_err(|e| (e, self.span))?;
                self.store_leaves(cur, ins[0][0], &offs, &ins[1]);
                Vec::new()
            }
            T::Yield => return Ok(Step::Yield(cur, ins.concat())),
            T::Return => {
                self.insert(cur, OpSpec::new(L::Return).operands(&ins.concat()));
                return Ok(Step::Dead);
            }
            T::If => return self.lower_if(op, ins[0][0], cur),
            T::Match => return self.lower_match(op, &ins[0], cur),
            T::Foreach => return self.lower_foreach(op, &ins[0], cur),
        };
        if matches!(
            kind,
            T::Add
                | T::Sub
                | T::Mul
                | T::Div
                | T::Rem
                | T::And
                | T::Or
                | T::Xor
                | T::Shl
                | T::Shr
                | T::Neg
                | T::BitNot
                | T::Not
                | T::Cmp
                | T::Select
                | T::Cast
                | T::Bitcast
        ) || (kind == T::Intrinsic
            && matches!(Intrinsic::of(o), Ok(Intrinsic::Min | Intrinsic::Max)))
        {
            self.tag_lanes(cur, res_ty, &out);
        }
        self.bind_results(op, out, cur)
    }

    /// Marks the ops that compute the lanes of one four- or eight-lane vector operation (the last
    /// `out.len()` ops of `cur`, one per lane, in lane order) with `lane = [group, k, n]`, so that
    /// a backend with vector registers can emit them as one vector operation
    /// (`scion-llvm`'s `translate::groups`); the ops stay scalar `lo`, which every other pass and
    /// backend reads as before. Nothing is marked when a lane reuses an operand (a cast to the
    /// same type) or the ops are not the block's last ones.
    fn tag_lanes(&mut self, cur: BlockId, res_ty: Option<TypeId>, out: &[ValueId]) {
        let n = out.len();
        let vector = res_ty.is_some_and(
            |t| matches!(self.src.types.get(t), Type::Vector { lanes, .. } if *lanes as usize == n),
        );
        if !vector || !(n == 4 || n == 8) {
            return;
        }
        let ops = &self.dst.blocks[cur].ops;
        if ops.len() < n {
            return;
        }
        let last = ops[ops.len() - n..].to_vec();
        let defines = last
            .iter()
            .zip(out)
            .all(|(&o, &v)| self.dst.ops[o].results.as_slice() == [v]);
        if !defines {
            return;
        }
        let group = self.lane_groups;
        self.lane_groups += 1;
        for (k, &o) in last.iter().enumerate() {
            self.dst.ops[o].attrs.set(
                "lane",
                Attr::List(vec![
                    Attr::Int(group as i128),
                    Attr::Int(k as i128),
                    Attr::Int(n as i128),
                ]),
            );
        }
    }

    /// Splits the flat leaves `flat` over `op`'s results.
    fn bind_results(&mut self, op: OpId, flat: Vec<ValueId>, cur: BlockId) -> R<Step> {
        let results = self.src.ops[op].results.clone();
        let mut it = flat.into_iter();
        for r in results {
            let n = leaves(self.src, self.src.values[r].ty)
                .map_err(|e| (e, self.span))?
                .len();
            let l: Vec<ValueId> = it.by_ref().take(n).collect();
            if l.len() != n {
                return self.err("result leaf count mismatch");
            }
            self.vals.insert(r, l);
        }
        Ok(Step::Next(cur))
    }

    fn store_leaves(&mut self, cur: BlockId, ptr: ValueId, offs: &[u64], vals: &[ValueId]) {
        for (&off, &v) in offs.iter().zip(vals) {
            self.insert(
                cur,
                OpSpec::new(L::Store)
                    .operands(&[ptr, v])
                    .attr("offset", Attr::Int(off as i128)),
            );
        }
    }

    fn pointee(&self, r: ValueId) -> R<TypeId> {
        match self.src.types.get(self.src.values[r].ty) {
            Type::Ref(t) => Ok(*t),
            _ => self.err("load or store through a non-reference"),
        }
    }

    /// The leaf range (start, count) of member `index` of an aggregate type.
    fn member_range(&self, agg: TypeId, index: usize) -> R<(usize, usize)> {
        let src = self.src;
        let members: Vec<TypeId> = match src.types.get(agg) {
            Type::Tuple(e) => e.clone(),
            Type::Vector { elem, lanes } => vec![*elem; *lanes as usize],
            Type::Array { elem, len: Some(n) } => vec![*elem; *n as usize],
            Type::Adt(name) => match src.adt(name) {
                Some(d) => d.shared.iter().map(|f| f.ty).collect(),
                None => return self.err("unknown type"),
            },
            _ => return self.err("not an aggregate"),
        };
        let mut start = 0;
        for (i, &m) in members.iter().enumerate() {
            let n = leaves(src, m).map_err(|e| (e, self.span))?.len();
            if i == index {
                return Ok((start, n));
            }
            start += n;
        }
        self.err("member index out of range")
    }

    /// `tree.index` on a vector or fixed array: a constant index picks leaves; a dynamic one is
    /// a chain of selects (element 0 when out of range, where `tree` has no meaning).
    fn index(
        &mut self,
        cur: BlockId,
        container: ValueId,
        leaves_in: &[ValueId],
        idx_src: ValueId,
        idx: ValueId,
    ) -> R<Vec<ValueId>> {
        let src = self.src;
        let n = match src.types.get(src.values[container].ty) {
            Type::Vector { lanes, .. } => *lanes as usize,
            Type::Array { len: Some(n), .. } => *n as usize,
            _ => return self.err("index into a container without a fixed length"),
        };
        if n == 0 {
            return self.err("index into an empty array");
        }
        let k = leaves_in.len() / n;
        let constant = src
            .def_op(idx_src)
            .filter(|&d| src.ops[d].kind == OpKind::Tree(T::Const))
            .and_then(|d| src.ops[d].int_attr("value"));
        if let Some(c) = constant {
            let c = c as usize;
            if c >= n {
                return self.err("constant index out of range");
            }
            return Ok(leaves_in[c * k..(c + 1) * k].to_vec());
        }
        let it = self.ty_of(idx);
        let mut acc: Vec<ValueId> = leaves_in[..k].to_vec();
        for i in 1..n {
            let ci = self.int_const(cur, it, i as i128);
            let hit = self.cmp(cur, CmpPred::Eq, idx, ci);
            for j in 0..k {
                let ty = self.ty_of(acc[j]);
                acc[j] = self.e1(cur, L::Select, &[hit, leaves_in[i * k + j], acc[j]], ty);
            }
        }
        Ok(acc)
    }

    /// `tree.bits`: `(v >> lo) & mask` computed on the unsigned view, then converted.
    fn bits(&mut self, cur: BlockId, op: OpId, ins: &[Vec<ValueId>]) -> R<Vec<ValueId>> {
        let o = &self.src.ops[op];
        let (Some(lo), Some(hi)) = (o.int_attr("lo"), o.int_attr("hi")) else {
            return self.err("`tree.bits` with a dynamic range has no lo form yet");
        };
        let v = ins[0][0];
        let it = self.dst.types.as_int(self.ty_of(v));
        let Some(it) = it else {
            return self.err("`tree.bits` of a non-integer");
        };
        let width = it.bits() as i128;
        if !(0 <= lo && lo <= hi && hi <= width) {
            return self.err("bit range outside the operand");
        }
        let ut = self.dst.types.int(unsigned(it));
        let mut x = if ut == self.ty_of(v) {
            v
        } else {
            self.e1(cur, L::Bitcast, &[v], ut)
        };
        if lo > 0 {
            let s = self.int_const(cur, ut, lo);
            x = self.e1(cur, L::Shr, &[x, s], ut);
        }
        if hi - lo < width {
            let mask = self.int_const(cur, ut, (1i128 << (hi - lo)) - 1);
            x = self.e1(cur, L::And, &[x, mask], ut);
        }
        let rt = self.lo_ty(self.src.values[o.results[0]].ty)?[0];
        Ok(vec![if rt == ut {
            x
        } else {
            self.e1(cur, L::Cast, &[x], rt)
        }])
    }

    /// A `lo` op already in the input (hand-written mixed IR): copied with its operands mapped.
    fn copy_lo(&mut self, op: OpId, k: L, cur: BlockId) -> R<Step> {
        let o = &self.src.ops[op];
        if !o.successors.is_empty() || k.is_terminator() {
            return self.err("lo control flow inside a structured region");
        }
        let mut operands = Vec::new();
        for &v in &o.operands {
            let l = self.get(v)?;
            if l.len() != 1 {
                return self.err("a lo op takes scalars");
            }
            operands.push(l[0]);
        }
        let mut tys = Vec::new();
        for &r in &o.results {
            tys.extend(self.lo_ty(self.src.values[r].ty)?);
        }
        let mut spec = OpSpec::new(k).operands(&operands).results(&tys);
        spec.attrs = o.attrs.clone();
        let c = self.insert(cur, spec);
        let flat = self.dst.ops[c].results.to_vec();
        self.bind_results(op, flat, cur)
    }
}

trait OrTy {
    fn unwrap_or_default_ty(self, cx: &FnLower<'_>) -> R<TypeId>;
}

impl OrTy for Option<TypeId> {
    fn unwrap_or_default_ty(self, cx: &FnLower<'_>) -> R<TypeId> {
        match self {
            Some(t) => Ok(t),
            None => cx.err("op without a result"),
        }
    }
}
