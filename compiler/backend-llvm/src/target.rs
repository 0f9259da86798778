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

/// Checks a command line's `--cpu` for `target` before any work: `native` only for this
/// machine's architecture, any other name one LLVM knows for the target (a near miss named).
pub fn validate_cpu(target: Target, cpu: &str) -> Result<(), LlvmError> {
    if cpu == "native" {
        return match Target::host() == Some(target) {
            true => Ok(()),
            false => Err(LlvmError(format!(
                "--cpu=native needs the target of this machine, not {}",
                target.name()
            ))),
        };
    }
    check_cpu(target, cpu)
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

/// The CPU names LLVM knows per target, read from `llc -mcpu=help` when this crate was built
/// (build.rs): `X86_64_CPUS`, `AARCH64_CPUS`, `NVPTX64_CPUS`. Empty when `llc` was missing.
pub mod cpus {
    include!(concat!(env!("OUT_DIR"), "/cpus.rs"));
}

impl Target {
    /// The CPU names LLVM knows for this target (empty when the build found no `llc`).
    pub fn known_cpus(self) -> &'static [&'static str] {
        match self {
            Target::X86_64 => cpus::X86_64_CPUS,
            Target::Aarch64 => cpus::AARCH64_CPUS,
            Target::Nvptx64 => cpus::NVPTX64_CPUS,
        }
    }
}

/// Rejects a CPU LLVM does not know for `target`: LLVM would only warn and emit generic code
/// (or, on NVPTX, abort). The error names a near miss when there is one.
fn check_cpu(target: Target, cpu: &str) -> Result<(), LlvmError> {
    let known = target.known_cpus();
    let ok = if known.is_empty() {
        // No list (no llc at build time): only the shape of the name.
        match target {
            Target::Nvptx64 => cpu.strip_prefix("sm_").is_some_and(|d| {
                let d = d.trim_end_matches(['a', 'f']);
                !d.is_empty() && d.chars().all(|c| c.is_ascii_digit())
            }),
            _ => {
                !cpu.is_empty()
                    && cpu
                        .chars()
                        .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'))
            }
        }
    } else {
        known.contains(&cpu)
    };
    if ok {
        return Ok(());
    }
    let what = match target {
        Target::Nvptx64 => "NVPTX cpu",
        Target::X86_64 => "x86_64 cpu",
        Target::Aarch64 => "aarch64 cpu",
    };
    let hint = match nearest(cpu, known) {
        Some(n) => format!(" (did you mean {n}?)"),
        None => match target {
            Target::Nvptx64 => " (e.g. sm_90 for H100/H200, sm_80 for A100)".to_string(),
            Target::X86_64 => " (e.g. x86-64-v3, znver4, sapphirerapids, or native)".to_string(),
            Target::Aarch64 => " (e.g. neoverse-v2, apple-m2, or native)".to_string(),
        },
    };
    let list = if known.is_empty() {
        String::new()
    } else {
        format!(
            "; LLVM 22 knows {} (`llc-22 -march={} -mcpu=help` lists them)",
            known.len(),
            target.llc_march()
        )
    };
    Err(LlvmError(format!("unknown {what} `{cpu}`{hint}{list}")))
}

impl Target {
    /// The `-march` name of `llc` for this target.
    pub fn llc_march(self) -> &'static str {
        match self {
            Target::X86_64 => "x86-64",
            Target::Aarch64 => "aarch64",
            Target::Nvptx64 => "nvptx64",
        }
    }
}

/// The known names closest to `cpu` by edit distance, when close (at most 2 edits, and fewer
/// than half the name's length), as "`a`", "`a` or `b`" (at most three).
fn nearest(cpu: &str, known: &[&str]) -> Option<String> {
    let scored: Vec<(usize, &str)> = known
        .iter()
        .map(|k| (edit_distance(cpu, k), *k))
        .filter(|(d, _)| *d <= 2 && *d * 2 < cpu.len())
        .collect();
    let best = scored.iter().map(|s| s.0).min()?;
    let names: Vec<String> = scored
        .iter()
        .filter(|s| s.0 == best)
        .take(3)
        .map(|s| format!("`{}`", s.1))
        .collect();
    Some(names.join(" or "))
}

/// Levenshtein distance over bytes.
fn edit_distance(a: &str, b: &str) -> usize {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + usize::from(ca != cb))
                .min(prev[j + 1] + 1)
                .min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// The host CPU's name and feature string.
pub fn host_cpu() -> (String, String) {
    (
        TargetMachine::get_host_cpu_name().to_string(),
        TargetMachine::get_host_cpu_features().to_string(),
    )
}

/// What the LLVM JIT compiles for: the host CPU, or the CPU named by `SCION_JIT_CPU` (an LLVM
/// CPU name such as `x86-64-v3`, with the features that name implies), so that code for another
/// level of the host's ISA can be timed on the host, e.g. without AVX-512 on a CPU that has it
/// (docs/backends.md). A CPU the host cannot run is the caller's mistake (SIGILL).
pub fn jit_cpu() -> (String, String) {
    match std::env::var("SCION_JIT_CPU") {
        Ok(cpu) if !cpu.is_empty() => (cpu, String::new()),
        _ => host_cpu(),
    }
}

/// Runs LLVM's `default<O{level}>` pipeline on `lm`. For a GPU (`gpu`) at `-O1` and above,
/// address-space inference runs first: the translation loads each layout buffer's base as a
/// global-space pointer and casts it to a generic one, so the accesses derived from a buffer
/// become global ones (`ld.global`) before inlining and merging; the later inference of
/// LLVM's NVPTX pipeline carries that through.
pub(crate) fn optimize(
    lm: &LModule,
    tm: &TargetMachine,
    level: u8,
    gpu: bool,
) -> Result<(), LlvmError> {
    let opts = PassBuilderOptions::create();
    opts.set_verify_each(cfg!(debug_assertions));
    let level = level.min(3);
    let pipeline = if gpu && level > 0 {
        format!("function(infer-address-spaces),default<O{level}>")
    } else {
        format!("default<O{level}>")
    };
    lm.run_passes(&pipeline, tm, opts)
        .map_err(|e| LlvmError(format!("optimization pipeline: {e}")))?;
    if tm
        .get_triple()
        .as_str()
        .to_string_lossy()
        .starts_with("x86_64")
    {
        crate::clamps::two_lane_clamps_as_selects(lm);
        if level > 0 {
            crate::mask_counts::mask_counts_as_ctpop(lm);
            crate::mask_counts::mask_lanes_as_bits(lm);
        }
    }
    Ok(())
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

    /// The lists came from this LLVM (build.rs) and hold the CPUs the docs name.
    #[test]
    fn known_cpus_come_from_llvm() {
        for (t, cpus) in [
            (
                Target::X86_64,
                &["x86-64", "x86-64-v3", "znver4", "sapphirerapids"][..],
            ),
            (Target::Aarch64, &["generic", "neoverse-v2", "apple-m2"][..]),
            (
                Target::Nvptx64,
                &["sm_75", "sm_80", "sm_90", "sm_100", "sm_120", "sm_121f"][..],
            ),
        ] {
            for cpu in cpus {
                assert!(
                    t.known_cpus().contains(cpu),
                    "{cpu} not in {:?}",
                    t.known_cpus()
                );
            }
            assert!(t.known_cpus().contains(&t.default_cpu()), "{t:?}");
        }
    }

    /// Every known CPU makes a target machine; unknown names are errors that say what is known.
    #[test]
    fn cpus_are_checked() {
        for cpu in ["sm_75", "sm_90", "sm_100", "sm_120"] {
            assert!(
                target_machine(Target::Nvptx64, Some(cpu), 3).is_ok(),
                "{cpu}"
            );
        }
        assert!(target_machine(Target::X86_64, Some("znver4"), 3).is_ok());
        assert!(target_machine(Target::Aarch64, Some("neoverse-v2"), 3).is_ok());
        for (t, cpu, start) in [
            (
                Target::Nvptx64,
                "sm90",
                "unknown NVPTX cpu `sm90` (did you mean `sm_90`?)",
            ),
            (
                Target::X86_64,
                "znver9",
                "unknown x86_64 cpu `znver9` (did you mean `znver",
            ),
            (
                Target::Aarch64,
                "gfx90a",
                "unknown aarch64 cpu `gfx90a` (e.g. neoverse-v2",
            ),
            (
                Target::Nvptx64,
                "gfx90a",
                "unknown NVPTX cpu `gfx90a` (e.g. sm_90 for H100/H200",
            ),
        ] {
            let e = target_machine(t, Some(cpu), 3).err().unwrap().0;
            assert!(e.starts_with(start), "{e}");
            let list = format!("`llc-22 -march={} -mcpu=help` lists them)", t.llc_march());
            assert!(e.ends_with(&list), "{e}");
        }
    }

    #[test]
    fn edit_distance_counts_edits() {
        assert_eq!(edit_distance("znver4", "znver4"), 0);
        assert_eq!(edit_distance("znver9", "znver4"), 1);
        assert_eq!(edit_distance("sm_99", "sm_90"), 1);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(nearest("x", &["y"]), None);
        assert_eq!(
            nearest("sm_99", &["sm_89", "sm_90", "sm_75"]).unwrap(),
            "`sm_89` or `sm_90`"
        );
    }
}
