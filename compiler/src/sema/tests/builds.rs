//! Build typing: parameters against the variant, targets, `this`, `build x`, `append`.

use super::{err, ok, structural};
use crate::sema::{Prim, Resolution, Ty};
use crate::syntax::ast::{ExprKind, Item, StmtKind};

const PBRT: &str = include_str!("../../../../library/layouts/pbrt.scion");
const PTR: &str = include_str!("../../../../library/layouts/ptr.scion");

#[test]
fn library_builds_type_check() {
    let t = ok(PBRT);
    assert_eq!(t.builds.len(), 1);
    assert_eq!(t.builds[0].variants.len(), 2);
    assert!(!t.build_targets.is_empty());
    ok(PTR);
}

#[test]
fn build_expression_yields_the_reference_type() {
    let (program, typed, diags, sm) = super::check_with_prelude(PBRT);
    assert!(diags.is_empty(), "{}", diags.render(&sm));
    let Some(Item::Build(b)) = program.items.last() else {
        panic!()
    };
    let body = &b.variants[0].body;
    let StmtKind::Let { value, .. } = &body[3].kind else {
        panic!("{:?}", body[3].kind)
    };
    assert!(matches!(value.kind, ExprKind::Build(_)));
    assert_eq!(typed.expr_ty(value.id), &Ty::Prim(Prim::U32));
    assert!(matches!(
        typed.resolution(value.id),
        Some(Resolution::BuildChild(_))
    ));
    // `build left;` is a recursive field: it builds the child.
    let target = typed.build_targets.get(&body[2].id).unwrap();
    assert!(target.child);
    // `build bounds;` copies into the stored field.
    let target = typed.build_targets.get(&body[0].id).unwrap();
    assert!(target.member.is_some() && !target.child);
}

#[test]
fn build_parameters_must_match_the_variant() {
    err(
        &PBRT.replace(
            "build Leaf(bounds: AABB, nprims: u16, data: Triangle[nprims])",
            "build Leaf(bounds: AABB, nprims: u16)",
        ),
        "E0452",
    );
    // A field out of its place is reported here; a name that is no field, by the build checks.
    err(
        &PBRT.replace(
            "build Leaf(bounds: AABB, nprims: u16, data: Triangle[nprims])",
            "build Leaf(bounds: AABB, data: Triangle[nprims], nprims: u16)",
        ),
        "E0453",
    );
    structural(
        &PBRT.replace(
            "build Leaf(bounds: AABB, nprims: u16, data: Triangle[nprims])",
            "build Leaf(bounds: AABB, count: u16, data: Triangle[count])",
        ),
        "E0415",
    );
    err(
        &PBRT.replace(
            "build Leaf(bounds: AABB, nprims: u16,",
            "build Leaf(bounds: AABB, nprims: u32,",
        ),
        "E0454",
    );
    structural(&PBRT.replace("build Leaf(", "build Leef("), "E0403");
    structural(&PBRT.replace("build LinearBVH[", "build Nope["), "E0401");
}

#[test]
fn build_targets_and_values() {
    err(
        &PBRT.replace("build nprims = 0;", "build nprims = 70000;"),
        "E0457",
    );
    err(
        &PBRT.replace("build nprims = 0;", "build nprims = 1.5;"),
        "E0456",
    );
    err(
        &PBRT.replace(
            "return this;\n  };\n  build Leaf",
            "return 1.5;\n  };\n  build Leaf",
        ),
        "E0461",
    );
    // The literal that does not fit is reported once.
    let (_, _, diags, _) =
        super::check_with_prelude(&PBRT.replace("build nprims = 0;", "build nprims = 70000;"));
    assert_eq!(diags.len(), 1);
    // Targets, children, appends and duplicate entries are the build checks' to report.
    structural(
        &PBRT.replace("build nprims = 0;", "build nope = 0;"),
        "E0406",
    );
    structural(
        &PBRT.replace(
            "build c_o = R - this;",
            "build c_o = R - this; build p_o = 1;",
        ),
        "E0406",
    );
    structural(
        &PBRT.replace("let R: u32 = build right;", "let R: u32 = build bounds;"),
        "E0410",
    );
    structural(
        &PBRT.replace(
            "build p_o = append(data, nprims);",
            "build p_o = append(bounds, nprims);",
        ),
        "E0412",
    );
    structural(
        &PBRT.replace(
            "build Leaf(",
            "build Interior(bounds: AABB, left: BVH, right: BVH) { return this; };\n  build Leaf(",
        ),
        "E0404",
    );
    structural(
        &PBRT.replace(
            "build bounds;\n    build nprims;",
            "build nothing;\n    build nprims;",
        ),
        "E0406",
    );
}

#[test]
fn build_copies_are_the_build_checks_to_reject() {
    // A copy into a stored field of another type is the layout checks' E0327 (on every
    // variant's route), a copy of a field the variant lacks is E0417.
    structural(
        "
type S(b: u32) = A(k: u16) | B(k: u32);
layout L(I: u32) { N: u32; group g[size=N] by I { b: u32; k: u16; split I[0:1] { 0 -> A { }; _ -> B { }; }; }; };
build L {
  build A(b: u32, k: u16) { build b; build k; return this; };
  build B(b: u32, k: u32) { build b; build k; return this; };
};",
        "E0327",
    );
    structural(
        &PBRT.replace("build c_o = R - this;", "build c_o;"),
        "E0417",
    );
}

#[test]
fn build_root_sees_globals_and_shared_fields() {
    let t = ok("
layout G(I: u32) {
  P: u32; N: u32; primitives: Triangle[P]; scene: AABB;
  group nodes[size=N] by I {
    bounds: AABB;
    split nprims { > 0 -> Leaf { p_o: u32; data = primitives[p_o : p_o + nprims]; };
                   0 -> Interior { c_o: u32; left = I + 1; right = I + c_o; }; };
    nprims: u16;
  };
};
build G[order=pre] {
  build root { build scene = bounds; };
  build Interior(bounds: AABB, left: BVH, right: BVH) {
    build bounds; build nprims = 0; build left; let R: u32 = build right; build c_o = R - this; return this;
  };
  build Leaf(bounds: AABB, nprims: u16, data: Triangle[nprims]) {
    build bounds; build nprims; build p_o = append(data, nprims);
    let wide: u64 = append(data, nprims);
    let narrow = append(data, 1);
    this[0:4] = 1;
    return this;
  };
};");
    let ty = |n: &str| {
        t.bindings
            .iter()
            .find(|b| b.name == n)
            .map(|b| b.ty.clone())
    };
    assert_eq!(ty("wide"), Some(Ty::Prim(Prim::U64)));
    assert_eq!(ty("narrow"), Some(Ty::Prim(Prim::U32)));
}

#[test]
fn array_of_children_builds_to_array_of_references() {
    ok("
type BVH8 = Interior(child_bounds: AABB[8], children: BVH8[8]) | Leaf(nprims: u16, data: Triangle[nprims]);
func lows(b: AABB[8]) -> f32x3 = b[0].low
layout Bvh8(R: u32) {
  P: u32; primitives: Triangle[P]; top: u32;
  indirect group nodes { child: u32[8]; start: f32x3; children = child; child_bounds = boxes(start); };
  split R {
    < 0x10000000 -> Interior from nodes[R];
    _ -> Leaf { nprims = R[28:32] as u16; data = primitives[R[0:28] : R[0:28] + nprims]; };
  };
};
func boxes(s: f32x3) -> AABB[8] = boxes(s)
build Bvh8[order=pre] {
  build root { build top = 0; };
  build Interior(child_bounds: AABB[8], children: BVH8[8]) {
    build start = lows(child_bounds);
    let C: u32[8] = build children;
    build child = C;
    return this;
  };
  build Leaf(nprims: u16, data: Triangle[nprims]) {
    let p: u32 = append(data, nprims);
    return ((nprims as u32) << 28) | p;
  };
};");
}
