//! `const-fold`: evaluates `tree` arithmetic, bitwise, comparison, cast and select ops whose
//! operands are scalar constants, replacing each by a `tree.const` (level: any → same).
//!
//! ```text
//! %0 = "tree.const"() {value = 1.5} : () -> f32
//! %1 = "tree.const"() {value = 2.0} : () -> f32
//! %2 = "tree.add"(%0, %1) : (f32, f32) -> f32
//! // becomes
//! %2 = "tree.const"() {value = 3.5} : () -> f32
//! ```
//!
//! Semantics are the IR's ([`crate::tree::scalar`]), exactly: integers wrap in two's complement at their width, shift
//! amounts are taken modulo the width, `shr` is arithmetic on signed types; integer division or
//! remainder by zero is left unfolded; floats compute in their own precision with IEEE
//! round-to-nearest (`f32` ops in `f32`, never through `f64`), `rem` is C `fmod`; ordered
//! comparisons are false on NaN and `ne` is true; float-to-integer casts saturate (NaN gives 0);
//! a cast to `i1` is `!= 0`. A NaN produced by arithmetic becomes the canonical quiet NaN (IEEE
//! leaves payloads open); `neg` and `bitcast` keep bits exactly. `f16` is not folded. The
//! replaced ops' results are aliased to the new constants; `dce` then removes the dead operands.
//! A `tree.if` on a constant condition is replaced by the ops of the region it would run, when
//! that region ends with `tree.yield`. A field of a record just built (`tree.field` of a
//! `tree.ctor`) and an element of a tuple just built (`tree.extract` of a `tree.tuple`) are the
//! operand that built them.

use crate::attr::Attr;
use crate::builder::{Builder, InsertPoint, OpSpec};
use crate::entity::{OpId, ValueId};
use crate::module::Module;
use crate::op::OpKind;
use crate::pass::{Pass, PassCx, PassError};
use crate::rewrite;
use crate::tree::scalar::{binary, bitcast, cast, compare, unary, Scalar};
use crate::tree::Op;
use crate::walk;
use rustc_hash::FxHashMap;

/// The `const-fold` pass.
#[derive(Default)]
pub struct ConstFold;

impl Pass for ConstFold {
    fn name(&self) -> &'static str {
        "const-fold"
    }

    fn summary(&self) -> &'static str {
        "Evaluate tree arithmetic, comparisons and casts on scalar constants (exact IEEE semantics)"
    }

    fn run(&mut self, m: &mut Module, _cx: &mut PassCx) -> Result<bool, PassError> {
        let mut changed = false;
        for f in m.func_order.clone() {
            let mut consts: FxHashMap<ValueId, Attr> = FxHashMap::default();
            for op in walk::func_ops(m, f, walk::Order::Pre) {
                let o = &m.ops[op];
                if o.kind.is_tree(Op::Const) {
                    if let Some(a) = o.attr("value") {
                        consts.insert(o.results[0], a.clone());
                    }
                    continue;
                }
                if o.kind.is_tree(Op::If) && o.parent.is_some() {
                    if let Some(Attr::Bool(c)) = o.operands.first().and_then(|v| consts.get(v)) {
                        changed |= fold_if(m, op, *c);
                    }
                    continue;
                }
                match fold_op(m, op, &consts) {
                    Some(Folded::Const(attr)) => {
                        let res = m.ops[op].results[0];
                        let ty = m.values[res].ty;
                        let span = m.span(op);
                        let mut b = Builder::new(m);
                        b.set_insertion_point(InsertPoint::Before(op));
                        b.set_span(span);
                        let new = b.insert(
                            OpSpec::new(Op::Const)
                                .attr("value", attr.clone())
                                .results(&[ty]),
                        );
                        let v = m.ops[new].results[0];
                        consts.insert(res, attr.clone());
                        consts.insert(v, attr);
                        rewrite::replace_op(m, op, &[v]);
                        changed = true;
                    }
                    Some(Folded::Alias(v)) => {
                        let res = m.ops[op].results[0];
                        if let Some(a) = consts.get(&v).cloned() {
                            consts.insert(res, a);
                        }
                        rewrite::replace_op(m, op, &[v]);
                        changed = true;
                    }
                    None => {}
                }
            }
        }
        Ok(changed)
    }
}

/// Replaces `tree.if` with a constant condition by the ops of the region it would run, when
/// that region ends with `tree.yield` (one ending with `tree.return` is left alone, as the rest
/// of the enclosing block would become dead). Returns whether it changed anything.
fn fold_if(m: &mut Module, op: OpId, cond: bool) -> bool {
    let Some(&region) = m.ops[op].regions.get(if cond { 0 } else { 1 }) else {
        return false;
    };
    let ends_in_yield = m.regions[region]
        .blocks
        .first()
        .and_then(|&b| m.blocks[b].ops.last())
        .is_some_and(|&t| m.ops[t].kind.is_tree(Op::Yield));
    if !ends_in_yield {
        return false;
    }
    let Some(term) = rewrite::inline_region_before(m, region, op, &[]) else {
        return false;
    };
    let yielded = m.ops[term].operands.clone();
    rewrite::replace_op(m, op, &yielded);
    true
}

/// What an op folds to.
#[derive(Clone, Debug, PartialEq)]
pub enum Folded {
    /// A new constant of the op's result type.
    Const(Attr),
    /// An existing value (e.g. a `select` with a constant condition).
    Alias(ValueId),
}

/// What `op` folds to given the constants known so far, if anything.
pub fn fold_op(m: &Module, op: OpId, consts: &FxHashMap<ValueId, Attr>) -> Option<Folded> {
    let o = &m.ops[op];
    let OpKind::Tree(kind) = o.kind else {
        return None;
    };
    if o.results.len() != 1 {
        return None;
    }
    let result_ty = m.values[o.results[0]].ty;
    // A component of a value just built: `tree.field {index = k}` of a `tree.ctor` (shared
    // fields come first in a variant's operands too) and `tree.extract {index = k}` of a
    // `tree.tuple` are its operand k.
    if matches!(kind, Op::Field | Op::Extract) {
        let k = usize::try_from(o.attr("index")?.as_int()?).ok()?;
        let src = rewrite::resolve_value(m, *o.operands.first()?);
        let crate::module::ValueDef::Result(def, 0) = m.values[src].def else {
            return None;
        };
        let d = &m.ops[def];
        let builds = match kind {
            Op::Field => d.kind.is_tree(Op::Ctor),
            _ => d.kind.is_tree(Op::Tuple),
        };
        let v = *d.operands.get(k).filter(|_| builds)?;
        return (m.values[v].ty == result_ty).then_some(Folded::Alias(v));
    }
    if kind == Op::Select {
        let c = consts.get(o.operands.first()?)?;
        return match c {
            Attr::Bool(true) => Some(Folded::Alias(*o.operands.get(1)?)),
            Attr::Bool(false) => Some(Folded::Alias(*o.operands.get(2)?)),
            _ => None,
        };
    }
    let args: Option<Vec<Scalar>> = o
        .operands
        .iter()
        .map(|&v| Scalar::from_attr(m, consts.get(&v)?, m.values[v].ty))
        .collect();
    let args = args?;
    let out = match (kind, args.as_slice()) {
        (
            Op::Add
            | Op::Sub
            | Op::Mul
            | Op::Div
            | Op::Rem
            | Op::And
            | Op::Or
            | Op::Xor
            | Op::Shl
            | Op::Shr,
            [a, b],
        ) => binary(kind, *a, *b)?,
        (Op::Neg | Op::BitNot | Op::Not, [a]) => unary(kind, *a)?,
        (Op::Cmp, [a, b]) => Scalar::Bool(compare(o.pred()?, *a, *b)?),
        (Op::Cast, [a]) => cast(*a, m.types.get(result_ty))?,
        (Op::Bitcast, [a]) => bitcast(*a, m.types.get(result_ty))?,
        _ => return None,
    };
    Some(Folded::Const(out.to_attr()))
}
