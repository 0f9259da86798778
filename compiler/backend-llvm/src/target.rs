//! Targets and code generation: the LLVM target machine of a [`Target`] and CPU, the
//! `default<On>` optimization pipelines, and writing a module as LLVM IR text, assembly (PTX
//! on NVPTX) or an ELF object.

use crate::LlvmError;
use inkwell::module::Module as LModule;
use inkwell::passes::PassBuilderOptions;
use inkwell::targets::{
    CodeModel, FileType, InitializationConfig, RelocMode, Target as LTarget, TargetMachine,
    TargetTriple,
};
use inkwell::OptimizationLevel;
use std::sync::Once;

/// A target architecture.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Target {
    /// `x86_64-unknown-linux-gnu`.
    X86_64,
    /// `aarch64-unknown-linux-gnu`.
    Aarch64,
    /// `nvptx64-nvidia-cuda`: PTX for NVIDIA GPUs.
    Nvptx64,
}

impl Target {
    /// The name used on the command line (`--target`).
    pub fn name(self) -> &'static str {
        match self {
            Target::X86_64 => "x86_64",
            Target::Aarch64 => "aarch64",
            Target::Nvptx64 => "nvptx64",
        }
    }

    /// The target of a command-line name (`x86_64`, `aarch64`, `nvptx64`; `x86-64`, `arm64`
    /// and `nvptx` also accepted).
    pub fn from_name(s: &str) -> Option<Target> {
        Some(match s {
            "x86_64" | "x86-64" => Target::X86_64,
            "aarch64" | "arm64" => Target::Aarch64,
            "nvptx64" | "nvptx" => Target::Nvptx64,
            _ => return None,
        })
    }

    /// The LLVM target triple.
    pub fn triple(self) -> &'static str {
        match self {
            Target::X86_64 => "x86_64-unknown-linux-gnu",
            Target::Aarch64 => "aarch64-unknown-linux-gnu",
            Target::Nvptx64 => "nvptx64-nvidia-cuda",
        }
    }

    /// The CPU when none is given: the baseline of the architecture, `sm_90` on NVPTX.
    pub fn default_cpu(self) -> &'static str {
        match self {
            Target::X86_64 => "x86-64",
            Target::Aarch64 => "generic",
            Target::Nvptx64 => "sm_90",
        }
    }

    /// The target of the machine running this code, when Scion supports it.
    pub fn host() -> Option<Target> {
        if cfg!(target_arch = "x86_64") {
            Some(Target::X86_64)
        } else if cfg!(target_arch = "aarch64") {
            Some(Target::Aarch64)
        } else {
            None
        }
    }

    /// True for GPU targets.
    pub fn is_gpu(self) -> bool {
        self == Target::Nvptx64
    }
}

/// Registers the three targets with LLVM (once per process).
pub(crate) fn init_targets() {
    static INIT: Once = Once::new();
    INIT.call_once(|| {
        let c = InitializationConfig::default();
        LTarget::initialize_x86(&c);
        LTarget::initialize_aarch64(&c);
        LTarget::initialize_nvptx(&c);
    });
}

/// The LLVM optimization level of `-O{level}`.
pub(crate) fn llvm_level(level: u8) -> OptimizationLevel {
    match level {
        0 => OptimizationLevel::None,
        1 => OptimizationLevel::Less,
        2 => OptimizationLevel::Default,
        _ => OptimizationLevel::Aggressive,
    }
}

/// The target machine for `target`, `cpu` (`None`: the default; `native`: this machine's CPU
/// and features, for the host's architecture only) at `-O{level}`.
pub fn target_machine(
    target: Target,
    cpu: Option<&str>,
    level: u8,
) -> Result<TargetMachine, LlvmError> {
    init_targets();
    let (cpu, features) = match cpu {
        Some("native") => {
            if Target::host() != Some(target) {
                return Err(LlvmError(format!(
                    "--cpu=native needs the target of this machine, not {}",
                    target.name()
                )));
            }
            host_cpu()
        }
        // No features on NVPTX: LLVM then writes the lowest PTX ISA version that has the SM
        // (7.8 for sm_90, 8.6 for sm_100, 6.3 for sm_75), the one the most drivers accept.
        Some(c) => (c.to_string(), String::new()),
        None => (target.default_cpu().to_string(), String::new()),
    };
    let triple = TargetTriple::create(target.triple());
    let t = LTarget::from_triple(&triple)
        .map_err(|e| LlvmError(format!("target {}: {e}", target.triple())))?;
    check_cpu(target, &cpu)?;
    t.create_target_machine(
        &triple,
        &cpu,
        &features,
        llvm_level(level),
        RelocMode::PIC,
        CodeModel::Default,
    )
    .ok_or_else(|| {
        LlvmError(format!(
            "LLVM cannot create a target machine for {} with cpu `{cpu}`",
            target.triple()
        ))
    })
}

/// The GPU architectures LLVM 22's NVPTX backend knows (`llc -march=nvptx64 -mcpu=help`; a
/// test keeps the list in step with the installed LLVM). LLVM would take any other name with a
/// warning and then abort or emit PTX for no GPU, so `--cpu` is checked against it first.
pub const NVPTX_CPUS: &[&str] = &[
    "sm_20", "sm_21", "sm_30", "sm_32", "sm_35", "sm_37", "sm_50", "sm_52", "sm_53", "sm_60",
    "sm_61", "sm_62", "sm_70", "sm_72", "sm_75", "sm_80", "sm_86", "sm_87", "sm_88", "sm_89",
    "sm_90", "sm_90a", "sm_100", "sm_100a", "sm_100f", "sm_101", "sm_101a", "sm_101f", "sm_103",
    "sm_103a", "sm_103f", "sm_110", "sm_110a", "sm_110f", "sm_120", "sm_120a", "sm_120f", "sm_121",
    "sm_121a", "sm_121f",
];

/// Rejects a CPU name that cannot be one: NVPTX wants one of [`NVPTX_CPUS`]; other names go to
/// LLVM, which ignores unknown ones with a warning.
fn check_cpu(target: Target, cpu: &str) -> Result<(), LlvmError> {
    if target == Target::Nvptx64 {
        if !NVPTX_CPUS.contains(&cpu) {
            let hint = if cpu.starts_with("sm_") {
                format!(
                    "LLVM 22 knows {} to {}",
                    NVPTX_CPUS[0],
                    NVPTX_CPUS[NVPTX_CPUS.len() - 1]
                )
            } else {
                "expected sm_XX".to_string()
            };
            return Err(LlvmError(format!(
                "unknown NVPTX cpu `{cpu}`: {hint} (e.g. sm_90 for H100/H200, sm_80 for A100)"
            )));
        }
    } else if cpu.is_empty()
        || !cpu
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_' || c == '.')
    {
        return Err(LlvmError(format!("bad cpu name `{cpu}`")));
    }
    Ok(())
}

/// The host CPU's name and feature string.
pub fn host_cpu() -> (String, String) {
    (
        TargetMachine::get_host_cpu_name().to_string(),
        TargetMachine::get_host_cpu_features().to_string(),
    )
}

/// Runs LLVM's `default<O{level}>` pipeline on `lm`.
pub(crate) fn optimize(lm: &LModule, tm: &TargetMachine, level: u8) -> Result<(), LlvmError> {
    let opts = PassBuilderOptions::create();
    opts.set_verify_each(cfg!(debug_assertions));
    lm.run_passes(&format!("default<O{}>", level.min(3)), tm, opts)
        .map_err(|e| LlvmError(format!("optimization pipeline: {e}")))
}

/// Machine code (`Asm` or `Object`) of `lm`.
pub(crate) fn codegen(
    lm: &LModule,
    tm: &TargetMachine,
    file: FileType,
) -> Result<Vec<u8>, LlvmError> {
    let buf = tm
        .write_to_memory_buffer(lm, file)
        .map_err(|e| LlvmError(format!("code generation: {e}")))?;
    Ok(buf.as_slice().to_vec())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`NVPTX_CPUS`] is what the installed LLVM's NVPTX backend lists, so `--cpu` neither
    /// rejects a GPU LLVM knows nor lets through one it would only warn about.
    #[test]
    fn nvptx_cpus_match_llc() {
        let llc = "/usr/lib/llvm-22/bin/llc";
        let out = std::process::Command::new(llc)
            .args(["-march=nvptx64", "-mcpu=help"])
            .output()
            .unwrap_or_else(|e| panic!("{llc}: {e} (scripts/setup.sh installs llvm-22-tools)"));
        let text = String::from_utf8_lossy(&out.stdout) + String::from_utf8_lossy(&out.stderr);
        let cpus_part = text
            .split("Available features")
            .next()
            .expect("llc -mcpu=help output");
        let mut listed: Vec<&str> = cpus_part
            .lines()
            .filter_map(|l| l.split_whitespace().next())
            .filter(|w| w.starts_with("sm_"))
            .collect();
        let mut ours = NVPTX_CPUS.to_vec();
        listed.sort_unstable();
        ours.sort_unstable();
        assert_eq!(ours, listed);
    }

    /// Every known SM makes a target machine; unknown names are errors that say what is known.
    #[test]
    fn nvptx_cpu_checked() {
        for cpu in ["sm_75", "sm_90", "sm_100", "sm_120"] {
            assert!(
                target_machine(Target::Nvptx64, Some(cpu), 3).is_ok(),
                "{cpu}"
            );
        }
        let e = target_machine(Target::Nvptx64, Some("sm_99"), 3)
            .err()
            .unwrap();
        assert!(e.0.contains("unknown NVPTX cpu `sm_99`"), "{}", e.0);
    }
}
