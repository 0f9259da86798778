//! `scion-tests`: the differential harness (issue 3, item 6, and the test plan of
//! docs/design/specialization.md). The backends it compares (the oracle, the runtime-contract
//! host, the mem interpreter and the JIT per layout) live in `scion-host`; this crate holds
//! what only the tests need.
//!
//! - [`cases`]: the scenes (real and generated hard cases), trees and ray sets the rows use,
//!   and [`cases::compare`], the bit-for-bit comparison with its one documented exception.
//! - `tests/differential.rs`, `tests/contract.rs`, `tests/jit.rs`, `tests/abi_entries.rs`,
//!   `tests/cpp_example.rs`: the differential table and the contract, JIT, C ABI and C++
//!   example tests.
pub mod cases;
