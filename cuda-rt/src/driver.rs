//! Finding and checking the CUDA driver before anything calls it. cudarc loads `libcuda`
//! lazily and panics when the library or one of its functions is missing; this module probes
//! first (the library, then every function this crate calls, then `cuInit` and the driver's
//! version), so a machine without a GPU gets [`CudaError::NoDriver`] and an old driver gets
//! [`CudaError::DriverTooOld`], never a panic. Input: the process's library search path;
//! output: [`DriverInfo`] or the error.

#![allow(unsafe_code)]

use crate::error::{CudaError, DriverCode, CUDA_ERROR_INSUFFICIENT_DRIVER, CUDA_ERROR_NO_DEVICE};
use cudarc::driver::sys;
use std::ffi::{c_char, c_int, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::OnceLock;

/// The oldest driver accepted: CUDA 11.8, the first to know sm_90 (H100) and PTX ISA 7.8.
pub const MIN_DRIVER_VERSION: i32 = 11080;

/// Every driver function this crate calls (cudarc resolves each on first use and panics when
/// one is missing, so they are all checked up front).
pub const REQUIRED_SYMBOLS: &[&str] = &[
    "cuInit",
    "cuDriverGetVersion",
    "cuGetErrorName",
    "cuGetErrorString",
    "cuDeviceGetCount",
    "cuDeviceGet",
    "cuDeviceGetName",
    "cuDeviceGetAttribute",
    "cuDevicePrimaryCtxRetain",
    "cuDevicePrimaryCtxRelease_v2",
    "cuCtxSetCurrent",
    "cuCtxSynchronize",
    "cuCtxGetLimit",
    "cuCtxSetLimit",
    "cuMemGetInfo_v2",
    "cuMemAlloc_v2",
    "cuMemFree_v2",
    "cuMemsetD8_v2",
    "cuMemcpyHtoD_v2",
    "cuMemcpyDtoH_v2",
    "cuModuleLoadDataEx",
    "cuModuleUnload",
    "cuModuleGetFunction",
    "cuLaunchKernel",
    "cuEventCreate",
    "cuEventRecord",
    "cuEventSynchronize",
    "cuEventDestroy_v2",
];

/// What the probe found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DriverInfo {
    /// `cuDriverGetVersion`: `major * 1000 + minor * 10`.
    pub version: i32,
    /// Which `cuEventElapsedTime` the driver exports (`_v2` from CUDA 12.8; `None` when
    /// neither: kernel times are then taken on the host around a synchronize).
    pub elapsed: Option<ElapsedFn>,
}

/// The event timing entry point available.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ElapsedFn {
    /// `cuEventElapsedTime_v2` (CUDA 12.8 and later).
    V2,
    /// `cuEventElapsedTime` (older drivers; kept by newer ones for old binaries).
    V1,
}

/// The library names cudarc tries for the driver, in order.
pub fn searched_names() -> Vec<String> {
    let mut names = cudarc::get_lib_name_candidates("cuda");
    let mut seen = std::collections::HashSet::new();
    names.retain(|n| seen.insert(n.clone()));
    names
}

/// Probes once per process: library, functions, `cuInit(0)`, version. Later calls return the
/// first answer.
pub fn probe() -> Result<DriverInfo, CudaError> {
    static PROBE: OnceLock<Result<DriverInfo, CudaError>> = OnceLock::new();
    PROBE
        .get_or_init(|| {
            catch_unwind(AssertUnwindSafe(probe_uncached)).unwrap_or_else(|p| {
                let what = p
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_else(|| "a panic".into());
                Err(CudaError::NoDriver {
                    searched: vec![format!("(loading the driver failed: {what})")],
                })
            })
        })
        .clone()
}

fn probe_uncached() -> Result<DriverInfo, CudaError> {
    // SAFETY: `is_culib_present` only tries `dlopen` on each candidate name and closes it.
    if !unsafe { sys::is_culib_present() } {
        return Err(CudaError::NoDriver {
            searched: searched_names(),
        });
    }
    // SAFETY: the library is present (just checked), so `culib` opens it instead of panicking.
    let lib = unsafe { sys::culib() };
    let has = |name: &str| {
        // SAFETY: looking a symbol up does not call it; the pointer type is irrelevant here.
        unsafe { lib.get::<*const ()>(name.as_bytes()) }.is_ok()
    };
    let version = has("cuDriverGetVersion").then(|| {
        let mut v: c_int = 0;
        // SAFETY: `cuDriverGetVersion` exists (checked) and writes one int; it needs no
        // `cuInit`.
        let r = unsafe { sys::cuDriverGetVersion(&mut v) };
        (r == sys::CUresult::CUDA_SUCCESS).then_some(v)
    });
    let version = version.flatten();
    let missing = REQUIRED_SYMBOLS.iter().copied().find(|s| !has(s));
    let version = check_library(version, missing)?;
    // SAFETY: `cuInit` exists (checked); flags must be 0.
    let r = unsafe { sys::cuInit(0) };
    if r != sys::CUresult::CUDA_SUCCESS {
        return Err(init_error(driver_code(r), version));
    }
    let elapsed = if has("cuEventElapsedTime_v2") {
        Some(ElapsedFn::V2)
    } else if has("cuEventElapsedTime") {
        Some(ElapsedFn::V1)
    } else {
        None
    };
    Ok(DriverInfo { version, elapsed })
}

/// The verdict on a loaded driver library: its version, or why it is too old (a function this
/// crate calls is missing, the version cannot be read, or it is older than
/// [`MIN_DRIVER_VERSION`]).
pub fn check_library(version: Option<i32>, missing: Option<&str>) -> Result<i32, CudaError> {
    if let Some(missing) = missing {
        return Err(CudaError::DriverTooOld {
            version,
            missing: format!("it has no `{missing}`"),
        });
    }
    let Some(version) = version else {
        return Err(CudaError::DriverTooOld {
            version: None,
            missing: "cuDriverGetVersion failed".into(),
        });
    };
    if version < MIN_DRIVER_VERSION {
        return Err(CudaError::DriverTooOld {
            version: Some(version),
            missing: format!(
                "CUDA {} or newer is required",
                crate::error::version_text(MIN_DRIVER_VERSION)
            ),
        });
    }
    Ok(version)
}

/// What a failed `cuInit` means: no device, a driver too old for the installed kernel
/// module, or another driver error.
pub fn init_error(code: DriverCode, version: i32) -> CudaError {
    match code.code {
        CUDA_ERROR_NO_DEVICE => CudaError::NoDevice {
            count: 0,
            ordinal: 0,
            code: Some(code),
        },
        CUDA_ERROR_INSUFFICIENT_DRIVER => CudaError::DriverTooOld {
            version: Some(version),
            missing: format!("cuInit: {code}"),
        },
        _ => CudaError::Driver {
            what: "cuInit".into(),
            code,
        },
    }
}

/// The driver's name and description of `r`.
pub fn driver_code(r: sys::CUresult) -> DriverCode {
    let text = |f: unsafe fn(sys::CUresult, *mut *const c_char) -> sys::CUresult| {
        let mut p: *const c_char = std::ptr::null();
        // SAFETY: only called after the probe found the library and these functions; they
        // write a pointer to a static string or fail.
        let ok = unsafe { f(r, &mut p) } == sys::CUresult::CUDA_SUCCESS;
        // SAFETY: on success `p` is a NUL-terminated static string owned by the driver.
        (ok && !p.is_null()).then(|| unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
    };
    DriverCode {
        code: r as u32,
        name: text(sys::cuGetErrorName),
        description: text(sys::cuGetErrorString),
    }
}

/// `Ok` on `CUDA_SUCCESS`, else the driver's code.
pub fn check(r: sys::CUresult) -> Result<(), DriverCode> {
    if r == sys::CUresult::CUDA_SUCCESS {
        Ok(())
    } else {
        Err(driver_code(r))
    }
}

/// `check` as a [`CudaError::Driver`] naming `what`.
pub fn check_what(r: sys::CUresult, what: impl FnOnce() -> String) -> Result<(), CudaError> {
    check(r).map_err(|code| CudaError::Driver { what: what(), code })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn code(n: u32) -> DriverCode {
        DriverCode {
            code: n,
            name: None,
            description: None,
        }
    }

    #[test]
    fn old_or_incomplete_drivers_are_too_old() {
        let e = check_library(Some(12080), Some("cuLaunchKernel")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "the CUDA driver is too old (it supports CUDA 12.8): it has no `cuLaunchKernel`"
        );
        let e = check_library(Some(11040), None).unwrap_err();
        assert_eq!(
            e.to_string(),
            "the CUDA driver is too old (it supports CUDA 11.4): CUDA 11.8 or newer is required"
        );
        assert!(matches!(
            check_library(None, None),
            Err(CudaError::DriverTooOld { version: None, .. })
        ));
        assert_eq!(check_library(Some(13000), None).unwrap(), 13000);
        assert_eq!(
            check_library(Some(MIN_DRIVER_VERSION), None).unwrap(),
            11080
        );
    }

    #[test]
    fn init_failures_are_classified() {
        assert!(matches!(
            init_error(code(CUDA_ERROR_NO_DEVICE), 13000),
            CudaError::NoDevice { count: 0, .. }
        ));
        assert!(init_error(code(CUDA_ERROR_NO_DEVICE), 13000)
            .to_string()
            .starts_with("no CUDA device"));
        assert!(matches!(
            init_error(code(CUDA_ERROR_INSUFFICIENT_DRIVER), 12000),
            CudaError::DriverTooOld { .. }
        ));
        assert_eq!(
            init_error(code(999), 13000).to_string(),
            "cuInit failed: CUDA error 999"
        );
    }

    #[test]
    fn every_needed_function_is_probed() {
        // The functions `device` and `module` call through cudarc's lazy loader.
        let sources = [include_str!("device.rs"), include_str!("module.rs")];
        for src in sources {
            for (i, _) in src.match_indices("sys::cu") {
                let name: String = src[i + 5..]
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                if name.starts_with("cuEventElapsedTime") {
                    continue; // probed separately: one of two versions
                }
                assert!(
                    REQUIRED_SYMBOLS.contains(&name.as_str()),
                    "`{name}` is not probed"
                );
            }
        }
    }
}
