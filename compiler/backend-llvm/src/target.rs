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
        Some(c) => (c.to_string(), String::new()),
        None => (target.default_cpu().to_string(), ptx_features(target)),
    };
    let features = if target == Target::Nvptx64 && features.is_empty() {
        ptx_features(target)
    } else {
        features
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

/// The PTX ISA version: 7.8 is the first with `sm_90` and is accepted by CUDA 12 and 13.
fn ptx_features(target: Target) -> String {
    if target == Target::Nvptx64 {
        "+ptx78".to_string()
    } else {
        String::new()
    }
}

/// Rejects a CPU name that cannot be one: NVPTX wants `sm_XX` (optionally `sm_XXa`); other
/// names go to LLVM, which ignores unknown ones with a warning.
fn check_cpu(target: Target, cpu: &str) -> Result<(), LlvmError> {
    if target == Target::Nvptx64 {
        let digits = cpu.strip_prefix("sm_").map(|d| d.trim_end_matches('a'));
        if !digits.is_some_and(|d| !d.is_empty() && d.chars().all(|c| c.is_ascii_digit())) {
            return Err(LlvmError(format!(
                "unknown NVPTX cpu `{cpu}`: expected sm_XX (e.g. sm_90)"
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
