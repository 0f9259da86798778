//! Kernel arguments and launch shapes, all on the host: a typed argument list checked against
//! the kernel's parameters as the PTX declares them, packed into the array of pointers
//! `cuLaunchKernel` takes, and the grid of a one-thread-per-query launch. Input: [`KernelArg`]s
//! and the kernel's [`PtxParam`]s; output: [`PackedArgs`] and [`Grid`].

use crate::error::CudaError;
use crate::ptx::PtxParam;
use std::ffi::c_void;

/// A device address (`CUdeviceptr`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DevicePtr(pub u64);

/// One argument of a kernel launch, by value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum KernelArg {
    /// A 32-bit integer (`.u32`, `.s32`, `.b32`).
    U32(u32),
    /// A 64-bit integer (`.u64`, `.s64`, `.b64`).
    U64(u64),
    /// A device address (a `.u64` parameter).
    Ptr(DevicePtr),
}

impl KernelArg {
    /// Its size in bytes.
    pub fn size(&self) -> usize {
        match self {
            KernelArg::U32(_) => 4,
            KernelArg::U64(_) | KernelArg::Ptr(_) => 8,
        }
    }

    fn describe(&self) -> String {
        match self {
            KernelArg::U32(v) => format!("u32 {v}"),
            KernelArg::U64(v) => format!("u64 {v}"),
            KernelArg::Ptr(p) => format!("device pointer {:#x}", p.0),
        }
    }
}

/// The arguments of one launch as `cuLaunchKernel` wants them: each value in its own 8-byte,
/// 8-aligned slot, and an array of pointers to the slots. The pointers point into `self`, so
/// the value must stay put (it is not moved between [`PackedArgs::pointers`] and the launch).
#[derive(Debug)]
pub struct PackedArgs {
    slots: Vec<u64>,
    sizes: Vec<usize>,
}

impl PackedArgs {
    /// Checks `args` against the kernel's parameters `params` (from its PTX `.entry`) and packs
    /// them. Each argument must have its parameter's size; a pointer must go to a 64-bit
    /// integer parameter.
    pub fn new(
        kernel: &str,
        params: &[PtxParam],
        args: &[KernelArg],
    ) -> Result<PackedArgs, CudaError> {
        let bad = |detail: String| CudaError::BadArguments {
            kernel: kernel.to_string(),
            detail,
        };
        if params.len() != args.len() {
            return Err(bad(format!(
                "the kernel takes {} parameter{}, {} given",
                params.len(),
                if params.len() == 1 { "" } else { "s" },
                args.len()
            )));
        }
        let mut slots = Vec::with_capacity(args.len());
        let mut sizes = Vec::with_capacity(args.len());
        for (i, (p, a)) in params.iter().zip(args).enumerate() {
            if p.bytes != a.size() || p.is_float || p.array {
                return Err(bad(format!(
                    "parameter {i} (`{}`) is {}, given {}",
                    p.name,
                    p.describe(),
                    a.describe()
                )));
            }
            let slot = match *a {
                KernelArg::U32(v) => u64::from(v),
                KernelArg::U64(v) => v,
                KernelArg::Ptr(p) => p.0,
            };
            slots.push(slot);
            sizes.push(a.size());
        }
        Ok(PackedArgs { slots, sizes })
    }

    /// The array of pointers to each argument's value (little-endian slots, so a `u32` is the
    /// slot's first 4 bytes).
    pub fn pointers(&mut self) -> Vec<*mut c_void> {
        self.slots
            .iter_mut()
            .map(|s| s as *mut u64 as *mut c_void)
            .collect()
    }

    /// The bytes of argument `i` as the kernel will read them.
    pub fn bytes(&self, i: usize) -> Vec<u8> {
        self.slots[i].to_le_bytes()[..self.sizes[i]].to_vec()
    }

    /// How many arguments.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// True when there are none.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }
}

/// Threads per block of a batch kernel (docs/design/backends.md §1).
pub const THREADS_PER_BLOCK: u32 = 256;

/// The largest grid x dimension (compute capability 3.0 and later).
pub const MAX_GRID_X: u64 = (1 << 31) - 1;

/// A one-dimensional launch shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Grid {
    /// Blocks (grid x dimension).
    pub blocks: u32,
    /// Threads per block (block x dimension).
    pub threads: u32,
}

impl Grid {
    /// One block of one thread (the packing kernels).
    pub const SINGLE: Grid = Grid {
        blocks: 1,
        threads: 1,
    };

    /// `ceil(n / threads)` blocks of `threads` threads, one thread per query; `None` for
    /// `n == 0` (nothing to launch).
    pub fn for_queries(n: u64, threads: u32) -> Result<Option<Grid>, CudaError> {
        if threads == 0 || threads > 1024 {
            return Err(CudaError::Host(format!(
                "{threads} threads per block: a block holds 1 to 1024 threads"
            )));
        }
        if n == 0 {
            return Ok(None);
        }
        let blocks = n.div_ceil(u64::from(threads));
        if blocks > MAX_GRID_X {
            return Err(CudaError::Host(format!(
                "{n} queries need {blocks} blocks of {threads}, more than the grid's limit of \
                 {MAX_GRID_X}"
            )));
        }
        Ok(Some(Grid {
            blocks: blocks as u32,
            threads,
        }))
    }
}

#[cfg(test)]
#[allow(unsafe_code)]
mod tests {
    use super::*;

    fn param(name: &str, bytes: usize) -> PtxParam {
        PtxParam {
            name: name.into(),
            bytes,
            is_float: false,
            array: false,
        }
    }

    #[test]
    fn packs_each_value_in_its_slot() {
        let params = [param("a", 8), param("b", 4), param("c", 8)];
        let args = [
            KernelArg::Ptr(DevicePtr(0x7f00_0000_1000)),
            KernelArg::U32(0xdead_beef),
            KernelArg::U64(u64::MAX - 1),
        ];
        let mut packed = PackedArgs::new("k", &params, &args).unwrap();
        assert_eq!(packed.len(), 3);
        assert_eq!(packed.bytes(0), 0x7f00_0000_1000u64.to_le_bytes());
        assert_eq!(packed.bytes(1), 0xdead_beefu32.to_le_bytes());
        let ptrs = packed.pointers();
        // SAFETY: each pointer points at a live, 8-aligned `u64` slot of `packed`, read with the
        // argument's own width as the driver does.
        let read = unsafe {
            (
                *(ptrs[0] as *const u64),
                *(ptrs[1] as *const u32),
                *(ptrs[2] as *const u64),
            )
        };
        assert_eq!(read, (0x7f00_0000_1000, 0xdead_beef, u64::MAX - 1));
        for p in ptrs {
            assert_eq!(p as usize % 8, 0);
        }
    }

    #[test]
    fn rejects_mismatches_naming_the_kernel_and_parameter() {
        let params = [param("k_param_0", 8), param("k_param_1", 4)];
        let e = PackedArgs::new("k", &params, &[KernelArg::U64(1)]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "kernel `k`: arguments do not match the PTX: the kernel takes 2 parameters, 1 given"
        );
        let e = PackedArgs::new("k", &params, &[KernelArg::U64(1), KernelArg::U64(2)]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "kernel `k`: arguments do not match the PTX: parameter 1 (`k_param_1`) is a 4-byte \
             integer, given u64 2"
        );
        let mut f = param("x", 4);
        f.is_float = true;
        assert!(PackedArgs::new("k", &[f], &[KernelArg::U32(0)]).is_err());
    }

    #[test]
    fn grids_cover_every_query_once() {
        assert_eq!(Grid::for_queries(0, 256).unwrap(), None);
        for (n, blocks) in [
            (1, 1),
            (255, 1),
            (256, 1),
            (257, 2),
            (65536, 256),
            (65537, 257),
        ] {
            let g = Grid::for_queries(n, THREADS_PER_BLOCK).unwrap().unwrap();
            assert_eq!((g.blocks, g.threads), (blocks, 256), "n = {n}");
            assert!(u64::from(g.blocks) * 256 >= n && u64::from(g.blocks - 1) * 256 < n);
        }
        assert!(Grid::for_queries(1 << 38, 256).is_ok());
        let e = Grid::for_queries(u64::MAX, 256).unwrap_err();
        assert!(e.to_string().contains("more than the grid's limit"), "{e}");
        assert!(Grid::for_queries(5, 0).is_err());
        assert!(Grid::for_queries(5, 2048).is_err());
    }
}
