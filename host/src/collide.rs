//! Collision entries (`QueryKind::Collide`) run as a C host runs them: one call of the batch
//! entry `scion_A_L(B, queries, results, 0, 1, root, B1, root1)` over two trees packed by the
//! same layout, its result record a sink (docs/c-abi.md: the address of a caller-owned array of
//! `(u32, u32)` pairs, its capacity, and the count the traversal sets to the number of pairs
//! it met). When the count exceeds the capacity the array was too small: the call runs again
//! with an array of that size. The pairs come back sorted, without repeats.

// Calling generated machine code through a function pointer needs unsafe; the call says why it
// is sound.
#![allow(unsafe_code)]

use crate::entries::{Entries, PackedEntries, RootTy, RunError};
use scion_ir::types::{IntTy, Type};

/// The pairs of a collision run.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Collision {
    /// `(face id in the first tree, face id in the second)`, sorted, no repeats.
    pub pairs: Vec<(u32, u32)>,
    /// Pairs the traversal inserted (before sorting; more than `pairs.len()` only if it met a
    /// pair twice).
    pub inserted: u64,
    /// Calls of the entry: 1, or 2 when the first array was too small.
    pub calls: u32,
}

/// The batch entry over two trees: `(B, q, r, begin, end, root, B1, root1) -> status`.
type Batch2<R> = unsafe extern "C" fn(
    *const *const u8,
    *const u8,
    *mut u8,
    u64,
    u64,
    R,
    *const *const u8,
    R,
) -> i32;

/// Calls `batch` for query 0 with the result record `record`.
///
/// # Safety
/// `batch` must be a batch entry over two trees whose root reference has the C type `R`, the
/// tables must be the packed buffers of two non-empty trees of its layout, and `record` a
/// result record whose sink array has room for `capacity` pairs.
unsafe fn call<R: Copy>(
    batch: *const u8,
    (ta, ra): (*const *const u8, R),
    (tb, rb): (*const *const u8, R),
    record: &mut [u8; 24],
) -> i32 {
    let f = std::mem::transmute::<*const u8, Batch2<R>>(batch);
    // The entry reads no query record (collision has no query parameter): any address does.
    f(ta, record.as_ptr(), record.as_mut_ptr(), 0, 1, ra, tb, rb)
}

impl Entries {
    /// Runs the collision entry over the trees `a` and `b` (both packed by this entry's
    /// layout), with a first sink of `capacity` pairs.
    pub fn collide(
        &self,
        a: &PackedEntries,
        b: &PackedEntries,
        capacity: usize,
    ) -> Result<Collision, RunError> {
        let sig = self.sig();
        let sink = [Type::Ptr, Type::Int(IntTy::U64), Type::Int(IntTy::U64)];
        let fields: Vec<&Type> = sig.result.fields.iter().map(|f| &f.ty).collect();
        if sig.trees() != 2 || sig.query.size != 0 || fields != sink.iter().collect::<Vec<_>>() {
            return Err(RunError::Setup(format!(
                "`{}` is not a collision entry (two trees, no query, a set as its result)",
                sig.algorithm
            )));
        }
        if !a.nonempty || !b.nonempty {
            return Ok(Collision::default());
        }
        let batch = self.function(&sig.batch_fn()).map_err(RunError::Setup)?;
        let (ta, tb) = (a.table(), b.table());
        let mut capacity = capacity;
        let mut calls = 0;
        loop {
            let mut data = vec![0u32; 2 * capacity];
            let mut record = [0u8; 24];
            record[..8].copy_from_slice(&(data.as_mut_ptr() as u64).to_le_bytes());
            record[8..16].copy_from_slice(&(capacity as u64).to_le_bytes());
            calls += 1;
            let (ta, tb) = (ta.as_ptr(), tb.as_ptr());
            // SAFETY: `batch` is this entry's `scion_A_L` over two trees (checked above: two
            // tree parameters, no query, a sink as the result), called with its root reference
            // type; the tables hold the buffers `build` filled, alive in `a` and `b`; the sink
            // array `data` has room for `capacity` pairs and lives across the call, which
            // writes at most `capacity` of them (`count < capacity` guards each store).
            let status = unsafe {
                match a.root_ty {
                    RootTy::Ptr => call(
                        batch,
                        (ta, a.root as *const u8),
                        (tb, b.root as *const u8),
                        &mut record,
                    ),
                    RootTy::U64 => call(batch, (ta, a.root), (tb, b.root), &mut record),
                    RootTy::U32 => {
                        call(batch, (ta, a.root as u32), (tb, b.root as u32), &mut record)
                    }
                }
            };
            if status != 0 {
                return Err(RunError::Query(crate::entries::BatchFailure {
                    query: 0,
                    status,
                }));
            }
            let count = u64::from_le_bytes(record[16..24].try_into().expect("8 bytes"));
            let n = usize::try_from(count).map_err(|_| {
                RunError::Setup(format!("{count} pairs do not fit this machine's memory"))
            })?;
            if n > capacity {
                capacity = n;
                continue;
            }
            let mut pairs: Vec<(u32, u32)> = data[..2 * n]
                .chunks_exact(2)
                .map(|p| (p[0], p[1]))
                .collect();
            pairs.sort_unstable();
            pairs.dedup();
            return Ok(Collision {
                pairs,
                inserted: count,
                calls,
            });
        }
    }
}

/// Compares `got` with the reference pairs `want` (both sorted): `Ok` says what was checked,
/// `Err` names the first pair only one side has.
pub fn check_pairs(got: &[(u32, u32)], want: &[(u32, u32)]) -> Result<String, String> {
    if got == want {
        return Ok(format!(
            "identical to the reference: {} pairs (sweep over the triangles' boxes, the \
             prelude's triangle test)",
            want.len()
        ));
    }
    let extra = got.iter().find(|p| want.binary_search(p).is_err());
    let missing = want.iter().find(|p| got.binary_search(p).is_err());
    Err(format!(
        "the pairs differ from the reference: {} pairs, reference {}; first extra {:?}, first \
         missing {:?}",
        got.len(),
        want.len(),
        extra,
        missing
    ))
}

/// The pairs file: 8 bytes per pair, `u32` face id in the scene then in the rotated copy,
/// little-endian (docs/formats.md).
pub fn pairs_to_bytes(pairs: &[(u32, u32)]) -> Vec<u8> {
    pairs
        .iter()
        .flat_map(|&(a, b)| [a.to_le_bytes(), b.to_le_bytes()])
        .flatten()
        .collect()
}
