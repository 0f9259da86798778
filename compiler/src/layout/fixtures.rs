//! Test fixtures: layouts of docs/design/layout-catalog.md written in the layout language, faithfully to
//! the catalog's §8 sources (with `build root` as a top-level entry of the build, as
//! `docs/language.md` places it). Used by the tests of `layout` and of the checks.

/// The prelude's types (functions are skipped by the test parser).
pub const PRELUDE: &str = include_str!("../../../library/prelude.scion");
/// library/layouts/pbrt.scion.
pub const PBRT: &str = include_str!("../../../library/layouts/pbrt.scion");
/// library/layouts/ptr.scion.
pub const PTR: &str = include_str!("../../../library/layouts/ptr.scion");

/// library/layouts/pbrt_align16.scion (catalog §3.3).
pub const PBRT_ALIGN16: &str = include_str!("../../../library/layouts/pbrt_align16.scion");

/// library/layouts/pbrt_soaos.scion (catalog §3.4, §8.2): 16 + 16 with `---`.
pub const PBRT_SOAOS: &str = include_str!("../../../library/layouts/pbrt_soaos.scion");

/// library/layouts/pbrt_q16.scion (catalog §3.6, §8.3): 16 B.
pub const PBRT_Q16: &str = include_str!("../../../library/layouts/pbrt_q16.scion");

/// library/layouts/sg_eq.scion (catalog §3.8, §8.4): 12 B.
pub const SG_EQ: &str = include_str!("../../../library/layouts/sg_eq.scion");

/// The eight-wide ADT of catalog §2.1.
pub const BVH8_TYPE: &str = r#"
type BVH8 = Interior(child_bounds: AABB[8], children: BVH8[8])
          | Leaf(nprims: u16, data: Triangle[nprims]);
"#;

/// Catalog §4.3 / §8.5 (non-`ci` form): `bvh8-q8`, 136 B records in an indirect group.
pub const BVH8_Q8: &str = r#"
layout Bvh8Q8(R: u64) {
  P: u32; primitives: Triangle[P];
  top: u64; scene: AABB;
  indirect group nodes {
    child: u64[8];
    lower_x: u8[8]; upper_x: u8[8];
    lower_y: u8[8]; upper_y: u8[8];
    lower_z: u8[8]; upper_z: u8[8];
    start: f32x3;
    scale: f32x3;
    children = child;
    child_bounds = dequant8(lower_x, lower_y, lower_z, upper_x, upper_y, upper_z, start, scale);
  };
  split R {
    0xFFFF_FFFF_FFFF_FFFF -> Leaf { nprims = 0; data = primitives[0 : 0]; };
    < 0x1_0000_0000       -> Interior from nodes[R];
    _                     -> Leaf { nprims = R[32:64] as u16;
                                    data = primitives[R[0:32] : R[0:32] + nprims]; };
  };
};

build Bvh8Q8[order=pre] {
  build root { build scene = root_bounds(); build top = 0; };
  build Interior(child_bounds: AABB[8], children: BVH8[8]) {
    let f: Frame = frame8(child_bounds, 255);
    build start = f.origin; build scale = f.step;
    build lower_x = q8_lo(child_bounds, f, 0); build upper_x = q8_hi(child_bounds, f, 0);
    build lower_y = q8_lo(child_bounds, f, 1); build upper_y = q8_hi(child_bounds, f, 1);
    build lower_z = q8_lo(child_bounds, f, 2); build upper_z = q8_hi(child_bounds, f, 2);
    let C: u64[8] = build children;
    build child = C;
    return this;
  };
  build Leaf(nprims: u16, data: Triangle[nprims]) {
    let p: u64 = append(data, nprims);
    return ((nprims as u64) << 32) | p;
  };
};
"#;

/// `bvh8-q8-align16`: the indirect group padded explicitly (catalog §9 item 7), 144 B.
pub fn bvh8_q8_align16() -> String {
    BVH8_Q8
        .replace("scale: f32x3;\n", "scale: f32x3;\n    8;\n")
        .replace("Bvh8Q8", "Bvh8Q8A16")
}

/// Prelude plus the given sources, parsed by the project's parser; the fixture must parse
/// without diagnostics.
pub fn program(sources: &[&str]) -> crate::syntax::ast::Program {
    let (p, d, sm) = parse_with_errors(sources);
    assert!(d.is_empty(), "fixture does not parse:\n{}", d.render(&sm));
    p
}

/// Prelude plus the given sources as one file, parsed with error recovery: the (possibly
/// partial) program, the parser's diagnostics and the source map.
pub fn parse_with_errors(
    sources: &[&str],
) -> (
    crate::syntax::ast::Program,
    scion_ir::diag::Diagnostics,
    scion_ir::diag::SourceMap,
) {
    let mut text = String::from(PRELUDE);
    for s in sources {
        text.push('\n');
        text.push_str(s);
    }
    let mut sm = scion_ir::diag::SourceMap::new();
    let f = sm.add("fixture.scion", text);
    let (p, d) = crate::syntax::parse_program(&sm, &[f]);
    (p, d, sm)
}

/// Catalog §8.6: the shared slab (tree-carried box in a 28-byte reference), 16 B nodes.
pub const SHARED_SLAB: &str = r#"
layout SharedSlab(I: u32, lo: f32x3, hi: f32x3) {
  P: u32; N: u32; primitives: Triangle[P]; scene: AABB;
  group nodes[size=N, align=16] by I {
    bounds = AABB(lo, hi);
    split nprims {
      0   -> Interior { pl: f32; pr: f32;
                        left  = (I + 1,   lo, with_axis(hi, axis, pl));
                        right = (I + c_o, with_axis(lo, axis, pr), hi); };
      > 0 -> Leaf     { p_o: u32; 4; data = primitives[p_o : p_o + nprims]; };
    };
    c_o: u32; nprims: u16; axis: u8; 1;
  };
};
"#;

/// Catalog §8.6: DOP-14 split into a hot and a cold array (32 + 32 B). The catalog's `BVH`
/// over `DOP14` is renamed `DopBVH` so that it can sit beside the prelude's `BVH`.
pub const DOP_SPLIT: &str = r#"
type DopBVH(bounds: DOP14) = Interior(left: DopBVH, right: DopBVH) | Leaf(nprims: u16, data: Triangle[nprims]);
layout DopSplit(I: u32) {
  P: u32; N: u32; primitives: Triangle[P];
  group nodes[size=N, align=32] by I {
    lo1: f32x3; hi1: f32x3; c0: u32; c1: u32;
    split c1[31:32] {
      0 -> Interior { left = c0; right = c1; };
      1 -> Leaf     { nprims = c1[0:31] as u16; data = primitives[c0 : c0 + nprims]; };
    };
    ---
    lo2: f32x4; hi2: f32x4;
    bounds = DOP14(lo1, hi1, lo2, hi2);
  };
};
"#;
