//! Progress of long interpreted runs: a process-wide count of the queries the interpreters
//! (the `tree` oracle and the `mem` interpreter) have answered, which they add to after every
//! query and a front end reads to draw a progress bar (`scion trace --backend interp` on a
//! large scene runs for hours). Counting is one relaxed atomic add per query, next to an
//! interpreted traversal of thousands of operations.

use std::sync::atomic::{AtomicU64, Ordering};

static DONE: AtomicU64 = AtomicU64::new(0);

/// Counts `n` more answered queries.
pub fn add(n: u64) {
    DONE.fetch_add(n, Ordering::Relaxed);
}

/// Queries answered since the process started (or since [`reset`]).
pub fn done() -> u64 {
    DONE.load(Ordering::Relaxed)
}

/// Starts counting from zero.
pub fn reset() {
    DONE.store(0, Ordering::Relaxed);
}
