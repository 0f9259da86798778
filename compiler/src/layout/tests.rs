//! Tests of the layout model, field resolution and buffer plans against docs/design/layout-catalog.md.

use crate::layout::fixtures::*;
use crate::layout::model::{GroupKind, LayoutModel, Storage};
use crate::layout::plan::{BufferPlan, Count};
use crate::layout::resolve::{
    evaluation_order, resolve_field, Dep, FieldPath, Index, ResolveError, Resolver,
};
use crate::syntax::ast::{ExprKind, Item, Program};

fn model(prog: &Program, name: &str) -> LayoutModel {
    let decl = prog
        .items
        .iter()
        .find_map(|i| match i {
            Item::Layout(l) if l.name.name == name => Some(l),
            _ => None,
        })
        .expect("layout in fixture");
    let m = LayoutModel::from_ast(decl, prog);
    assert!(m.diagnostics.is_empty(), "{:?}", m.diagnostics);
    m
}

fn elem(m: &LayoutModel, field: &str) -> (usize, u64) {
    match m.offset_of(field) {
        Some(Storage::Element { array, offset, .. }) => (array, offset),
        other => panic!("{field}: {other:?}"),
    }
}

#[test]
fn pbrt_node_is_32_bytes() {
    let p = program(&[PBRT]);
    let m = model(&p, "LinearBVH");
    let g = &m.groups[m.group_named("nodes").unwrap()];
    assert_eq!(g.kind, GroupKind::Direct);
    assert_eq!(g.arrays.len(), 1);
    assert_eq!(
        (g.arrays[0].size, g.arrays[0].align, g.arrays[0].stride),
        (30, 32, 32)
    );
    assert_eq!(elem(&m, "bounds"), (0, 0));
    assert_eq!(elem(&m, "p_o"), (0, 24));
    assert_eq!(elem(&m, "c_o"), (0, 24));
    assert_eq!(elem(&m, "nprims"), (0, 28));
    assert_eq!((m.splits[0].offset, m.splits[0].size), (24, 4));
    assert_eq!(m.offset_of("N"), Some(Storage::Globals { offset: 4 }));
    assert_eq!(m.globals.size, 8);
    assert_eq!(m.global_arrays[0].shape.size, 40);
    assert_eq!(m.node_bytes(), 32);
    assert_eq!(m.adt.as_ref().unwrap().name, "BVH");
}

#[test]
fn ptr_node_is_48_bytes() {
    let p = program(&[PTR]);
    let m = model(&p, "PtrBVH");
    let g = &m.groups[0];
    assert_eq!(g.kind, GroupKind::Pointer);
    assert_eq!(g.arrays[0].stride, 48);
    assert_eq!(elem(&m, "left"), (0, 24));
    assert_eq!(elem(&m, "right"), (0, 32));
    assert_eq!(elem(&m, "p_o"), (0, 24));
    assert_eq!(elem(&m, "nprims"), (0, 40));
    assert_eq!(m.reference.size, 8);
}

#[test]
fn catalog_binary_layouts_have_table1_sizes() {
    let p = program(&[PBRT_ALIGN16, PBRT_SOAOS, PBRT_Q16, SG_EQ]);
    let a16 = model(&p, "PbrtAlign16");
    assert_eq!(
        (
            a16.groups[0].arrays[0].stride,
            a16.groups[0].arrays[0].align
        ),
        (32, 16)
    );

    let soaos = model(&p, "PbrtSoAoS");
    let arrays = &soaos.groups[0].arrays;
    assert_eq!(
        arrays.iter().map(|a| a.stride).collect::<Vec<_>>(),
        vec![16, 16]
    );
    assert_eq!(elem(&soaos, "low"), (0, 0));
    assert_eq!(elem(&soaos, "c_o"), (0, 12));
    assert_eq!(elem(&soaos, "high"), (1, 0));
    assert_eq!(elem(&soaos, "nprims"), (1, 12));
    assert_eq!(soaos.node_bytes(), 32);

    let q16 = model(&p, "PbrtQ16");
    assert_eq!(q16.node_bytes(), 16);
    assert_eq!(elem(&q16, "qhi"), (0, 6));
    assert_eq!(elem(&q16, "w"), (0, 12));
    assert_eq!(
        q16.offset_of("wstep"),
        Some(Storage::Globals { offset: 20 })
    );

    let sg = model(&p, "SgEq");
    assert_eq!(sg.node_bytes(), 12);
    assert_eq!(sg.groups[0].arrays[0].align, 4);
}

#[test]
fn bvh8_q8_records_are_136_and_144_bytes() {
    let a16 = bvh8_q8_align16();
    let p = program(&[BVH8_TYPE, BVH8_Q8, &a16]);
    let m = model(&p, "Bvh8Q8");
    let g = &m.groups[m.group_named("nodes").unwrap()];
    assert_eq!(g.kind, GroupKind::Indirect);
    assert_eq!(g.arrays[0].stride, 136);
    assert_eq!(elem(&m, "lower_x"), (0, 64));
    assert_eq!(elem(&m, "start"), (0, 112));
    assert_eq!(elem(&m, "scale"), (0, 124));
    assert_eq!(m.node_bytes(), 0, "no direct group: leaves have no record");
    let m16 = model(&p, "Bvh8Q8A16");
    assert_eq!(m16.groups[0].arrays[0].stride, 144);
    assert_eq!(m.adt.as_ref().unwrap().name, "BVH8");
}

#[test]
fn align_attribute_rounds_the_stride() {
    let src = r#"
type T = One(a: u8);
layout L(I: u32) { N: u32; group g[size=N, align=16] by I { a: u8; b: u64; c: u8; }; };
"#;
    let p = program(&[src]);
    let m = model(&p, "L");
    assert_eq!(elem(&m, "b"), (0, 8));
    assert_eq!(elem(&m, "c"), (0, 16));
    assert_eq!(
        (m.groups[0].arrays[0].size, m.groups[0].arrays[0].stride),
        (17, 32)
    );
}

#[test]
fn nested_groups_are_tiles() {
    let src = r#"
type T = One(a: f32, b: u16);
layout Tiled(I: u32) {
  N: u32;
  group outer[size=N] by I {
    group inner[4] { a: f32; --- b: u16; };
  };
};
"#;
    let p = program(&[src]);
    let m = model(&p, "Tiled");
    let inner = &m.groups[1];
    assert_eq!(inner.kind, GroupKind::Nested);
    assert_eq!(
        inner
            .arrays
            .iter()
            .map(|a| (a.offset, a.stride))
            .collect::<Vec<_>>(),
        vec![(0, 4), (16, 2)]
    );
    assert_eq!(m.groups[0].arrays[0].size, 24);
    match resolve_field(&m, "One", "b").unwrap() {
        FieldPath::Stored { steps, storage, .. } => {
            assert_eq!(steps.len(), 2);
            assert_eq!(steps[1].index, Index::Tile { count: 4 });
            assert_eq!(
                storage,
                Storage::Element {
                    group: 1,
                    array: 1,
                    offset: 0
                }
            );
        }
        other => panic!("{other:?}"),
    }
    let plan = BufferPlan::of(&m);
    assert_eq!(plan.buffers.len(), 2, "{plan:?}");
    assert_eq!(
        plan.buffer("outer").unwrap().count,
        Count::Nodes {
            per_element: 4,
            size_global: Some("N".into())
        }
    );
}

#[test]
fn resolves_pbrt_fields() {
    let p = program(&[PBRT]);
    let m = model(&p, "LinearBVH");
    let mut r = Resolver::new(&m);
    match r.resolve("Interior", "bounds").unwrap() {
        FieldPath::Stored {
            steps,
            storage,
            size,
            ..
        } => {
            assert_eq!(steps.len(), 1);
            assert!(
                matches!(&steps[0].index, Index::Value(e) if matches!(&e.kind, ExprKind::Name(n) if n.name == "I"))
            );
            assert_eq!(
                storage,
                Storage::Element {
                    group: 0,
                    array: 0,
                    offset: 0
                }
            );
            assert_eq!(size, 24);
        }
        other => panic!("{other:?}"),
    }
    match r.resolve("Interior", "right").unwrap() {
        FieldPath::Derived { deps, .. } => {
            let names: Vec<_> = deps.iter().map(|(n, _)| n.name.as_str()).collect();
            assert_eq!(names, vec!["I", "c_o"]);
            assert_eq!(deps[0].1, Dep::Component(0));
            assert!(matches!(deps[1].1, Dep::Member(_)));
        }
        other => panic!("{other:?}"),
    }
    match r.resolve("Leaf", "data").unwrap() {
        FieldPath::Derived { deps, .. } => {
            assert!(
                deps.iter().all(|(_, d)| matches!(d, Dep::Member(_))),
                "{deps:?}"
            );
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        r.resolve("Leaf", "nprims").unwrap(),
        FieldPath::Stored { size: 2, .. }
    ));
    assert!(matches!(
        r.resolve("Leaf", "c_o"),
        Err(ResolveError::Missing { .. })
    ));
    assert!(matches!(
        r.resolve("Nope", "bounds"),
        Err(ResolveError::UnknownVariant(_))
    ));
    // Cached: the same answer again.
    assert!(matches!(
        r.resolve("Leaf", "c_o"),
        Err(ResolveError::Missing { .. })
    ));
}

#[test]
fn resolves_pointer_and_indirect_paths() {
    let p = program(&[PTR, BVH8_TYPE, BVH8_Q8]);
    let ptr = model(&p, "PtrBVH");
    match resolve_field(&ptr, "Interior", "left").unwrap() {
        FieldPath::Stored { steps, storage, .. } => {
            assert!(matches!(steps[0].index, Index::Pointer(_)));
            assert_eq!(
                storage,
                Storage::Element {
                    group: 0,
                    array: 0,
                    offset: 24
                }
            );
        }
        other => panic!("{other:?}"),
    }
    let b8 = model(&p, "Bvh8Q8");
    match resolve_field(&b8, "Interior", "child_bounds").unwrap() {
        FieldPath::Derived { steps, .. } => assert!(matches!(steps[0].index, Index::Key(_))),
        other => panic!("{other:?}"),
    }
    // Leaf is realized by two arms (the SENTINEL and `_`), each deriving nprims differently.
    match resolve_field(&b8, "Leaf", "nprims").unwrap() {
        FieldPath::Alternatives(cases) => {
            assert_eq!(cases.len(), 2);
            assert_eq!(cases[0].0, vec![(0, 0)]);
            assert_eq!(cases[1].0, vec![(0, 2)]);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn resolves_through_soaos_parts_and_q16_slices() {
    let p = program(&[PBRT_SOAOS, PBRT_Q16]);
    let s = model(&p, "PbrtSoAoS");
    match resolve_field(&s, "Leaf", "nprims").unwrap() {
        FieldPath::Stored { storage, .. } => assert_eq!(
            storage,
            Storage::Element {
                group: 0,
                array: 1,
                offset: 12
            }
        ),
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        resolve_field(&s, "Interior", "bounds").unwrap(),
        FieldPath::Derived { .. }
    ));
    let q = model(&p, "PbrtQ16");
    match resolve_field(&q, "Interior", "right").unwrap() {
        FieldPath::Derived { deps, .. } => assert!(matches!(deps[1].1, Dep::Member(_))),
        other => panic!("{other:?}"),
    }
}

#[test]
fn buffer_plans_of_pbrt_and_ptr() {
    let p = program(&[PBRT, PTR]);
    let plan = BufferPlan::of(&model(&p, "LinearBVH"));
    let names: Vec<_> = plan.buffers.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names, vec!["globals", "primitives", "nodes"]);
    let g = plan.buffer("globals").unwrap();
    assert_eq!((g.elem_size, g.align, g.count.clone()), (8, 4, Count::One));
    let prims = plan.buffer("primitives").unwrap();
    assert_eq!((prims.elem_size, prims.stride, prims.align), (40, 40, 4));
    assert_eq!(
        prims.count,
        Count::LogicalLength {
            field: "data".into(),
            variants: vec!["Leaf".into()],
            len_global: "P".into()
        }
    );
    let nodes = plan.buffer("nodes").unwrap();
    assert_eq!((nodes.elem_size, nodes.stride, nodes.align), (30, 32, 32));
    assert_eq!(
        nodes.count,
        Count::Nodes {
            per_element: 1,
            size_global: Some("N".into())
        }
    );

    let plan = BufferPlan::of(&model(&p, "PtrBVH"));
    let nodes = plan.buffer("nodes").unwrap();
    assert_eq!((nodes.elem_size, nodes.stride, nodes.align), (42, 48, 8));
}

#[test]
fn buffer_plans_of_soaos_and_indirect_groups() {
    let p = program(&[PBRT_SOAOS, BVH8_TYPE, BVH8_Q8]);
    let plan = BufferPlan::of(&model(&p, "PbrtSoAoS"));
    assert_eq!(plan.buffer("nodes#0").unwrap().stride, 16);
    assert_eq!(plan.buffer("nodes#1").unwrap().stride, 16);
    let plan = BufferPlan::of(&model(&p, "Bvh8Q8"));
    let nodes = plan.buffer("nodes").unwrap();
    assert_eq!(nodes.stride, 136);
    assert_eq!(
        nodes.count,
        Count::VariantNodes {
            variants: vec!["Interior".into()]
        }
    );
    assert_eq!(
        plan.buffer("globals").unwrap().elem_size,
        40,
        "P @0, top @8, scene @16..40"
    );
    // Both arms realizing Leaf slice `primitives`, so its length is the total of `data`.
    assert_eq!(
        plan.buffer("primitives").unwrap().count,
        Count::LogicalLength {
            field: "data".into(),
            variants: vec!["Leaf".into()],
            len_global: "P".into()
        }
    );
}

#[test]
fn derived_fields_have_an_evaluation_order() {
    let p = program(&[SG_EQ]);
    let m = model(&p, "SgEq");
    let mut r = Resolver::new(&m);
    let route = r.routes("Leaf").0[0].clone();
    let order = evaluation_order(&m, &route).expect("acyclic");
    let names: Vec<String> = order
        .iter()
        .map(|x| m.members[*x].kind.value_name().unwrap().name.clone())
        .collect();
    let pos = |n: &str| names.iter().position(|x| x == n).unwrap();
    assert!(
        pos("lo") < pos("bounds") && pos("hi") < pos("bounds"),
        "{names:?}"
    );
    assert!(pos("nprims") < pos("data"), "{names:?}");

    let cyclic = PBRT.replace("left = I + 1;", "left = I + k; k = left;");
    let p = program(&[&cyclic]);
    let decl = p.items.iter().find_map(|i| match i {
        Item::Layout(l) => Some(l),
        _ => None,
    });
    let m = LayoutModel::from_ast(decl.unwrap(), &p);
    let mut r = Resolver::new(&m);
    let route = r.routes("Interior").0[0].clone();
    let stuck = evaluation_order(&m, &route).unwrap_err();
    assert_eq!(stuck.len(), 2);
}

#[test]
fn case_study_layouts_have_catalog_sizes() {
    let p = program(&[SHARED_SLAB, DOP_SPLIT]);
    let slab = model(&p, "SharedSlab");
    assert_eq!(
        slab.reference.size, 28,
        "the reference carries the node's box"
    );
    assert_eq!(slab.node_bytes(), 16);
    assert_eq!(elem(&slab, "pl"), (0, 0));
    assert_eq!(elem(&slab, "pr"), (0, 4));
    assert_eq!(elem(&slab, "c_o"), (0, 8));
    assert_eq!(elem(&slab, "nprims"), (0, 12));
    assert_eq!(elem(&slab, "axis"), (0, 14));
    let dop = model(&p, "DopSplit");
    assert_eq!(
        dop.groups[0]
            .arrays
            .iter()
            .map(|a| a.stride)
            .collect::<Vec<_>>(),
        vec![32, 32]
    );
    assert_eq!(dop.adt.as_ref().unwrap().name, "DopBVH");
    match resolve_field(&dop, "Leaf", "bounds").unwrap() {
        FieldPath::Derived { deps, .. } => assert_eq!(deps.len(), 4),
        other => panic!("{other:?}"),
    }
}

#[test]
fn byte_map_of_pbrt() {
    let p = program(&[PBRT]);
    let m = model(&p, "LinearBVH");
    expect_test::expect![[r#"
        layout LinearBVH(I: u32): reference 4 B
        realizes BVH
        globals: 8 B, align 4
          @0     P: u32 (4 B)
          @4     N: u32 (4 B)
          array  primitives: Triangle[P] (40 B each)
        group nodes (direct)
          array 0: 30 B, align 32, stride 32
            @0     bounds: AABB (24 B)
            @24    split (4 B)
              > 0 -> Leaf
                @24    p_o: u32 (4 B)
                       data = ...
              0 -> Interior
                @24    c_o: u32 (4 B)
                       left = ...
                       right = ...
            @28    nprims: u16 (2 B)
    "#]]
    .assert_eq(&crate::layout::byte_map(&m));
}

#[test]
fn byte_map_of_soaos() {
    let p = program(&[PBRT_SOAOS]);
    let m = model(&p, "PbrtSoAoS");
    expect_test::expect![[r#"
        layout PbrtSoAoS(I: u32): reference 4 B
        realizes BVH
        globals: 8 B, align 4
          @0     P: u32 (4 B)
          @4     N: u32 (4 B)
          array  primitives: Triangle[P] (40 B each)
        group nodes (direct)
          array 0: 16 B, align 4, stride 16
            @0     low: f32x3 (12 B)
            @12    split (4 B)
              > 0 -> Leaf
                @12    p_o: u32 (4 B)
                       data = ...
              0 -> Interior
                @12    c_o: u32 (4 B)
                       left = ...
                       right = ...
          array 1: 16 B, align 4, stride 16
            @0     high: f32x3 (12 B)
            @12    nprims: u16 (2 B)
            @14    padding (2 B)
                   bounds = ...
    "#]]
    .assert_eq(&crate::layout::byte_map(&m));
}

fn member_text() -> impl proptest::strategy::Strategy<Value = String> {
    use proptest::prelude::*;
    prop_oneof![
        prop::sample::select(vec![
            "u8", "u16", "u32", "u64", "f32x3", "u16x3", "ptr", "AABB", "u8[5]"
        ])
        .prop_map(|t| format!("FIELD: {t};")),
        (1u64..9).prop_map(|n| format!("{n};")),
    ]
}

proptest::proptest! {
    /// Placement invariants on random groups: fields at their natural alignment, in textual
    /// order, never overlapping; the stride a multiple of the element alignment covering them.
    #[test]
    fn random_groups_are_placed_consistently(
        members in proptest::collection::vec(member_text(), 1..12),
        align in proptest::sample::select(vec![0u64, 1, 2, 4, 8, 16, 32]),
    ) {
        let mut body = String::new();
        for (i, m) in members.iter().enumerate() {
            body.push_str(&m.replace("FIELD", &format!("f{i}")));
            body.push(' ');
        }
        let attr = if align == 0 { String::new() } else { format!(", align={align}") };
        let src = format!("type T = One(x: u8);\nlayout L(I: u32) {{ N: u32; group g[size=N{attr}] by I {{ {body} }}; }};");
        let p = program(&[&src]);
        let m = model(&p, "L");
        let arr = m.groups[0].arrays[0];
        let mut end = 0;
        for info in &m.members {
            if let crate::layout::model::MemberModel::Stored(s) = &info.kind {
                if let Storage::Element { offset, .. } = s.storage {
                    proptest::prop_assert_eq!(offset % s.align, 0);
                    proptest::prop_assert!(offset >= end, "overlap at {}", s.name.name);
                    end = offset + s.size;
                }
            }
        }
        proptest::prop_assert!(arr.size >= end);
        proptest::prop_assert_eq!(arr.stride % arr.align, 0);
        proptest::prop_assert!(arr.stride >= arr.size && arr.stride < arr.size + arr.align);
        proptest::prop_assert!(arr.align >= align.max(1));
    }
}
