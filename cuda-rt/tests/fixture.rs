//! Host-side checks of the stand-in kernels the GPU tests load: the checked-in PTX is what
//! LLVM 22's `llc` makes of `fixtures/probe.ll` (when `llc` is installed), and its kernels
//! have the shapes of backends.md §1, read by the PTX parser the launches rely on.

mod common;

use common::PROBE_PTX;
use scion_cuda::ptx;
use scion_cuda::trace::{check_ptx_kernels, KernelNames, RootRef};
use std::path::Path;
use std::process::Command;

#[test]
fn the_fixture_kernels_have_the_contract_shapes() {
    let names = KernelNames::new("Fixture", "probe");
    assert_eq!(check_ptx_kernels(PROBE_PTX, &names).unwrap(), RootRef::U32);
    assert_eq!(ptx::directive(PROBE_PTX, ".target"), Some("sm_75"));
}

#[test]
fn the_fixture_ptx_is_llc_output_of_probe_ll() {
    let llc = std::env::var("LLC").unwrap_or_else(|_| "/usr/lib/llvm-22/bin/llc".into());
    if !Path::new(&llc).exists() {
        println!("skip: no LLVM 22 llc at {llc} (set LLC) to regenerate the fixture");
        return;
    }
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    if !dir.join("probe.ll").exists() {
        // A test binary carried to another machine (gpu-kit) has no sources beside it.
        println!(
            "skip: no {} (a test binary away from its sources)",
            dir.display()
        );
        return;
    }
    let out = Command::new(&llc)
        .args(["-O2", "-march=nvptx64", "-mcpu=sm_75", "-o", "-"])
        .arg(dir.join("probe.ll"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        String::from_utf8(out.stdout).unwrap(),
        PROBE_PTX,
        "tests/fixtures/probe.ptx is stale: run tests/fixtures/regen.sh"
    );
}
