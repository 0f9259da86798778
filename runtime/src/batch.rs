//! Batch driver: a range of queries -> calls `f(begin, end)` on blocks of 64 queries spread
//! over threads with dynamic scheduling, like the paper's OpenMP set-up (`schedule(dynamic,
//! 64)`, architecture §5): the generated batch entry `scion_A_L(buffers, queries, results,
//! begin, end)` holds the per-query loop, the runtime only hands out blocks.
//!
//! The blocks are rayon's items, one per task (`with_max_len(1)`), so an idle thread steals
//! the next ones and a slow block never holds up the others. (A shared atomic counter read by
//! every thread of `ThreadPool::broadcast` did the same in principle, but two threads ran only
//! 1.64-1.71 times as fast as one on teapot's primary rays, against 1.89 now: docs/
//! performance-eight-wide.md, "Thirteenth session".) One thread means the calling thread runs every
//! block in order; `0` means one thread per core (rayon's default, which honors
//! `RAYON_NUM_THREADS`).

use rayon::prelude::*;

/// Queries per block.
pub const BLOCK: usize = 64;

/// Runs batches of queries on a fixed set of threads.
pub struct BatchDriver {
    /// `None`: run on the calling thread.
    pool: Option<rayon::ThreadPool>,
}

impl std::fmt::Debug for BatchDriver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BatchDriver")
            .field("threads", &self.threads())
            .finish()
    }
}

impl BatchDriver {
    /// A driver with `threads` threads: 1 = the calling thread, 0 = one per core.
    pub fn new(threads: usize) -> Result<BatchDriver, String> {
        if threads == 1 {
            return Ok(BatchDriver::sequential());
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("scion-batch-{i}"))
            .build()
            .map_err(|e| format!("cannot start {threads} batch threads: {e}"))?;
        Ok(BatchDriver { pool: Some(pool) })
    }

    /// A driver that runs everything on the calling thread.
    pub fn sequential() -> BatchDriver {
        BatchDriver { pool: None }
    }

    /// Number of threads that run blocks.
    pub fn threads(&self) -> usize {
        self.pool.as_ref().map_or(1, |p| p.current_num_threads())
    }

    /// Calls `f(begin, end)` for every block `[begin, end)` of `0..n` (blocks of [`BLOCK`],
    /// the last one shorter), each exactly once, in any order across threads.
    pub fn run(&self, n: usize, f: impl Fn(usize, usize) + Sync) {
        self.run_range(0..n, f)
    }

    /// Calls `f(begin, end)` for every block of `range`: blocks of [`BLOCK`] queries starting
    /// at `range.start`, the last one shorter, each exactly once.
    pub fn run_range(&self, range: std::ops::Range<usize>, f: impl Fn(usize, usize) + Sync) {
        let (start, n) = (range.start, range.end.saturating_sub(range.start));
        let blocks = n.div_ceil(BLOCK);
        let block = |b: usize| f(start + b * BLOCK, start + ((b + 1) * BLOCK).min(n));
        match &self.pool {
            None => (0..blocks).for_each(block),
            Some(pool) => {
                pool.install(|| (0..blocks).into_par_iter().with_max_len(1).for_each(block))
            }
        }
    }

    /// Calls `f(begin, chunk)` for every block of `items.len() / per_query` queries (blocks of
    /// [`BLOCK`] queries starting at 0, the last one shorter), `chunk` being the block's part
    /// of `items`, `per_query` items per query: [`run`](Self::run)'s blocks, each with its own
    /// results to write, so that nothing is locked per block. `per_query` 0 counts as 1.
    pub fn run_chunks<T: Send>(
        &self,
        items: &mut [T],
        per_query: usize,
        f: impl Fn(usize, &mut [T]) + Sync,
    ) {
        let per_block = per_query.max(1) * BLOCK;
        let each = |(b, chunk): (usize, &mut [T])| f(b * BLOCK, chunk);
        match &self.pool {
            None => items.chunks_mut(per_block).enumerate().for_each(each),
            Some(pool) => pool.install(|| {
                items
                    .par_chunks_mut(per_block)
                    .enumerate()
                    .with_max_len(1)
                    .for_each(each)
            }),
        }
    }

    /// `items.map(f)` in blocks of [`BLOCK`] over the driver's threads (work stealing over
    /// blocks); the result is in item order whatever the thread count.
    pub fn map<T: Sync, R: Send + Clone + Default>(
        &self,
        items: &[T],
        f: impl Fn(&T) -> R + Sync,
    ) -> Vec<R> {
        let mut out = vec![R::default(); items.len()];
        let fill = |(b, chunk): (usize, &mut [R])| {
            for (k, slot) in chunk.iter_mut().enumerate() {
                *slot = f(&items[b * BLOCK + k]);
            }
        };
        match &self.pool {
            None => out.chunks_mut(BLOCK).enumerate().for_each(fill),
            Some(pool) => pool.install(|| {
                out.par_chunks_mut(BLOCK)
                    .enumerate()
                    .with_max_len(1)
                    .for_each(fill)
            }),
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    #[test]
    fn every_block_once_for_any_thread_count() {
        for threads in [1, 2, 3] {
            let d = BatchDriver::new(threads).unwrap();
            assert_eq!(d.threads(), threads);
            for n in [0, 1, 63, 64, 65, 1000] {
                let seen = Mutex::new(vec![0u32; n]);
                d.run(n, |b, e| {
                    assert!(e - b <= BLOCK && b < e && b % BLOCK == 0);
                    let mut s = seen.lock().unwrap();
                    for x in &mut s[b..e] {
                        *x += 1;
                    }
                });
                assert!(seen.into_inner().unwrap().iter().all(|&c| c == 1));
            }
            let seen = Mutex::new(Vec::new());
            d.run_range(100..230, |b, e| seen.lock().unwrap().push((b, e)));
            let mut seen = seen.into_inner().unwrap();
            seen.sort();
            assert_eq!(seen, vec![(100, 164), (164, 228), (228, 230)]);
            for per_query in [1, 3] {
                let mut items = vec![0u32; 130 * per_query];
                d.run_chunks(&mut items, per_query, |b, chunk| {
                    assert_eq!(b % BLOCK, 0);
                    assert_eq!(chunk.len(), per_query * BLOCK.min(130 - b));
                    for (k, x) in chunk.iter_mut().enumerate() {
                        *x += (b * per_query + k) as u32 + 1;
                    }
                });
                assert!(items.iter().enumerate().all(|(i, &x)| x == i as u32 + 1));
            }
            let v: Vec<u32> = (0..1000).collect();
            let m = d.map(&v, |x| x * 2);
            assert_eq!(m, v.iter().map(|x| x * 2).collect::<Vec<_>>());
        }
    }

    #[test]
    fn one_thread_runs_on_the_caller_in_order() {
        let d = BatchDriver::sequential();
        let me = std::thread::current().id();
        let order = Mutex::new(Vec::new());
        d.run(200, |b, _| {
            assert_eq!(std::thread::current().id(), me);
            order.lock().unwrap().push(b);
        });
        assert_eq!(order.into_inner().unwrap(), vec![0, 64, 128, 192]);
    }
}
