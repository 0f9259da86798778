//! The errors of the CUDA runtime: every way opening a device, moving memory, loading PTX or
//! launching a kernel can fail, as values with a message a user can act on. Input: a CUDA
//! driver result code and what was being done (the buffer, the kernel); output: [`CudaError`],
//! whose `Display` is the one-line message `scion` prints.

use std::fmt;

/// A CUDA driver result code (`CUresult`) with its name and description, as the driver gives
/// them (`cuGetErrorName` / `cuGetErrorString`), or just the number when the driver could not
/// name it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DriverCode {
    /// The numeric `CUresult`.
    pub code: u32,
    /// `CUDA_ERROR_...`, when known.
    pub name: Option<String>,
    /// The driver's description, when known.
    pub description: Option<String>,
}

impl fmt::Display for DriverCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.name, &self.description) {
            (Some(n), Some(d)) => write!(f, "{n} ({}): {d}", self.code),
            (Some(n), None) => write!(f, "{n} ({})", self.code),
            (None, _) => write!(f, "CUDA error {}", self.code),
        }
    }
}

/// `CUDA_ERROR_OUT_OF_MEMORY`.
pub const CUDA_ERROR_OUT_OF_MEMORY: u32 = 2;
/// `CUDA_ERROR_NO_DEVICE`.
pub const CUDA_ERROR_NO_DEVICE: u32 = 100;
/// `CUDA_ERROR_INVALID_DEVICE`.
pub const CUDA_ERROR_INVALID_DEVICE: u32 = 101;
/// `CUDA_ERROR_INSUFFICIENT_DRIVER`.
pub const CUDA_ERROR_INSUFFICIENT_DRIVER: u32 = 35;
/// `CUDA_ERROR_UNSUPPORTED_PTX_VERSION`.
pub const CUDA_ERROR_UNSUPPORTED_PTX_VERSION: u32 = 222;
/// `CUDA_ERROR_LAUNCH_OUT_OF_RESOURCES`.
pub const CUDA_ERROR_LAUNCH_OUT_OF_RESOURCES: u32 = 701;

/// Everything the CUDA runtime reports.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CudaError {
    /// No CUDA driver library could be loaded (no NVIDIA driver on this machine).
    NoDriver {
        /// The library names tried.
        searched: Vec<String>,
    },
    /// The driver library is there but lacks a function this runtime needs, or reports a
    /// version older than the one required.
    DriverTooOld {
        /// The driver's CUDA version (`major * 1000 + minor * 10`), when it could be read.
        version: Option<i32>,
        /// What is missing: a function name or the required version.
        missing: String,
    },
    /// The driver loaded but reports no CUDA device (or the requested ordinal does not exist).
    NoDevice {
        /// How many devices the driver reports.
        count: i32,
        /// The ordinal asked for.
        ordinal: i32,
        /// The driver's code, when `cuInit` or `cuDeviceGet` failed.
        code: Option<DriverCode>,
    },
    /// A device allocation failed for lack of memory.
    OutOfMemory {
        /// The buffer being allocated.
        buffer: String,
        /// Its size.
        bytes: u64,
        /// Free and total device memory at the time, when the driver could tell.
        free_total: Option<(u64, u64)>,
    },
    /// The driver rejected a PTX module; `log` is the JIT's error log.
    ModuleLoad {
        /// The driver's code.
        code: DriverCode,
        /// The PTX JIT error log (may be empty).
        log: String,
    },
    /// The module has no kernel of this name.
    MissingKernel {
        /// The kernel looked for.
        kernel: String,
        /// The entry points the PTX declares.
        available: Vec<String>,
    },
    /// A launch's arguments do not match the kernel's parameters in the PTX.
    BadArguments {
        /// The kernel.
        kernel: String,
        /// What does not match.
        detail: String,
    },
    /// A kernel launch, or the execution it started, failed.
    Launch {
        /// The kernel.
        kernel: String,
        /// The driver's code.
        code: DriverCode,
    },
    /// Any other driver call failed.
    Driver {
        /// What was being done.
        what: String,
        /// The driver's code.
        code: DriverCode,
    },
    /// A misuse caught on the host before calling the driver (sizes, counts).
    Host(String),
    /// A packing kernel (`@L.build` on the device) reported a nonzero status.
    BuildStatus {
        /// The kernel.
        kernel: String,
        /// The status word.
        status: i32,
    },
    /// The batch kernel reported a status: 1 is a traversal stack overflow.
    Status {
        /// The kernel.
        kernel: String,
        /// The status word.
        status: i32,
    },
}

/// The status the batch kernel stores when a traversal's explicit stack overflows.
pub const STATUS_STACK_OVERFLOW: i32 = 1;

impl fmt::Display for CudaError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CudaError::NoDriver { searched } => write!(
                f,
                "no CUDA driver (libcuda.so.1 not found; {} library names tried on the \
                 loader's path): install the NVIDIA driver or add its folder to \
                 LD_LIBRARY_PATH",
                searched.len()
            ),
            CudaError::DriverTooOld { version, missing } => {
                write!(f, "the CUDA driver is too old")?;
                if let Some(v) = version {
                    write!(f, " (it supports CUDA {})", version_text(*v))?;
                }
                write!(f, ": {missing}")
            }
            CudaError::NoDevice {
                count,
                ordinal,
                code,
            } => match code {
                Some(c) if *count == 0 => write!(f, "no CUDA device: {c}"),
                _ if *count == 0 => write!(f, "no CUDA device: the driver reports 0 devices"),
                Some(c) => write!(
                    f,
                    "no CUDA device {ordinal}: the driver reports {count} device{} ({c})",
                    plural(*count as i64)
                ),
                None => write!(
                    f,
                    "no CUDA device {ordinal}: the driver reports {count} device{}",
                    plural(*count as i64)
                ),
            },
            CudaError::OutOfMemory {
                buffer,
                bytes,
                free_total,
            } => {
                write!(
                    f,
                    "out of device memory allocating `{buffer}` ({bytes} bytes, {})",
                    mib(*bytes)
                )?;
                if let Some((free, total)) = free_total {
                    write!(f, "; {} free of {}", mib(*free), mib(*total))?;
                }
                Ok(())
            }
            CudaError::ModuleLoad { code, log } => {
                write!(f, "the driver rejected the PTX module: {code}")?;
                if code.code == CUDA_ERROR_UNSUPPORTED_PTX_VERSION {
                    write!(
                        f,
                        " (the PTX's .version is newer than this driver supports; update the \
                         driver)"
                    )?;
                }
                let log = log.trim();
                if log.is_empty() {
                    write!(f, " (the JIT log is empty)")
                } else {
                    write!(f, "\nJIT log:\n{log}")
                }
            }
            CudaError::MissingKernel { kernel, available } => {
                write!(f, "the PTX module has no kernel `{kernel}`")?;
                if available.is_empty() {
                    write!(f, " (it declares no .entry)")
                } else {
                    write!(f, " (its kernels: {})", available.join(", "))
                }
            }
            CudaError::BadArguments { kernel, detail } => {
                write!(
                    f,
                    "kernel `{kernel}`: arguments do not match the PTX: {detail}"
                )
            }
            CudaError::Launch { kernel, code } => {
                write!(f, "kernel `{kernel}` failed: {code}")?;
                if code.code == CUDA_ERROR_LAUNCH_OUT_OF_RESOURCES {
                    write!(f, " (too many registers or too much stack per thread)")?;
                }
                Ok(())
            }
            CudaError::Driver { what, code } => write!(f, "{what} failed: {code}"),
            CudaError::Host(m) => f.write_str(m),
            CudaError::BuildStatus { kernel, status } => {
                write!(
                    f,
                    "packing failed: kernel `{kernel}` returned status {status}"
                )?;
                if *status == 1 {
                    write!(f, " (a value did not fit in its bit slice)")?;
                }
                Ok(())
            }
            CudaError::Status { kernel, status } => match *status {
                STATUS_STACK_OVERFLOW => write!(
                    f,
                    "kernel `{kernel}`: traversal stack overflow (the tree is deeper than the \
                     generated code's stack)"
                ),
                s => write!(f, "kernel `{kernel}` returned status {s}"),
            },
        }
    }
}

impl std::error::Error for CudaError {}

/// `12080` as `12.8`.
pub fn version_text(v: i32) -> String {
    format!("{}.{}", v / 1000, (v % 1000) / 10)
}

fn plural(n: i64) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

fn mib(bytes: u64) -> String {
    format!("{:.1} MiB", bytes as f64 / (1024.0 * 1024.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn code(n: u32, name: &str) -> DriverCode {
        DriverCode {
            code: n,
            name: Some(name.into()),
            description: Some("desc".into()),
        }
    }

    #[test]
    fn messages_name_what_failed() {
        let e = CudaError::NoDriver {
            searched: vec!["libcuda.so".into(), "libcuda.so.1".into()],
        };
        let m = e.to_string();
        assert!(m.starts_with("no CUDA driver"), "{m}");
        assert!(
            m.contains("libcuda.so.1 not found; 2 library names tried"),
            "{m}"
        );
        assert!(!m.contains('\n'), "one line: {m}");

        let e = CudaError::OutOfMemory {
            buffer: "nodes".into(),
            bytes: 3 << 20,
            free_total: Some((1 << 20, 80 << 30)),
        };
        assert_eq!(
            e.to_string(),
            "out of device memory allocating `nodes` (3145728 bytes, 3.0 MiB); 1.0 MiB free of \
             81920.0 MiB"
        );

        let e = CudaError::Launch {
            kernel: "scion_closest_hit_LinearBVH_kernel".into(),
            code: code(700, "CUDA_ERROR_ILLEGAL_ADDRESS"),
        };
        assert_eq!(
            e.to_string(),
            "kernel `scion_closest_hit_LinearBVH_kernel` failed: CUDA_ERROR_ILLEGAL_ADDRESS \
             (700): desc"
        );

        let e = CudaError::Status {
            kernel: "k".into(),
            status: STATUS_STACK_OVERFLOW,
        };
        assert!(e.to_string().contains("traversal stack overflow"));

        let e = CudaError::DriverTooOld {
            version: Some(11040),
            missing: "CUDA 11.8 or newer is required".into(),
        };
        assert_eq!(
            e.to_string(),
            "the CUDA driver is too old (it supports CUDA 11.4): CUDA 11.8 or newer is required"
        );
    }

    #[test]
    fn no_device_messages() {
        let none = CudaError::NoDevice {
            count: 0,
            ordinal: 0,
            code: Some(code(CUDA_ERROR_NO_DEVICE, "CUDA_ERROR_NO_DEVICE")),
        };
        assert_eq!(
            none.to_string(),
            "no CUDA device: CUDA_ERROR_NO_DEVICE (100): desc"
        );
        let bad = CudaError::NoDevice {
            count: 1,
            ordinal: 3,
            code: None,
        };
        assert_eq!(
            bad.to_string(),
            "no CUDA device 3: the driver reports 1 device"
        );
    }

    #[test]
    fn module_load_carries_the_jit_log() {
        let e = CudaError::ModuleLoad {
            code: code(218, "CUDA_ERROR_INVALID_PTX"),
            log: "ptxas application ptx input, line 3; error   : bad\n".into(),
        };
        let m = e.to_string();
        assert!(m.contains("CUDA_ERROR_INVALID_PTX"), "{m}");
        assert!(m.ends_with("JIT log:\nptxas application ptx input, line 3; error   : bad"));
        let e = CudaError::ModuleLoad {
            code: code(CUDA_ERROR_UNSUPPORTED_PTX_VERSION, "X"),
            log: String::new(),
        };
        assert!(e.to_string().contains("update the driver"));
        let e = CudaError::MissingKernel {
            kernel: "a".into(),
            available: vec!["b".into(), "c".into()],
        };
        assert_eq!(
            e.to_string(),
            "the PTX module has no kernel `a` (its kernels: b, c)"
        );
    }

    #[test]
    fn versions_print_as_major_minor() {
        assert_eq!(version_text(12080), "12.8");
        assert_eq!(version_text(13000), "13.0");
    }
}
