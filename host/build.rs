//! The library's files, found here so that a new layout or algorithm is one `.scion` file in
//! `library/` and no Rust: writes `$OUT_DIR/library_files.rs` with the stem and text
//! (`include_str!`) of every `library/layouts/*.scion` and `library/algorithms/*.scion`, sorted
//! by stem. `src/library.rs` includes it; what each file declares is read by the front end.

use std::fmt::Write as _;
use std::path::Path;

fn files(dir: &Path) -> Vec<(String, String)> {
    println!("cargo:rerun-if-changed={}", dir.display());
    let mut out: Vec<(String, String)> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| {
            let path = e.ok()?.path();
            if path.extension()? != "scion" {
                return None;
            }
            println!("cargo:rerun-if-changed={}", path.display());
            let stem = path.file_stem()?.to_str()?.to_string();
            Some((stem, path.canonicalize().ok()?.display().to_string()))
        })
        .collect();
    out.sort();
    out
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../library");
    let mut code = String::new();
    for (konst, dir) in [
        ("LAYOUT_FILES", "layouts"),
        ("ALGORITHM_FILES", "algorithms"),
    ] {
        writeln!(
            code,
            "/// `library/{dir}/*.scion`: file stem and text, sorted by stem.\n\
             pub static {konst}: &[(&str, &str)] = &["
        )
        .unwrap();
        for (stem, path) in files(&root.join(dir)) {
            writeln!(code, "    ({stem:?}, include_str!({path:?})),").unwrap();
        }
        code.push_str("];\n");
    }
    let out = Path::new(&std::env::var("OUT_DIR").unwrap()).join("library_files.rs");
    std::fs::write(out, code).unwrap();
}
