//! A CUDA device and its memory: opening device `n` (its primary context, made current on the
//! calling thread), named device buffers (allocated zeroed, uploaded, downloaded, freed on
//! drop), the per-thread stack limit, memory information and synchronization. Input: host data
//! as plain-old-data slices; output: [`DeviceBuffer`]s and their contents back. Every failure
//! is a [`CudaError`] naming the buffer.

#![allow(unsafe_code)]

use crate::args::DevicePtr;
use crate::driver::{self, check, check_what, DriverInfo};
use crate::error::{CudaError, CUDA_ERROR_INVALID_DEVICE, CUDA_ERROR_OUT_OF_MEMORY};
use cudarc::driver::sys;
use scion_runtime::geom::{Ray, Triangle};
use std::ffi::{c_char, c_int, c_void, CStr};

/// Types whose values are plain bytes: no padding, no pointers the device could not use, and
/// every bit pattern a valid value, so they can be copied to and from the device as bytes.
///
/// # Safety
/// Implementors must be `#[repr(C)]` (or primitive) with no padding bytes and no invalid bit
/// patterns.
pub unsafe trait DeviceCopy: Copy {}

// SAFETY: primitives: no padding, every bit pattern valid.
unsafe impl DeviceCopy for u8 {}
// SAFETY: as above.
unsafe impl DeviceCopy for u32 {}
// SAFETY: as above.
unsafe impl DeviceCopy for i32 {}
// SAFETY: as above.
unsafe impl DeviceCopy for u64 {}
// SAFETY: as above.
unsafe impl DeviceCopy for f32 {}
// SAFETY: an array of a `DeviceCopy` type has no padding between elements.
unsafe impl<T: DeviceCopy, const N: usize> DeviceCopy for [T; N] {}
// SAFETY: `#[repr(C)]`, eight `f32`s (32 bytes, checked in `trace`), no padding.
unsafe impl DeviceCopy for Ray {}
// SAFETY: `#[repr(C)]`, nine `f32`s and a `u32` (40 bytes), no padding.
unsafe impl DeviceCopy for Triangle {}
// SAFETY: `#[repr(C)]`, eight `f32`s and a `u32` (36 bytes, checked in the runtime), no padding.
unsafe impl DeviceCopy for scion_runtime::primitive::Segment {}
// SAFETY: `#[repr(C)]`, nine `[f32; 4]` and a `[u32; 4]` (160 bytes, checked in the runtime),
// no padding.
unsafe impl DeviceCopy for scion_runtime::triangle4::Triangle4 {}

/// The bytes of a `DeviceCopy` slice.
pub fn bytes_of<T: DeviceCopy>(data: &[T]) -> &[u8] {
    // SAFETY: `T: DeviceCopy` has no padding, so every byte of the slice is initialized; the
    // length is the slice's size in bytes.
    unsafe { std::slice::from_raw_parts(data.as_ptr().cast::<u8>(), std::mem::size_of_val(data)) }
}

/// Checks that copying `bytes` (`what`: `writing` or `reading`) fits buffer `name` of `holds`
/// bytes; the error names the buffer.
pub fn check_copy_len(name: &str, holds: u64, bytes: usize, what: &str) -> Result<(), CudaError> {
    if bytes as u64 > holds {
        return Err(CudaError::Host(format!(
            "{what} {bytes} bytes {} `{name}`, which holds {holds} bytes",
            if what == "writing" { "into" } else { "from" },
        )));
    }
    Ok(())
}

/// An open CUDA device with its primary context.
pub struct Device {
    ordinal: i32,
    device: sys::CUdevice,
    context: sys::CUcontext,
    /// The device's name (`NVIDIA H100 80GB HBM3`).
    pub name: String,
    /// Compute capability (major, minor).
    pub compute_capability: (i32, i32),
    /// What the driver probe found.
    pub driver: DriverInfo,
}

impl std::fmt::Debug for Device {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Device({}: {}, sm_{}{})",
            self.ordinal, self.name, self.compute_capability.0, self.compute_capability.1
        )
    }
}

impl Device {
    /// Opens device `ordinal`: probes the driver ([`driver::probe`]), checks the ordinal,
    /// retains the primary context and makes it current on this thread.
    pub fn open(ordinal: i32) -> Result<Device, CudaError> {
        let info = driver::probe()?;
        let mut count: c_int = 0;
        // SAFETY: the probe checked that the driver has this function and ran `cuInit`.
        let r = unsafe { sys::cuDeviceGetCount(&mut count) };
        check(r).map_err(|code| CudaError::NoDevice {
            count: 0,
            ordinal,
            code: Some(code),
        })?;
        if count == 0 || ordinal < 0 || ordinal >= count {
            return Err(CudaError::NoDevice {
                count,
                ordinal,
                code: None,
            });
        }
        let mut device: sys::CUdevice = 0;
        // SAFETY: as above; `ordinal` is in range.
        let r = unsafe { sys::cuDeviceGet(&mut device, ordinal) };
        check(r).map_err(|code| CudaError::NoDevice {
            count,
            ordinal,
            code: Some(code),
        })?;
        let mut name = [0 as c_char; 256];
        // SAFETY: writes at most 256 bytes including the NUL into `name`.
        let r = unsafe { sys::cuDeviceGetName(name.as_mut_ptr(), name.len() as c_int, device) };
        check_what(r, || "cuDeviceGetName".into())?;
        // SAFETY: the driver NUL-terminated the name inside the buffer.
        let name = unsafe { CStr::from_ptr(name.as_ptr()) }
            .to_string_lossy()
            .into_owned();
        let attr = |a: sys::CUdevice_attribute| -> Result<i32, CudaError> {
            let mut v: c_int = 0;
            // SAFETY: writes one int for a valid device.
            let r = unsafe { sys::cuDeviceGetAttribute(&mut v, a, device) };
            check_what(r, || format!("cuDeviceGetAttribute({a:?})"))?;
            Ok(v)
        };
        let cc = (
            attr(sys::CUdevice_attribute::CU_DEVICE_ATTRIBUTE_COMPUTE_CAPABILITY_MAJOR)?,
            attr(sys::CUdevice_attribute::CU_DEVICE_ATTRIBUTE_COMPUTE_CAPABILITY_MINOR)?,
        );
        let mut context: sys::CUcontext = std::ptr::null_mut();
        // SAFETY: retains the device's primary context (released in `Drop`).
        let r = unsafe { sys::cuDevicePrimaryCtxRetain(&mut context, device) };
        check(r).map_err(|code| match code.code {
            CUDA_ERROR_INVALID_DEVICE => CudaError::NoDevice {
                count,
                ordinal,
                code: Some(code.clone()),
            },
            _ => CudaError::Driver {
                what: format!("creating a context on device {ordinal} ({name})"),
                code,
            },
        })?;
        let dev = Device {
            ordinal,
            device,
            context,
            name,
            compute_capability: cc,
            driver: info,
        };
        dev.bind()?;
        Ok(dev)
    }

    /// Makes this device's context current on the calling thread.
    pub fn bind(&self) -> Result<(), CudaError> {
        // SAFETY: `context` is the retained primary context, alive until `Drop`.
        let r = unsafe { sys::cuCtxSetCurrent(self.context) };
        check_what(r, || {
            format!("making device {}'s context current", self.ordinal)
        })
    }

    /// The device's ordinal.
    pub fn ordinal(&self) -> i32 {
        self.ordinal
    }

    /// Free and total device memory in bytes.
    pub fn memory(&self) -> Result<(u64, u64), CudaError> {
        self.bind()?;
        let (mut free, mut total) = (0usize, 0usize);
        // SAFETY: writes two sizes; the context is current.
        let r = unsafe { sys::cuMemGetInfo_v2(&mut free, &mut total) };
        check_what(r, || "cuMemGetInfo".into())?;
        Ok((free as u64, total as u64))
    }

    /// Allocates `bytes` (at least 1) of zeroed device memory named `name` (the name is in
    /// every error about it). `cuMemAlloc` aligns to 256 bytes, more than any layout asks for.
    pub fn alloc(&self, name: &str, bytes: u64) -> Result<DeviceBuffer<'_>, CudaError> {
        self.bind()?;
        let len = usize::try_from(bytes.max(1)).map_err(|_| CudaError::OutOfMemory {
            buffer: name.to_string(),
            bytes,
            free_total: None,
        })?;
        let mut ptr: sys::CUdeviceptr = 0;
        // SAFETY: allocates `len` bytes in the current context.
        let r = unsafe { sys::cuMemAlloc_v2(&mut ptr, len) };
        if let Err(code) = check(r) {
            return Err(match code.code {
                CUDA_ERROR_OUT_OF_MEMORY => CudaError::OutOfMemory {
                    buffer: name.to_string(),
                    bytes,
                    free_total: self.memory().ok(),
                },
                _ => CudaError::Driver {
                    what: format!("allocating `{name}` ({bytes} bytes)"),
                    code,
                },
            });
        }
        let buf = DeviceBuffer {
            device: self,
            ptr,
            bytes,
            name: name.to_string(),
        };
        // SAFETY: `ptr` is a fresh allocation of `len` bytes.
        let r = unsafe { sys::cuMemsetD8_v2(ptr, 0, len) };
        check_what(r, || format!("zeroing `{name}` ({bytes} bytes)"))?;
        Ok(buf)
    }

    /// A new buffer named `name` holding `data`.
    pub fn upload<T: DeviceCopy>(
        &self,
        name: &str,
        data: &[T],
    ) -> Result<DeviceBuffer<'_>, CudaError> {
        let bytes = bytes_of(data);
        let buf = self.alloc(name, bytes.len() as u64)?;
        buf.write(data)?;
        Ok(buf)
    }

    /// Waits for all work on the device; `kernel` names the last launch for errors that
    /// surface here (a kernel's faults are reported at the next synchronization).
    pub fn synchronize(&self, kernel: &str) -> Result<(), CudaError> {
        self.bind()?;
        // SAFETY: waits on the current context.
        let r = unsafe { sys::cuCtxSynchronize() };
        check(r).map_err(|code| CudaError::Launch {
            kernel: kernel.to_string(),
            code,
        })
    }

    /// The per-thread stack size in bytes (`CU_LIMIT_STACK_SIZE`).
    pub fn stack_limit(&self) -> Result<usize, CudaError> {
        self.bind()?;
        let mut v = 0usize;
        // SAFETY: writes one size; the context is current.
        let r = unsafe { sys::cuCtxGetLimit(&mut v, sys::CUlimit::CU_LIMIT_STACK_SIZE) };
        check_what(r, || "reading the stack limit".into())?;
        Ok(v)
    }

    /// Sets the per-thread stack size (`cuCtxSetLimit(CU_LIMIT_STACK_SIZE)`); the driver
    /// reserves it for every resident thread, so a large value can fail for lack of memory.
    pub fn set_stack_limit(&self, bytes: usize) -> Result<(), CudaError> {
        self.bind()?;
        // SAFETY: sets a limit of the current context; no kernel is running (callers
        // synchronize first, and the driver waits otherwise).
        let r = unsafe { sys::cuCtxSetLimit(sys::CUlimit::CU_LIMIT_STACK_SIZE, bytes) };
        check(r).map_err(|code| match code.code {
            CUDA_ERROR_OUT_OF_MEMORY => CudaError::OutOfMemory {
                buffer: "the per-thread stack (CU_LIMIT_STACK_SIZE)".into(),
                bytes: bytes as u64,
                free_total: self.memory().ok(),
            },
            _ => CudaError::Driver {
                what: format!("setting the stack limit to {bytes} bytes"),
                code,
            },
        })
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: releases the primary context retained in `open`; buffers and modules borrow
        // the device, so they are gone already.
        let _ = unsafe { sys::cuDevicePrimaryCtxRelease_v2(self.device) };
    }
}

/// A device allocation with a name, freed on drop.
pub struct DeviceBuffer<'d> {
    device: &'d Device,
    ptr: sys::CUdeviceptr,
    bytes: u64,
    name: String,
}

impl std::fmt::Debug for DeviceBuffer<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "DeviceBuffer(`{}`, {} bytes @ {:#x})",
            self.name, self.bytes, self.ptr
        )
    }
}

impl DeviceBuffer<'_> {
    /// Its device address.
    pub fn ptr(&self) -> DevicePtr {
        DevicePtr(self.ptr)
    }

    /// Its size in bytes (as asked; the allocation holds at least 1).
    pub fn len(&self) -> u64 {
        self.bytes
    }

    /// True for a 0-byte buffer.
    pub fn is_empty(&self) -> bool {
        self.bytes == 0
    }

    /// Its name.
    pub fn name(&self) -> &str {
        &self.name
    }

    fn check_len(&self, bytes: usize, what: &str) -> Result<(), CudaError> {
        check_copy_len(&self.name, self.bytes, bytes, what)
    }

    /// Copies `data` to the start of the buffer.
    pub fn write<T: DeviceCopy>(&self, data: &[T]) -> Result<(), CudaError> {
        let bytes = bytes_of(data);
        self.check_len(bytes.len(), "writing")?;
        if bytes.is_empty() {
            return Ok(());
        }
        self.device.bind()?;
        // SAFETY: copies `bytes.len()` bytes, at most the allocation's size (checked), from a
        // live host slice; synchronous.
        let r =
            unsafe { sys::cuMemcpyHtoD_v2(self.ptr, bytes.as_ptr().cast::<c_void>(), bytes.len()) };
        check_what(r, || {
            format!("uploading {} bytes to `{}`", bytes.len(), self.name)
        })
    }

    /// Copies the start of the buffer into `out`.
    pub fn read<T: DeviceCopy>(&self, out: &mut [T]) -> Result<(), CudaError> {
        let len = std::mem::size_of_val(out);
        self.check_len(len, "reading")?;
        if len == 0 {
            return Ok(());
        }
        self.device.bind()?;
        // SAFETY: copies `len` bytes, at most the allocation's size (checked), into `out`,
        // whose type accepts any bit pattern (`DeviceCopy`); synchronous.
        let r = unsafe { sys::cuMemcpyDtoH_v2(out.as_mut_ptr().cast::<c_void>(), self.ptr, len) };
        check_what(r, || {
            format!("downloading {len} bytes from `{}`", self.name)
        })
    }

    /// The buffer's first `n` elements of `T`.
    pub fn download<T: DeviceCopy>(&self, n: usize) -> Result<Vec<T>, CudaError> {
        // SAFETY: every bit pattern, all zeros included, is a valid `T` (`DeviceCopy`).
        let zero: T = unsafe { std::mem::zeroed() };
        let mut v = vec![zero; n];
        self.read(&mut v)?;
        Ok(v)
    }
}

impl Drop for DeviceBuffer<'_> {
    fn drop(&mut self) {
        if self.device.bind().is_ok() {
            // SAFETY: frees this buffer's own allocation, once.
            let _ = unsafe { sys::cuMemFree_v2(self.ptr) };
        }
    }
}
