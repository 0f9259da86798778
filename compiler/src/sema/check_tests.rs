//! Tests of the layout and build well-formedness checks: each check once rejecting and once
//! accepting, and the library and catalog layouts accepted with no diagnostics at all.

use crate::layout::check_build::check_builds;
use crate::layout::check_layout::check_layouts;
use crate::layout::fixtures::*;
use scion_ir::diag::{Diagnostics, SourceMap};

fn diags(sources: &[&str]) -> Diagnostics {
    let p = program(sources);
    let models = crate::layout::model::Models::inferred(&p);
    let mut d = check_layouts(&p, &models);
    d.extend(check_builds(&p, &models));
    d
}

fn codes(sources: &[&str]) -> Vec<String> {
    diags(sources)
        .list
        .iter()
        .filter_map(|d| d.code.clone())
        .collect()
}

/// Asserts `code` is reported for `bad` and nothing at all for `good`.
fn rejects_and_accepts(code: &str, bad: &str, good: &str) {
    let got = codes(&[bad]);
    assert!(
        got.iter().any(|c| c == code),
        "expected {code}, got {got:?}"
    );
    let ok = diags(&[good]);
    assert!(ok.is_empty(), "expected no diagnostics, got {:#?}", ok.list);
}

/// `PBRT` with one substitution (which must apply).
fn pbrt_with(from: &str, to: &str) -> String {
    assert!(PBRT.contains(from), "fixture lacks {from:?}");
    PBRT.replacen(from, to, 1)
}

#[test]
fn library_layouts_pass_every_check() {
    let d = diags(&[PBRT, PTR, PBRT_ALIGN16, PBRT_SOAOS, PBRT_Q16]);
    assert!(d.is_empty(), "{:#?}", d.list);
}

#[test]
fn catalog_layouts_pass_every_check() {
    let a16 = bvh8_q8_align16();
    for srcs in [
        vec![PBRT_ALIGN16],
        vec![PBRT_SOAOS],
        vec![PBRT_Q16],
        vec![SG_EQ],
        vec![BVH8_TYPE, BVH8_Q8],
        vec![BVH8_TYPE, a16.as_str()],
        vec![SHARED_SLAB],
        vec![DOP_SPLIT],
    ] {
        let d = diags(&srcs);
        assert!(d.is_empty(), "{:#?}", d.list);
    }
}

#[test]
fn diagnostics_render_with_code_and_position() {
    let bad = pbrt_with("c_o: u32;", "c_o: u32; c_o: u32;");
    let p = program(&[&bad]);
    let d = check_layouts(&p, &crate::layout::model::Models::inferred(&p));
    let mut sm = SourceMap::new();
    let mut text = String::from(PRELUDE);
    text.push('\n');
    text.push_str(&bad);
    sm.add("pbrt.scion", text);
    let out = d.render(&sm);
    assert!(
        out.contains("error[E0302]: `c_o` is declared twice"),
        "{out}"
    );
    assert!(out.contains("first declared here"), "{out}");
}

// ------------------------------------------------------------------ layout checks (E03xx)

#[test]
fn e0301_unsized_type() {
    // (An unknown type name is the type checker's E0202, not the layout model's.)
    rejects_and_accepts(
        "E0301",
        &pbrt_with("bounds: AABB;", "bounds: AABB; extra: Triangle[N];"),
        PBRT,
    );
}

#[test]
fn e0302_duplicate_member() {
    rejects_and_accepts(
        "E0302",
        &pbrt_with("nprims: u16;", "nprims: u16; nprims: u16;"),
        PBRT,
    );
    rejects_and_accepts("E0302", &pbrt_with("P: u32;", "P: u32; I: u32;"), PBRT);
}

#[test]
fn e0303_zero_padding() {
    rejects_and_accepts(
        "E0303",
        &pbrt_with("nprims: u16;", "nprims: u16; 0;"),
        &pbrt_with("nprims: u16;", "nprims: u16; 2;"),
    );
}

#[test]
fn e0304_separator_outside_group() {
    rejects_and_accepts("E0304", &pbrt_with("N: u32;", "N: u32; ---"), PBRT_SOAOS);
    rejects_and_accepts("E0304", &pbrt_with("p_o: u32;", "p_o: u32; ---"), PBRT);
}

#[test]
fn e0305_align_power_of_two() {
    rejects_and_accepts("E0305", &pbrt_with("align=32", "align=24"), PBRT_ALIGN16);
}

#[test]
fn e0306_direct_group_needs_size() {
    rejects_and_accepts(
        "E0306",
        &pbrt_with("[size=N, align=32]", "[align=32]"),
        PBRT,
    );
}

#[test]
fn e0307_direct_group_needs_by() {
    rejects_and_accepts("E0307", &pbrt_with(" by I {", " {"), PBRT);
}

#[test]
fn e0308_nested_group_count() {
    let tiled = |inner: &str| {
        format!(
            "type T = One(a: f32);\nlayout Tiled(I: u32) {{ N: u32; group outer[size=N] by I {{ group inner{inner} {{ a: f32; }}; }}; }};"
        )
    };
    rejects_and_accepts("E0308", &tiled(""), &tiled("[4]"));
    rejects_and_accepts("E0308", &tiled("[0]"), &tiled("[1]"));
}

#[test]
fn e0309_from_names_an_indirect_group() {
    let bad = BVH8_Q8.replace("indirect group nodes", "group nodes[size=P] by R");
    let got = codes(&[BVH8_TYPE, &bad]);
    assert!(got.contains(&"E0309".to_string()), "{got:?}");
    let bad = BVH8_Q8.replace("from nodes[R]", "from nodez[R]");
    let got = codes(&[BVH8_TYPE, &bad]);
    assert!(got.contains(&"E0309".to_string()), "{got:?}");
    assert!(diags(&[BVH8_TYPE, BVH8_Q8]).is_empty());
}

#[test]
fn e0310_parent_names_a_field() {
    let good = pbrt_with(
        "layout LinearBVH(I: u32)",
        "layout LinearBVH(I: u32, b: AABB = parent.bounds)",
    );
    let bad = pbrt_with(
        "layout LinearBVH(I: u32)",
        "layout LinearBVH(I: u32, b: AABB = parent.bouncs)",
    );
    rejects_and_accepts("E0310", &bad, &good);
}

#[test]
fn e0311_one_adt() {
    rejects_and_accepts("E0311", &pbrt_with("0 -> Interior {", "0 -> Inner {"), PBRT);
    let mixed = format!(
        "type Other = Solo(x: u32);\n{}",
        pbrt_with("0 -> Interior {", "0 -> Solo {")
    );
    rejects_and_accepts("E0311", &mixed, PBRT);
}

#[test]
fn e0312_missing_field() {
    rejects_and_accepts("E0312", &pbrt_with("right = I + c_o;", ""), PBRT);
}

#[test]
fn e0313_two_paths() {
    let bad = pbrt_with(
        "left = I + 1;",
        "left = I + 1; bounds = AABB(f32x3(0.0, 0.0, 0.0), f32x3(1.0, 1.0, 1.0));",
    );
    let d = diags(&[&bad]);
    let e = d
        .list
        .iter()
        .find(|d| d.code.as_deref() == Some("E0313"))
        .expect("E0313");
    assert_eq!(e.labels.len(), 2, "both declarations are shown");
    assert!(diags(&[PBRT]).is_empty());
}

#[test]
fn e0314_variant_realized() {
    let bad = pbrt_with("0 -> Interior {", "0 -> Leaf {");
    let got = codes(&[&bad]);
    assert!(got.contains(&"E0314".to_string()), "{got:?}");
    let single =
        "type One = Only(a: u32);\nlayout L(I: u32) { N: u32; group g[size=N] by I { a: u32; }; };";
    assert!(diags(&[single]).is_empty(), "{:#?}", diags(&[single]).list);
    let unsplit = "layout L(I: u32) { N: u32; group g[size=N] by I { bounds: AABB; }; };\nbuild L { build Leaf(bounds: AABB) { return this; }; };";
    assert!(codes(&[unsplit]).contains(&"E0314".to_string()));
}

#[test]
fn e0315_split_without_arm_for_a_variant() {
    let bad = pbrt_with(
        "nprims: u16;",
        "nprims: u16; flag: u8; split flag { _ -> Interior { }; };",
    );
    rejects_and_accepts("E0315", &bad, &pbrt_with("nprims: u16;", "nprims: u16; 2;"));
}

#[test]
fn e0316_split_coverage() {
    let bad = pbrt_with("> 0 -> Leaf", "> 5 -> Leaf").replace("0 -> Interior", "< 5 -> Interior");
    let d = diags(&[&bad]);
    let e = d
        .list
        .iter()
        .find(|d| d.code.as_deref() == Some("E0316"))
        .expect("E0316");
    assert!(e.labels[0].message.contains("value 5"), "{e:?}");
    assert!(diags(&[PBRT]).is_empty());
}

#[test]
fn w0317_unreachable_arm() {
    // `_` covers everything, so the `7` arm after it can never match.
    let bad = pbrt_with("0 -> Interior {", "_ -> Interior {").replace(
        "      };\n    };\n    nprims: u16;",
        "      };\n      7 -> Leaf { p_o: u32; data = primitives[p_o : p_o + nprims]; };\n    };\n    nprims: u16;",
    );
    let d = diags(&[&bad]);
    assert!(
        d.list
            .iter()
            .any(|d| d.code.as_deref() == Some("W0317") && !d.is_error()),
        "{:#?}",
        d.list
    );
    assert!(!d.has_errors(), "{:#?}", d.list);
}

#[test]
fn e0318_derived_cycle() {
    let bad = pbrt_with("left = I + 1;", "left = I + k; k = j + 1; j = left;");
    let d = diags(&[&bad]);
    let e = d
        .list
        .iter()
        .find(|d| d.code.as_deref() == Some("E0318"))
        .expect("E0318");
    assert!(
        e.message.contains("left -> k -> j -> left")
            || e.message.contains("k -> j -> left -> k")
            || e.message.contains("j -> left -> k -> j"),
        "{}",
        e.message
    );
    rejects_and_accepts(
        "E0318",
        &bad,
        &pbrt_with("left = I + 1;", "left = I + k; k = j + 1; j = 0;"),
    );
}

#[test]
fn e0319_unknown_name_in_derived_field() {
    rejects_and_accepts(
        "E0319",
        &pbrt_with(
            "data = primitives[p_o : p_o + nprims];",
            "data = primitives[c_o : c_o + nprims];",
        ),
        PBRT,
    );
    rejects_and_accepts("E0319", &pbrt_with("size=N", "size=M"), PBRT);
}

#[test]
fn e0320_discriminant_type() {
    let bad = pbrt_with("split nprims {", "split bounds {");
    rejects_and_accepts("E0320", &bad, PBRT);
}

#[test]
fn e0322_stored_field_without_storage() {
    let bad = BVH8_Q8.replace("Leaf { nprims = 0;", "Leaf { junk: u32; nprims = 0;");
    let got = codes(&[BVH8_TYPE, &bad]);
    assert!(got.contains(&"E0322".to_string()), "{got:?}");
}

#[test]
fn e0327_stored_type_preserves_logical_type() {
    let bad = pbrt_with("nprims: u16;", "nprims: u32;");
    rejects_and_accepts("E0327", &bad, PBRT);
    let bad = PTR.replacen("left: ptr;", "left: u32;", 1);
    let got = codes(&[&bad]);
    assert!(got.contains(&"E0327".to_string()), "{got:?}");
}

#[test]
fn collects_every_error_of_a_layout() {
    let bad = pbrt_with("bounds: AABB;", "bounds: AABB; extra: Triangle[N]; 0;")
        .replace("align=32", "align=3");
    let got = codes(&[&bad]);
    for c in ["E0301", "E0303", "E0305"] {
        assert!(got.contains(&c.to_string()), "{c} missing from {got:?}");
    }
}

// ------------------------------------------------------------------ build checks (E04xx)

#[test]
fn e0401_build_names_a_layout() {
    rejects_and_accepts(
        "E0401",
        &PBRT.replace("build LinearBVH", "build LinearBHV"),
        PBRT,
    );
}

#[test]
fn e0403_e0404_e0405_variants_built_once() {
    rejects_and_accepts("E0403", &pbrt_with("build Leaf(", "build Lef("), PBRT);
    let twice = pbrt_with(
        "  build Leaf(",
        "  build Leaf(bounds: AABB) { return this; };\n  build Leaf(",
    );
    rejects_and_accepts("E0404", &twice, PBRT);
    let i = PBRT.find("  build Leaf(").unwrap();
    let j = PBRT[i..].find("  };\n").unwrap() + i + 5;
    let missing = format!("{}{}", &PBRT[..i], &PBRT[j..]);
    rejects_and_accepts("E0405", &missing, PBRT);
}

#[test]
fn e0406_build_target_exists() {
    rejects_and_accepts(
        "E0406",
        &pbrt_with("build nprims = 0;", "build nprims = 0; build p_o = 1;"),
        PBRT,
    );
    rejects_and_accepts(
        "E0406",
        &pbrt_with("build nprims = 0;", "build nprims = 0; build N = 1;"),
        PBRT,
    );
    let derived = PBRT_SOAOS.replacen("build low = bounds.low;", "build bounds;", 1);
    let d = diags(&[&derived]);
    assert!(
        d.list
            .iter()
            .any(|d| d.code.as_deref() == Some("E0406") && d.message.contains("derived")),
        "{:#?}",
        d.list
    );
}

#[test]
fn e0407_stored_field_populated() {
    rejects_and_accepts("E0407", &pbrt_with("build nprims = 0;", ""), PBRT);
    let branchy = pbrt_with(
        "build nprims = 0;",
        "if bounds.low.x < 0.0 { build nprims = 0; }",
    );
    rejects_and_accepts(
        "E0407",
        &branchy,
        &pbrt_with(
            "build nprims = 0;",
            "if bounds.low.x < 0.0 { build nprims = 0; } else { build nprims = 0; }",
        ),
    );
}

#[test]
fn e0408_written_twice() {
    rejects_and_accepts(
        "E0408",
        &pbrt_with("build nprims = 0;", "build nprims = 0; build nprims = 0;"),
        PBRT,
    );
}

#[test]
fn e0409_read_before_write() {
    let bad = pbrt_with(
        "build c_o = R - this;",
        "let x: u32 = c_o; build c_o = R - this;",
    );
    let good = pbrt_with(
        "build c_o = R - this;",
        "build c_o = R - this; let x: u32 = c_o;",
    );
    rejects_and_accepts("E0409", &bad, &good);
}

#[test]
fn e0410_children_built_once() {
    rejects_and_accepts("E0410", &pbrt_with("build left;", ""), PBRT);
    rejects_and_accepts(
        "E0410",
        &pbrt_with("build left;", "build left; build left;"),
        PBRT,
    );
}

#[test]
fn e0411_every_path_returns() {
    let i = PBRT.find("build c_o = R - this; return this;");
    let bad = match i {
        Some(_) => pbrt_with(
            "build c_o = R - this; return this;",
            "build c_o = R - this;",
        ),
        None => pbrt_with(
            "    build c_o = R - this;\n    return this;",
            "    build c_o = R - this;",
        ),
    };
    rejects_and_accepts("E0411", &bad, PBRT);
    let partial = pbrt_with(
        "    return this;\n  };\n  build Leaf",
        "    if nprims == 0 { return this; }\n  };\n  build Leaf",
    );
    let got = codes(&[&partial]);
    assert!(got.contains(&"E0411".to_string()), "{got:?}");
}

#[test]
fn e0412_append_names_a_logical_array() {
    rejects_and_accepts(
        "E0412",
        &pbrt_with("append(data, nprims)", "append(bounds, nprims)"),
        PBRT,
    );
}

#[test]
fn e0413_bit_range_within_reference() {
    let bad = pbrt_with(
        "build c_o = R - this;",
        "build c_o = R - this; this[28:40] = 1;",
    );
    let good = pbrt_with(
        "build c_o = R - this;",
        "build c_o = R - this; this[28:32] = 1;",
    );
    rejects_and_accepts("E0413", &bad, &good);
}

#[test]
fn e0414_one_build_per_layout() {
    let i = PBRT.find("build LinearBVH").unwrap();
    let twice = format!("{PBRT}\n{}", &PBRT[i..]);
    rejects_and_accepts("E0414", &twice, PBRT);
}

#[test]
fn e0415_build_parameters_are_logical_fields() {
    rejects_and_accepts(
        "E0415",
        &pbrt_with(
            "build Interior(bounds: AABB,",
            "build Interior(bounds: AABB, extra: u32,",
        ),
        PBRT,
    );
}

#[test]
fn e0416_root_writes_only_plain_globals() {
    let bad = PBRT_Q16.replace("build root {", "build root {\n    build N = 3;");
    let got = codes(&[&bad]);
    assert!(got.contains(&"E0416".to_string()), "{got:?}");
    assert!(diags(&[PBRT_Q16]).is_empty());
}

#[test]
fn e0407_globals_written_by_root() {
    let no_root = PBRT_Q16.replace("build wstep = frame_step(wlo, bounds.high, 65535);", "");
    let got = codes(&[&no_root]);
    assert!(got.contains(&"E0407".to_string()), "{got:?}");
    let twice = PBRT_Q16.replace(
        "build wstep = frame_step(wlo, bounds.high, 65535);",
        "build wstep = wlo; build wstep = wlo;",
    );
    assert!(codes(&[&twice]).contains(&"E0408".to_string()));
    let early = PBRT_Q16.replace(
        "build wlo = frame_origin(bounds.low);\n    build wstep = frame_step(wlo, bounds.high, 65535);",
        "build wstep = frame_step(wlo, bounds.high, 65535);\n    build wlo = frame_origin(bounds.low);",
    );
    assert!(
        codes(&[&early]).contains(&"E0409".to_string()),
        "{:?}",
        codes(&[&early])
    );
}

#[test]
fn e0417_copy_needs_a_logical_field() {
    rejects_and_accepts(
        "E0417",
        &pbrt_with("build c_o = R - this;", "build c_o;"),
        PBRT,
    );
}

#[test]
fn loops_count_as_many_writes() {
    let bad = pbrt_with(
        "build nprims = 0;",
        "foreach t in bounds.low { build nprims = 0; }",
    );
    let got = codes(&[&bad]);
    assert!(
        got.contains(&"E0407".to_string()) || got.contains(&"E0408".to_string()),
        "{got:?}"
    );
}

#[test]
fn e0418_fields_of_other_variants() {
    let bad = pbrt_with(
        "build p_o = append(data, nprims);",
        "build p_o = append(data, nprims) + c_o;",
    );
    rejects_and_accepts("E0418", &bad, PBRT);
}

#[test]
fn e0323_cyclic_from() {
    let src = r#"
type T = Node(a: u32) | Empty;
layout L(R: u32) {
  indirect group g { k: u32; a: u32; split k { _ -> Node from g[k]; }; };
  split R { 0 -> Empty { }; _ -> Node from g[R]; };
};
"#;
    let got = codes(&[src]);
    assert!(got.contains(&"E0323".to_string()), "{got:?}");
    let ok = src.replace("split k { _ -> Node from g[k]; };", "");
    assert!(diags(&[&ok]).is_empty(), "{:#?}", diags(&[&ok]).list);
}

#[test]
fn e0324_too_many_routes() {
    // Nine splits in a row, each realizing `Node` with two arms: 512 routes.
    let mut body = String::new();
    for i in 0..9 {
        body.push_str(&format!(
            "f{i}: u8; split f{i} {{ 0 -> Node {{ }}; _ -> Node {{ }}; }};\n"
        ));
    }
    let src = format!("type T = Node(a: u8);\nlayout L(I: u32) {{ N: u32; group g[size=N] by I {{ a: u8; {body} }}; }};");
    let got = codes(&[&src]);
    assert!(got.contains(&"E0324".to_string()), "{got:?}");
    let few = src
        .replace("f8: u8; split f8 { 0 -> Node { }; _ -> Node { }; };", "")
        .replace("f7: u8; split f7 { 0 -> Node { }; _ -> Node { }; };", "");
    assert!(!codes(&[&few]).contains(&"E0324".to_string()));
}

#[test]
fn nested_splits_give_alternative_paths() {
    let src = r#"
type T = Node(a: u32) | Empty;
layout L(I: u32) {
  N: u32;
  group g[size=N, align=8] by I {
    tag: u8;
    split tag {
      0 -> Empty { };
      _ -> Node {
        wide: u8;
        split wide {
          0 -> Node { a: u32; };
          _ -> Node { big: u64; a = big as u32; };
        };
      };
    };
  };
};
"#;
    assert!(diags(&[src]).is_empty(), "{:#?}", diags(&[src]).list);
    let p = program(&[src]);
    let crate::syntax::ast::Item::Layout(l) = p.items.last().unwrap() else {
        panic!()
    };
    let m = crate::layout::LayoutModel::from_ast(l, &p);
    match crate::layout::resolve_field(&m, "Node", "a").unwrap() {
        crate::layout::FieldPath::Alternatives(cases) => {
            assert_eq!(cases.len(), 2);
            assert!(matches!(
                cases[0].1,
                crate::layout::FieldPath::Stored { .. }
            ));
            assert!(matches!(
                cases[1].1,
                crate::layout::FieldPath::Derived { .. }
            ));
        }
        other => panic!("{other:?}"),
    }
    // Like a C union, a split is aligned to its most aligned arm: the outer overlay starts at
    // 8 (its Node arm holds a u64), so tag @0, wide @8, the inner overlay @16, 24 bytes.
    assert_eq!(
        m.offset_of("wide"),
        Some(crate::layout::model::Storage::Element {
            group: 0,
            array: 0,
            offset: 8
        })
    );
    assert_eq!(
        m.offset_of("big"),
        Some(crate::layout::model::Storage::Element {
            group: 0,
            array: 0,
            offset: 16
        })
    );
    assert_eq!(m.groups[0].arrays[0].stride, 24);
}

#[test]
fn root_writes_inside_blocks_count_once() {
    let nested = PBRT_Q16.replace(
        "build wstep = frame_step(wlo, bounds.high, 65535);",
        "if true { build wstep = frame_step(wlo, bounds.high, 65535); }",
    );
    assert!(
        diags(&[&nested]).is_empty(),
        "{:#?}",
        diags(&[&nested]).list
    );
    let early = PBRT_Q16.replace(
        "build wlo = frame_origin(bounds.low);",
        "{ let z: f32x3 = wlo; };\n    build wlo = frame_origin(bounds.low);",
    );
    let d = diags(&[&early]);
    assert_eq!(
        d.list
            .iter()
            .filter(|d| d.code.as_deref() == Some("E0409"))
            .count(),
        1,
        "{:#?}",
        d.list
    );
}

#[test]
fn e0325_bit_slices_fit() {
    let bad = PBRT_Q16.replace("p_o = w[0:28];", "p_o = w[0:40];");
    let got = codes(&[&bad]);
    assert!(got.contains(&"E0325".to_string()), "{got:?}");
    let bad = PBRT_Q16.replace("split w[28:32]", "split w[28:28]");
    assert!(codes(&[&bad]).contains(&"E0325".to_string()));
    assert!(diags(&[PBRT_Q16]).is_empty());
}
