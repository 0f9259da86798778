//! The specializations on text IR: for every layout of the library and of the lit inputs
//! (binary, wide, quantized, tuple references, `parent.`, DOP-14, the hair BVH's three
//! variants), `scionc --emit=tree` piped through `scion-opt --layout L
//! --passes=destructor-specialize,constructor-specialize` (the layout read from the module's
//! `tree.layout` record) prints exactly what `scionc --emit=mem --layout L` prints.

use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Stdio};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn scionc(args: &[&str], files: &[&str]) -> String {
    let r = repo();
    let out = Command::new(env!("CARGO_BIN_EXE_scionc"))
        .args(args)
        .args(files.iter().map(|f| r.join(f)))
        .output()
        .expect("runs scionc");
    assert!(
        out.status.success(),
        "scionc {args:?} {files:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

fn scion_opt(args: &[&str], input: &str) -> String {
    let mut child = Command::new(env!("CARGO_BIN_EXE_scion-opt"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("runs scion-opt");
    child
        .stdin
        .take()
        .unwrap()
        .write_all(input.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "scion-opt {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

#[test]
fn specializations_on_text_ir_match_the_driver() {
    let cases: &[(&[&str], &str)] = &[
        (
            &[
                "library/algorithms/closest_hit.scion",
                "library/layouts/pbrt.scion",
            ],
            "LinearBVH",
        ),
        (
            &[
                "library/algorithms/closest_hit.scion",
                "library/layouts/ptr.scion",
            ],
            "PtrBVH",
        ),
        (
            &[
                "library/algorithms/closest_hit.scion",
                "library/layouts/pbrt_q16.scion",
            ],
            "PbrtQ16",
        ),
        (
            &[
                "library/algorithms/closest_hit.scion",
                "library/layouts/sg_eq.scion",
            ],
            "SgEq",
        ),
        (
            &[
                "library/algorithms/closest_hit.scion",
                "library/layouts/pbrt_soaos.scion",
            ],
            "PbrtSoAoS",
        ),
        (
            &[
                "library/algorithms/closest_hit_dop14.scion",
                "library/layouts/dop14_split.scion",
            ],
            "DopSplit",
        ),
        (
            &[
                "library/algorithms/closest_hit_hair.scion",
                "library/layouts/hair_bvh.scion",
            ],
            "HairBVH",
        ),
        (
            &[
                "library/algorithms/closest_hit.scion",
                "lit-tests/Inputs/shared_slab.scion",
            ],
            "SharedSlab",
        ),
        (
            &[
                "library/algorithms/closest_hit.scion",
                "lit-tests/Inputs/shared_slab.scion",
            ],
            "SharedSlabParent",
        ),
        (
            &[
                "library/algorithms/closest_hit8.scion",
                "library/layouts/bvh8.scion",
            ],
            "Bvh8",
        ),
        (
            &[
                "library/algorithms/closest_hit8.scion",
                "library/layouts/bvh8_q8_ci.scion",
            ],
            "Bvh8Q8CI",
        ),
    ];
    for (files, layout) in cases {
        let tree = scionc(&["--emit=tree"], files);
        assert!(
            tree.contains(&format!("tree.layout @{layout} ")),
            "{layout}"
        );
        let via_text = scion_opt(
            &[
                "--layout",
                layout,
                "--passes=destructor-specialize,constructor-specialize",
            ],
            &tree,
        );
        let direct = scionc(&["--emit=mem", "--layout", layout], files);
        assert!(
            via_text == direct,
            "{layout}: scion-opt on the tree text differs from scionc --emit=mem"
        );
    }
}
