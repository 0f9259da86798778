//! Split coverage (paper §6.1: "the split construct must cover the full domain of its
//! discriminant").
//!
//! Input: the patterns of a split's arms, in order, and the discriminant's value range (from its
//! integer type, or from the width of a bit slice). Output: which arms can never match (every
//! value they accept was taken by earlier arms) and one value no arm accepts, if any. Sets of
//! integers are kept as sorted, disjoint, inclusive intervals, so the cost is linear in the
//! number of arms times the number of intervals (at most one more per arm).

use crate::syntax::ast::SplitPatternKind;

/// Sorted, disjoint, inclusive intervals of integers.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct IntervalSet(pub Vec<(i128, i128)>);

impl IntervalSet {
    /// All of `lo..=hi` (empty when `lo > hi`).
    pub fn range(lo: i128, hi: i128) -> IntervalSet {
        if lo > hi {
            IntervalSet(Vec::new())
        } else {
            IntervalSet(vec![(lo, hi)])
        }
    }

    /// True when no value is in the set.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The smallest value in the set.
    pub fn first(&self) -> Option<i128> {
        self.0.first().map(|iv| iv.0)
    }

    /// The values in both sets.
    pub fn intersect(&self, other: &IntervalSet) -> IntervalSet {
        let mut out = Vec::new();
        for &(a, b) in &self.0 {
            for &(c, d) in &other.0 {
                let (lo, hi) = (a.max(c), b.min(d));
                if lo <= hi {
                    out.push((lo, hi));
                }
            }
        }
        out.sort_unstable();
        IntervalSet(out)
    }

    /// The values of `self` not in `other`.
    pub fn minus(&self, other: &IntervalSet) -> IntervalSet {
        let mut cur = self.0.clone();
        for &(c, d) in &other.0 {
            let mut next = Vec::new();
            for (a, b) in cur {
                if d < a || c > b {
                    next.push((a, b));
                    continue;
                }
                if a < c {
                    next.push((a, c - 1));
                }
                if d < b {
                    next.push((d + 1, b));
                }
            }
            cur = next;
        }
        IntervalSet(cur)
    }
}

/// The values of `lo..=hi` that `pattern` accepts.
pub fn accepted(pattern: &SplitPatternKind, lo: i128, hi: i128) -> IntervalSet {
    let all = IntervalSet::range(lo, hi);
    let part = match *pattern {
        SplitPatternKind::Eq(n) => IntervalSet::range(n, n),
        SplitPatternKind::Ne(n) => return all.minus(&IntervalSet::range(n, n)),
        SplitPatternKind::Lt(n) => IntervalSet::range(lo, n.saturating_sub(1)),
        SplitPatternKind::Le(n) => IntervalSet::range(lo, n),
        SplitPatternKind::Gt(n) => IntervalSet::range(n.saturating_add(1), hi),
        SplitPatternKind::Ge(n) => IntervalSet::range(n, hi),
        SplitPatternKind::Wildcard => return all,
    };
    all.intersect(&part)
}

/// What a split's arms cover.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Coverage {
    /// Indices of arms that can never match.
    pub unreachable: Vec<usize>,
    /// Whether some value reaches no arm.
    pub uncovered: Uncovered,
}

/// Whether a split leaves values unmatched.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Uncovered {
    /// Every value matches some arm.
    No,
    /// This value (the smallest such) matches no arm.
    Value(i128),
    /// The discriminant's domain is unknown and there is no `_` arm.
    Unknown,
}

/// Coverage of `patterns` (in order) over `domain` (inclusive), or over an unknown domain.
pub fn coverage(patterns: &[SplitPatternKind], domain: Option<(i128, i128)>) -> Coverage {
    let mut unreachable = Vec::new();
    let Some((lo, hi)) = domain else {
        let wild = patterns
            .iter()
            .position(|p| *p == SplitPatternKind::Wildcard);
        if let Some(w) = wild {
            unreachable.extend(w + 1..patterns.len());
        }
        let uncovered = if wild.is_some() {
            Uncovered::No
        } else {
            Uncovered::Unknown
        };
        return Coverage {
            unreachable,
            uncovered,
        };
    };
    let mut left = IntervalSet::range(lo, hi);
    for (i, p) in patterns.iter().enumerate() {
        let takes = accepted(p, lo, hi).intersect(&left);
        if takes.is_empty() {
            unreachable.push(i);
        }
        left = left.minus(&takes);
    }
    let uncovered = match left.first() {
        Some(v) => Uncovered::Value(v),
        None => Uncovered::No,
    };
    Coverage {
        unreachable,
        uncovered,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use SplitPatternKind::*;

    const U16: Option<(i128, i128)> = Some((0, 65535));

    #[test]
    fn gt_zero_and_zero_cover_u16() {
        let c = coverage(&[Gt(0), Eq(0)], U16);
        assert_eq!(
            c,
            Coverage {
                unreachable: vec![],
                uncovered: Uncovered::No
            }
        );
    }

    #[test]
    fn lt_and_gt_five_leave_five() {
        let c = coverage(&[Lt(5), Gt(5)], U16);
        assert_eq!(c.uncovered, Uncovered::Value(5));
    }

    #[test]
    fn arms_after_a_covering_set_are_unreachable() {
        let c = coverage(&[Le(3), Ne(2), Eq(7), Wildcard], Some((0, 15)));
        assert_eq!(
            c,
            Coverage {
                unreachable: vec![2, 3],
                uncovered: Uncovered::No
            }
        );
        let c = coverage(&[Wildcard, Eq(0)], None);
        assert_eq!(
            c,
            Coverage {
                unreachable: vec![1],
                uncovered: Uncovered::No
            }
        );
        assert_eq!(coverage(&[Eq(0)], None).uncovered, Uncovered::Unknown);
    }

    #[test]
    fn literal_outside_the_domain_is_unreachable() {
        let c = coverage(
            &[Eq(0xFFFF_FFFF), Lt(0x1000_0000), Wildcard],
            Some((0, (1 << 32) - 1)),
        );
        assert_eq!(c.unreachable, Vec::<usize>::new());
        let c = coverage(&[Eq(70000), Wildcard], U16);
        assert_eq!(c.unreachable, vec![0]);
    }

    fn matches(p: &SplitPatternKind, v: i128) -> bool {
        match *p {
            Eq(n) => v == n,
            Ne(n) => v != n,
            Lt(n) => v < n,
            Le(n) => v <= n,
            Gt(n) => v > n,
            Ge(n) => v >= n,
            Wildcard => true,
        }
    }

    fn pattern() -> impl proptest::strategy::Strategy<Value = SplitPatternKind> {
        use proptest::prelude::*;
        let lit = -3i128..260;
        prop_oneof![
            lit.clone().prop_map(Eq),
            lit.clone().prop_map(Ne),
            lit.clone().prop_map(Lt),
            lit.clone().prop_map(Le),
            lit.clone().prop_map(Gt),
            lit.prop_map(Ge),
            Just(Wildcard),
        ]
    }

    proptest::proptest! {
        /// Interval arithmetic agrees with trying every value of a `u8` discriminant.
        #[test]
        fn coverage_matches_brute_force(patterns in proptest::collection::vec(pattern(), 0..6)) {
            let c = coverage(&patterns, Some((0, 255)));
            let mut used = vec![false; patterns.len()];
            let mut first_uncovered = None;
            for v in 0..=255i128 {
                match patterns.iter().position(|p| matches(p, v)) {
                    Some(i) => used[i] = true,
                    None => {
                        if first_uncovered.is_none() {
                            first_uncovered = Some(v);
                        }
                    }
                }
            }
            let unreachable: Vec<usize> = (0..patterns.len()).filter(|i| !used[*i]).collect();
            proptest::prop_assert_eq!(c.unreachable, unreachable);
            let expected = match first_uncovered {
                Some(v) => Uncovered::Value(v),
                None => Uncovered::No,
            };
            proptest::prop_assert_eq!(c.uncovered, expected);
        }
    }
}
