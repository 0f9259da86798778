//! Shared by the GPU test binaries: the device or a skip line, and the fixture PTX.

#![allow(dead_code)]

use scion_cuda::Device;
use std::sync::{Mutex, MutexGuard};

/// Held by the tests that change or check the context's stack limit (one per process, shared
/// by the test threads).
static STACK_LIMIT: Mutex<()> = Mutex::new(());

/// Serializes the tests that touch the stack limit.
pub fn stack_limit_lock() -> MutexGuard<'static, ()> {
    STACK_LIMIT.lock().unwrap_or_else(|p| p.into_inner())
}

/// The stand-in kernels of `fixtures/probe.ll` (layout `Fixture`, algorithm `probe`).
pub const PROBE_PTX: &str = include_str!("../fixtures/probe.ptx");

/// Device 0 (or `SCION_CUDA_DEVICE`), or `None` after printing `skip: <reason>` for `test`.
pub fn device_or_skip(test: &str) -> Option<Device> {
    match scion_cuda::open_for_tests() {
        Ok(d) => Some(d),
        Err(reason) => {
            println!("skip: {reason} [{test}]");
            None
        }
    }
}
