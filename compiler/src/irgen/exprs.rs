//! Expressions: names, literals, calls and constructors, fields, indexing, slicing, operators,
//! casts.
//!
//! Every expression's type comes from `sema`'s side table; implicit widenings that `sema`
//! recorded become `tree.cast`s right after the operand is computed.

use super::FuncCx;
use crate::sema::{Builtin, Resolution};
use crate::syntax::ast::{BinaryOp, Expr, ExprKind, Item, UnaryOp};
use scion_ir::attr::Attr;
use scion_ir::diag::InternalError;
use scion_ir::entity::{TypeId, ValueId};
use scion_ir::tree::{CmpPred, Intrinsic, Op};
use scion_ir::types::Type;
use scion_ir::{Builder, OpSpec};

impl FuncCx<'_> {
    /// Lowers an expression for its effect only (a call whose result is unused).
    pub(super) fn expr_effect(
        &mut self,
        b: &mut Builder<'_>,
        e: &Expr,
    ) -> Result<(), InternalError> {
        if let ExprKind::Call { .. } = e.kind {
            self.call(b, e)?;
            return Ok(());
        }
        self.expr(b, e).map(|_| ())
    }

    /// Lowers an expression to the value it computes, widened where `sema` said so.
    pub(super) fn expr(&mut self, b: &mut Builder<'_>, e: &Expr) -> Result<ValueId, InternalError> {
        let v = self.expr_inner(b, e)?;
        match self.typed.widenings.get(&e.id) {
            Some(wide) => {
                let t = self.ty(b, wide)?;
                b.set_span(Some(e.span));
                Ok(b.build1(Op::Cast, &[v], t))
            }
            None => Ok(v),
        }
    }

    fn expr_ty(&mut self, b: &mut Builder<'_>, e: &Expr) -> Result<TypeId, InternalError> {
        let t = self.typed.expr_ty(e.id).clone();
        self.ty(b, &t)
    }

    fn expr_inner(&mut self, b: &mut Builder<'_>, e: &Expr) -> Result<ValueId, InternalError> {
        b.set_span(Some(e.span));
        match &e.kind {
            ExprKind::If {
                branches,
                otherwise,
            } => {
                let t = self.expr_ty(b, e)?;
                self.if_chain(b, branches, Some(otherwise), Some(t))?
                    .ok_or_else(|| self.bug("an `if` expression without a value"))
            }
            ExprKind::Name(id) => match self.typed.resolution(e.id) {
                Some(Resolution::Local(binding)) => {
                    let v = self.locals.get(binding).copied().ok_or_else(|| {
                        self.bug(format!("`{}` used before its binding", id.name))
                    })?;
                    if self.is_cell(*binding) {
                        let t = self.expr_ty(b, e)?;
                        Ok(b.build1(Op::Load, &[v], t))
                    } else {
                        Ok(v)
                    }
                }
                Some(Resolution::Param(i)) => {
                    let i = *i as usize;
                    let v = self.params[i];
                    if self.typed.func(self.func).params[i].mutable {
                        let t = self.expr_ty(b, e)?;
                        Ok(b.build1(Op::Load, &[v], t))
                    } else {
                        Ok(v)
                    }
                }
                Some(Resolution::LayoutMember(_)) if self.build.is_some() => {
                    let t = self.expr_ty(b, e)?;
                    let op = b.insert(
                        scion_ir::OpSpec::new(Op::BuildLoad)
                            .results(&[t])
                            .attr("field", scion_ir::attr::Attr::str(id.name.clone())),
                    );
                    Ok(b.result(op, 0))
                }
                Some(Resolution::BuildField(i)) if self.build.is_some() => self
                    .params
                    .get(*i as usize)
                    .copied()
                    .ok_or_else(|| self.bug(format!("build field `{}` out of range", id.name))),
                // A bare field-less variant is its constructor with no arguments (sema
                // resolves a bare variant with fields to E0234 instead).
                Some(Resolution::Variant(adt, v)) => {
                    let (adt, v) = (*adt, *v as usize);
                    let def = self
                        .typed
                        .adts
                        .get(adt)
                        .ok_or_else(|| self.bug("unknown sum"))?;
                    if !def.variant_fields(v).is_empty() {
                        return Err(self.bug(format!("bare variant `{}` with fields", id.name)));
                    }
                    let name = def.variants()[v].name.clone();
                    let t = self.expr_ty(b, e)?;
                    b.set_span(Some(e.span));
                    Ok(b.ctor(t, Some(&name), &[]))
                }
                other => Err(self.bug(format!("name `{}` resolved to {other:?}", id.name))),
            },
            ExprKind::Int(n) => {
                let t = self.expr_ty(b, e)?;
                match b.m.types.get(t) {
                    Type::Float(_) => Ok(b.const_float(t, *n as f64)),
                    _ => Ok(b.const_int(t, *n as i128)),
                }
            }
            ExprKind::Float(x) => {
                let t = self.expr_ty(b, e)?;
                Ok(b.const_float(t, *x))
            }
            ExprKind::Bool(v) => Ok(b.const_bool(*v)),
            ExprKind::Call { .. } => match self.call(b, e)? {
                Some(v) => Ok(v),
                None => Err(self.bug("the value of a call that returns nothing")),
            },
            ExprKind::Field { base, name } => {
                let v = self.expr(b, base)?;
                let t = self.expr_ty(b, e)?;
                let base_ty = b.value_type(v);
                // In a build, a logical child is its node index: its field is read from the
                // logical tree (`left.bounds`).
                if let Some(bc) = &self.build {
                    let adt = self.typed.layouts[bc.layout].adt;
                    let child = matches!(self.typed.expr_ty(base.id), crate::sema::Ty::Adt(a) if Some(*a) == adt);
                    if child && b.m.types.as_int(base_ty).is_some() {
                        let op = b.insert(
                            OpSpec::new(Op::ChildField)
                                .operands(&[v])
                                .attr("field", Attr::str(name.name.clone()))
                                .results(&[t]),
                        );
                        return Ok(b.result(op, 0));
                    }
                }
                if let Type::Vector { .. } = b.m.types.get(base_ty) {
                    let lane = match name.name.as_str() {
                        "x" => 0,
                        "y" => 1,
                        "z" => 2,
                        "w" => 3,
                        _ => return Err(self.bug(format!("vector component `{}`", name.name))),
                    };
                    let op = b.insert(
                        OpSpec::new(Op::Lane)
                            .operands(&[v])
                            .attr("index", Attr::Int(lane))
                            .results(&[t]),
                    );
                    return Ok(b.result(op, 0));
                }
                b.field(v, &name.name)
                    .ok_or_else(|| self.bug(format!("no field `{}` to read", name.name)))
            }
            ExprKind::Index { base, index } => {
                let v = self.expr(b, base)?;
                let t = self.expr_ty(b, e)?;
                let base_ty = b.value_type(v);
                let literal = match index.kind {
                    ExprKind::Int(i) => Some(i as i128),
                    _ => None,
                };
                match (b.m.types.get(base_ty), literal) {
                    (Type::Tuple(_), Some(i)) => {
                        let op = b.insert(
                            OpSpec::new(Op::Extract)
                                .operands(&[v])
                                .attr("index", Attr::Int(i))
                                .results(&[t]),
                        );
                        Ok(b.result(op, 0))
                    }
                    (Type::Vector { .. }, Some(i)) => {
                        let op = b.insert(
                            OpSpec::new(Op::Lane)
                                .operands(&[v])
                                .attr("index", Attr::Int(i))
                                .results(&[t]),
                        );
                        Ok(b.result(op, 0))
                    }
                    (Type::Tuple(_), None) => Err(self.bug("tuple index that is not a literal")),
                    _ => {
                        let i = self.expr(b, index)?;
                        b.set_span(Some(e.span));
                        Ok(b.build1(Op::Index, &[v, i], t))
                    }
                }
            }
            ExprKind::Slice { base, lo, hi } => {
                let v = self.expr(b, base)?;
                let t = self.expr_ty(b, e)?;
                let is_int = b.m.types.as_int(b.value_type(v)).is_some();
                if is_int {
                    if let (ExprKind::Int(l), ExprKind::Int(h)) = (&lo.kind, &hi.kind) {
                        let op = b.insert(
                            OpSpec::new(Op::Bits)
                                .operands(&[v])
                                .attr("lo", Attr::Int(*l as i128))
                                .attr("hi", Attr::Int(*h as i128))
                                .results(&[t]),
                        );
                        return Ok(b.result(op, 0));
                    }
                    let l = self.expr(b, lo)?;
                    let h = self.expr(b, hi)?;
                    b.set_span(Some(e.span));
                    return Ok(b.build1(Op::Bits, &[v, l, h], t));
                }
                let l = self.expr(b, lo)?;
                let h = self.expr(b, hi)?;
                b.set_span(Some(e.span));
                Ok(b.build1(Op::Slice, &[v, l, h], t))
            }
            ExprKind::Tuple(items) | ExprKind::Array(items) => {
                let mut vals = Vec::with_capacity(items.len());
                for it in items {
                    vals.push(self.expr(b, it)?);
                }
                let t = self.expr_ty(b, e)?;
                b.set_span(Some(e.span));
                let op = if matches!(e.kind, ExprKind::Array(_)) {
                    Op::Array
                } else {
                    Op::Tuple
                };
                Ok(b.build1(op, &vals, t))
            }
            ExprKind::Unary { op, operand } => {
                let v = self.expr(b, operand)?;
                let kind = match op {
                    UnaryOp::Neg => Op::Neg,
                    UnaryOp::Not => Op::Not,
                    UnaryOp::BitNot => Op::BitNot,
                };
                b.set_span(Some(e.span));
                Ok(b.unary(kind, v))
            }
            ExprKind::Binary { op, lhs, rhs } => self.binary(b, e, *op, lhs, rhs),
            ExprKind::Cast { expr, .. } | ExprKind::BitCast { expr, .. } => {
                let v = self.expr(b, expr)?;
                let t = self.expr_ty(b, e)?;
                if b.value_type(v) == t {
                    return Ok(v);
                }
                let kind = if matches!(e.kind, ExprKind::Cast { .. }) {
                    Op::Cast
                } else {
                    Op::Bitcast
                };
                b.set_span(Some(e.span));
                Ok(b.build1(kind, &[v], t))
            }
            ExprKind::This | ExprKind::Build(_) if self.build.is_some() => self.build_expr(b, e),
            ExprKind::This | ExprKind::Parent(_) | ExprKind::Build(_) => {
                Err(self.bug("a layout or build expression inside a function"))
            }
        }
    }

    fn binary(
        &mut self,
        b: &mut Builder<'_>,
        e: &Expr,
        op: BinaryOp,
        lhs: &Expr,
        rhs: &Expr,
    ) -> Result<ValueId, InternalError> {
        if matches!(op, BinaryOp::And | BinaryOp::Or) {
            return self.short_circuit(b, e, op, lhs, rhs);
        }
        let l = self.expr(b, lhs)?;
        let r = self.expr(b, rhs)?;
        b.set_span(Some(e.span));
        let pred = match op {
            BinaryOp::Eq => Some(CmpPred::Eq),
            BinaryOp::Ne => Some(CmpPred::Ne),
            BinaryOp::Lt => Some(CmpPred::Lt),
            BinaryOp::Le => Some(CmpPred::Le),
            BinaryOp::Gt => Some(CmpPred::Gt),
            BinaryOp::Ge => Some(CmpPred::Ge),
            _ => None,
        };
        if let Some(p) = pred {
            return Ok(b.cmp(p, l, r));
        }
        let kind = match op {
            BinaryOp::BitOr => Op::Or,
            BinaryOp::BitXor => Op::Xor,
            BinaryOp::BitAnd => Op::And,
            BinaryOp::Shl => Op::Shl,
            BinaryOp::Shr => Op::Shr,
            BinaryOp::Add => Op::Add,
            BinaryOp::Sub => Op::Sub,
            BinaryOp::Mul => Op::Mul,
            BinaryOp::Div => Op::Div,
            BinaryOp::Rem => Op::Rem,
            _ => return Err(self.bug(format!("operator `{}`", op.as_str()))),
        };
        let t = self.expr_ty(b, e)?;
        // A vector shifted by one amount: every lane by it (the IR shifts lane by lane).
        let lanes = b.m.types.lanes(b.value_type(l));
        let r = match (lanes, b.m.types.lanes(b.value_type(r))) {
            (Some(n), None) if matches!(kind, Op::Shl | Op::Shr) => b
                .vector(&vec![r; n as usize])
                .ok_or_else(|| self.bug("splat of a shift amount"))?,
            _ => r,
        };
        Ok(b.build1(kind, &[l, r], t))
    }

    /// `a && b` is `if a { b } else { false }`; `a || b` is `if a { true } else { b }`.
    fn short_circuit(
        &mut self,
        b: &mut Builder<'_>,
        e: &Expr,
        op: BinaryOp,
        lhs: &Expr,
        rhs: &Expr,
    ) -> Result<ValueId, InternalError> {
        let c = self.expr(b, lhs)?;
        let mut err = None;
        let mut eval_rhs = |b: &mut Builder<'_>| match self.expr(b, rhs) {
            Ok(v) => {
                b.yield_(&[v]);
            }
            Err(x) => err = Some(x),
        };
        let constant = |b: &mut Builder<'_>, v: bool| {
            let k = b.const_bool(v);
            b.yield_(&[k]);
        };
        let (then_r, else_r) = if op == BinaryOp::And {
            let t = b.region(&[], |b, _| eval_rhs(b));
            let f = b.region(&[], |b, _| constant(b, false));
            (t, f)
        } else {
            let t = b.region(&[], |b, _| constant(b, true));
            let f = b.region(&[], |b, _| eval_rhs(b));
            (t, f)
        };
        if let Some(x) = err {
            return Err(x);
        }
        let i1 = b.m.types.bool();
        b.set_span(Some(e.span));
        let op = b.insert(
            OpSpec::new(Op::If)
                .operands(&[c])
                .results(&[i1])
                .region(then_r)
                .region(else_r),
        );
        Ok(b.result(op, 0))
    }

    /// A call, constructor, builtin or conversion. Returns its value (`None` for a function
    /// that returns nothing).
    pub(super) fn call(
        &mut self,
        b: &mut Builder<'_>,
        e: &Expr,
    ) -> Result<Option<ValueId>, InternalError> {
        let ExprKind::Call { callee, args } = &e.kind else {
            return Err(self.bug("not a call"));
        };
        let res = self.typed.resolution(e.id).cloned();
        let t = self.expr_ty(b, e)?;
        match res {
            Some(Resolution::Func(fid)) => {
                let info = self.typed.func(fid).clone();
                let mut vals = Vec::with_capacity(info.params.len());
                for (i, p) in info.params.iter().enumerate() {
                    match args.get(i) {
                        Some(a) if p.mutable => vals.push(self.place_ref(a)?),
                        Some(a) => vals.push(self.expr(b, a)?),
                        None => vals.push(self.param_default(b, fid, i)?),
                    }
                }
                b.set_span(Some(e.span));
                let results: Vec<TypeId> = if self.typed.expr_ty(e.id).is_unit() {
                    vec![]
                } else {
                    vec![t]
                };
                let op = b.call(&info.unique_name, &vals, &results);
                Ok(b.m.ops[op].results.first().copied())
            }
            Some(Resolution::Builtin(Builtin::Append)) if self.build.is_some() => {
                self.append(b, e, args, t).map(Some)
            }
            Some(Resolution::Builtin(Builtin::Insert)) => {
                // insert(s, x) on a `mut set[T]` parameter: load, add, store back.
                let [set, x] = args.as_slice() else {
                    return Err(self.bug("insert takes 2 arguments"));
                };
                let r = self.place_ref(set)?;
                let v = self.expr(b, x)?;
                let set_ty = match b.m.types.get(b.value_type(r)) {
                    scion_ir::types::Type::Ref(t) => *t,
                    _ => return Err(self.bug("insert into a non-reference")),
                };
                b.set_span(Some(e.span));
                let old = b.build1(Op::Load, &[r], set_ty);
                let new = b.intrinsic(Intrinsic::SetInsert, &[old, v], set_ty);
                b.build(Op::Store, &[r, new], &[]);
                Ok(None)
            }
            Some(Resolution::Builtin(bi)) => {
                let mut vals = Vec::with_capacity(args.len());
                for a in args {
                    vals.push(self.expr(b, a)?);
                }
                b.set_span(Some(e.span));
                Ok(Some(self.builtin(b, bi, &vals, t)?))
            }
            Some(Resolution::Ctor(adt)) => {
                let def = self
                    .typed
                    .adts
                    .get(adt)
                    .ok_or_else(|| self.bug("unknown record"))?
                    .clone();
                let mut vals = Vec::with_capacity(def.fields.len());
                for (i, _) in def.fields.iter().enumerate() {
                    match args.get(i) {
                        Some(a) => vals.push(self.expr(b, a)?),
                        None => vals.push(self.field_default(b, adt, i)?),
                    }
                }
                b.set_span(Some(e.span));
                Ok(Some(b.ctor(t, None, &vals)))
            }
            Some(Resolution::Variant(adt, v)) => {
                let def = self
                    .typed
                    .adts
                    .get(adt)
                    .ok_or_else(|| self.bug("unknown sum"))?;
                let name = def.variants()[v as usize].name.clone();
                let mut vals = Vec::with_capacity(args.len());
                for a in args {
                    vals.push(self.expr(b, a)?);
                }
                b.set_span(Some(e.span));
                Ok(Some(b.ctor(t, Some(&name), &vals)))
            }
            Some(Resolution::VectorCtor(..)) => {
                let mut vals = Vec::with_capacity(args.len());
                for a in args {
                    vals.push(self.expr(b, a)?);
                }
                b.set_span(Some(e.span));
                Ok(Some(b.build1(Op::Vector, &vals, t)))
            }
            Some(Resolution::PrimConv(_)) => {
                let a = args
                    .first()
                    .ok_or_else(|| self.bug("conversion without an argument"))?;
                let v = self.expr(b, a)?;
                if b.value_type(v) == t {
                    return Ok(Some(v));
                }
                b.set_span(Some(e.span));
                Ok(Some(b.build1(Op::Cast, &[v], t)))
            }
            other => Err(self.bug(format!("call of `{}` resolved to {other:?}", callee.name))),
        }
    }

    fn builtin(
        &mut self,
        b: &mut Builder<'_>,
        bi: Builtin,
        vals: &[ValueId],
        t: TypeId,
    ) -> Result<ValueId, InternalError> {
        Ok(match bi {
            // clamp(x, lo, hi) = min(max(x, lo), hi), with the NaN rule of min and max.
            Builtin::Clamp => {
                let [x, lo, hi] = vals else {
                    return Err(self.bug("clamp takes 3 arguments"));
                };
                let m = b.intrinsic(Intrinsic::Max, &[*x, *lo], t);
                b.intrinsic(Intrinsic::Min, &[m, *hi], t)
            }
            Builtin::Select => {
                let [c, x, y] = vals else {
                    return Err(self.bug("select takes 3 arguments"));
                };
                b.build1(Op::Select, &[*c, *x, *y], t)
            }
            // any(m) / all(m): the lanes of `m` or-ed / and-ed, first lane first.
            Builtin::Any | Builtin::All => {
                let [m] = vals else {
                    return Err(self.bug("any/all take 1 argument"));
                };
                let mt = b.value_type(*m);
                let n = b.m.types.lanes(mt).unwrap_or(0);
                let fold = if bi == Builtin::Any { Op::Or } else { Op::And };
                let lane = |b: &mut Builder<'_>, k: u32| b.lane(*m, k);
                let mut acc = lane(b, 0).ok_or_else(|| self.bug("any/all of a non-vector"))?;
                for k in 1..n {
                    let x = lane(b, k).ok_or_else(|| self.bug("any/all of a non-vector"))?;
                    acc = b.build1(fold, &[acc, x], t);
                }
                acc
            }
            Builtin::Append => return Err(self.bug("`append` outside a build")),
            Builtin::Insert => return Err(self.bug("`insert` as a value")),
            Builtin::Intrinsic(i) => b.intrinsic(i, vals, t),
        })
    }

    /// The default argument of parameter `i` of `f`, evaluated at the call.
    fn param_default(
        &mut self,
        b: &mut Builder<'_>,
        f: crate::sema::FuncId,
        i: usize,
    ) -> Result<ValueId, InternalError> {
        let item = self.typed.func(f).item;
        let default = match self.program.items.get(item) {
            Some(Item::Func(d)) => d.params.get(i).and_then(|p| p.default.clone()),
            _ => None,
        };
        let d = default.ok_or_else(|| self.bug("missing argument without a default"))?;
        self.expr(b, &d)
    }

    /// The default value of field `i` of record `adt`, for a constructor call that omits it.
    fn field_default(
        &mut self,
        b: &mut Builder<'_>,
        adt: crate::sema::AdtId,
        i: usize,
    ) -> Result<ValueId, InternalError> {
        let item = self.typed.adts.get(adt).map(|d| d.item);
        let default = match item.and_then(|it| self.program.items.get(it)) {
            Some(Item::Type(d)) => d.fields.get(i).and_then(|f| f.default.clone()),
            _ => None,
        };
        let d = default.ok_or_else(|| self.bug("omitted field without a default"))?;
        self.expr(b, &d)
    }
}
