//! The dump of a typed program (`dump_types`).

use super::check_files;
use crate::sema::dump_types;
use expect_test::expect;

#[test]
fn dump_of_closest_hit_and_pbrt() {
    let src = "
type AABB(low: f32x3, high: f32x3);
type Tri(p0: f32x3, id: u32);
type BVH(bounds: AABB) = Interior(left: BVH, right: BVH) | Leaf(nprims: u16, data: Tri[nprims]);
func hit(b: AABB) -> bool = b.low.x < b.high.x
func hit(t: Tri) -> bool = t.id > 0
func walk(bvh: BVH, best: mut u32) = match bvh {
  | Interior(bounds, left, right) -> if hit(bounds) { walk(left, best); walk(right, best); }
  | Leaf(_, n, data) -> foreach t in data { let ok = hit(t); if ok { best = t.id; } }
}
layout L(I: u32) {
  P: u32; N: u32; primitives: Tri[P];
  group nodes[size=N, align=32] by I {
    bounds: AABB;
    split nprims {
      > 0 -> Leaf { p_o: u32; data = primitives[p_o : p_o + nprims]; };
      0 -> Interior { c_o: u32; left = I + 1; right = I + c_o; };
    };
    nprims: u16;
  };
};
build L[order=pre] {
  build Interior(bounds: AABB, left: BVH, right: BVH) {
    build bounds; build nprims = 0; build left; let R: u32 = build right; build c_o = R - this; return this;
  };
  build Leaf(bounds: AABB, nprims: u16, data: Tri[nprims]) {
    build bounds; build nprims; build p_o = append(data, nprims); return this;
  };
};
";
    let (program, typed, diags, sm) = check_files(&[("t.scion", src)]);
    assert!(diags.is_empty(), "{}", diags.render(&sm));
    expect![[r#"
        type AABB(low: f32x3, high: f32x3)
        type Tri(p0: f32x3, id: u32)
        type BVH(bounds: AABB) = Interior(left: BVH, right: BVH) | Leaf(nprims: u16, data: Tri[nprims])
        func hit(b: AABB) -> bool  [hit]
        func hit(t: Tri) -> bool  [hit.1]
        func walk(bvh: BVH, best: mut u32) -> ()  [walk]
          | Interior(bounds: AABB, left: BVH, right: BVH)
          | Leaf(n: u16, data: Tri[..])
            foreach t: Tri
              let ok: bool
        layout L realizes BVH, reference u32
          P: u32 (stored)
          N: u32 (stored)
          primitives: Tri[..] (stored)
          group nodes
            bounds: AABB (stored)
            p_o: u32 (stored in Leaf)
            data: Tri[..] (derived in Leaf)
            c_o: u32 (stored in Interior)
            left: u32 (derived in Interior)
            right: u32 (derived in Interior)
            nprims: u16 (stored)
        build L
          Interior(bounds: AABB, left: BVH, right: BVH)
          Leaf(bounds: AABB, nprims: u16, data: Tri[..])
    "#]].assert_eq(&dump_types(&program, &typed));
}
