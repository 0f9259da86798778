//! Build functions (design note `docs/design/specialization.md` §1): each `build L` becomes one
//! `tree` function per variant, `@L.build.<Variant>`, and one for `build root`, `@L.build.root`.
//!
//! A variant's function takes the variant's logical fields (shared first; a recursive field as
//! the logical child's index `u32`, an array of `n` children as `u32[n]`, an array field as a
//! slice) and returns `this`, the layout's
//! reference. Its body uses the build ops of the tree dialect: `tree.this`, `tree.build_store
//! {field}` (`build x = e`, and `build x` copying logical field `x`), `tree.build_child {field}`
//! (`build x` of a recursive field, in statement or expression position) and `tree.append
//! {field}`. The root function takes the root's shared fields and returns nothing. Function
//! attributes: `build_of = "L"`, `variant` (or `"root"`), `order = "pre" | "post"`.
//! Constructor specialization (`passes::tree_to_mem::constructor`) turns them into stores.
//!
//! A build whose body uses something these functions cannot express (a layout member read
//! inside the build, such as a global set by `build root`) becomes a declaration with an
//! `unsupported` attribute saying why; constructor specialization reports it.

use super::types::TypeMap;
use super::FuncCx;
use crate::sema::{FuncId, Ty, TypedProgram};
use crate::syntax::ast::{BuildOrder, Expr, ExprKind, Ident, Item, Program, Stmt, StmtKind};
use rustc_hash::FxHashMap;
use scion_ir::attr::Attr;
use scion_ir::diag::InternalError;
use scion_ir::tree::Op;
use scion_ir::{Builder, Module, OpSpec, TypeId, ValueId};

/// What a [`FuncCx`] knows while lowering a build function.
pub(super) struct BuildCx {
    /// The function's name (for messages).
    pub name: String,
    /// The layout's reference type.
    pub this_ty: TypeId,
    /// Logical field names, by index.
    pub fields: Vec<String>,
    /// The layout (index in `typed.layouts`).
    pub layout: usize,
}

/// Adds the build functions of every `build` of `program`.
pub(super) fn generate_builds(
    m: &mut Module,
    tys: &mut TypeMap,
    program: &Program,
    typed: &TypedProgram,
) -> Result<(), InternalError> {
    for info in &typed.builds {
        let (Some(layout), Some(Item::Build(decl))) = (info.layout, program.items.get(info.item))
        else {
            continue;
        };
        let linfo = &typed.layouts[layout.0 as usize];
        let lname = linfo.name.clone();
        let this_ty = tys.lower(m, typed, &linfo.build_ref_ty)?;
        let order = match decl.order {
            BuildOrder::Pre => "pre",
            BuildOrder::Post => "post",
        };
        let adt = linfo.adt;
        let u32t = m.types.u32();
        let lower_field =
            |m: &mut Module, tys: &mut TypeMap, t: &Ty| -> Result<TypeId, InternalError> {
                match t {
                    Ty::Adt(a) if Some(*a) == adt => Ok(u32t),
                    // An array of children: the children's logical indices.
                    Ty::Array(e, n) if matches!(&**e, Ty::Adt(a) if Some(*a) == adt) => {
                        Ok(m.ty(scion_ir::types::Type::Array {
                            elem: u32t,
                            len: Some(*n),
                        }))
                    }
                    _ => tys.lower(m, typed, t),
                }
            };
        if let Some(root) = &decl.root {
            let shared: Vec<(String, Ty)> = adt
                .and_then(|a| typed.adts.get(a))
                .map(|d| {
                    d.fields
                        .iter()
                        .map(|f| (f.name.clone(), f.ty.clone()))
                        .collect()
                })
                .unwrap_or_default();
            let mut params = Vec::new();
            for (_, t) in &shared {
                params.push(lower_field(m, tys, t)?);
            }
            let name = format!("{lname}.build.root");
            let names = shared.into_iter().map(|(n, _)| n).collect();
            let body = block(&root.body, root.span);
            let attrs = [
                ("build_of", lname.as_str()),
                ("variant", "root"),
                ("order", order),
            ];
            one(
                m,
                tys,
                program,
                typed,
                &name,
                &params,
                &[],
                names,
                this_ty,
                layout.0 as usize,
                &body,
                &attrs,
            );
        }
        for v in &info.variants {
            let Some(bv) = decl.variants.get(v.entry) else {
                continue;
            };
            let mut params = Vec::new();
            for (_, t) in &v.fields {
                params.push(lower_field(m, tys, t)?);
            }
            let name = format!("{lname}.build.{}", bv.name.name);
            let names = v.fields.iter().map(|(n, _)| n.clone()).collect();
            let body = block(&bv.body, bv.span);
            let attrs = [
                ("build_of", lname.as_str()),
                ("variant", bv.name.name.as_str()),
                ("order", order),
            ];
            one(
                m,
                tys,
                program,
                typed,
                &name,
                &params,
                &[this_ty],
                names,
                this_ty,
                layout.0 as usize,
                &body,
                &attrs,
            );
        }
    }
    Ok(())
}

/// A block statement holding `stmts` (the body of a build entry).
fn block(stmts: &[Stmt], span: scion_ir::diag::Span) -> Stmt {
    Stmt {
        id: crate::syntax::ast::NodeId(u32::MAX),
        kind: StmtKind::Block(stmts.to_vec()),
        span,
    }
}

/// Lowers one build function; drops it when its body cannot be expressed.
#[allow(clippy::too_many_arguments)]
fn one(
    m: &mut Module,
    tys: &mut TypeMap,
    program: &Program,
    typed: &TypedProgram,
    name: &str,
    params: &[TypeId],
    results: &[TypeId],
    fields: Vec<String>,
    this_ty: TypeId,
    layout: usize,
    body: &Stmt,
    attrs: &[(&str, &str)],
) {
    let (fid, entry) = m.add_func(name, params, results);
    m.func_spans.insert(fid, body.span);
    for (k, v) in attrs {
        m.funcs[fid].attrs.set(k, Attr::str(*v));
    }
    let args: Vec<ValueId> = m.blocks[entry].args.to_vec();
    let mut b = Builder::at_end(m, entry);
    let mut cx = FuncCx {
        program,
        typed,
        tys,
        func: FuncId(u32::MAX),
        params: args,
        locals: FxHashMap::default(),
        build: Some(BuildCx {
            name: name.to_string(),
            this_ty,
            fields,
            layout,
        }),
    };
    let ok = if results.is_empty() {
        cx.lower_body(&mut b, body, results)
    } else {
        // The body ends in `return this;`; a body that falls off the end returns `this`.
        match cx.stmt(&mut b, body) {
            Ok(super::stmts::Flow::Next) => {
                let this = b.build1(Op::This, &[], this_ty);
                b.ret(&[this]);
                Ok(())
            }
            Ok(super::stmts::Flow::Returned) => Ok(()),
            Err(e) => Err(e),
        }
    };
    if let Err(e) = ok {
        // Keep the signature as a declaration that says why it has no body; constructor
        // specialization reports it for the chosen layout.
        let body = m.funcs[fid].body;
        m.regions[body].blocks.clear();
        let why = e
            .message
            .split_once(": ")
            .map_or(e.message.clone(), |(_, w)| w.to_string());
        m.funcs[fid].attrs.set("unsupported", Attr::str(why));
    }
}

impl FuncCx<'_> {
    fn build_cx(&self) -> Result<&BuildCx, InternalError> {
        self.build
            .as_ref()
            .ok_or_else(|| self.bug("a build construct outside a build"))
    }

    fn field_index(&self, name: &Ident) -> Result<usize, InternalError> {
        let bc = self.build_cx()?;
        bc.fields
            .iter()
            .position(|f| *f == name.name)
            .ok_or_else(|| self.bug(format!("`{}` is no logical field", name.name)))
    }

    /// `this` and `build x` in expression position.
    pub(super) fn build_expr(
        &mut self,
        b: &mut Builder<'_>,
        e: &Expr,
    ) -> Result<ValueId, InternalError> {
        b.set_span(Some(e.span));
        match &e.kind {
            ExprKind::This => {
                let t = self.build_cx()?.this_ty;
                Ok(b.build1(Op::This, &[], t))
            }
            ExprKind::Build(id) => {
                let i = self.field_index(id)?;
                let t = self.ty(b, &self.typed.expr_ty(e.id).clone())?;
                let idx = self.param(i as u32)?;
                Ok(self.child(b, &id.name, idx, t))
            }
            _ => Err(self.bug("not a build expression")),
        }
    }

    fn child(&mut self, b: &mut Builder<'_>, field: &str, index: ValueId, t: TypeId) -> ValueId {
        let op = b.insert(
            OpSpec::new(Op::BuildChild)
                .operands(&[index])
                .results(&[t])
                .attr("field", Attr::str(field)),
        );
        b.result(op, 0)
    }

    /// `append(x, n)`.
    pub(super) fn append(
        &mut self,
        b: &mut Builder<'_>,
        e: &Expr,
        args: &[Expr],
        t: TypeId,
    ) -> Result<ValueId, InternalError> {
        let [data, n] = args else {
            return Err(self.bug("append takes 2 arguments"));
        };
        let ExprKind::Name(id) = &data.kind else {
            return Err(self.bug("append of something other than a logical field"));
        };
        let d = self.expr(b, data)?;
        let n = self.expr(b, n)?;
        b.set_span(Some(e.span));
        let op = b.insert(
            OpSpec::new(Op::Append)
                .operands(&[d, n])
                .results(&[t])
                .attr("field", Attr::str(id.name.clone())),
        );
        Ok(b.result(op, 0))
    }

    /// An assignment in a build: `this[a:b] = e` is `tree.build_store_bits`; others as usual.
    pub(super) fn build_assign(
        &mut self,
        b: &mut Builder<'_>,
        s: &Stmt,
        target: &Expr,
        value: &Expr,
    ) -> Result<(), InternalError> {
        let v = self.expr(b, value)?;
        if let ExprKind::Slice { base, lo, hi } = &target.kind {
            if let (ExprKind::This, ExprKind::Int(a), ExprKind::Int(z)) =
                (&base.kind, &lo.kind, &hi.kind)
            {
                b.set_span(Some(s.span));
                b.insert(
                    OpSpec::new(Op::BuildStoreBits)
                        .operands(&[v])
                        .attr("lo", Attr::Int(*a as i128))
                        .attr("hi", Attr::Int(*z as i128)),
                );
                return Ok(());
            }
        }
        self.assign(b, target, v)
    }

    fn param(&self, i: u32) -> Result<ValueId, InternalError> {
        self.params
            .get(i as usize)
            .copied()
            .ok_or_else(|| self.bug(format!("logical field {i} out of range")))
    }

    /// True when `member` is a stored field of the build's layout.
    fn stores(&self, member: Option<crate::sema::MemberId>) -> bool {
        let Some(mid) = member else {
            return false;
        };
        let bc = self.build.as_ref();
        bc.and_then(|bc| self.typed.layouts.get(bc.layout))
            .and_then(|l| l.members.get(mid.0 as usize))
            .is_some_and(|mi| mi.kind == crate::sema::MemberKindInfo::Stored)
    }

    /// `build x`, `build x = e`.
    pub(super) fn build_stmt(
        &mut self,
        b: &mut Builder<'_>,
        s: &Stmt,
        field: &Ident,
        value: Option<&Expr>,
    ) -> Result<(), InternalError> {
        let target = self
            .typed
            .build_targets
            .get(&s.id)
            .cloned()
            .ok_or_else(|| self.bug(format!("`build {}` has no target", field.name)))?;
        let v = match (value, target.field, target.child) {
            (Some(e), _, _) => self.expr(b, e)?,
            (None, Some(i), true) => {
                let t = self.build_cx()?.this_ty;
                let idx = self.param(i)?;
                b.set_span(Some(s.span));
                let r = self.child(b, &field.name, idx, t);
                // A recursive field the layout stores (`left: ptr`) keeps the child's
                // reference; a derived one (`left = I + 1`) only places the child.
                if !self.stores(target.member) {
                    return Ok(());
                }
                r
            }
            (None, Some(i), false) => self.param(i)?,
            (None, None, _) => {
                return Err(self.bug(format!("`build {}` copies nothing", field.name)))
            }
        };
        b.set_span(Some(s.span));
        b.insert(
            OpSpec::new(Op::BuildStore)
                .operands(&[v])
                .attr("field", Attr::str(field.name.clone())),
        );
        Ok(())
    }
}
