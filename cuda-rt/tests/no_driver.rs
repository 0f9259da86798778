//! Opening a device never panics: without a driver (this project's CI) it is one clear
//! error line; with one, an ordinal past the last device is a clear `no CUDA device` error.

use scion_cuda::{CudaError, Device};

#[test]
fn opening_a_device_is_a_value_not_a_panic() {
    match Device::open(0) {
        Err(e) => {
            let m = e.to_string();
            println!("no device here: {m}");
            assert!(!m.contains('\n'), "one line: {m}");
            match &e {
                CudaError::NoDriver { searched } => {
                    assert!(m.starts_with("no CUDA driver"), "{m}");
                    assert!(searched.iter().any(|s| s == "libcuda.so.1"), "{searched:?}");
                }
                CudaError::NoDevice { .. } => assert!(m.starts_with("no CUDA device"), "{m}"),
                CudaError::DriverTooOld { .. } => {
                    assert!(m.starts_with("the CUDA driver is too old"), "{m}")
                }
                other => panic!("unexpected error opening device 0: {other:?}"),
            }
            // The probe's answer is stable.
            assert_eq!(Device::open(0).unwrap_err(), e);
        }
        Ok(dev) => {
            println!("device 0: {dev:?}");
            let e = Device::open(1 << 20).unwrap_err();
            assert!(matches!(e, CudaError::NoDevice { .. }), "{e:?}");
            assert!(e.to_string().starts_with("no CUDA device 1048576"), "{e}");
        }
    }
}
