//! `scionc --emit=header` output compiles as C99, C11 and C++17 (`gcc`/`g++ -fsyntax-only` with
//! warnings as errors), two generated headers and the runtime's `scion_runtime.h` in one
//! translation unit (the contract's structs are shared under one guard). Skips with a clear line when gcc or g++ is missing.

use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn header(layout: &str, file: &str, dir: &Path) -> PathBuf {
    header_of("closest_hit", layout, file, dir)
}

/// The header of `--entry entry` (from `library/algorithms/{entry}.scion`) for `layout`.
fn header_of(entry: &str, layout: &str, file: &str, dir: &Path) -> PathBuf {
    let r = repo();
    let out = Command::new(env!("CARGO_BIN_EXE_scionc"))
        .args(["--emit=header", "--layout", layout, "--entry", entry])
        .arg(r.join(format!("library/algorithms/{entry}.scion")))
        .arg(r.join("library/layouts").join(file))
        .output()
        .expect("runs scionc");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let path = dir.join(format!("{entry}_{layout}.h"));
    std::fs::write(&path, &out.stdout).unwrap();
    path
}

fn have(tool: &str) -> bool {
    Command::new(tool)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

#[test]
fn generated_headers_compile_as_c_and_cpp() {
    let dir = std::env::temp_dir().join(format!("scion-abi-header-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let pbrt = header("LinearBVH", "pbrt.scion", &dir);
    let ptr = header("PtrBVH", "ptr.scion", &dir);
    // A logical node with a DOP-14 (56 bytes of bounds: the struct's size assertion checks it).
    let dop = header_of("closest_hit_dop14", "DopSplit", "dop14_split.scion", &dir);
    // Three variants, two interior, oriented child boxes (260 bytes: the size assertion).
    let hair = header_of("closest_hit_hair", "HairBVH", "hair_bvh.scion", &dir);
    // An entry over two trees with a set (a sink) as its result, and an empty query record.
    let collide = header_of("collide", "PbrtAlign16", "pbrt_align16.scion", &dir);
    // The runtime's hand-written header shares the contract's structs with the generated ones.
    let runtime_h = repo().join("runtime/capi/include/scion_runtime.h");
    let mut ran = 0;
    for (tool, lang, std) in [
        ("gcc", "c", "-std=c99"),
        ("gcc", "c", "-std=c11"),
        ("g++", "c++", "-std=c++17"),
    ] {
        if !have(tool) {
            eprintln!("skip: `{tool}` not found; the header is not compiled as {lang} {std}");
            continue;
        }
        let src = dir.join(format!("use.{lang}"));
        std::fs::write(
            &src,
            format!(
                "#include \"{}\"\n#include \"{}\"\n#include \"{}\"\n#include \"{}\"\n\
                 #include \"{}\"\n#include \"{}\"\n\
                 int main(void) {{\n  \
                 scion_closest_hit_query q; scion_closest_hit_result r;\n  \
                 scion_collide_result pairs = {{0, 0, 0}};\n  \
                 (void)q; (void)r; (void)pairs;\n  \
                 int32_t (*collide)(void *const *, const scion_collide_query *,\n    \
                 scion_collide_result *, uint64_t, uint64_t, scion_PbrtAlign16_ref,\n    \
                 void *const *, scion_PbrtAlign16_ref) = scion_collide_PbrtAlign16;\n  \
                 (void)collide;\n  \
                 return (int)sizeof(ScionTreeView) + SCION_LinearBVH_BUFFER_COUNT \
                 + SCION_PtrBVH_BUFFER_ALIGN + (int)sizeof(ScionRay) + SCION_RT_OK \
                 + (int)sizeof(ScionLogical_DopBVH) + (int)sizeof(ScionLogical_Hair) \
                 + SCION_HairBVH_BUFFER_COUNT;\n}}\n",
                pbrt.display(),
                runtime_h.display(),
                ptr.display(),
                dop.display(),
                hair.display(),
                collide.display()
            ),
        )
        .unwrap();
        let out = Command::new(tool)
            .args([
                std,
                "-fsyntax-only",
                "-Wall",
                "-Wextra",
                "-Werror",
                "-x",
                lang,
            ])
            .arg(&src)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{tool} {std}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        ran += 1;
    }
    let _ = std::fs::remove_dir_all(&dir);
    if ran == 0 {
        eprintln!("skip: neither gcc nor g++ is installed; only scionc --emit=header ran");
    }
}

/// The runtime's `scion_runtime.h` holds the contract's structs and role numbers exactly as
/// every generated header does (one text, `scion_compiler::abi::header::CONTRACT_TYPES`), so
/// whichever is included first defines what the other needs (a DOP-14 or hair header's schema
/// names `SCION_ROLE_DOP14_BOUNDS` and `SCION_ROLE_CHILD_OBBS`).
#[test]
fn the_runtime_header_has_the_generated_contract_types() {
    let runtime_h =
        std::fs::read_to_string(repo().join("runtime/capi/include/scion_runtime.h")).unwrap();
    assert!(
        runtime_h.contains(scion_compiler::abi::header::CONTRACT_TYPES),
        "runtime/capi/include/scion_runtime.h differs from CONTRACT_TYPES"
    );
}
