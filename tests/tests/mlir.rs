//! `--emit=mlir` over the whole library: every library layout with each entry of a known kind
//! over its type (closest hit, any hit, closest point, collision), specialized and lowered with
//! its exported C entries as `scionc -O3 --entry` does, printed as upstream MLIR
//! (`scion_compiler::mlir`) and given to MLIR's verifier (`mlir-opt --verify-each`, Debian's
//! mlir-22-tools, which scripts/setup.sh installs); what mlir-opt prints reads back unchanged.

use scion_compiler::abi::EntryTarget;
use scion_host::jit::{program_lo, LoOptions};
use scion_host::library::{resolve_kind, QueryKind, LAYOUT_FILES};
use std::process::Command;

const MLIR_OPT: &str = "/usr/lib/llvm-22/bin/mlir-opt";

fn mlir_opt(input: &std::path::Path, args: &[&str]) -> Result<String, String> {
    let o = Command::new(MLIR_OPT)
        .args(args)
        .arg(input)
        .output()
        .map_err(|e| {
            format!("cannot run {MLIR_OPT} (scripts/setup.sh installs mlir-22-tools): {e}")
        })?;
    if !o.status.success() {
        return Err(String::from_utf8_lossy(&o.stderr).into_owned());
    }
    Ok(String::from_utf8_lossy(&o.stdout).into_owned())
}

#[test]
fn every_library_program_is_valid_mlir() {
    let dir = std::env::temp_dir().join(format!("scion-mlir-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut checked = Vec::new();
    for &(stem, _) in LAYOUT_FILES {
        for kind in QueryKind::ALL {
            let Ok(r) = resolve_kind(stem, None, kind) else {
                continue;
            };
            let lo = program_lo(
                &r.program,
                &LoOptions {
                    stack_size: None,
                    opt_level: 3,
                    dsl_opt: true,
                    target: EntryTarget::Host,
                },
            )
            .unwrap_or_else(|e| panic!("{stem} {}: {e}", kind.name()));
            let text = scion_compiler::mlir::print_mlir(&lo.module)
                .unwrap_or_else(|d| panic!("{stem} {}: {}", kind.name(), d.message));
            let path = dir.join(format!("{stem}-{}.mlir", kind.name()));
            std::fs::write(&path, &text).unwrap();
            let printed = mlir_opt(&path, &["--verify-each"])
                .unwrap_or_else(|e| panic!("{stem} {}: MLIR's verifier: {e}", kind.name()));
            let again = dir.join(format!("{stem}-{}.1.mlir", kind.name()));
            std::fs::write(&again, &printed).unwrap();
            let reprinted = mlir_opt(&again, &[]).unwrap();
            assert_eq!(printed, reprinted, "{stem} {}: no round trip", kind.name());
            checked.push(format!("{stem}/{}", kind.name()));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    eprintln!("{} programs: {}", checked.len(), checked.join(" "));
    assert!(checked.len() >= 40, "{checked:?}");
}
