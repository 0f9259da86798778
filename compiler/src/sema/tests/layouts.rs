//! Layout typing: scopes, member types, the realized ADT, physical-type preservation.

use super::{err, ok, structural};
use crate::sema::{MemberKindInfo, Prim, Ty};

const PBRT: &str = include_str!("../../../../library/layouts/pbrt.scion");
const PTR: &str = include_str!("../../../../library/layouts/ptr.scion");

fn member_ty(t: &crate::sema::TypedProgram, layout: &str, name: &str) -> Ty {
    let l = &t.layouts[t.layout_named(layout).unwrap().0 as usize];
    l.members
        .iter()
        .find(|m| m.name == name)
        .map(|m| m.ty.clone())
        .expect("member")
}

#[test]
fn pbrt_member_types() {
    let t = ok(PBRT);
    let l = &t.layouts[0];
    assert_eq!(l.ref_ty, Ty::Prim(Prim::U32));
    assert_eq!(l.adt, t.adts.by_name("BVH"));
    assert_eq!(member_ty(&t, "LinearBVH", "left"), Ty::Prim(Prim::U32));
    let tri = Ty::Adt(t.adts.by_name("Triangle").unwrap());
    assert_eq!(member_ty(&t, "LinearBVH", "data"), Ty::Slice(Box::new(tri)));
    let data = l.members.iter().find(|m| m.name == "data").unwrap();
    assert_eq!(data.kind, MemberKindInfo::Derived);
    // `data` sits in the Leaf arm.
    let leaf = t
        .adts
        .get(l.adt.unwrap())
        .unwrap()
        .variant_index("Leaf")
        .unwrap() as u32;
    assert_eq!(data.variant, Some(leaf));
    assert_eq!(l.arms.len(), 2);
    assert_eq!(l.arms[0].variant, Some(leaf));
}

const Q16: &str = "
layout PbrtQ16(I: u32) {
  P: u32; N: u32; primitives: Triangle[P];
  wlo: f32x3; wstep: f32x3;
  group nodes[size=N, align=16] by I {
    qlo: u16x3;
    qhi: u16x3;
    w: u32;
    bounds = AABB(fma(qlo as f32x3, wstep, wlo), fma(qhi as f32x3, wstep, wlo));
    split w[28:32] {
      0 -> Interior { c_o = w[0:28]; left = I + 1; right = I + c_o; };
      _ -> Leaf { nprims = w[28:32] as u16; p_o = w[0:28]; data = primitives[p_o : p_o + nprims]; };
    };
  };
};
";

#[test]
fn quantized_layout_types() {
    let t = ok(Q16);
    assert_eq!(
        member_ty(&t, "PbrtQ16", "bounds"),
        Ty::Adt(t.adts.by_name("AABB").unwrap())
    );
    assert_eq!(member_ty(&t, "PbrtQ16", "c_o"), Ty::Prim(Prim::U32));
    assert_eq!(member_ty(&t, "PbrtQ16", "nprims"), Ty::Prim(Prim::U16));
}

#[test]
fn soa_layout_with_separator() {
    ok("
layout PbrtSoAoS(I: u32) {
  P: u32; N: u32; primitives: Triangle[P];
  group nodes[size=N] by I {
    low: f32x3;
    split nprims {
      > 0 -> Leaf { p_o: u32; data = primitives[p_o : p_o + nprims]; };
      0 -> Interior { c_o: u32; left = I + 1; right = I + c_o; };
    };
    ---
    high: f32x3;
    nprims: u16;
    2;
    bounds = AABB(low, high);
  };
};");
}

#[test]
fn indirect_group_and_array_children() {
    let t = ok("
type BVH8 = Interior(child_bounds: AABB[8], children: BVH8[8]) | Leaf(nprims: u16, data: Triangle[nprims]);
func unpack(lo: f32x3, hi: f32x3) -> AABB[8] = { let b: AABB[8] = ubox(lo, hi); return b; }
func ubox(lo: f32x3, hi: f32x3) -> AABB[8] = ubox(hi, lo)
layout Bvh8(R: u32) {
  P: u32; primitives: Triangle[P];
  indirect group nodes {
    child: u32[8];
    start: f32x3;
    scale: f32x3;
    children = child;
    child_bounds = unpack(start, scale);
  };
  split R {
    0xFFFFFFFF -> Leaf { nprims = 0; data = primitives[0 : 0]; };
    < 0x10000000 -> Interior from nodes[R];
    _ -> Leaf { nprims = R[28:32] as u16; data = primitives[R[0:28] : R[0:28] + nprims]; };
  };
};");
    let l = &t.layouts[0];
    assert_eq!(l.adt, t.adts.by_name("BVH8"));
    assert!(l.arms[1].from_group.is_some());
}

#[test]
fn tuple_reference_and_parent() {
    let t = ok("
layout Slab(I: u32, lo: f32x3, hi: f32x3) {
  P: u32; N: u32; primitives: Triangle[P]; scene: AABB;
  group nodes[size=N, align=16] by I {
    bounds = AABB(lo, hi);
    split nprims {
      0 -> Interior { pl: f32; pr: f32;
                      left = (I + 1, lo, with_axis(hi, axis, pl));
                      right = (I + c_o, with_axis(lo, axis, pr), hi); };
      > 0 -> Leaf { p_o: u32; 4; data = primitives[p_o : p_o + nprims]; };
    };
    c_o: u32; nprims: u16; axis: u8; 1;
  };
};");
    let l = &t.layouts[0];
    assert_eq!(
        l.ref_ty,
        Ty::Tuple(vec![
            Ty::Prim(Prim::U32),
            Ty::Vector(Prim::F32, 3),
            Ty::Vector(Prim::F32, 3)
        ])
    );
    ok("
layout Carry(I: u32, b: AABB = parent.bounds) {
  N: u32;
  group nodes[size=N] by I {
    bounds: AABB;
    split nprims { 0 -> Interior { left = I + 1; right = I + 2; };
                   _ -> Leaf { data = primitives[0:0]; }; };
    nprims: u16;
  };
  P: u32; primitives: Triangle[P];
};");
}

#[test]
fn physical_types_preserve_logical_types() {
    // A stored field of the wrong type is `check_layout`'s E0327; a child stored in a
    // same-sized wrong type is caught here.
    let text = err(&PTR.replace("left: ptr;", "left: u64;"), "E0357");
    assert!(text.contains("`left`"), "{text}");
    ok(PTR);
    err(&PBRT.replace("left = I + 1;", "left = 1.0;"), "E0357");
    err(
        &PBRT.replace("data = primitives[p_o : p_o + nprims];", "data = p_o;"),
        "E0357",
    );
}

#[test]
fn layout_scope_errors() {
    err(
        &PBRT.replace("primitives: Triangle[P];", "primitives: Triangle[Q];"),
        "E0361",
    );
    // Names, members and variants that do not resolve are the layout checks' to report.
    structural(&PBRT.replace("left = I + 1;", "left = J + 1;"), "E0319");
    // Members of one split arm are not visible in another.
    structural(
        &PBRT.replace("right = I + c_o;", "right = I + p_o;"),
        "E0319",
    );
    structural(
        &PBRT.replace("bounds: AABB;", "bounds: AABB; bounds: AABB;"),
        "E0302",
    );
    structural(
        &PBRT.replace(
            "layout LinearBVH(I: u32) {",
            "layout LinearBVH(I: u32) { x = parent.y;",
        ),
        "E0310",
    );
}

#[test]
fn layout_expression_kinds() {
    // A discriminant whose type only inference finds is checked here; one whose type the
    // syntax shows, or one without a `_` arm, by the layout checks (E0320).
    err(
        &Q16.replace("split w[28:32]", "split wf")
            .replace("w: u32;", "w: u32; wf = 1.5;"),
        "E0353",
    );
    ok(&Q16
        .replace("split w[28:32]", "split wi")
        .replace("w: u32;", "w: u32; wi = w >> 28;"));
    structural(&PBRT.replace("split nprims", "split 1.0"), "E0320");
    err(&PBRT.replace("size=N", "size=1.5"), "E0354");
    err(&PBRT.replace("by I", "by 2.0"), "E0355");
    err(
        "layout L(I: u32) { indirect group nodes { x: u32; }; split I { 0 -> Interior from nodes[1.0]; _ -> Leaf { }; }; };",
        "E0359",
    );
}

#[test]
fn layout_adt_resolution() {
    structural(&PBRT.replace("> 0 -> Leaf", "> 0 -> Leef"), "E0311");
    structural(
        "type A = X(a: u32) | Y(b: u32);\ntype B = X(a: u32) | Y(b: u32);\nlayout L(I: u32) { split I { 0 -> X { a = I; }; _ -> Y { b = I; }; }; };",
        "E0311",
    );
    structural(
        "layout L(I: u32) { P: u32; primitives: Triangle[P]; split I { 0 -> Interior from nodes[I]; _ -> Leaf { nprims = 0; data = primitives[0:0]; }; }; };",
        "E0309",
    );
}

#[test]
fn named_members_numbers_like_member_ids() {
    let (program, typed, diags, _) = super::check_with_prelude(Q16);
    assert!(diags.is_empty());
    let Some(crate::syntax::ast::Item::Layout(decl)) = program.items.last() else {
        panic!()
    };
    let named = crate::sema::named_members(decl);
    let info = &typed.layouts[0];
    assert_eq!(named.len(), info.members.len());
    for (m, mi) in named.iter().zip(info.members.iter()) {
        assert!(
            m.span.start <= mi.span.start && mi.span.end <= m.span.end,
            "{}",
            mi.name
        );
    }
}

#[test]
fn member_types_choose_between_look_alike_types() {
    let t = ok("
type DopBVH(bounds: DOP14) = Interior(left: DopBVH, right: DopBVH) | Leaf(nprims: u16, data: Triangle[nprims]);
layout DopSplit(I: u32) {
  P: u32; N: u32; primitives: Triangle[P];
  group nodes[size=N, align=32] by I {
    lo1: f32x3; hi1: f32x3; c0: u32; c1: u32;
    split c1[31:32] {
      0 -> Interior { left = c0; right = c1; };
      1 -> Leaf { nprims = c1[0:31] as u16; data = primitives[c0 : c0 + nprims]; };
    };
    ---
    lo2: f32x4; hi2: f32x4;
    bounds = DOP14(lo1, hi1, lo2, hi2);
  };
};");
    assert_eq!(t.layouts[0].adt, t.adts.by_name("DopBVH"));
    assert!(t.layouts[0].arms.iter().all(|a| a.variant.is_some()));
    // Types that agree equally well stay ambiguous (the layout checks' E0311).
    let (_, t, _, _) = super::check_with_prelude(
        "type A = X(a: u32) | Y(b: u32);\ntype B = X(a: u32) | Y(b: u32);\nlayout L(I: u32) { split I { 0 -> X { a = I; }; _ -> Y { b = I; }; }; };",
    );
    assert_eq!(t.layouts[0].adt, None);
}
