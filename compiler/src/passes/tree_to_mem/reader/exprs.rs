//! Layout expressions (derived fields, group indexes, discriminants, keys) lowered to `tree`
//! and `mem` ops at the reader's insertion point: names, literals, operators, casts, slices of
//! global arrays and bit slices, indexes, calls (user functions, record and vector
//! constructors, builtins), fields and lanes, tuples and arrays.

use super::Reader;
use super::R;
use crate::layout::plan::BufferKind;
use crate::passes::tree_to_mem::{ir_type, unsupported};
use crate::syntax::ast::{BinaryOp, Expr, ExprKind, UnaryOp};
use scion_ir::attr::Attr;
use scion_ir::tree::{CmpPred, Intrinsic, Op};
use scion_ir::types::Type;
use scion_ir::{mem, FuncId, Module, OpSpec, TypeId, ValueId};

impl<'a> Reader<'a> {
    /// Lowers a layout expression (a derived field, a group index, a discriminant, a key).
    pub fn expr(
        &mut self,
        m: &mut Module,
        variant: &str,
        e: &Expr,
        want: Option<TypeId>,
    ) -> R<ValueId> {
        match &e.kind {
            ExprKind::Name(id) => {
                if let Some(i) = self.spec.model.component(&id.name) {
                    return self.components.get(i).copied().ok_or_else(|| {
                        unsupported(
                            Some(id.span),
                            format!(
                                "reference component `{}` where only the placed one is known (a \
                                 build places the first component; the others are the traversal's)",
                                id.name
                            ),
                        )
                    });
                }
                self.field(m, variant, &id.name)
            }
            ExprKind::Int(n) => {
                let t = want.unwrap_or_else(|| m.types.u32());
                Ok(self.builder(m, false).const_int(t, *n as i128))
            }
            ExprKind::Bool(v) => Ok(self.builder(m, false).const_bool(*v)),
            ExprKind::Binary { op, lhs, rhs } => {
                let (l, r) = if matches!(lhs.kind, ExprKind::Int(_)) {
                    let r = self.expr(m, variant, rhs, want)?;
                    let l = self.expr(m, variant, lhs, Some(m.values[r].ty))?;
                    (l, r)
                } else {
                    let l = self.expr(m, variant, lhs, want)?;
                    let r = self.expr(m, variant, rhs, Some(m.values[l].ty))?;
                    (l, r)
                };
                let (l, r) = self.unify(m, l, r);
                let mut bd = self.builder(m, false);
                let pred = |p| Some(p);
                let (kind, cmp) = match op {
                    BinaryOp::Add => (Op::Add, None),
                    BinaryOp::Sub => (Op::Sub, None),
                    BinaryOp::Mul => (Op::Mul, None),
                    BinaryOp::Div => (Op::Div, None),
                    BinaryOp::Rem => (Op::Rem, None),
                    BinaryOp::BitAnd | BinaryOp::And => (Op::And, None),
                    BinaryOp::BitOr | BinaryOp::Or => (Op::Or, None),
                    BinaryOp::BitXor => (Op::Xor, None),
                    BinaryOp::Shl => (Op::Shl, None),
                    BinaryOp::Shr => (Op::Shr, None),
                    BinaryOp::Eq => (Op::Cmp, pred(CmpPred::Eq)),
                    BinaryOp::Ne => (Op::Cmp, pred(CmpPred::Ne)),
                    BinaryOp::Lt => (Op::Cmp, pred(CmpPred::Lt)),
                    BinaryOp::Le => (Op::Cmp, pred(CmpPred::Le)),
                    BinaryOp::Gt => (Op::Cmp, pred(CmpPred::Gt)),
                    BinaryOp::Ge => (Op::Cmp, pred(CmpPred::Ge)),
                };
                Ok(match cmp {
                    Some(p) => bd.cmp(p, l, r),
                    None => bd.binary(kind, l, r),
                })
            }
            ExprKind::Unary { op, operand } => {
                let v = self.expr(m, variant, operand, want)?;
                let k = match op {
                    UnaryOp::Neg => Op::Neg,
                    UnaryOp::Not => Op::Not,
                    UnaryOp::BitNot => Op::BitNot,
                };
                Ok(self.builder(m, false).unary(k, v))
            }
            ExprKind::Cast { expr, ty } => {
                let v = self.expr(m, variant, expr, None)?;
                let Some(t) = ir_type(m, ty) else {
                    return Err(unsupported(Some(ty.span), "a cast to this type"));
                };
                Ok(self.builder(m, false).cast(v, t))
            }
            ExprKind::Slice { base, lo, hi } => {
                if let ExprKind::Name(id) = &base.kind {
                    if let Some((kind, elem)) = self.global_array(m, variant, &id.name) {
                        return self.view(m, variant, kind, elem, lo, hi);
                    }
                }
                let v = self.expr(m, variant, base, None)?;
                let (Some(a), Some(z)) = (const_int(lo), const_int(hi)) else {
                    return Err(unsupported(
                        Some(e.span),
                        "a bit slice with non-literal bounds",
                    ));
                };
                let t = m.values[v].ty;
                if m.types.as_int(t).is_none() || a >= z {
                    return Err(unsupported(
                        Some(e.span),
                        "a slice of something other than an integer or a global array",
                    ));
                }
                Ok(self.builder(m, false).bits(v, a as u32, z as u32, t))
            }
            ExprKind::Index { base, index } => {
                let ExprKind::Name(id) = &base.kind else {
                    return Err(unsupported(
                        Some(e.span),
                        "an index into something other than a global array",
                    ));
                };
                let Some((kind, elem)) = self.global_array(m, variant, &id.name) else {
                    return Err(unsupported(
                        Some(e.span),
                        "an index into something other than a global array",
                    ));
                };
                let i = self.expr(m, variant, index, None)?;
                let (base, stride) = self.buffer(m, &kind)?;
                Ok(self.load(m, base, Some(i), 0, stride, elem))
            }
            ExprKind::Call { callee, args } => self.call(m, variant, e, &callee.name, args),
            ExprKind::Field { base, name } => {
                let v = self.expr(m, variant, base, None)?;
                let mut bd = self.builder(m, false);
                let lane = match name.name.as_str() {
                    "x" => Some(0),
                    "y" => Some(1),
                    "z" => Some(2),
                    "w" => Some(3),
                    _ => None,
                };
                let r = match (bd.m.types.lanes(bd.value_type(v)), lane) {
                    (Some(_), Some(i)) => bd.lane(v, i),
                    _ => bd.field(v, &name.name),
                };
                r.ok_or_else(|| {
                    unsupported(Some(e.span), format!("field `{}` of this value", name.name))
                })
            }
            ExprKind::Tuple(items) => {
                let mut vals = Vec::new();
                for it in items {
                    vals.push(self.expr(m, variant, it, None)?);
                }
                Ok(self.builder(m, false).tuple(&vals))
            }
            ExprKind::Array(items) => {
                let mut vals: Vec<ValueId> = Vec::new();
                for it in items {
                    let want = vals.first().map(|&v| m.values[v].ty);
                    vals.push(self.expr(m, variant, it, want)?);
                }
                let Some(&first) = vals.first() else {
                    return Err(unsupported(Some(e.span), "an empty array"));
                };
                let elem = m.values[first].ty;
                let t = m.ty(Type::Array {
                    elem,
                    len: Some(vals.len() as u64),
                });
                Ok(self.builder(m, false).build1(Op::Array, &vals, t))
            }
            // The component that carries `x` (declared `c: T = parent.x`, or added for it).
            ExprKind::Parent(id) => {
                let model = &self.spec.model;
                let Some(i) = model
                    .components
                    .iter()
                    .position(|c| c.carried.as_ref().is_some_and(|x| x.name == id.name))
                else {
                    return Err(unsupported(
                        Some(id.span),
                        format!("`parent.{}` carried by no reference component", id.name),
                    ));
                };
                self.components.get(i).copied().ok_or_else(|| {
                    unsupported(
                        Some(id.span),
                        format!(
                            "`parent.{}` where only the placed component is known (a build \
                             places the first component; the carried ones are the traversal's)",
                            id.name
                        ),
                    )
                })
            }
            _ => Err(unsupported(Some(e.span), "this form of layout expression")),
        }
    }

    /// A call in a layout expression: a user function (`decode16(q, lo, s)`, called as is),
    /// a record constructor, a vector constructor (`f32x3(..)`) or a builtin whose result has
    /// its first argument's type (`fma`, `min`, `fadd_rd`, ...).
    fn call(
        &mut self,
        m: &mut Module,
        variant: &str,
        e: &Expr,
        callee: &str,
        args: &[Expr],
    ) -> R<ValueId> {
        if let Some(v) = self.user_call(m, variant, e, callee, args)? {
            return Ok(v);
        }
        let mut vals: Vec<ValueId> = Vec::new();
        for a in args {
            let want = vals.first().map(|&v| m.values[v].ty);
            vals.push(self.expr(m, variant, a, want)?);
        }
        if m.adt(callee).is_some_and(|a| a.is_record()) {
            let t = m.types.adt(callee);
            return Ok(self.builder(m, false).ctor(t, None, &vals));
        }
        if let Some(t) = vector_type(m, callee) {
            let elem = match m.types.get(t) {
                Type::Vector { elem, .. } => *elem,
                _ => t,
            };
            let vals: Vec<ValueId> = vals.into_iter().map(|v| self.convert(m, v, elem)).collect();
            return self
                .builder(m, false)
                .vector(&vals)
                .ok_or_else(|| unsupported(Some(e.span), "a vector constructor with mixed lanes"));
        }
        match vals.first() {
            Some(&first) => match Intrinsic::from_name(callee) {
                Some(i) if i.keeps_first_type() => {
                    let t = m.values[first].ty;
                    Ok(self.builder(m, false).intrinsic(i, &vals, t))
                }
                _ => Err(unsupported(
                    Some(e.span),
                    format!("a call of `{callee}` in a layout expression"),
                )),
            },
            _ => Err(unsupported(
                Some(e.span),
                format!("a call of `{callee}` in a layout expression"),
            )),
        }
    }

    /// A call of a user function of the program (its overloads are `callee`, `callee.1`, ...,
    /// sema's unique names): the one whose parameter types the arguments have, with integer
    /// literals taking the parameter's type. `None` when no function has that name.
    fn user_call(
        &mut self,
        m: &mut Module,
        variant: &str,
        e: &Expr,
        callee: &str,
        args: &[Expr],
    ) -> R<Option<ValueId>> {
        let is_overload = |name: &str| {
            name == callee
                || name.strip_prefix(callee).is_some_and(|rest| {
                    rest.strip_prefix('.')
                        .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
                })
        };
        let candidates: Vec<FuncId> = m
            .func_order
            .iter()
            .copied()
            .filter(|&f| is_overload(&m.funcs[f].name) && m.funcs[f].params.len() == args.len())
            .collect();
        if candidates.is_empty() {
            return Ok(None);
        }
        // Literals take the parameter type when every candidate agrees on it.
        let mut vals = Vec::new();
        for (k, a) in args.iter().enumerate() {
            let t0 = m.funcs[candidates[0]].params[k];
            let want = candidates
                .iter()
                .all(|&f| m.funcs[f].params[k] == t0)
                .then_some(t0);
            vals.push(self.expr(m, variant, a, want)?);
        }
        let tys: Vec<TypeId> = vals.iter().map(|&v| m.values[v].ty).collect();
        let Some(&f) = candidates.iter().find(|&&f| m.funcs[f].params == tys) else {
            let shown: Vec<String> = tys
                .iter()
                .map(|&t| m.types.display(t).to_string())
                .collect();
            return Err(unsupported(
                Some(e.span),
                format!(
                    "a call of `{callee}` with arguments ({}) that no overload takes",
                    shown.join(", ")
                ),
            ));
        };
        let name = m.funcs[f].name.clone();
        let results = m.funcs[f].results.clone();
        let [result] = results[..] else {
            return Err(unsupported(
                Some(e.span),
                format!("a call of `{callee}`, which returns no single value"),
            ));
        };
        let mut bd = self.builder(m, false);
        let op = bd.call(&name, &vals, &[result]);
        Ok(Some(bd.result(op, 0)))
    }

    /// `mem.view` of `array[lo : hi]`; when `hi` is written `lo + n` the length is `n` itself.
    fn view(
        &mut self,
        m: &mut Module,
        variant: &str,
        kind: BufferKind,
        elem: TypeId,
        lo: &Expr,
        hi: &Expr,
    ) -> R<ValueId> {
        let start = self.expr(m, variant, lo, None)?;
        let st = m.values[start].ty;
        let len = match (&lo.kind, &hi.kind) {
            (
                ExprKind::Name(a),
                ExprKind::Binary {
                    op: BinaryOp::Add,
                    lhs,
                    rhs,
                },
            ) if matches!(&lhs.kind, ExprKind::Name(b) if b.name == a.name) => {
                let n = self.expr(m, variant, rhs, Some(st))?;
                self.convert(m, n, st)
            }
            _ => {
                let end = self.expr(m, variant, hi, Some(st))?;
                let end = self.convert(m, end, st);
                self.builder(m, false).binary(Op::Sub, end, start)
            }
        };
        let (base, stride) = self.buffer(m, &kind)?;
        let vt = m.ty(Type::View(elem));
        let mut bd = self.builder(m, false);
        let op = bd.insert(
            OpSpec::new(mem::Op::View)
                .operands(&[base, start, len])
                .results(&[vt])
                .attr("stride", Attr::Int(stride as i128)),
        );
        Ok(bd.result(op, 0))
    }

    pub(super) fn convert(&mut self, m: &mut Module, v: ValueId, to: TypeId) -> ValueId {
        if m.values[v].ty == to {
            v
        } else {
            self.builder(m, false).cast(v, to)
        }
    }

    /// Widens the narrower of two integers to the wider one's type (sema's widening rule).
    fn unify(&mut self, m: &mut Module, l: ValueId, r: ValueId) -> (ValueId, ValueId) {
        let (lt, rt) = (m.values[l].ty, m.values[r].ty);
        match (m.types.as_int(lt), m.types.as_int(rt)) {
            (Some(a), Some(b)) if a != b => {
                if a.bits() >= b.bits() {
                    (l, self.convert(m, r, lt))
                } else {
                    (self.convert(m, l, rt), r)
                }
            }
            _ => (l, r),
        }
    }
}

/// The vector type a constructor name denotes (`f32x3`, `u16x3`).
fn vector_type(m: &mut Module, name: &str) -> Option<TypeId> {
    let pos = name.rfind('x')?;
    let lanes: u32 = name[pos + 1..].parse().ok()?;
    let elem = crate::passes::tree_to_mem::prim(&name[..pos])?;
    let e = m.ty(elem);
    Some(m.types.vector(e, lanes))
}

pub(in crate::passes::tree_to_mem) fn const_int(e: &Expr) -> Option<i128> {
    match e.kind {
        ExprKind::Int(n) => Some(n as i128),
        _ => None,
    }
}
