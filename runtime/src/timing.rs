//! Timing by the paper's method (§9, architecture §7): a closure -> [`Timing`].
//!
//! One warm-up run (not recorded), 9 timed runs, the 2 lowest and 2 highest dropped, and the
//! mean of the remaining 5 reported, together with every raw time. Timing assertions never go
//! into tests (machines are shared and noisy); compare against a peer measured in the same run.

use std::time::{Duration, Instant};

/// How many runs to make and how many to drop at each end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TimingPlan {
    /// Untimed runs first.
    pub warmup: usize,
    /// Timed runs.
    pub runs: usize,
    /// Lowest times dropped.
    pub drop_low: usize,
    /// Highest times dropped.
    pub drop_high: usize,
}

impl TimingPlan {
    /// The paper's plan: 1 warm-up, 9 runs, drop 2 + 2, mean of 5.
    pub const PAPER: TimingPlan = TimingPlan {
        warmup: 1,
        runs: 9,
        drop_low: 2,
        drop_high: 2,
    };
}

impl Default for TimingPlan {
    fn default() -> TimingPlan {
        TimingPlan::PAPER
    }
}

/// The outcome of a measurement.
#[derive(Clone, Debug, PartialEq)]
pub struct Timing {
    /// Every timed run, in the order they ran.
    pub raw: Vec<Duration>,
    /// Mean of the runs left after dropping the lowest and highest.
    pub mean: Duration,
}

impl Timing {
    /// Mean time per query, in nanoseconds, for a batch of `queries`.
    pub fn ns_per_query(&self, queries: usize) -> f64 {
        self.mean.as_secs_f64() * 1e9 / queries.max(1) as f64
    }

    /// Queries per second for a batch of `queries`.
    pub fn queries_per_second(&self, queries: usize) -> f64 {
        queries as f64 / self.mean.as_secs_f64().max(f64::MIN_POSITIVE)
    }
}

/// Measures `f` by the paper's plan.
pub fn measure(f: impl FnMut()) -> Timing {
    measure_with(&TimingPlan::PAPER, f)
}

/// Measures `f` by `plan`. If the plan would drop every run, nothing is dropped.
pub fn measure_with(plan: &TimingPlan, mut f: impl FnMut()) -> Timing {
    for _ in 0..plan.warmup {
        f();
    }
    let raw: Vec<Duration> = (0..plan.runs.max(1))
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed()
        })
        .collect();
    let mean = trimmed_mean(&raw, plan.drop_low, plan.drop_high);
    Timing { raw, mean }
}

/// Mean of `times` without the `low` smallest and `high` largest (all of them if that would
/// leave none).
pub fn trimmed_mean(times: &[Duration], low: usize, high: usize) -> Duration {
    if times.is_empty() {
        return Duration::ZERO;
    }
    let mut sorted = times.to_vec();
    sorted.sort_unstable();
    let kept = if low + high < sorted.len() {
        &sorted[low..sorted.len() - high]
    } else {
        &sorted[..]
    };
    kept.iter().sum::<Duration>() / kept.len() as u32
}

/// The columns of a peers file: one peer library's measurement of a context (scene, query
/// kind, query set, size, threads) together with a Scion contender's measured in the same run,
/// its anchor (`BACKEND LAYOUT`, as `llvm-O3 pbrt`), so that the ratio between them, measured in
/// one run, can place the peer among the layouts of another run (`scion explore --peers`).
/// `bytes` is the peer's structure (empty when it does not say), `triangles` the scene's.
/// Written by the peers benchmark (`--peer-csv`) and scripts/bench-closest-point.sh.
pub const PEER_FIELDS: [&str; 11] = [
    "scene",
    "kind",
    "queries",
    "n",
    "threads",
    "peer",
    "bytes",
    "triangles",
    "ns_per_query",
    "anchor",
    "anchor_ns_per_query",
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn drops_two_lowest_and_two_highest() {
        let ms = |v: &[u64]| {
            v.iter()
                .map(|&x| Duration::from_millis(x))
                .collect::<Vec<_>>()
        };
        let times = ms(&[100, 1, 2, 10, 11, 12, 13, 14, 200]);
        assert_eq!(trimmed_mean(&times, 2, 2), Duration::from_millis(12));
        assert_eq!(trimmed_mean(&ms(&[5]), 2, 2), Duration::from_millis(5));
        assert_eq!(trimmed_mean(&[], 2, 2), Duration::ZERO);
    }

    #[test]
    fn runs_warmup_plus_nine() {
        let mut calls = 0;
        let t = measure(|| calls += 1);
        assert_eq!(calls, 10);
        assert_eq!(t.raw.len(), 9);
        assert!(t.ns_per_query(10) >= 0.0);
    }
}
