//! A kernel that faults: the error names the kernel. Alone in its test binary, since a fault
//! leaves the process's CUDA context unusable. Prints one `skip:` line without a GPU.

mod common;

use common::{device_or_skip, PROBE_PTX};
use scion_cuda::{CudaError, DevicePtr, Grid, KernelArg, Module};

#[test]
fn a_faulting_kernel_is_a_launch_error_naming_it() {
    let Some(dev) = device_or_skip("a_faulting_kernel_is_a_launch_error_naming_it") else {
        return;
    };
    let m = Module::load(&dev, PROBE_PTX).unwrap();
    let k = m.kernel("fault_kernel").unwrap();
    let e = k
        .run(Grid::SINGLE, &[KernelArg::Ptr(DevicePtr(0))])
        .unwrap_err();
    println!("{e}");
    match &e {
        CudaError::Launch { kernel, code } => {
            assert_eq!(kernel, "fault_kernel");
            assert_ne!(code.code, 0);
        }
        other => panic!("expected a launch error, got {other:?}"),
    }
    assert!(
        e.to_string().starts_with("kernel `fault_kernel` failed: "),
        "{e}"
    );
}
