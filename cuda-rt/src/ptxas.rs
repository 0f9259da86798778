//! NVIDIA's offline PTX assembler, for checks on machines without a GPU: the same PTX the
//! driver's JIT compiles on the device, assembled by `ptxas` (CUDA 13.5, which
//! `scripts/setup.sh` installs from the Python package registry's `nvidia-cuda-nvcc` wheel),
//! with its verbose log: registers, stack frames and spills per function, in the format of the
//! JIT's info log ([`crate::trace::stack_frames`] reads both).

use std::path::{Path, PathBuf};
use std::process::Command;

/// The version `scripts/setup.sh` installs (keep the two in step).
pub const PTXAS_VERSION: &str = "13.5.37";

/// Where `scripts/setup.sh` puts the ptxas it installs.
pub fn cached_ptxas() -> Option<PathBuf> {
    let home = std::env::var_os("HOME")?;
    Some(PathBuf::from(home).join(format!(".cache/scion/cuda-{PTXAS_VERSION}/bin/ptxas")))
}

/// A working ptxas: `$SCION_PTXAS`, then `ptxas` on `PATH`, `/usr/local/cuda/bin/ptxas`, then
/// the copy `scripts/setup.sh` installs (the order of setup.sh and lit-tests/lit.cfg.py).
pub fn find() -> Option<PathBuf> {
    let from_env = std::env::var_os("SCION_PTXAS").map(PathBuf::from);
    let on_path: Vec<PathBuf> = std::env::var_os("PATH")
        .map(|p| std::env::split_paths(&p).map(|d| d.join("ptxas")).collect())
        .unwrap_or_default();
    from_env
        .into_iter()
        .chain(on_path)
        .chain(Some(PathBuf::from("/usr/local/cuda/bin/ptxas")))
        .chain(cached_ptxas())
        .find(|p| {
            Command::new(p)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        })
}

/// Assembles `ptx` for `arch` (`sm_90`) with `ptxas -v` and returns its info log, or ptxas's
/// diagnostics when it rejects the PTX. Works in a fresh folder under the system temp folder.
pub fn assemble(ptxas: &Path, ptx: &str, arch: &str) -> Result<String, String> {
    let dir = std::env::temp_dir().join(format!(
        "scion-ptxas-{}-{}",
        std::process::id(),
        NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    ));
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let input = dir.join("in.ptx");
    let result = std::fs::write(&input, ptx)
        .map_err(|e| format!("{}: {e}", input.display()))
        .and_then(|()| {
            Command::new(ptxas)
                .arg(format!("-arch={arch}"))
                .arg("-v")
                .arg(&input)
                .arg("-o")
                .arg(dir.join("out.cubin"))
                .output()
                .map_err(|e| format!("{}: {e}", ptxas.display()))
        })
        .and_then(|o| {
            let log = String::from_utf8_lossy(&o.stdout).into_owned()
                + &String::from_utf8_lossy(&o.stderr);
            if o.status.success() {
                Ok(log)
            } else {
                Err(format!("ptxas rejected the PTX ({}):\n{log}", o.status))
            }
        });
    let _ = std::fs::remove_dir_all(&dir);
    result
}

static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
