//! Tests of destructor specialization on the layouts of the catalog (`layout::fixtures`) and on
//! small layouts written for one feature each: reads at resolved offsets, at-most-once
//! evaluation, split predicates, bit slices, `---` arrays, indirect groups, nested groups,
//! multi-component references, and the diagnostics for what is not supported.

use crate::driver::cli::Emit;
use crate::driver::session::PRELUDE;
use crate::frontend::{compile, Frontend, PassOptions};
use crate::layout::fixtures;
use scion_ir::diag::SourceMap;

/// `--emit=mem -O0 --layout layout` of the prelude plus `sources`: the IR text, or the rendered
/// diagnostics.
fn mem(sources: &[&str], layout: &str) -> Result<String, String> {
    let mut map = SourceMap::new();
    let prelude = map.add("prelude.scion", PRELUDE.to_string());
    let inputs: Vec<_> = sources
        .iter()
        .enumerate()
        .map(|(i, s)| map.add(format!("input{i}.scion"), s.to_string()))
        .collect();
    let fe = Frontend {
        sources: &map,
        prelude: &[prelude],
        inputs: &inputs,
    };
    let popts = PassOptions {
        layout: Some(layout.to_string()),
        ..PassOptions::default()
    };
    let r = compile(
        &fe,
        Emit::Mem,
        &["destructor-specialize".to_string()],
        &popts,
    );
    if let Some(ice) = r.internal_error {
        panic!("internal error: {ice}");
    }
    if r.diagnostics.has_errors() {
        return Err(r.diagnostics.render(&map));
    }
    Ok(r.output.expect("output"))
}

/// The text of function `@name` in `ir`.
fn func<'a>(ir: &'a str, name: &str) -> &'a str {
    let start = ir
        .find(&format!("func @{name}("))
        .unwrap_or_else(|| panic!("no @{name} in\n{ir}"));
    let rest = &ir[start..];
    let end = rest.find("\n}\n").map_or(rest.len(), |e| e + 3);
    &rest[..end]
}

fn count(hay: &str, needle: &str) -> usize {
    hay.matches(needle).count()
}

const COUNT: &str = r#"
func count(bvh: BVH) -> u32 =
  match bvh {
    | Interior(_, left, right) -> count(left) + count(right)
    | Leaf(_, nprims, _) -> nprims as u32
  }
"#;

const LEAF_FIRST: &str = r#"
func count(bvh: BVH) -> u32 =
  match bvh {
    | Leaf(_, nprims, _) -> nprims as u32
    | Interior(_, left, right) -> count(left) + count(right)
  }
"#;

const VISIT: &str = r#"
func visit(bvh: BVH, acc: mut u32) =
  match bvh {
    | Interior(bounds, left, right) -> {
      acc = acc + 1;
      visit(left, acc);
      visit(right, acc);
      visit(right, acc);
    }
    | Leaf(bounds, nprims, data) -> {
      acc = acc + (nprims as u32) + len(data);
      foreach t in data { acc = acc + t.id; }
    }
  }

func low_x(bvh: BVH) -> f32 = bvh.bounds.low.x
"#;

#[test]
fn pbrt_reads_each_field_once_per_destruction() {
    let ir = mem(&[VISIT, fixtures::PBRT], "LinearBVH").unwrap();
    let f = func(&ir, "visit");
    assert!(
        f.starts_with("func @visit(%0: ptr, %1: u32, %2: !tree.ref<u32>)"),
        "{f}"
    );
    // One nodes base, one nprims load (the test, reused by Leaf), one load at 24 per arm
    // (c_o for Interior, used twice through `right`; p_o for Leaf).
    assert_eq!(count(f, r#"name = "nodes""#), 1, "{f}");
    assert_eq!(
        count(f, "{offset = 28, stride = 32} : (ptr, u32) -> u16"),
        1,
        "{f}"
    );
    assert_eq!(
        count(f, "{offset = 24, stride = 32} : (ptr, u32) -> u32"),
        2,
        "{f}"
    );
    assert_eq!(count(f, r#""mem.view"("#), 1, "{f}");
    // `bounds` is bound but unused: never loaded.
    assert_eq!(count(f, "AABB"), 0, "{f}");
    assert_eq!(count(f, "callee = @visit"), 3, "{f}");
    assert_eq!(count(f, r#""tree.call"(%0, "#), 3, "{f}");
    // A shared field read outside a match.
    let g = func(&ir, "low_x");
    assert!(
        g.contains(
            r#""mem.load"(%2, %1) {offset = 0, stride = 32} : (ptr, u32) -> !tree.adt<"AABB">"#
        ),
        "{g}"
    );
}

/// A layout with a `u8` discriminant `k` and the given split arms.
fn split_layout(arms: &str) -> String {
    format!(
        r#"
layout S(I: u32) {{
  P: u32; N: u32; primitives: Triangle[P];
  group nodes[size=N] by I {{
    bounds: AABB;
    split k {{
{arms}
    }};
    k: u8;
  }};
}};
"#
    )
}

const INTERIOR: &str = "Interior { c_o: u32; left = I + 1; right = I + c_o; }";
const LEAF: &str = "Leaf { nprims: u16; p_o: u32; data = primitives[p_o : p_o + nprims]; }";

/// The variant test of the first arm of `count` under `arms` (the `tree.cmp`s and the ops that
/// combine them, in order).
fn test_of(arms: &str, algo: &str) -> Vec<String> {
    let ir = mem(&[algo, &split_layout(arms)], "S").unwrap_or_else(|e| panic!("{e}"));
    let f = func(&ir, "count");
    let head = &f[..f.find("\"tree.if\"").expect("an if chain")];
    head.lines()
        .filter(|l| {
            l.contains("tree.cmp")
                || l.contains("tree.or")
                || l.contains("tree.and")
                || l.contains("tree.const")
        })
        .map(|l| {
            let op = l.split('"').nth(1).unwrap_or("").to_string();
            let attr = l
                .split('{')
                .nth(1)
                .map(|a| a.split('}').next().unwrap_or("").to_string());
            format!("{op} {}", attr.unwrap_or_default())
        })
        .collect()
}

#[test]
fn split_predicates_take_what_earlier_arms_left() {
    // `> 0` then `0`: Interior is `k == 0`.
    let t = test_of(&format!("> 0 -> {LEAF}; 0 -> {INTERIOR};"), COUNT);
    assert_eq!(t, ["tree.const value = 0", "tree.cmp pred = \"eq\""]);
    // `0` then `_`: Leaf (tested first) is everything above 0 of the u8 domain.
    let t = test_of(&format!("0 -> {INTERIOR}; _ -> {LEAF};"), LEAF_FIRST);
    assert_eq!(t, ["tree.const value = 0", "tree.cmp pred = \"gt\""]);
    // `4` then `_`: Leaf is everything but 4.
    let t = test_of(&format!("4 -> {INTERIOR}; _ -> {LEAF};"), LEAF_FIRST);
    assert_eq!(t, ["tree.const value = 4", "tree.cmp pred = \"ne\""]);
    // `~ 0` then `_`: Interior is what `~ 0` left, `0`.
    let t = test_of(&format!("~ 0 -> {LEAF}; _ -> {INTERIOR};"), COUNT);
    assert_eq!(t, ["tree.const value = 0", "tree.cmp pred = \"eq\""]);
    // `< 4` then `>= 4`: Leaf is `k > 3`.
    let t = test_of(&format!("< 4 -> {INTERIOR}; >= 4 -> {LEAF};"), LEAF_FIRST);
    assert_eq!(t, ["tree.const value = 3", "tree.cmp pred = \"gt\""]);
    // A range left between two arms, and a variant realized by two arms (their disjunction).
    let arms = format!("< 2 -> {LEAF}; <= 5 -> {INTERIOR}; _ -> {LEAF};");
    // (Leaf's `nprims` is placed by two arms: a select on the second arm's test, emitted
    // after Interior's own test.)
    let t = test_of(&arms, COUNT);
    assert_eq!(
        t[..5],
        [
            "tree.const value = 2",
            "tree.const value = 5",
            "tree.cmp pred = \"ge\"",
            "tree.cmp pred = \"le\"",
            "tree.and ",
        ]
    );
    let t = test_of(&arms, LEAF_FIRST);
    assert_eq!(
        t,
        [
            "tree.const value = 1",
            "tree.cmp pred = \"le\"",
            "tree.const value = 5",
            "tree.cmp pred = \"gt\"",
            "tree.or ",
        ]
    );
}

#[test]
fn bit_slices_of_a_stored_word() {
    let ir = mem(&[COUNT, fixtures::PBRT_Q16], "PbrtQ16").unwrap_or_else(|e| panic!("{e}"));
    let f = func(&ir, "count");
    // `split w[28:32] { 0 -> Interior; _ -> Leaf }`: the domain is 0..=15.
    assert!(
        f.contains(r#""tree.bits"(%3) {hi = 32, lo = 28} : (u32) -> u32"#),
        "{f}"
    );
    assert!(f.contains(r#"{pred = "eq"}"#), "{f}");
    // Interior: `c_o = w[0:28]`, `right = I + c_o`.
    assert!(f.contains(r#"{hi = 28, lo = 0} : (u32) -> u32"#), "{f}");
    // Leaf: `nprims = w[28:32] as u16`, the same bits read once per arm.
    assert!(f.contains(r#"(u32) -> u16"#), "{f}");
}

#[test]
fn bit_slices_of_the_reference_and_indirect_groups() {
    let layout = r#"
layout Ind(R: u32) {
  P: u32; primitives: Triangle[P];
  indirect group inner { bounds: AABB; left: u32; right: u32; };
  indirect group leaves { bounds: AABB; p_o: u32; nprims: u16; data = primitives[p_o : p_o + nprims]; };
  split R[31:32] {
    0 -> Interior from inner[R];
    1 -> Leaf from leaves[R[0:31]];
  };
};
"#;
    let ir = mem(&[COUNT, layout], "Ind").unwrap_or_else(|e| panic!("{e}"));
    let f = func(&ir, "count");
    assert!(
        f.contains(r#""tree.bits"(%1) {hi = 32, lo = 31} : (u32) -> u32"#),
        "{f}"
    );
    assert!(f.contains(r#"{index = 2, name = "inner"}"#), "{f}");
    assert!(f.contains(r#"{index = 3, name = "leaves"}"#), "{f}");
    // Interior children at 24 and 28 of `inner[R]` (32-byte elements).
    assert!(
        f.contains(r#", %1) {offset = 24, stride = 32} : (ptr, u32) -> u32"#),
        "{f}"
    );
    assert!(
        f.contains(r#", %1) {offset = 28, stride = 32} : (ptr, u32) -> u32"#),
        "{f}"
    );
    // Leaf: `leaves[R[0:31]]`.
    assert!(f.contains(r#""tree.bits"(%1) {hi = 31, lo = 0}"#), "{f}");
}

#[test]
fn soa_arrays_read_from_their_own_buffers() {
    let algo = "func lo(bvh: BVH) -> f32 = bvh.bounds.high.x";
    let ir = mem(&[algo, fixtures::PBRT_SOAOS], "PbrtSoAoS").unwrap_or_else(|e| panic!("{e}"));
    let f = func(&ir, "lo");
    // `low` in part 0, `high` in part 1 (`---`), each its own buffer.
    assert_eq!(count(f, "mem.buffer"), 2, "{f}");
    assert!(
        f.contains(r#"name = "nodes#1""#) || f.contains(r#"name = "nodes""#),
        "{f}"
    );
    assert!(f.contains(r#""tree.ctor""#), "{f}");
}

#[test]
fn tuple_references_and_intrinsics() {
    let ir = mem(&[COUNT, fixtures::SHARED_SLAB], "SharedSlab").unwrap_or_else(|e| panic!("{e}"));
    let f = func(&ir, "count");
    assert!(
        f.starts_with("func @count(%0: ptr, %1: tuple<u32, vector<3xf32>, vector<3xf32>>)"),
        "{f}"
    );
    assert!(f.contains(r#"{name = "with_axis"}"#), "{f}");
    assert_eq!(count(f, "tree.extract"), 3, "{f}");
}

#[test]
fn nested_groups_read_tiles() {
    let layout = r#"
layout Nest(I: u32) {
  P: u32; N: u32; primitives: Triangle[P];
  group tiles[size=N] by I {
    group nodes[4] {
      bounds: AABB;
      split nprims {
        > 0 -> Leaf { p_o: u32; data = primitives[p_o : p_o + nprims]; };
        0 -> Interior { c_o: u32; left = I + 1; right = I + c_o; };
      };
      nprims: u16;
    };
  };
};
"#;
    let ir = mem(&[COUNT, layout], "Nest").unwrap_or_else(|e| panic!("{e}"));
    let f = func(&ir, "count");
    // Tile `I / 4` of the 128-byte `tiles` elements, slot `I % 4` of 32 bytes, computed once.
    assert_eq!(
        count(f, r#""mem.addr"(%5, %3) {offset = 0, stride = 128}"#),
        1,
        "{f}"
    );
    assert_eq!(count(f, r#""tree.div"(%1, %2)"#), 1, "{f}");
    assert_eq!(count(f, r#""tree.rem"(%1, %2)"#), 1, "{f}");
    assert!(
        f.contains(r#""mem.load"(%6, %4) {offset = 28, stride = 32} : (ptr, u32) -> u16"#),
        "{f}"
    );
    assert!(
        f.contains(r#""mem.load"(%6, %4) {offset = 24, stride = 32} : (ptr, u32) -> u32"#),
        "{f}"
    );
}

#[test]
fn unsupported_uses_are_diagnosed() {
    // Tree values built by the traversal.
    let build = r#"
func mk(bvh: BVH) -> BVH = bvh
"#;
    let e = mem(&[build, fixtures::PBRT], "LinearBVH").unwrap_err();
    assert!(e.contains("E0380"), "{e}");
    // Tree values put in a tuple.
    let tuple = r#"
func pair(bvh: BVH) -> u32 =
  match bvh {
    | Interior(_, left, right) -> { let p: (BVH, BVH) = (left, right); pair(p[1]) }
    | Leaf(_, _, _) -> 0
  }
"#;
    let e = mem(&[tuple, fixtures::PBRT], "LinearBVH").unwrap_err();
    assert!(
        e.contains("E0380") && e.contains("`tree.tuple` on a tree value"),
        "{e}"
    );
    // A layout that does not exist.
    let e = mem(&[COUNT, fixtures::PBRT], "Nope").unwrap_err();
    assert!(e.contains("E0908"), "{e}");
}

#[test]
fn parent_values_are_carried_or_diagnosed() {
    // `pb` carries the parent's derived `bounds`; `parent.hi` of a stored field adds a
    // component of its own.
    let layout = r#"
layout Par(I: u32, pb: AABB = parent.bounds) {
  P: u32; N: u32; primitives: Triangle[P];
  group nodes[size=N] by I {
    hi: f32x3;
    bounds = AABB(min(pb.low, parent.hi), hi);
    split nprims {
      > 0 -> Leaf { p_o: u32; data = primitives[p_o : p_o + nprims]; };
      0 -> Interior { c_o: u32; left = I + 1; right = I + c_o; };
    };
    nprims: u16;
  };
};
"#;
    let algo = "func lo(bvh: BVH) -> f32 = bvh.bounds.low.x";
    let out = mem(&[COUNT, algo, layout], "Par").unwrap();
    // The reference: the index, the parent's box and the parent's `hi`.
    assert!(
        out.contains("(u32, !tree.adt<\"AABB\">, vector<3xf32>)"),
        "{out}"
    );
    // The placed component cannot be carried.
    let first = layout.replace(
        "Par(I: u32, pb: AABB = parent.bounds)",
        "Par(I: u32 = parent.c_o)",
    );
    let e = mem(&[COUNT, &first], "Par").unwrap_err();
    assert!(
        e.contains("E0328") && e.contains("first reference component"),
        "{e}"
    );
    // A derived field is carried in a component of its checked type, declared by the
    // compiler; one of a type no component takes (a tuple) is E0328.
    let derived = layout
        .replace("Par(I: u32, pb: AABB = parent.bounds)", "Par(I: u32)")
        .replace("min(pb.low, parent.hi)", "parent.bounds.low");
    let out = mem(&[COUNT, algo, &derived], "Par").unwrap();
    assert!(
        out.contains("layout Par(I: u32, parent_bounds: AABB = parent.bounds)"),
        "{out}"
    );
    assert!(out.contains("(tuple<u32, !tree.adt<\"AABB\">>)"), "{out}");
    let tuple = derived
        .replace("hi: f32x3;", "hi: f32x3; pair = (hi, hi);")
        .replace("parent.bounds.low", "parent.pair[0]");
    let e = mem(&[COUNT, &tuple], "Par").unwrap_err();
    assert!(e.contains("E0328") && e.contains("`parent.pair`"), "{e}");
}

#[test]
fn every_catalog_layout_specializes_or_is_diagnosed() {
    let dop = COUNT.replace("BVH", "DopBVH");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec![COUNT, fixtures::PBRT], "LinearBVH"),
        (vec![COUNT, fixtures::PTR], "PtrBVH"),
        (vec![COUNT, fixtures::PBRT_ALIGN16], "PbrtAlign16"),
        (vec![COUNT, fixtures::PBRT_SOAOS], "PbrtSoAoS"),
        (vec![COUNT, fixtures::PBRT_Q16], "PbrtQ16"),
        (vec![COUNT, fixtures::SG_EQ], "SgEq"),
        (vec![COUNT, fixtures::SHARED_SLAB], "SharedSlab"),
        (vec![&dop, fixtures::DOP_SPLIT], "DopSplit"),
    ];
    for (sources, layout) in cases {
        let mut map = SourceMap::new();
        let prelude = map.add("prelude.scion", PRELUDE.to_string());
        let inputs: Vec<_> = sources
            .iter()
            .enumerate()
            .map(|(i, s)| map.add(format!("input{i}.scion"), s.to_string()))
            .collect();
        let fe = Frontend {
            sources: &map,
            prelude: &[prelude],
            inputs: &inputs,
        };
        let popts = PassOptions {
            layout: Some(layout.to_string()),
            ..PassOptions::default()
        };
        let pipeline = [
            "destructor-specialize",
            "constructor-specialize",
            "const-fold",
            "dce",
        ]
        .map(String::from);
        let r = compile(&fe, Emit::Mem, &pipeline, &popts);
        assert!(
            r.internal_error.is_none(),
            "{layout}: {:?}",
            r.internal_error
        );
        let text = r.diagnostics.render(&map);
        if r.diagnostics.has_errors() {
            assert!(text.contains("error[E0"), "{layout}: {text}");
        } else {
            let ir = r.output.expect("output");
            assert!(ir.contains("mem.load"), "{layout}: {ir}");
        }
    }
}
