//! Statements: blocks, `let`, assignment, `return`, `if`, `match`, `foreach`.
//!
//! Every lowering function returns [`Flow`]: whether control can reach the next statement. A
//! block stops emitting after a statement that cannot fall through (a `return`).

use super::FuncCx;
use crate::sema::Resolution;
use crate::syntax::ast::{Expr, ExprKind, MatchArm, PatternKind, Stmt, StmtKind};
use scion_ir::attr::Attr;
use scion_ir::diag::InternalError;
use scion_ir::entity::{TypeId, ValueId};
use scion_ir::tree::{CmpPred, Op};
use scion_ir::types::Type;
use scion_ir::{Builder, OpSpec};

/// Whether control falls through a lowered statement.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Flow {
    /// The next statement runs.
    Next,
    /// The statement left the function.
    Returned,
}

/// The outcome of lowering in value mode.
enum Value {
    /// The statement produced this value.
    Some(ValueId),
    /// The statement left the function (every path returned).
    Returned,
}

impl FuncCx<'_> {
    /// Lowers the function body into the entry block and terminates it.
    pub(super) fn lower_body(
        &mut self,
        b: &mut Builder<'_>,
        body: &Stmt,
        results: &[TypeId],
    ) -> Result<(), InternalError> {
        if results.is_empty() {
            if self.stmt(b, body)? == Flow::Next {
                b.ret(&[]);
            }
        } else if let Value::Some(v) = self.value_stmt(b, body, results[0])? {
            b.ret(&[v]);
        }
        Ok(())
    }

    /// Lowers a statement whose value is not used.
    pub(super) fn stmt(&mut self, b: &mut Builder<'_>, s: &Stmt) -> Result<Flow, InternalError> {
        b.set_span(Some(s.span));
        match &s.kind {
            StmtKind::Expr(e) => {
                self.expr_effect(b, e)?;
                Ok(Flow::Next)
            }
            StmtKind::Assign { target, value } if self.build.is_some() => {
                self.build_assign(b, s, target, value)?;
                Ok(Flow::Next)
            }
            StmtKind::Assign { target, value } => {
                let v = self.expr(b, value)?;
                self.assign(b, target, v)?;
                Ok(Flow::Next)
            }
            StmtKind::Block(stmts) => {
                for st in stmts {
                    if self.stmt(b, st)? == Flow::Returned {
                        return Ok(Flow::Returned);
                    }
                }
                Ok(Flow::Next)
            }
            StmtKind::Return(e) => {
                let vals = match e {
                    Some(e) if !self.typed.expr_ty(e.id).is_unit() => vec![self.expr(b, e)?],
                    Some(e) => {
                        self.expr_effect(b, e)?;
                        vec![]
                    }
                    None => vec![],
                };
                b.set_span(Some(s.span));
                b.ret(&vals);
                Ok(Flow::Returned)
            }
            StmtKind::Let { value, mutable, .. } => {
                let v = self.expr(b, value)?;
                let binding = self.binder(s.id)?;
                let v = if *mutable { b.var(v) } else { v };
                self.locals.insert(binding, v);
                Ok(Flow::Next)
            }
            StmtKind::If {
                branches,
                otherwise,
            } => {
                self.if_chain(b, branches, otherwise.as_deref(), None)?;
                Ok(Flow::Next)
            }
            StmtKind::Match { scrutinee, arms } => {
                self.match_stmt(b, scrutinee, arms, None)?;
                Ok(Flow::Next)
            }
            StmtKind::Foreach { iter, body, .. } => {
                let arr = self.expr(b, iter)?;
                let binding = self.binder(s.id)?;
                let elem = match b.m.types.get(b.value_type(arr)) {
                    Type::Array { elem, .. } => *elem,
                    _ => return Err(self.bug("foreach over a non-array value")),
                };
                let index = self.typed.foreach_index.get(&s.id).copied();
                let u32t = b.m.types.u32();
                let arg_tys: &[TypeId] = if index.is_some() {
                    &[elem, u32t]
                } else {
                    &[elem]
                };
                let mut err = None;
                let region = b.region(arg_tys, |b, args| {
                    self.locals.insert(binding, args[0]);
                    if let Some(k) = index {
                        self.locals.insert(k, args[1]);
                    }
                    match self.stmt(b, body) {
                        Ok(Flow::Next) => {
                            b.yield_(&[]);
                        }
                        Ok(Flow::Returned) => {}
                        Err(e) => err = Some(e),
                    }
                });
                if let Some(e) = err {
                    return Err(e);
                }
                b.set_span(Some(s.span));
                b.insert(OpSpec::new(Op::Foreach).operands(&[arr]).region(region));
                Ok(Flow::Next)
            }
            StmtKind::Build { field, value } if self.build.is_some() => {
                self.build_stmt(b, s, field, value.as_ref())?;
                Ok(Flow::Next)
            }
            StmtKind::Build { .. } => Err(self.bug("a `build` statement inside a function")),
        }
    }

    /// Lowers a statement in value mode: its tail expression is the value of type `ty`.
    fn value_stmt(
        &mut self,
        b: &mut Builder<'_>,
        s: &Stmt,
        ty: TypeId,
    ) -> Result<Value, InternalError> {
        b.set_span(Some(s.span));
        match &s.kind {
            StmtKind::Expr(e) => Ok(Value::Some(self.expr(b, e)?)),
            StmtKind::Block(stmts) => {
                let Some((last, init)) = stmts.split_last() else {
                    return Err(self.bug("an empty block must produce a value"));
                };
                for st in init {
                    if self.stmt(b, st)? == Flow::Returned {
                        return Ok(Value::Returned);
                    }
                }
                self.value_stmt(b, last, ty)
            }
            StmtKind::Return(_) => {
                self.stmt(b, s)?;
                Ok(Value::Returned)
            }
            StmtKind::If {
                branches,
                otherwise,
            } => match self.if_chain(b, branches, otherwise.as_deref(), Some(ty))? {
                Some(v) => Ok(Value::Some(v)),
                None => Err(self.bug("a value `if` without a result")),
            },
            StmtKind::Match { scrutinee, arms } => {
                match self.match_stmt(b, scrutinee, arms, Some(ty))? {
                    Some(v) => Ok(Value::Some(v)),
                    None => Err(self.bug("a value `match` without a result")),
                }
            }
            _ => Err(self.bug("a statement that cannot produce the function's value")),
        }
    }

    /// Lowers a region body in statement or value mode and ends it with `tree.yield` when
    /// control falls through.
    fn region_body(
        &mut self,
        b: &mut Builder<'_>,
        s: &Stmt,
        result: Option<TypeId>,
    ) -> Result<(), InternalError> {
        match result {
            None => {
                if self.stmt(b, s)? == Flow::Next {
                    b.yield_(&[]);
                }
            }
            Some(ty) => {
                if let Value::Some(v) = self.value_stmt(b, s, ty)? {
                    b.yield_(&[v]);
                }
            }
        }
        Ok(())
    }

    /// `if c1 { } elif c2 { } else { }` as nested `tree.if`s; with `result`, each yields it.
    pub(super) fn if_chain(
        &mut self,
        b: &mut Builder<'_>,
        branches: &[(Expr, Stmt)],
        otherwise: Option<&Stmt>,
        result: Option<TypeId>,
    ) -> Result<Option<ValueId>, InternalError> {
        let Some(((cond, then), rest)) = branches.split_first() else {
            return Err(self.bug("`if` without a condition"));
        };
        let c = self.expr(b, cond)?;
        let mut err = None;
        let then_r = b.region(&[], |b, _| {
            if let Err(e) = self.region_body(b, then, result) {
                err = Some(e);
            }
        });
        let else_r = b.region(&[], |b, _| {
            let r = if !rest.is_empty() {
                self.if_chain(b, rest, otherwise, result).map(|v| {
                    if let Some(v) = v {
                        b.yield_(&[v]);
                    } else {
                        b.yield_(&[]);
                    }
                })
            } else if let Some(o) = otherwise {
                self.region_body(b, o, result)
            } else {
                b.yield_(&[]);
                Ok(())
            };
            if let Err(e) = r {
                err = Some(e);
            }
        });
        if let Some(e) = err {
            return Err(e);
        }
        b.set_span(Some(cond.span));
        let results: Vec<TypeId> = result.into_iter().collect();
        let op = b.insert(
            OpSpec::new(Op::If)
                .operands(&[c])
                .results(&results)
                .region(then_r)
                .region(else_r),
        );
        Ok(result.map(|_| b.result(op, 0)))
    }

    /// `match e { arms }` as `tree.match`, one region per arm.
    fn match_stmt(
        &mut self,
        b: &mut Builder<'_>,
        scrutinee: &Expr,
        arms: &[MatchArm],
        result: Option<TypeId>,
    ) -> Result<Option<ValueId>, InternalError> {
        let v = self.expr(b, scrutinee)?;
        let mut names = Vec::with_capacity(arms.len());
        let mut regions = Vec::with_capacity(arms.len());
        for arm in arms {
            let (name, arg_types): (String, Vec<TypeId>) = match &arm.pattern.kind {
                PatternKind::Variant { name, .. } => {
                    let adt =
                        b.m.adt_of_type(b.value_type(v))
                            .ok_or_else(|| self.bug("match on a non-ADT value"))?;
                    let fields = adt
                        .fields_of(Some(&name.name))
                        .ok_or_else(|| self.bug(format!("no variant `{}`", name.name)))?;
                    (name.name.clone(), fields.iter().map(|f| f.ty).collect())
                }
                PatternKind::Wildcard | PatternKind::Bind { .. } => ("_".to_string(), Vec::new()),
            };
            let mut err = None;
            let region = b.region(&arg_types, |b, args| {
                let r = self
                    .bind_pattern(arm, v, args)
                    .and_then(|_| self.region_body(b, &arm.body, result));
                if let Err(e) = r {
                    err = Some(e);
                }
            });
            if let Some(e) = err {
                return Err(e);
            }
            names.push(Attr::str(name));
            regions.push(region);
        }
        b.set_span(Some(scrutinee.span));
        let results: Vec<TypeId> = result.into_iter().collect();
        let mut spec = OpSpec::new(Op::Match)
            .operands(&[v])
            .results(&results)
            .attr("arms", Attr::List(names));
        for r in regions {
            spec = spec.region(r);
        }
        let op = b.insert(spec);
        Ok(result.map(|_| b.result(op, 0)))
    }

    fn bind_pattern(
        &mut self,
        arm: &MatchArm,
        scrutinee: ValueId,
        args: &[ValueId],
    ) -> Result<(), InternalError> {
        match &arm.pattern.kind {
            PatternKind::Wildcard => Ok(()),
            PatternKind::Bind { .. } => {
                let binding = self.binder(arm.pattern.id)?;
                self.locals.insert(binding, scrutinee);
                Ok(())
            }
            PatternKind::Variant { fields, .. } => {
                for (i, p) in fields.iter().enumerate() {
                    if let PatternKind::Bind { .. } = p.kind {
                        let binding = self.binder(p.id)?;
                        let arg = *args.get(i).ok_or_else(|| {
                            self.bug("pattern binds more fields than the variant has")
                        })?;
                        self.locals.insert(binding, arg);
                    }
                }
                Ok(())
            }
        }
    }

    fn binder(
        &self,
        id: crate::syntax::ast::NodeId,
    ) -> Result<crate::sema::BindingId, InternalError> {
        self.typed
            .binders
            .get(&id)
            .copied()
            .ok_or_else(|| self.bug("a binding without a binder"))
    }

    /// Stores `v` into an assignment target: a `mut` parameter, a `let mut` local, or a
    /// component of one (a tuple's, array's or vector's element, a vector's lane, a record's
    /// field, nested): the enclosing value is read, rebuilt with the component replaced, and
    /// assigned in turn. An array or vector element at an index that is not a literal is
    /// replaced lane by lane (`k == i ? v : old[i]`); an index out of range changes nothing.
    pub(super) fn assign(
        &mut self,
        b: &mut Builder<'_>,
        target: &Expr,
        v: ValueId,
    ) -> Result<(), InternalError> {
        match &target.kind {
            ExprKind::Name(_) => {
                let r = self.place_ref(target)?;
                b.build(Op::Store, &[r, v], &[]);
                Ok(())
            }
            ExprKind::Index { base, index } => {
                let old = self.expr(b, base)?;
                let at = match index.kind {
                    ExprKind::Int(i) => Component::At(i as i128),
                    _ => Component::Dynamic(self.expr(b, index)?),
                };
                b.set_span(Some(target.span));
                let new = self.replaced(b, old, at, v)?;
                self.assign(b, base, new)
            }
            ExprKind::Field { base, name } => {
                let old = self.expr(b, base)?;
                b.set_span(Some(target.span));
                let ty = b.value_type(old);
                let at = match b.m.types.get(ty) {
                    Type::Vector { .. } => match name.name.as_str() {
                        "x" => Component::At(0),
                        "y" => Component::At(1),
                        "z" => Component::At(2),
                        "w" => Component::At(3),
                        other => return Err(self.bug(format!("vector component `{other}`"))),
                    },
                    _ => Component::Field(name.name.clone()),
                };
                let new = self.replaced(b, old, at, v)?;
                self.assign(b, base, new)
            }
            _ => Err(self.bug("unsupported assignment target")),
        }
    }

    /// `old` with the component `at` replaced by `v`.
    fn replaced(
        &mut self,
        b: &mut Builder<'_>,
        old: ValueId,
        at: Component,
        v: ValueId,
    ) -> Result<ValueId, InternalError> {
        let ty = b.value_type(old);
        let u32t = b.m.types.u32();
        match (b.m.types.get(ty).clone(), at) {
            (Type::Tuple(_), Component::At(i)) => {
                let op = b.insert(
                    OpSpec::new(Op::Insert)
                        .operands(&[old, v])
                        .attr("index", Attr::Int(i))
                        .results(&[ty]),
                );
                Ok(b.result(op, 0))
            }
            (Type::Array { len: Some(len), .. }, at) => {
                let mut elems = Vec::with_capacity(len as usize);
                for i in 0..i128::from(len) {
                    let k = b.const_int(u32t, i);
                    let e = b.build1(Op::Index, &[old, k], b.value_type(v));
                    elems.push(self.pick(b, &at, i, v, e)?);
                }
                Ok(b.build1(Op::Array, &elems, ty))
            }
            (Type::Vector { lanes, .. }, at) => {
                let mut elems = Vec::with_capacity(lanes as usize);
                for i in 0..i128::from(lanes) {
                    let op = b.insert(
                        OpSpec::new(Op::Lane)
                            .operands(&[old])
                            .attr("index", Attr::Int(i))
                            .results(&[b.value_type(v)]),
                    );
                    let e = b.result(op, 0);
                    elems.push(self.pick(b, &at, i, v, e)?);
                }
                Ok(b.build1(Op::Vector, &elems, ty))
            }
            (Type::Adt(_), Component::Field(name)) => {
                let names: Vec<String> = match b.m.adt_of_type(ty) {
                    Some(adt) if adt.is_record() => {
                        adt.shared.iter().map(|f| f.name.clone()).collect()
                    }
                    _ => return Err(self.bug("assignment to a field of a sum's value")),
                };
                let mut fields = Vec::with_capacity(names.len());
                for f in &names {
                    fields.push(if *f == name {
                        v
                    } else {
                        b.field(old, f)
                            .ok_or_else(|| self.bug(format!("no field `{f}` to read")))?
                    });
                }
                Ok(b.ctor(ty, None, &fields))
            }
            _ => Err(self.bug("unsupported assignment target")),
        }
    }

    /// Element `i` of a rebuilt array or vector: `v` where `at` names it, else `old`.
    fn pick(
        &mut self,
        b: &mut Builder<'_>,
        at: &Component,
        i: i128,
        v: ValueId,
        old: ValueId,
    ) -> Result<ValueId, InternalError> {
        match at {
            Component::At(j) => Ok(if *j == i { v } else { old }),
            Component::Dynamic(k) => {
                let kt = b.value_type(*k);
                let c = b.const_int(kt, i);
                let hit = b.cmp(CmpPred::Eq, *k, c);
                Ok(b.select(hit, v, old))
            }
            Component::Field(_) => Err(self.bug("a field of an array or vector")),
        }
    }

    /// The reference (`!tree.ref<T>`) of the `mut` parameter or `let mut` local named by `e`.
    pub(super) fn place_ref(&self, e: &Expr) -> Result<ValueId, InternalError> {
        match self.typed.resolution(e.id) {
            Some(Resolution::Param(i))
                if self.typed.func(self.func).params[*i as usize].mutable =>
            {
                Ok(self.params[*i as usize])
            }
            Some(Resolution::Local(binding)) if self.is_cell(*binding) => self
                .locals
                .get(binding)
                .copied()
                .ok_or_else(|| self.bug("a `let mut` local used before its binding")),
            _ => Err(self.bug("expected a `mut` parameter or a `let mut` local")),
        }
    }

    /// Whether `binding` is a `let mut` local (held in a cell).
    pub(super) fn is_cell(&self, binding: crate::sema::BindingId) -> bool {
        self.typed
            .bindings
            .get(binding.0 as usize)
            .is_some_and(|b| b.mutable)
    }
}

/// Which component of a value an assignment replaces.
enum Component {
    /// Element or lane `i`, a literal.
    At(i128),
    /// The element at a computed index.
    Dynamic(ValueId),
    /// A record's field.
    Field(String),
}
