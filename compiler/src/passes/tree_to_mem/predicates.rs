//! Variant tests of the [`Reader`]: the split predicates (paper §7.1), as the exact set of
//! discriminant values each arm takes after the arms before it (interval arithmetic over the
//! discriminant's domain: its integer type, or `2^(b-a)` values for a bit slice `x[a:b]`),
//! and-ed with the enclosing arm's test for nested splits and or-ed over the arms that realize
//! one variant. Tests are emitted in layer 0, before the chain of `tree.if`s.

use super::reader::{const_int, Reader};
use super::unsupported;
use crate::layout::domain::{accepted, IntervalSet};
use crate::layout::model::{ArmBody, GroupKind, ScopeId, ScopeKind, SplitId};
use crate::syntax::ast::ExprKind;
use scion_ir::diag::Diagnostic;
use scion_ir::tree::{CmpPred, Op};
use scion_ir::{Module, TypeId, ValueId};

type R<T> = Result<T, Diagnostic>;

impl Reader<'_> {
    /// The `i1` that is true when the node is of `variant`: the disjunction over the split arms
    /// realizing it of their effective predicates (an arm takes what earlier arms left).
    pub fn variant_test(&mut self, m: &mut Module, variant: &str) -> R<ValueId> {
        let model = &self.spec.model;
        let arms: Vec<(SplitId, usize)> = model
            .splits
            .iter()
            .enumerate()
            .flat_map(|(s, sp)| {
                sp.arms
                    .iter()
                    .enumerate()
                    .filter(|(_, a)| a.variant.name == variant)
                    .map(move |(k, _)| (s, k))
            })
            .collect();
        if arms.is_empty() {
            return Err(unsupported(
                Some(model.span),
                format!(
                    "no split arm of layout `{}` realizes variant `{variant}`",
                    model.name.name
                ),
            ));
        }
        let mut acc: Option<ValueId> = None;
        for (s, k) in arms {
            let c = self.arm_test(m, s, k)?;
            acc = Some(match acc {
                None => c,
                Some(a) => self.builder(m, true).binary(Op::Or, a, c),
            });
        }
        Ok(acc.expect("at least one arm"))
    }

    pub(super) fn arm_test(&mut self, m: &mut Module, s: SplitId, k: usize) -> R<ValueId> {
        let key = format!("#arm{s}.{k}");
        if let Some(v) = self.lookup(&key) {
            return Ok(v);
        }
        let model = &self.spec.model;
        let split = &model.splits[s];
        let scope = split.scope;
        let disc = split.discriminant.clone();
        let first_variant = split.arms[0].variant.name.clone();
        let patterns: Vec<_> = split.arms.iter().map(|a| a.pattern.kind.clone()).collect();
        // Discriminants are read before the chain of tests, in layer 0.
        let saved = self.layers.split_off(1);
        let d = self.expr(m, &first_variant, &disc, None);
        self.layers.extend(saved);
        let d = d?;
        let t = m.values[d].ty;
        let Some(it) = m.types.as_int(t) else {
            return Err(unsupported(
                Some(disc.span),
                "a split on a non-integer discriminant",
            ));
        };
        let (lo, hi) = match &disc.kind {
            ExprKind::Slice { lo, hi, .. } => match (const_int(lo), const_int(hi)) {
                (Some(a), Some(z)) if z > a && z - a < 64 => (0, (1i128 << (z - a)) - 1),
                _ => it.range(),
            },
            _ => it.range(),
        };
        let mut taken = IntervalSet(Vec::new());
        for p in &patterns[..k] {
            let acc = accepted(p, lo, hi);
            let mut all = taken.0.clone();
            all.extend(acc.0);
            all.sort_unstable();
            taken = IntervalSet(all);
        }
        let own = accepted(&patterns[k], lo, hi).minus(&taken);
        let pred = self.interval_test(m, d, t, &own, (lo, hi));
        let outer = self.scope_test(m, scope)?;
        let v = match outer {
            Some(o) => self.builder(m, true).binary(Op::And, o, pred),
            None => pred,
        };
        self.remember(key, v, true);
        Ok(v)
    }

    /// The condition under which members of `scope` exist (true at the top level).
    fn scope_test(&mut self, m: &mut Module, scope: ScopeId) -> R<Option<ValueId>> {
        let model = &self.spec.model;
        match model.scopes[scope].kind {
            ScopeKind::Top => Ok(None),
            ScopeKind::Arm { split, arm } => self.arm_test(m, split, arm).map(Some),
            ScopeKind::Group(g) if model.groups[g].kind == GroupKind::Indirect => {
                let from: Vec<(SplitId, usize)> = model
                    .splits
                    .iter()
                    .enumerate()
                    .flat_map(|(s, sp)| {
                        sp.arms
                            .iter()
                            .enumerate()
                            .filter_map(move |(k, a)| match &a.body {
                                ArmBody::From { group: Some(h), .. } if *h == g => Some((s, k)),
                                _ => None,
                            })
                    })
                    .collect();
                let mut acc = None;
                for (s, k) in from {
                    let c = self.arm_test(m, s, k)?;
                    acc = Some(match acc {
                        None => c,
                        Some(a) => self.builder(m, true).binary(Op::Or, a, c),
                    });
                }
                Ok(acc)
            }
            ScopeKind::Group(_) => match model.scopes[scope].parent {
                Some(p) => self.scope_test(m, p),
                None => Ok(None),
            },
        }
    }

    /// `d ∈ set` as comparisons against constants of `d`'s type, in layer 0.
    fn interval_test(
        &mut self,
        m: &mut Module,
        d: ValueId,
        t: TypeId,
        set: &IntervalSet,
        dom: (i128, i128),
    ) -> ValueId {
        let mut bd = self.builder(m, true);
        let (dlo, dhi) = dom;
        if set.0.is_empty() {
            return bd.const_bool(false);
        }
        if set.0 == [(dlo, dhi)] {
            return bd.const_bool(true);
        }
        // The complement of one value reads best as `!=`.
        if let [(a, b), (c, e)] = set.0[..] {
            if a == dlo && e == dhi && c == b + 2 {
                let k = bd.const_int(t, b + 1);
                return bd.cmp(CmpPred::Ne, d, k);
            }
        }
        let mut acc: Option<ValueId> = None;
        for &(a, b) in &set.0 {
            let c = if a == b {
                let k = bd.const_int(t, a);
                bd.cmp(CmpPred::Eq, d, k)
            } else if a == dlo {
                let k = bd.const_int(t, b);
                bd.cmp(CmpPred::Le, d, k)
            } else if b == dhi {
                let k = bd.const_int(t, a - 1);
                bd.cmp(CmpPred::Gt, d, k)
            } else {
                let ka = bd.const_int(t, a);
                let kb = bd.const_int(t, b);
                let x = bd.cmp(CmpPred::Ge, d, ka);
                let y = bd.cmp(CmpPred::Le, d, kb);
                bd.binary(Op::And, x, y)
            };
            acc = Some(match acc {
                None => c,
                Some(p) => bd.binary(Op::Or, p, c),
            });
        }
        acc.expect("non-empty set")
    }
}
