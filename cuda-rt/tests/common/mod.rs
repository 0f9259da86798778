//! Shared by the GPU test binaries: the device or a skip line, and the fixture PTX.

#![allow(dead_code)]

use scion_cuda::Device;

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
