//! What the backends need to know about NaNs in one `lo` function, so that they compute exactly
//! what the interpreters compute without paying for NaNs that cannot occur or cannot be seen.
//! Input: the blocks of a `lo` function; output: [`NanFacts`].
//!
//! **Canonical NaNs.** `lo` float `add sub mul div rem` (and the directed `add_rd` .. `mul_ru`)
//! produce the canonical quiet NaN ([`crate::tree::scalar`]): the interpreters canonicalize
//! after every such op. The hardware's NaN payloads differ (x86 makes `0xFFC00000`), so a
//! backend replaces a NaN by the canonical one with a compare and a select, but only where the
//! payload can be seen. A use *blind* to payloads sees only whether its operand is a NaN: float
//! `add sub mul div rem`, the directed ops, compares, and float-to-integer casts (a NaN gives 0).
//! A *transparent* use passes the operand's payload on to its own result, whose bits are then
//! canonical when the operand's are: `min`/`max` (which return an operand), the two values of a
//! `select`, branch arguments (block arguments), and `neg`/`abs` (which change only the sign
//! bit, as the interpreters do to the canonical NaN). Every other use (store, return, call
//! argument, bitcast, `sqrt`, `fma`, float casts, ...) *observes* the payload.
//!
//! So a backend canonicalizes an arithmetic result where it is defined
//! ([`NanFacts::canonicalize`]) only when its payload reaches an observing use, directly or
//! through transparent uses (the backends' `min`/`max`/`select` return an operand's bits, as the
//! interpreters do); otherwise it leaves the hardware's NaN. Values that are never NaN need
//! nothing, and pass no demand on to their operands.
//!
//! **Values that are never NaN** ([`NanFacts::never_nan`]), by a forward analysis to the
//! greatest fixed point (block arguments are never NaN when no incoming value can be):
//! non-NaN constants; `min`/`max` with an operand that is never NaN (they return the non-NaN
//! operand); `select` of two such values; `neg`, `abs`, `floor`, `ceil`, `trunc` and float
//! widening or narrowing of one; `x + c`, `x - c`, `c - x` with `c` a finite constant, `x * c`
//! and `x / c` with `c` finite and non-zero; integer-to-float casts. Loads, parameters and call
//! results may be NaN.
//!
//! **Cheap `min`/`max`** ([`NanFacts::min_max_form`]). The language's float `min(p, q)`
//! (minNum: the non-NaN operand when one is NaN, else the smaller, `p` on ties) is in general
//! `isnan(p) ? q : (q < p ? q : p)`. When `p` is never NaN it is `q < p ? q : p`: one x86
//! `minss`, one compare-and-select elsewhere. When `q` is a non-zero constant that is not NaN it
//! is `p < q ? p : q` (a tie is then `p == q` with equal bits, so either operand is right).

use crate::attr::Attr;
use crate::entity::{BlockId, OpId, ValueId};
use crate::lo::Op as L;
use crate::module::Module;
use crate::op::OpKind;
use crate::types::Type;
use rustc_hash::{FxHashMap, FxHashSet};

/// A set of values.
pub type ValueSet = FxHashSet<ValueId>;

/// How a backend lowers a float `min(p, q)` / `max(p, q)` (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MinMaxForm {
    /// `p` is never NaN: `q < p ? q : p` (`max`: `q > p ? q : p`).
    Select,
    /// `q` is a constant, neither NaN nor zero: `p < q ? p : q` (`max`: `p > q ? p : q`).
    SelectSwapped,
    /// Anything: `isnan(p) ? q : (q < p ? q : p)` (`max`: with `>`).
    General,
}

/// The NaN facts of one function (see the module documentation).
#[derive(Clone, Debug, Default)]
pub struct NanFacts {
    never_nan: ValueSet,
    canonicalize: ValueSet,
    constants: FxHashMap<ValueId, f64>,
}

impl NanFacts {
    /// The facts of the function whose body is `blocks`.
    pub fn of(m: &Module, blocks: &[BlockId]) -> NanFacts {
        let mut facts = NanFacts::default();
        let ops: Vec<OpId> = blocks
            .iter()
            .flat_map(|&b| m.blocks[b].ops.iter().copied())
            .collect();
        for &op in &ops {
            let o = &m.ops[op];
            if o.kind == OpKind::Lo(L::Const) {
                if let (Some(&r), Some(Attr::Float(bits))) = (o.results.first(), o.attr("value")) {
                    facts.constants.insert(r, f64::from_bits(*bits));
                }
            }
        }
        facts.never_nan = never_nan(m, blocks, &ops, &facts.constants);
        facts.canonicalize = to_canonicalize(m, &ops, &facts.never_nan);
        facts
    }

    /// True when float value `v` is never NaN.
    pub fn never_nan(&self, v: ValueId) -> bool {
        self.never_nan.contains(&v)
    }

    /// True when the backend must canonicalize the NaN of `v` (the result of a float arithmetic
    /// or directed op) where it is defined.
    pub fn canonicalize(&self, v: ValueId) -> bool {
        self.canonicalize.contains(&v)
    }

    /// The form every op of a lane group of `min`s or `max`s `ops` allows when they agree (one
    /// vector instruction lowers them all), or `None`.
    pub fn lanes_min_max_form(&self, m: &Module, ops: &[OpId]) -> Option<MinMaxForm> {
        let mut forms = ops
            .iter()
            .map(|&o| self.min_max_form(m.ops[o].operands[0], m.ops[o].operands[1]));
        let first = forms.next()?;
        forms.all(|f| f == first).then_some(first)
    }

    /// How to lower a float `min(p, q)` or `max(p, q)`.
    pub fn min_max_form(&self, p: ValueId, q: ValueId) -> MinMaxForm {
        if self.never_nan(p) {
            MinMaxForm::Select
        } else if self
            .constants
            .get(&q)
            .is_some_and(|c| !c.is_nan() && *c != 0.0)
        {
            MinMaxForm::SelectSwapped
        } else {
            MinMaxForm::General
        }
    }
}

fn is_float(m: &Module, v: ValueId) -> bool {
    matches!(m.types.get(m.values[v].ty), Type::Float(_))
}

fn is_arith(kind: OpKind) -> bool {
    matches!(
        kind,
        OpKind::Lo(
            L::Add | L::Sub | L::Mul | L::Div | L::Rem | L::AddRd | L::AddRu | L::MulRd | L::MulRu
        )
    )
}

/// How use number `i` of op `op` treats a NaN payload.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Use {
    Blind,
    Transparent,
    Observes,
}

fn use_of(m: &Module, op: OpId, i: usize) -> Use {
    let o = &m.ops[op];
    let result_float = o.results.first().is_some_and(|&r| is_float(m, r));
    match o.kind {
        OpKind::Lo(L::Add | L::Sub | L::Mul | L::Div | L::Rem) if result_float => Use::Blind,
        OpKind::Lo(L::AddRd | L::AddRu | L::MulRd | L::MulRu | L::Cmp) => Use::Blind,
        OpKind::Lo(L::Cast) if !result_float => Use::Blind,
        OpKind::Lo(L::Min | L::Max | L::Neg | L::Abs) if result_float => Use::Transparent,
        OpKind::Lo(L::Select) if i > 0 => Use::Transparent,
        _ => Use::Observes,
    }
}

fn finite_const(c: &FxHashMap<ValueId, f64>, v: ValueId) -> bool {
    c.get(&v).is_some_and(|x| x.is_finite())
}

fn nonzero_finite_const(c: &FxHashMap<ValueId, f64>, v: ValueId) -> bool {
    c.get(&v).is_some_and(|x| x.is_finite() && *x != 0.0)
}

/// The float values of the function that are never NaN (greatest fixed point).
fn never_nan(
    m: &Module,
    blocks: &[BlockId],
    ops: &[OpId],
    consts: &FxHashMap<ValueId, f64>,
) -> ValueSet {
    // Start from "every float op result and non-entry block argument may be never NaN" and
    // remove what the rules cannot show, until nothing changes.
    let mut nn: ValueSet = FxHashSet::default();
    for &op in ops {
        nn.extend(
            m.ops[op]
                .results
                .iter()
                .copied()
                .filter(|&r| is_float(m, r)),
        );
    }
    for &b in blocks.iter().skip(1) {
        nn.extend(m.blocks[b].args.iter().copied().filter(|&a| is_float(m, a)));
    }
    loop {
        let mut changed = false;
        for &op in ops {
            let o = &m.ops[op];
            // Every result: a call's second and later results are as unknown as its first.
            for (i, &r) in o.results.iter().enumerate() {
                if nn.contains(&r) && (i > 0 || !result_never_nan(m, op, &nn, consts)) {
                    nn.remove(&r);
                    changed = true;
                }
            }
            for s in &o.successors {
                for (k, &a) in s.args.iter().enumerate() {
                    let param = m.blocks[s.block].args[k];
                    if nn.contains(&param) && !nn.contains(&a) {
                        nn.remove(&param);
                        changed = true;
                    }
                }
            }
        }
        if !changed {
            return nn;
        }
    }
}

fn result_never_nan(m: &Module, op: OpId, nn: &ValueSet, consts: &FxHashMap<ValueId, f64>) -> bool {
    let o = &m.ops[op];
    let a = |i: usize| o.operands[i];
    let n = |i: usize| nn.contains(&o.operands[i]);
    let OpKind::Lo(kind) = o.kind else {
        return false;
    };
    match kind {
        L::Const => o
            .results
            .first()
            .is_some_and(|r| consts.get(r).is_some_and(|c| !c.is_nan())),
        L::Min | L::Max => n(0) || n(1),
        L::Select => n(1) && n(2),
        L::Neg | L::Abs | L::Floor | L::Ceil | L::Trunc => n(0),
        L::Add => n(0) && n(1) && (finite_const(consts, a(0)) || finite_const(consts, a(1))),
        L::Sub => n(0) && n(1) && (finite_const(consts, a(0)) || finite_const(consts, a(1))),
        L::Mul => {
            n(0) && n(1)
                && (nonzero_finite_const(consts, a(0)) || nonzero_finite_const(consts, a(1)))
        }
        L::Div => n(0) && nonzero_finite_const(consts, a(1)),
        L::Cast => !is_float(m, a(0)) || n(0),
        _ => false,
    }
}

/// The arithmetic results to canonicalize where they are defined: those whose payload reaches
/// an observing use, directly or through transparent uses (least fixed point, backward).
fn to_canonicalize(m: &Module, ops: &[OpId], nn: &ValueSet) -> ValueSet {
    // Values whose NaN must carry the interpreters' bits.
    let mut must: ValueSet = FxHashSet::default();
    for &op in ops {
        for (i, &v) in m.ops[op].operands.iter().enumerate() {
            if use_of(m, op, i) == Use::Observes && !nn.contains(&v) {
                must.insert(v);
            }
        }
    }
    loop {
        let mut changed = false;
        for &op in ops {
            let o = &m.ops[op];
            let passes: &[ValueId] = match o.kind {
                OpKind::Lo(L::Min | L::Max | L::Neg | L::Abs) => &o.operands,
                OpKind::Lo(L::Select) => &o.operands[1..],
                _ => &[],
            };
            if o.results.first().is_some_and(|r| must.contains(r)) {
                for &v in passes {
                    if !nn.contains(&v) {
                        changed |= must.insert(v);
                    }
                }
            }
            for s in &o.successors {
                for (k, &a) in s.args.iter().enumerate() {
                    if must.contains(&m.blocks[s.block].args[k]) && !nn.contains(&a) {
                        changed |= must.insert(a);
                    }
                }
            }
        }
        if !changed {
            break;
        }
    }
    let mut canon: ValueSet = FxHashSet::default();
    for &op in ops {
        let o = &m.ops[op];
        if is_arith(o.kind) {
            canon.extend(
                o.results
                    .iter()
                    .copied()
                    .filter(|r| must.contains(r) && is_float(m, *r)),
            );
        }
    }
    canon
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diag::FileId;
    use crate::parse::parse_module;

    /// The module of `src`, the facts of its first function, and its values in order of
    /// definition: block arguments, then op results, block by block (`%0`, `%1`, ... as
    /// printed).
    fn facts(src: &str) -> (NanFacts, Vec<ValueId>) {
        let m = parse_module(src, FileId(0)).expect("parses");
        let f = m.func_order[0];
        let blocks = m.regions[m.funcs[f].body].blocks.clone();
        let mut values = Vec::new();
        for &b in &blocks {
            values.extend(m.blocks[b].args.iter().copied());
            for &op in &m.blocks[b].ops {
                values.extend(m.ops[op].results.iter().copied());
            }
        }
        (NanFacts::of(&m, &blocks), values)
    }

    #[test]
    fn slab_distances_are_never_nan_and_need_no_canonicalization() {
        // t = (lo - o) * inv may be NaN (0 * inf); max(t, -inf) is not, nor min/max of such.
        let (f, v) = facts(
            r#"func @f(%0: f32, %1: f32, %2: f32, %3: f32) -> (f32) {
  %4 = "lo.sub"(%0, %1) : (f32, f32) -> f32
  %5 = "lo.mul"(%4, %2) : (f32, f32) -> f32
  %6 = "lo.const"() {value = -inf} : () -> f32
  %7 = "lo.max"(%5, %6) : (f32, f32) -> f32
  %8 = "lo.min"(%7, %3) : (f32, f32) -> f32
  %9 = "lo.const"() {value = 1.0000004 : f32} : () -> f32
  %10 = "lo.mul"(%8, %9) : (f32, f32) -> f32
  "lo.return"(%10) : (f32) -> ()
}
"#,
        );
        assert!(!f.never_nan(v[5]));
        assert!(f.never_nan(v[7]) && f.never_nan(v[8]) && f.never_nan(v[10]));
        assert_eq!(f.min_max_form(v[5], v[6]), MinMaxForm::SelectSwapped);
        assert_eq!(f.min_max_form(v[7], v[3]), MinMaxForm::Select);
        assert_eq!(f.min_max_form(v[3], v[7]), MinMaxForm::General);
        // The product's NaN only reaches `max`, which drops it: nothing is canonicalized.
        assert!(!f.canonicalize(v[4]) && !f.canonicalize(v[5]) && !f.canonicalize(v[10]));
    }

    #[test]
    fn a_raw_nan_passed_on_is_canonicalized_where_it_is_observed() {
        // %3 reaches a store through `min` and a block argument: it is canonicalized where it
        // is made (the `min` and the block argument pass its bits on).
        let (f, v) = facts(
            r#"func @f(%0: f32, %1: f32, %2: ptr) -> () {
  %3 = "lo.mul"(%0, %1) : (f32, f32) -> f32
  %4 = "lo.min"(%3, %0) : (f32, f32) -> f32
  "lo.br"()[^bb1(%4 : f32)] : () -> ()
^bb1(%5: f32):
  "lo.store"(%2, %5) {offset = 0} : (ptr, f32) -> ()
  %6 = "lo.add"(%0, %1) : (f32, f32) -> f32
  "lo.store"(%2, %6) {offset = 4} : (ptr, f32) -> ()
  "lo.return"() : () -> ()
}
"#,
        );
        assert!(f.canonicalize(v[3]));
        assert!(!f.canonicalize(v[4]) && !f.canonicalize(v[5]));
        assert!(f.canonicalize(v[6]));
        assert!(!f.never_nan(v[5]));
    }

    #[test]
    fn every_result_of_a_call_may_be_nan() {
        // A call's lanes are all unknown: `max(%4, %0)` needs the general form (a regression:
        // only the first result used to be checked, so the second stayed "never NaN").
        let (f, v) = facts(
            r#"func @f(%0: f32) -> (f32, f32) {
  %1, %2 = "lo.call"(%0) {callee = @g} : (f32) -> (f32, f32)
  %3 = "lo.max"(%1, %0) : (f32, f32) -> f32
  %4 = "lo.max"(%2, %0) : (f32, f32) -> f32
  "lo.return"(%3, %4) : (f32, f32) -> ()
}
func @g(%0: f32) -> (f32, f32)
"#,
        );
        assert!(!f.never_nan(v[1]) && !f.never_nan(v[2]));
        assert_eq!(f.min_max_form(v[2], v[0]), MinMaxForm::General);
    }

    #[test]
    fn loop_arguments_are_never_nan_only_when_every_incoming_value_is() {
        let (f, v) = facts(
            r#"func @f(%0: f32, %1: i1) -> (f32) {
  %2 = "lo.const"() {value = 0.0 : f32} : () -> f32
  "lo.br"()[^bb1(%2 : f32)] : () -> ()
^bb1(%3: f32):
  %4 = "lo.const"() {value = 1.0 : f32} : () -> f32
  %5 = "lo.add"(%3, %4) : (f32, f32) -> f32
  "lo.cond_br"(%1)[^bb1(%5 : f32), ^bb2] : (i1) -> ()
^bb2:
  %6 = "lo.add"(%3, %0) : (f32, f32) -> f32
  "lo.return"(%6) : (f32) -> ()
}
"#,
        );
        assert!(f.never_nan(v[3]) && f.never_nan(v[5]));
        assert!(!f.never_nan(v[6]));
        assert!(f.canonicalize(v[6]));
        // A zero constant keeps `min(x, 0)` general: the tie of +0 and -0 needs the order.
        assert_eq!(f.min_max_form(v[0], v[2]), MinMaxForm::General);
    }
}
