//! Execution of `tree` ops: one `match` arm per op kind, each computing the op's results from
//! its operands in the environment, or leaving the region (`yield`, `return`).

use super::{err, AdtVal, Env, Flow, Interp, InterpError, Val};
use crate::attr::Attr;
use crate::entity::{OpId, TypeId, ValueId};
use crate::op::OpKind;
use crate::tree::scalar::{self, Scalar};
use crate::tree::Op;
use crate::types::Type;
use std::rc::Rc;

impl Interp<'_> {
    fn get(&self, env: &Env, v: ValueId, op: OpId) -> Result<Val, InterpError> {
        env.get(&v)
            .cloned()
            .ok_or_else(|| err(Some(op), "operand has no value (IR not verified?)"))
    }

    fn result_type(&self, op: OpId) -> Result<TypeId, InterpError> {
        let o = &self.m.ops[op];
        o.results
            .first()
            .map(|&r| self.m.values[r].ty)
            .ok_or_else(|| err(Some(op), "op has no result"))
    }

    /// The single operand of `match`, `field` or `is` as an ADT value, resolving a lazy
    /// [`Val::Extern`] through the provider.
    fn adt_operand(&mut self, args: &[Val], op: OpId, kind: Op) -> Result<Rc<AdtVal>, InterpError> {
        let bad = |what: &str| err(Some(op), format!("`tree.{}`: {what}", kind.mnemonic()));
        let [v] = args else {
            return Err(bad("one operand expected"));
        };
        match self.resolve_adt(v) {
            Ok(Some(a)) => Ok(a),
            Ok(None) => Err(bad("operand is not an ADT value")),
            Err(e) => Err(bad(&e)),
        }
    }

    /// Executes one op: binds its results in `env`, or returns how the region is left.
    ///
    /// Ops that run regions or calls go through [`Interp::exec_control`], whose frame is small,
    /// so that deep recursion of the interpreted program costs little native stack; all other
    /// ops are computed in [`Interp::exec_data`], which never recurses.
    pub(crate) fn exec(&mut self, op: OpId, env: &mut Env) -> Result<Option<Flow>, InterpError> {
        let o = &self.m.ops[op];
        let kind = match o.kind {
            OpKind::Tree(kind) => kind,
            OpKind::Mem(kind) => {
                let args: Vec<Val> = o
                    .operands
                    .iter()
                    .map(|&v| self.get(env, v, op))
                    .collect::<Result<_, _>>()?;
                let results = self.exec_mem(op, kind, args)?;
                for (&r, v) in self.m.ops[op].results.iter().zip(results) {
                    env.insert(r, v);
                }
                return Ok(None);
            }
            OpKind::Lo(_) => {
                return Err(err(Some(op), "the tree interpreter runs only tree ops"));
            }
        };
        let args: Vec<Val> = o
            .operands
            .iter()
            .map(|&v| self.get(env, v, op))
            .collect::<Result<_, _>>()?;
        let step = match kind {
            Op::Match | Op::If | Op::Foreach | Op::Call => {
                self.exec_control(op, kind, args, env)?
            }
            _ => self.exec_data(op, kind, args)?,
        };
        let results = match step {
            Step::Leave(flow) => return Ok(Some(flow)),
            Step::Values(v) => v,
        };
        let o = &self.m.ops[op];
        if results.len() != o.results.len() {
            let msg = format!(
                "`tree.{}`: {} values for {} results",
                kind.mnemonic(),
                results.len(),
                o.results.len()
            );
            return Err(err(Some(op), msg));
        }
        for (&r, v) in o.results.iter().zip(results) {
            env.insert(r, v);
        }
        Ok(None)
    }

    /// Runs `match`, `if`, `foreach` and `call`.
    #[inline(never)]
    fn exec_control(
        &mut self,
        op: OpId,
        kind: Op,
        args: Vec<Val>,
        env: &mut Env,
    ) -> Result<Step, InterpError> {
        let m = self.m;
        let o = &m.ops[op];
        let bad = |what: &str| err(Some(op), format!("`tree.{}`: {what}", kind.mnemonic()));
        Ok(Step::Values(match kind {
            Op::Match => {
                let a = self.adt_operand(&args, op, kind)?;
                let adt = m.adt(&a.ty).ok_or_else(|| bad("undeclared ADT"))?;
                let arms = o
                    .attr("arms")
                    .and_then(Attr::as_list)
                    .ok_or_else(|| bad("no arms"))?;
                let name = a
                    .variant
                    .and_then(|i| adt.variants.get(i))
                    .map(|v| v.name.as_str());
                let chosen = arms
                    .iter()
                    .position(|arm| arm.as_str().is_some() && arm.as_str() == name)
                    .or_else(|| arms.iter().position(|arm| arm.as_str() == Some("_")))
                    .ok_or_else(|| bad("no arm matches"))?;
                let region = *o
                    .regions
                    .get(chosen)
                    .ok_or_else(|| bad("missing arm region"))?;
                let block = *m.regions[region]
                    .blocks
                    .first()
                    .ok_or_else(|| bad("empty arm"))?;
                let nargs = m.blocks[block].args.len();
                let bound: Vec<Val> = a.fields.iter().take(nargs).cloned().collect();
                match self.run_block(block, bound, env)? {
                    Flow::Yield(v) => v,
                    ret => return Ok(Step::Leave(ret)),
                }
            }
            Op::If => {
                let [Val::Bool(c)] = &args[..] else {
                    return Err(bad("condition must be i1"));
                };
                let region = *o
                    .regions
                    .get(if *c { 0 } else { 1 })
                    .ok_or_else(|| bad("missing region"))?;
                let block = *m.regions[region]
                    .blocks
                    .first()
                    .ok_or_else(|| bad("empty region"))?;
                match self.run_block(block, Vec::new(), env)? {
                    Flow::Yield(v) => v,
                    ret => return Ok(Step::Leave(ret)),
                }
            }
            Op::Foreach => {
                let elems = match &args[..] {
                    [Val::Array(a)] | [Val::Set(a)] => a.clone(),
                    _ => return Err(bad("operand is not an array or set")),
                };
                let region = *o.regions.first().ok_or_else(|| bad("missing body"))?;
                let block = *m.regions[region]
                    .blocks
                    .first()
                    .ok_or_else(|| bad("empty body"))?;
                let index_ty = m.blocks[block]
                    .args
                    .get(1)
                    .map(|&a| m.values[a].ty)
                    .and_then(|t| m.types.as_int(t));
                for (i, e) in elems.iter().enumerate() {
                    let mut bound = vec![e.clone()];
                    if let Some(t) = index_ty {
                        bound.push(Val::Int(t.wrap(i as i128), t));
                    }
                    if let Flow::Return(v) = self.run_block(block, bound, env)? {
                        return Ok(Step::Leave(Flow::Return(v)));
                    }
                }
                Vec::new()
            }
            Op::Call => {
                let callee = o.callee().ok_or_else(|| bad("no callee"))?;
                let f = m
                    .func_by_name(callee)
                    .ok_or_else(|| bad(&format!("unknown function `@{callee}`")))?;
                self.call_func(f, args, Some(op))?
            }
            _ => return Err(bad("not a control op")),
        }))
    }

    /// Computes every op that neither runs a region nor calls.
    #[inline(never)]
    fn exec_data(&mut self, op: OpId, kind: Op, args: Vec<Val>) -> Result<Step, InterpError> {
        let m = self.m;
        let o = &m.ops[op];
        let bad = |what: &str| err(Some(op), format!("`tree.{}`: {what}", kind.mnemonic()));
        let results: Vec<Val> = match kind {
            Op::Yield => return Ok(Step::Leave(Flow::Yield(args))),
            Op::Return => return Ok(Step::Leave(Flow::Return(args))),
            Op::This
            | Op::BuildStore
            | Op::BuildStoreBits
            | Op::BuildChild
            | Op::BuildLoad
            | Op::ChildField
            | Op::Append => {
                return Err(bad(
                    "build ops run only after constructor specialization, not in the interpreter",
                ))
            }
            Op::Const => {
                let ty = self.result_type(op)?;
                let a = o.attr("value").ok_or_else(|| bad("no value"))?;
                let s = Scalar::from_attr(m, a, ty)
                    .ok_or_else(|| bad("constant of a type the interpreter lacks (f16?)"))?;
                vec![Val::from_scalar(s)]
            }
            Op::Add
            | Op::Sub
            | Op::Mul
            | Op::Div
            | Op::Rem
            | Op::And
            | Op::Or
            | Op::Xor
            | Op::Shl
            | Op::Shr => {
                let [a, b] = &args[..] else {
                    return Err(bad("two operands expected"));
                };
                vec![lanewise2(a, b, &|x, y| {
                    scalar::binary(kind, x, y).ok_or_else(|| match (kind, y) {
                        (Op::Div | Op::Rem, Scalar::Int(0, _)) => {
                            "integer division by zero".to_string()
                        }
                        _ => "operands of the wrong types".to_string(),
                    })
                })
                .map_err(|e| bad(&e))?]
            }
            Op::Neg | Op::BitNot | Op::Not => {
                let [a] = &args[..] else {
                    return Err(bad("one operand expected"));
                };
                vec![lanewise1(a, &|x| {
                    scalar::unary(kind, x).ok_or_else(|| "wrong operand type".to_string())
                })
                .map_err(|e| bad(&e))?]
            }
            Op::Cmp => {
                let [a, b] = &args[..] else {
                    return Err(bad("two operands expected"));
                };
                let pred = o.pred().ok_or_else(|| bad("bad predicate"))?;
                vec![lanewise2(a, b, &|x, y| {
                    scalar::compare(pred, x, y)
                        .map(Scalar::Bool)
                        .ok_or_else(|| "operands of different types".to_string())
                })
                .map_err(|e| bad(&e))?]
            }
            Op::Select => {
                let [c, a, b] = &args[..] else {
                    return Err(bad("three operands expected"));
                };
                vec![match (c, a, b) {
                    (Val::Bool(c), a, b) => {
                        if *c {
                            a.clone()
                        } else {
                            b.clone()
                        }
                    }
                    (Val::Vector(cs), Val::Vector(xs), Val::Vector(ys)) => Val::Vector(
                        cs.iter()
                            .zip(xs.iter().zip(ys))
                            .map(|(c, (x, y))| {
                                if matches!(c, Val::Bool(true)) {
                                    x.clone()
                                } else {
                                    y.clone()
                                }
                            })
                            .collect(),
                    ),
                    _ => return Err(bad("condition must be i1")),
                }]
            }
            Op::Cast | Op::Bitcast => {
                let [a] = &args[..] else {
                    return Err(bad("one operand expected"));
                };
                let to = m.types.scalar_of(self.result_type(op)?);
                let to = m.types.get(to);
                let f = |x: Scalar| -> Result<Scalar, String> {
                    let r = if kind == Op::Cast {
                        scalar::cast(x, to)
                    } else {
                        scalar::bitcast(x, to)
                    };
                    r.ok_or_else(|| "unsupported conversion".to_string())
                };
                vec![lanewise1(a, &f).map_err(|e| bad(&e))?]
            }
            Op::Tuple => vec![Val::Tuple(args)],
            Op::Array => vec![Val::Array(std::rc::Rc::new(args))],
            Op::Extract => {
                let i = index_attr(o.int_attr("index"));
                match &args[..] {
                    [Val::Tuple(t)] => {
                        vec![t.get(i).cloned().ok_or_else(|| bad("index out of range"))?]
                    }
                    _ => return Err(bad("operand is not a tuple")),
                }
            }
            Op::Insert => {
                let i = index_attr(o.int_attr("index"));
                match &args[..] {
                    [Val::Tuple(t), v] if i < t.len() => {
                        let mut t = t.clone();
                        t[i] = v.clone();
                        vec![Val::Tuple(t)]
                    }
                    _ => return Err(bad("operand is not a tuple with that element")),
                }
            }
            Op::Vector => vec![Val::Vector(args)],
            Op::Lane => {
                let i = index_attr(o.int_attr("index"));
                match &args[..] {
                    [Val::Vector(l)] => {
                        vec![l.get(i).cloned().ok_or_else(|| bad("lane out of range"))?]
                    }
                    _ => return Err(bad("operand is not a vector")),
                }
            }
            Op::Field => {
                let i = index_attr(o.int_attr("index"));
                let a = self.adt_operand(&args, op, kind)?;
                vec![a
                    .fields
                    .get(i)
                    .cloned()
                    .ok_or_else(|| bad("field out of range"))?]
            }
            Op::Ctor => {
                let ty = self.result_type(op)?;
                let adt = m
                    .adt_of_type(ty)
                    .ok_or_else(|| bad("result is not a declared ADT"))?;
                let variant = match o.str_attr("variant") {
                    Some(v) => Some(adt.variant(v).ok_or_else(|| bad("unknown variant"))?.0),
                    None => None,
                };
                vec![Val::Adt(Rc::new(AdtVal {
                    ty: adt.name.clone(),
                    variant,
                    fields: args,
                }))]
            }
            Op::Is => {
                let a = self.adt_operand(&args, op, kind)?;
                let adt = m.adt(&a.ty).ok_or_else(|| bad("undeclared ADT"))?;
                let want = o
                    .str_attr("variant")
                    .and_then(|v| adt.variant(v))
                    .map(|(i, _)| i);
                vec![Val::Bool(want.is_some() && a.variant == want)]
            }
            Op::Index => match &args[..] {
                [Val::Array(a), Val::Int(i, _)] => vec![element(a, *i).ok_or_else(|| {
                    bad(&format!("index {i} out of bounds for length {}", a.len()))
                })?],
                [Val::Vector(a), Val::Int(i, _)] => vec![element(a, *i).ok_or_else(|| {
                    bad(&format!("lane {i} out of bounds for {} lanes", a.len()))
                })?],
                _ => return Err(bad("operands of the wrong types")),
            },
            Op::Slice => match &args[..] {
                [Val::Array(a), Val::Int(lo, _), Val::Int(hi, _)] => {
                    if *lo < 0 || lo > hi || *hi > a.len() as i128 {
                        return Err(bad(&format!(
                            "slice [{lo}, {hi}) out of bounds for length {}",
                            a.len()
                        )));
                    }
                    vec![Val::Array(Rc::new(a[*lo as usize..*hi as usize].to_vec()))]
                }
                _ => return Err(bad("operands of the wrong types")),
            },
            Op::Bits => {
                let (v, width) = match args.first() {
                    Some(Val::Int(v, t)) => (*v, t.bits()),
                    _ => return Err(bad("operand is not an integer")),
                };
                let (lo, hi) = match (o.int_attr("lo"), o.int_attr("hi"), args.get(1), args.get(2))
                {
                    (Some(lo), Some(hi), _, _) => (lo, hi),
                    (None, None, Some(Val::Int(lo, _)), Some(Val::Int(hi, _))) => (*lo, *hi),
                    _ => return Err(bad("bit range missing")),
                };
                if !(0 <= lo && lo <= hi && hi <= width as i128) {
                    return Err(bad(&format!("bit range [{lo}, {hi}) outside 0..{width}")));
                }
                let raw = (v as u128) & ((1u128 << width) - 1);
                let field = (raw >> lo) & ((1u128 << (hi - lo)) - 1);
                let rt = m
                    .types
                    .as_int(self.result_type(op)?)
                    .ok_or_else(|| bad("result is not an integer"))?;
                vec![Val::Int(rt.wrap(field as i128), rt)]
            }
            Op::Intrinsic => {
                let intrinsic = crate::tree::Intrinsic::of(o).map_err(|e| bad(&e))?;
                let ty = self.result_type(op)?;
                vec![super::intrinsics::eval(m, intrinsic, &args, ty).map_err(|e| bad(&e))?]
            }
            Op::Var => {
                let [v] = &args[..] else {
                    return Err(bad("one operand expected"));
                };
                vec![self.alloc(v.clone())]
            }
            Op::Match | Op::If | Op::Foreach | Op::Call => return Err(bad("a control op")),
            Op::Load => match &args[..] {
                [Val::Ref(i)] => vec![self
                    .heap
                    .get(*i)
                    .cloned()
                    .ok_or_else(|| bad("dangling reference"))?],
                _ => return Err(bad("operand is not a reference")),
            },
            Op::Store => match &args[..] {
                [Val::Ref(i), v] if *i < self.heap.len() => {
                    self.heap[*i] = v.clone();
                    Vec::new()
                }
                _ => return Err(bad("operand is not a reference")),
            },
        };
        Ok(Step::Values(results))
    }
}

/// What executing one op did.
enum Step {
    /// It computed its results.
    Values(Vec<Val>),
    /// It left the region.
    Leave(Flow),
}

fn index_attr(v: Option<i128>) -> usize {
    v.and_then(|i| usize::try_from(i).ok())
        .unwrap_or(usize::MAX)
}

fn element(items: &[Val], i: i128) -> Option<Val> {
    usize::try_from(i).ok().and_then(|i| items.get(i)).cloned()
}

/// Applies `f` to a scalar or to each lane of a vector.
pub(crate) fn lanewise1(
    a: &Val,
    f: &dyn Fn(Scalar) -> Result<Scalar, String>,
) -> Result<Val, String> {
    match a {
        Val::Vector(l) => l
            .iter()
            .map(|x| lanewise1(x, f))
            .collect::<Result<_, _>>()
            .map(Val::Vector),
        _ => Ok(Val::from_scalar(f(a.scalar().ok_or("not a scalar")?)?)),
    }
}

/// Applies `f` to two scalars or to each pair of lanes of two vectors of equal length.
pub(crate) fn lanewise2(
    a: &Val,
    b: &Val,
    f: &dyn Fn(Scalar, Scalar) -> Result<Scalar, String>,
) -> Result<Val, String> {
    match (a, b) {
        (Val::Vector(x), Val::Vector(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .map(|(p, q)| lanewise2(p, q, f))
            .collect::<Result<_, _>>()
            .map(Val::Vector),
        _ => Ok(Val::from_scalar(f(
            a.scalar().ok_or("not a scalar")?,
            b.scalar().ok_or("not a scalar")?,
        )?)),
    }
}

/// The result type's scalar for a lane-wise op; used by intrinsics.
pub(crate) fn scalar_type(m: &crate::module::Module, ty: TypeId) -> &Type {
    m.types.get(m.types.scalar_of(ty))
}
