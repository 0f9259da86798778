//! Every layout file of `library/layouts` (found by listing the folder, so a new file is
//! checked without editing this test's list of files) against the bytes the layout catalog
//! (docs/design/layout-catalog.md, Table 1 and the case studies) gives it: the stride of each
//! array of its node groups, in order, and the field offsets the catalog's byte tables pin.
//! A file the table below does not know fails: its catalog bytes belong here.

use scion_compiler::layout::model::{LayoutModel, Storage};
use scion_compiler::syntax::ast::{Item, Program};
use std::path::Path;

/// Catalog bytes: file stem, layout name, strides of the node groups' arrays (declaration
/// order), and fields with (array, offset).
type Expect = (
    &'static str,
    &'static str,
    &'static [u64],
    &'static [(&'static str, usize, u64)],
);

const CATALOG: &[Expect] = &[
    // §3.1: bounds 0..24, p_o/c_o 24, nprims 28.
    (
        "pbrt",
        "LinearBVH",
        &[32],
        &[("p_o", 0, 24), ("c_o", 0, 24), ("nprims", 0, 28)],
    ),
    // §3.2: 48 bytes with two child pointers.
    ("ptr", "PtrBVH", &[48], &[]),
    // §3.3: pbrt with align 16.
    ("pbrt_align16", "PbrtAlign16", &[32], &[("nprims", 0, 28)]),
    // §3.4: 16 + 16.
    (
        "pbrt_soaos",
        "PbrtSoAoS",
        &[16, 16],
        &[
            ("low", 0, 0),
            ("c_o", 0, 12),
            ("high", 1, 0),
            ("nprims", 1, 12),
        ],
    ),
    // §3.5: as 3.4, aligned.
    (
        "pbrt_soaos_align16",
        "PbrtSoAoSAlign16",
        &[16, 16],
        &[
            ("low", 0, 0),
            ("c_o", 0, 12),
            ("high", 1, 0),
            ("nprims", 1, 12),
        ],
    ),
    // §3.6: 16 bytes: qlo 0, qhi 6, w 12.
    (
        "pbrt_q16",
        "PbrtQ16",
        &[16],
        &[("qlo", 0, 0), ("qhi", 0, 6), ("w", 0, 12)],
    ),
    // §3.7: 12 + 4.
    (
        "pbrt_q16_soaos",
        "PbrtQ16SoAoS",
        &[12, 4],
        &[("qlo", 0, 0), ("qhi", 0, 6), ("w", 1, 0)],
    ),
    // §3.8: 12 bytes: qlo 0, qhi 4, w 8.
    (
        "sg_eq",
        "SgEq",
        &[12],
        &[("qlo", 0, 0), ("qhi", 0, 4), ("w", 0, 8)],
    ),
    // §3.9: sg-eq padded to 16.
    (
        "sg_eq_align16",
        "SgEqAlign16",
        &[16],
        &[("qlo", 0, 0), ("qhi", 0, 4), ("w", 0, 8)],
    ),
    // §4.1-4.2: links 0..64, six f32[8] planes.
    (
        "bvh8",
        "Bvh8",
        &[256],
        &[("child", 0, 0), ("lower_x", 0, 64), ("upper_z", 0, 224)],
    ),
    // `bvh8` with Embree's Triangle4 leaves (not a Table 1 row): the same interior records.
    (
        "bvh8_tri4",
        "Bvh8Tri4",
        &[256],
        &[("child", 0, 0), ("lower_x", 0, 64), ("upper_z", 0, 224)],
    ),
    (
        "bvh8_align16",
        "Bvh8Align16",
        &[256],
        &[("child", 0, 0), ("lower_x", 0, 64), ("upper_z", 0, 224)],
    ),
    // §4.3-4.4: links 0..64, six u8[8] planes 64..112, start 112, scale 124.
    (
        "bvh8_q8",
        "Bvh8Q8",
        &[136],
        &[
            ("qlo_x", 0, 64),
            ("qhi_z", 0, 104),
            ("start", 0, 112),
            ("scale", 0, 124),
        ],
    ),
    (
        "bvh8_q8_align16",
        "Bvh8Q8Align16",
        &[144],
        &[("qlo_x", 0, 64), ("start", 0, 112), ("scale", 0, 124)],
    ),
    // §4.5-4.6: u32 links 0..32, planes 32..80, start 80, scale 92.
    (
        "bvh8_q8_ci",
        "Bvh8Q8CI",
        &[104],
        &[("qlo_x", 0, 32), ("start", 0, 80), ("scale", 0, 92)],
    ),
    (
        "bvh8_q8_ci_align16",
        "Bvh8Q8CIAlign16",
        &[112],
        &[("qlo_x", 0, 32), ("start", 0, 80), ("scale", 0, 92)],
    ),
    // §4.7-4.8: links 0..64, six u16[8] planes 64..160, start 160, scale 172.
    (
        "bvh8_q16",
        "Bvh8Q16",
        &[184],
        &[
            ("qlo_x", 0, 64),
            ("qhi_x", 0, 80),
            ("start", 0, 160),
            ("scale", 0, 172),
        ],
    ),
    (
        "bvh8_q16_align16",
        "Bvh8Q16Align16",
        &[192],
        &[("qlo_x", 0, 64), ("start", 0, 160), ("scale", 0, 172)],
    ),
    // §4.9-4.10: u32 links 0..32, planes 32..128, start 128, scale 140.
    (
        "bvh8_q16_ci",
        "Bvh8Q16CI",
        &[152],
        &[("qlo_x", 0, 32), ("start", 0, 128), ("scale", 0, 140)],
    ),
    (
        "bvh8_q16_ci_align16",
        "Bvh8Q16CIAlign16",
        &[160],
        &[("qlo_x", 0, 32), ("start", 0, 128), ("scale", 0, 140)],
    ),
    // §5: hot 32 (axis slabs and links), cold 32 (diagonal slabs).
    (
        "dop14_split",
        "DopSplit",
        &[32, 32],
        &[("c0", 0, 24), ("c1", 0, 28), ("lo2", 1, 0)],
    ),
    // §6: 128-byte axis-aligned nodes, 96-byte oriented nodes (indirect groups: node_bytes
    // counts direct groups only, so no strides here; the sizes are checked below).
    ("hair_bvh", "HairBVH", &[], &[]),
    // The same bytes over strand segments.
    ("hair_bvh_strands", "HairStrandsBVH", &[], &[]),
];

fn library() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../library")
}

/// The prelude, every algorithm file (the types some layouts realize live there) and `layout`.
fn program(layout: &str) -> Program {
    let lib = library();
    let mut text = std::fs::read_to_string(lib.join("prelude.scion")).unwrap();
    let mut algorithms: Vec<_> = std::fs::read_dir(lib.join("algorithms"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    algorithms.sort();
    for a in algorithms {
        text.push('\n');
        text.push_str(&std::fs::read_to_string(a).unwrap());
    }
    text.push('\n');
    text.push_str(layout);
    let mut sm = scion_ir::diag::SourceMap::new();
    let f = sm.add("library.scion", text);
    let (p, d) = scion_compiler::syntax::parse_program(&sm, &[f]);
    assert!(d.is_empty(), "{}", d.render(&sm));
    p
}

fn model(p: &Program, name: &str) -> LayoutModel {
    let decl = p
        .items
        .iter()
        .find_map(|i| match i {
            Item::Layout(l) if l.name.name == name => Some(l),
            _ => None,
        })
        .unwrap_or_else(|| panic!("no layout {name}"));
    let m = LayoutModel::from_ast(decl, p);
    assert!(m.diagnostics.is_empty(), "{name}: {:?}", m.diagnostics);
    m
}

#[test]
fn every_library_layout_has_its_catalog_bytes() {
    let mut files: Vec<_> = std::fs::read_dir(library().join("layouts"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "scion"))
        .collect();
    files.sort();
    assert!(files.len() >= CATALOG.len());
    for path in files {
        let stem = path.file_stem().unwrap().to_str().unwrap().to_string();
        let (_, name, strides, fields) = CATALOG
            .iter()
            .find(|c| c.0 == stem)
            .unwrap_or_else(|| panic!("library/layouts/{stem}.scion: add its catalog bytes here"));
        let m = model(&program(&std::fs::read_to_string(&path).unwrap()), name);
        if !strides.is_empty() {
            let got: Vec<u64> = m
                .groups
                .iter()
                .flat_map(|g| g.arrays.iter().map(|a| a.stride))
                .collect();
            assert_eq!(got, *strides, "{stem}: node array strides");
            // Direct groups are a node's bytes (an indirect group's records live behind links).
            if m.node_bytes() != 0 {
                assert_eq!(
                    m.node_bytes(),
                    strides.iter().sum::<u64>(),
                    "{stem}: node bytes"
                );
            }
        }
        for &(field, array, offset) in *fields {
            match m.offset_of(field) {
                Some(Storage::Element {
                    array: a,
                    offset: o,
                    ..
                }) => {
                    assert_eq!((a, o), (array, offset), "{stem}: field {field}")
                }
                other => panic!("{stem}: field {field}: {other:?}"),
            }
        }
        if stem.starts_with("hair_bvh") {
            let sizes: Vec<u64> = m
                .groups
                .iter()
                .flat_map(|g| g.arrays.iter().map(|a| a.stride))
                .collect();
            assert_eq!(sizes, vec![128, 96], "{stem}: AABB and OBB node records");
        }
    }
}
