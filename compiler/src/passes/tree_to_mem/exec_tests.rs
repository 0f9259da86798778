//! Executable checks of both specializations: the generated `@L.sizes` and `@L.build` pack a
//! logical tree (built here as the C-ABI bytes of `docs/design/specialization.md` §3.1) in the
//! interpreter's byte memory, the packed bytes are checked, and the specialized closest-hit run
//! on them must give bit for bit the result of the tree-level closest-hit on ADT values.

use crate::driver::cli::Emit;
use crate::driver::session::PRELUDE;
use crate::frontend::{compile, Frontend, PassOptions};
use scion_ir::diag::{FileId, SourceMap};
use scion_ir::interp::{AdtVal, Interp, Val};
use scion_ir::types::IntTy;
use scion_ir::Module;
use scion_runtime::bvh::schema::{binary_bvh, LogicalBytes, Schema};
use std::rc::Rc;

const CLOSEST_HIT: &str = include_str!("../../../../library/algorithms/closest_hit.scion");
const PBRT: &str = include_str!("../../../../library/layouts/pbrt.scion");
const PTR: &str = include_str!("../../../../library/layouts/ptr.scion");

/// The module of `emit` for closest-hit over `layout_src`, read back from its text form.
fn module(layout_src: &str, layout: Option<&str>) -> Module {
    module_and_schema(layout_src, layout).0
}

/// [`module`] and the schema of the logical tree the layout's constructor reads.
fn module_and_schema(layout_src: &str, layout: Option<&str>) -> (Module, Option<Schema>) {
    let mut map = SourceMap::new();
    let prelude = map.add("prelude.scion", PRELUDE.to_string());
    let a = map.add("closest_hit.scion", CLOSEST_HIT.to_string());
    let l = map.add("layout.scion", layout_src.to_string());
    let inputs = [a, l];
    let fe = Frontend {
        sources: &map,
        prelude: &[prelude],
        inputs: &inputs,
    };
    let (emit, pipeline) = match layout {
        Some(_) => (
            Emit::Mem,
            vec![
                "destructor-specialize".to_string(),
                "constructor-specialize".to_string(),
            ],
        ),
        None => (Emit::Tree, vec![]),
    };
    let popts = PassOptions {
        layout: layout.map(String::from),
        ..PassOptions::default()
    };
    let r = compile(&fe, emit, &pipeline, &popts);
    assert!(r.internal_error.is_none(), "{:?}", r.internal_error);
    assert!(
        !r.diagnostics.has_errors(),
        "{}",
        r.diagnostics.render(&map)
    );
    let text = r.output.expect("output");
    let m = scion_ir::parse_module(&text, FileId(0)).unwrap_or_else(|e| panic!("{e:?}\n{text}"));
    (m, r.logical)
}

#[derive(Clone)]
struct Tri {
    p: [[f32; 3]; 3],
    id: u32,
}

struct LNode {
    kind: u32,
    bounds: [f32; 6],
    child: [u32; 2],
    prim_offset: u32,
    prim_count: u32,
}

/// A deterministic scene and a logical BVH over it whose node order is *not* pre-order (children
/// are pushed before their parent), so the packer must reorder.
fn scene() -> (Vec<LNode>, u32, Vec<Tri>) {
    let mut seed = 12345u32;
    let mut rnd = move || {
        seed = seed.wrapping_mul(1_103_515_245).wrapping_add(12345);
        (seed >> 8) as f32 / (1u32 << 24) as f32
    };
    let mut tris: Vec<Tri> = (0..13)
        .map(|i| {
            let c = [rnd() * 4.0, rnd() * 4.0, rnd() * 4.0];
            let mut p = [[0.0; 3]; 3];
            for v in &mut p {
                for k in 0..3 {
                    v[k] = c[k] + rnd() * 0.8 - 0.4;
                }
            }
            Tri { p, id: 100 + i }
        })
        .collect();
    let mut nodes = Vec::new();
    let mut prims = Vec::new();
    fn bounds(ts: &[Tri]) -> [f32; 6] {
        let mut b = [
            f32::INFINITY,
            f32::INFINITY,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NEG_INFINITY,
            f32::NEG_INFINITY,
        ];
        for t in ts {
            for v in &t.p {
                for k in 0..3 {
                    b[k] = b[k].min(v[k]);
                    b[3 + k] = b[3 + k].max(v[k]);
                }
            }
        }
        b
    }
    fn build(ts: &mut [Tri], axis: usize, nodes: &mut Vec<LNode>, prims: &mut Vec<Tri>) -> u32 {
        let b = bounds(ts);
        if ts.len() <= 2 {
            let off = prims.len() as u32;
            prims.extend(ts.iter().cloned());
            nodes.push(LNode {
                kind: 1,
                bounds: b,
                child: [0, 0],
                prim_offset: off,
                prim_count: ts.len() as u32,
            });
            return nodes.len() as u32 - 1;
        }
        ts.sort_by(|x, y| x.p[0][axis].total_cmp(&y.p[0][axis]));
        let mid = ts.len() / 2;
        let (l, r) = ts.split_at_mut(mid);
        let li = build(l, (axis + 1) % 3, nodes, prims);
        let ri = build(r, (axis + 1) % 3, nodes, prims);
        nodes.push(LNode {
            kind: 0,
            bounds: b,
            child: [li, ri],
            prim_offset: 0,
            prim_count: 0,
        });
        nodes.len() as u32 - 1
    }
    let root = build(&mut tris, 0, &mut nodes, &mut prims);
    (nodes, root, prims)
}

fn vec3(v: [f32; 3]) -> Val {
    Val::Vector(v.iter().map(|&x| Val::F32(x)).collect())
}

fn adt(ty: &str, variant: Option<usize>, fields: Vec<Val>) -> Val {
    Val::Adt(Rc::new(AdtVal {
        ty: ty.into(),
        variant,
        fields,
    }))
}

fn aabb(b: &[f32; 6]) -> Val {
    adt(
        "AABB",
        None,
        vec![vec3([b[0], b[1], b[2]]), vec3([b[3], b[4], b[5]])],
    )
}

fn tri(t: &Tri) -> Val {
    adt(
        "Triangle",
        None,
        vec![
            vec3(t.p[0]),
            vec3(t.p[1]),
            vec3(t.p[2]),
            Val::Int(t.id as i128, IntTy::U32),
        ],
    )
}

/// The logical tree as a value of the prelude's `BVH` (Interior = variant 0, Leaf = 1).
fn value(nodes: &[LNode], i: u32, prims: &[Tri]) -> Val {
    let n = &nodes[i as usize];
    if n.kind == 0 {
        adt(
            "BVH",
            Some(0),
            vec![
                aabb(&n.bounds),
                value(nodes, n.child[0], prims),
                value(nodes, n.child[1], prims),
            ],
        )
    } else {
        let data = prims[n.prim_offset as usize..(n.prim_offset + n.prim_count) as usize]
            .iter()
            .map(tri)
            .collect();
        adt(
            "BVH",
            Some(1),
            vec![
                aabb(&n.bounds),
                Val::Int(n.prim_count as i128, IntTy::U16),
                Val::Array(Rc::new(data)),
            ],
        )
    }
}

/// The C-ABI bytes of the logical tree in `it`'s memory, its nodes in the shape of the
/// prelude's `BVH` (the runtime's fill); returns the `LogicalTreeView` address.
fn put_tree(it: &mut Interp<'_>, nodes: &[LNode], root: u32, prims: &[Tri]) -> u64 {
    put_tree_as(it, nodes, root, prims, &binary_bvh())
}

/// [`put_tree`] with the nodes in `schema`'s shape.
fn put_tree_as(
    it: &mut Interp<'_>,
    nodes: &[LNode],
    root: u32,
    prims: &[Tri],
    schema: &Schema,
) -> u64 {
    let tree: scion_runtime::bvh::LogicalTree = scion_runtime::bvh::LogicalTree {
        nodes: nodes
            .iter()
            .map(|n| scion_runtime::bvh::LogicalNode {
                kind: n.kind,
                bounds: n.bounds,
                child: n.child,
                prim_offset: n.prim_offset,
                prim_count: n.prim_count,
            })
            .collect(),
        root,
        primitives: Vec::new(),
    };
    let filled = LogicalBytes::fill(&tree, schema).expect("the runtime fills the schema");
    let nb = filled.nodes().to_vec();
    let mut pb = Vec::new();
    for t in prims {
        for v in t.p {
            for x in v {
                pb.extend(x.to_le_bytes());
            }
        }
        pb.extend(t.id.to_le_bytes());
    }
    let na = it.alloc_bytes(&nb, 4);
    let pa = it.alloc_bytes(&pb, 4);
    let mut h = Vec::new();
    h.extend(na.to_le_bytes());
    h.extend((filled.node_count as u32).to_le_bytes());
    h.extend(filled.root.to_le_bytes());
    h.extend(pa.to_le_bytes());
    h.extend((prims.len() as u32).to_le_bytes());
    h.extend(0u32.to_le_bytes());
    it.alloc_bytes(&h, 8)
}

fn u64_of(v: &Val) -> u64 {
    match v {
        Val::Int(x, _) => *x as u64,
        other => panic!("not an integer: {other}"),
    }
}

fn u32_at(it: &Interp<'_>, addr: u64) -> u32 {
    u32::from_le_bytes(
        it.bytes(addr, 4)
            .expect("in memory")
            .try_into()
            .expect("4 bytes"),
    )
}

/// Packs the scene with `@L.sizes` / `@L.build`; returns `%B` and the buffer addresses.
fn pack(it: &mut Interp<'_>, layout: &str, nbuf: usize, tree: u64) -> (u64, Vec<u64>) {
    let sizes = it.alloc_bytes(&vec![0u8; 8 * nbuf], 8);
    let ptr = |a: u64| Val::Int(a as i128, IntTy::U64);
    it.call(&format!("{layout}.sizes"), vec![ptr(tree), ptr(sizes)])
        .expect("sizes runs");
    let mut bufs = Vec::new();
    for i in 0..nbuf {
        let n = u64::from_le_bytes(
            it.bytes(sizes + 8 * i as u64, 8)
                .unwrap()
                .try_into()
                .unwrap(),
        );
        bufs.push(it.alloc_bytes(&vec![0u8; n as usize], 64));
    }
    let table: Vec<u8> = bufs.iter().flat_map(|a| a.to_le_bytes()).collect();
    let b = it.alloc_bytes(&table, 8);
    let status = it
        .call(&format!("{layout}.build"), vec![ptr(tree), ptr(b)])
        .expect("build runs");
    assert_eq!(u64_of(&status[0]), 0, "build status");
    (b, bufs)
}

fn rays() -> Vec<Val> {
    let mut out = Vec::new();
    for i in 0..24 {
        let f = i as f32;
        let o = [-3.0 + (f * 0.37) % 2.0, -2.0 + (f * 0.53) % 3.0, -4.0];
        let target = [(f * 0.61) % 4.0, (f * 0.29) % 4.0, 2.0];
        let d = [target[0] - o[0], target[1] - o[1], target[2] - o[2]];
        out.push(adt(
            "Ray",
            None,
            vec![vec3(o), vec3(d), Val::F32(0.0), Val::F32(f32::INFINITY)],
        ));
    }
    out
}

/// Rays from outside the scene at each triangle's centroid (each hits something).
fn rays_at(prims: &[Tri]) -> Vec<Val> {
    prims
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let c = [0, 1, 2].map(|k| (t.p[0][k] + t.p[1][k] + t.p[2][k]) / 3.0);
            let o = [-2.0 + i as f32 * 0.1, 6.0, -3.0 + i as f32 * 0.05];
            let d = [c[0] - o[0], c[1] - o[1], c[2] - o[2]];
            adt(
                "Ray",
                None,
                vec![vec3(o), vec3(d), Val::F32(0.0), Val::F32(f32::INFINITY)],
            )
        })
        .collect()
}

/// `entry(B, ray, root, best)` for each ray, `best` starting at `(inf, u32::MAX)`.
fn closest_hits(
    it: &mut Interp<'_>,
    entry: &str,
    b: u64,
    root: Val,
    rays: Vec<Val>,
) -> Vec<(u32, u32)> {
    rays.into_iter()
        .map(|ray| {
            let cell = it.alloc(Val::Tuple(vec![
                Val::F32(f32::INFINITY),
                Val::Int(0xFFFF_FFFF, IntTy::U32),
            ]));
            let bv = Val::Int(b as i128, IntTy::U64);
            best_of(it, entry, vec![bv, ray, root.clone()], cell)
        })
        .collect()
}

fn best_of(it: &mut Interp<'_>, name: &str, args: Vec<Val>, cell: Val) -> (u32, u32) {
    let mut all = args;
    all.push(cell.clone());
    it.call(name, all).unwrap_or_else(|e| panic!("{name}: {e}"));
    match it.read(&cell) {
        Some(Val::Tuple(t)) => match (&t[0], &t[1]) {
            (Val::F32(d), Val::Int(id, _)) => (d.to_bits(), *id as u32),
            other => panic!("bad best {other:?}"),
        },
        other => panic!("bad cell {other:?}"),
    }
}

/// Closest hit of every ray on the tree level (ADT values).
fn reference(nodes: &[LNode], root: u32, prims: &[Tri]) -> Vec<(u32, u32)> {
    reference_for(nodes, root, prims, &rays())
}

/// Closest hits of `rays` at the tree level (the binary tree as an algebraic value).
fn reference_for(nodes: &[LNode], root: u32, prims: &[Tri], rays: &[Val]) -> Vec<(u32, u32)> {
    let m = module(PBRT, None);
    let mut it = Interp::new(&m);
    let bvh = value(nodes, root, prims);
    rays.iter()
        .cloned()
        .map(|ray| {
            let cell = it.alloc(Val::Tuple(vec![
                Val::F32(f32::INFINITY),
                Val::Int(0xFFFF_FFFF, IntTy::U32),
            ]));
            best_of(&mut it, "closest_hit", vec![ray, bvh.clone()], cell)
        })
        .collect()
}

#[test]
fn pbrt_packs_and_traverses_like_the_tree_level() {
    let (nodes, root, prims) = scene();
    let want = reference(&nodes, root, prims.as_slice());
    assert!(want.iter().any(|&(_, id)| id != u32::MAX), "some ray hits");
    assert!(
        want.iter().any(|&(_, id)| id == u32::MAX),
        "some ray misses"
    );
    let m = module(PBRT, Some("LinearBVH"));
    let mut it = Interp::new(&m);
    let tree = put_tree(&mut it, &nodes, root, &prims);
    let (b, bufs) = pack(&mut it, "LinearBVH", 3, tree);
    // Globals: P then N; nodes are 32 bytes, pre-order: the root's left child is node 1 and
    // its right child `c_o` nodes further; leaves' `p_o` ranges tile the primitives.
    assert_eq!(u32_at(&it, bufs[0]), prims.len() as u32);
    assert_eq!(u32_at(&it, bufs[0] + 4), nodes.len() as u32);
    let node = |i: u32| bufs[2] + 32 * i as u64;
    let nprims = |it: &Interp<'_>, i: u32| u32_at(it, node(i) + 28) & 0xFFFF;
    let mut next_prim = 0;
    let mut stack = vec![0u32];
    let mut visited = 0;
    while let Some(i) = stack.pop() {
        visited += 1;
        let n = nprims(&it, i);
        if n == 0 {
            let c_o = u32_at(&it, node(i) + 24);
            assert!(c_o > 1, "right child after the left subtree");
            stack.push(i + c_o);
            stack.push(i + 1);
        } else {
            assert_eq!(u32_at(&it, node(i) + 24), next_prim, "p_o of node {i}");
            next_prim += n;
        }
    }
    assert_eq!(visited, nodes.len());
    assert_eq!(next_prim as usize, prims.len());
    let got = closest_hits(&mut it, "closest_hit", b, Val::Int(0, IntTy::U32), rays());
    assert_eq!(got, want);
}

#[test]
fn ptr_packs_and_traverses_like_the_tree_level() {
    let (nodes, root, prims) = scene();
    let want = reference(&nodes, root, prims.as_slice());
    let m = module(PTR, Some("PtrBVH"));
    let mut it = Interp::new(&m);
    let tree = put_tree(&mut it, &nodes, root, &prims);
    let (b, bufs) = pack(&mut it, "PtrBVH", 3, tree);
    // 48-byte nodes; the root's children are absolute addresses into the nodes buffer.
    let left = u64::from_le_bytes(it.bytes(bufs[2] + 24, 8).unwrap().try_into().unwrap());
    let right = u64::from_le_bytes(it.bytes(bufs[2] + 32, 8).unwrap().try_into().unwrap());
    assert_eq!(left, bufs[2] + 48);
    assert!(right > left && (right - bufs[2]) % 48 == 0);
    let got: Vec<(u32, u32)> = rays()
        .into_iter()
        .map(|ray| {
            let cell = it.alloc(Val::Tuple(vec![
                Val::F32(f32::INFINITY),
                Val::Int(0xFFFF_FFFF, IntTy::U32),
            ]));
            let bv = Val::Int(b as i128, IntTy::U64);
            let r = Val::Int(bufs[2] as i128, IntTy::U64);
            best_of(&mut it, "closest_hit", vec![bv, ray, r], cell)
        })
        .collect();
    assert_eq!(got, want);
}

/// The status of `@LinearBVH.build` for pbrt with `stmt` added to the leaf build.
fn status_with(stmt: &str) -> i128 {
    let src = PBRT.replace(
        "build p_o = append(data, nprims);",
        &format!("build p_o = append(data, nprims);\n    {stmt}"),
    );
    assert_ne!(src, PBRT);
    let m = module(&src, Some("LinearBVH"));
    let (nodes, root, prims) = scene();
    let mut it = Interp::new(&m);
    let tree = put_tree(&mut it, &nodes, root, &prims);
    let sizes = it.alloc_bytes(&[0u8; 24], 8);
    let ptr = |a: u64| Val::Int(a as i128, IntTy::U64);
    it.call("LinearBVH.sizes", vec![ptr(tree), ptr(sizes)])
        .expect("sizes runs");
    let mut table = Vec::new();
    for i in 0..3u64 {
        let n = u64::from_le_bytes(it.bytes(sizes + 8 * i, 8).unwrap().try_into().unwrap());
        table.extend(it.alloc_bytes(&vec![0u8; n as usize], 64).to_le_bytes());
    }
    let b = it.alloc_bytes(&table, 8);
    match &it
        .call("LinearBVH.build", vec![ptr(tree), ptr(b)])
        .expect("build runs")[0]
    {
        Val::Int(s, _) => *s,
        other => panic!("status {other}"),
    }
}

#[test]
fn bit_slice_stores_report_values_that_do_not_fit() {
    // Leaves hold one or two triangles: `nprims - 1` fits in one bit, `nprims` does not.
    assert_eq!(status_with("this[31:32] = (nprims as u32) - 1;"), 0);
    assert_eq!(status_with("this[31:32] = nprims as u32;"), 1);
}

/// Packs the scene into `layout` (declared in `src`, `nbuf` buffers) and checks closest hit
/// over the packed buffers against the tree level.
fn packs_and_traverses_like_the_tree_level(src: &str, layout: &str, nbuf: usize) {
    let (nodes, root, prims) = scene();
    let want = reference(&nodes, root, prims.as_slice());
    let m = module(src, Some(layout));
    let mut it = Interp::new(&m);
    let tree = put_tree(&mut it, &nodes, root, &prims);
    let (b, _) = pack(&mut it, layout, nbuf, tree);
    let got = closest_hits(&mut it, "closest_hit", b, Val::Int(0, IntTy::U32), rays());
    assert_eq!(got, want);
}

#[test]
fn soa_layout_packs_and_traverses_like_the_tree_level() {
    // `pbrt-soaos`: `low` and the split in one array, `high` and `nprims` in another (`---`).
    packs_and_traverses_like_the_tree_level(crate::layout::fixtures::PBRT_SOAOS, "PbrtSoAoS", 4);
}

#[test]
fn user_functions_in_layout_expressions() {
    // `bounds = box_of(lo, hi)` and `left = shifted(I, 1)`: calls of the program's functions,
    // in the destructor's reads and in the packer's placement of the left child.
    let src = include_str!("../../../../lit-tests/Inputs/user_functions_layout.scion");
    packs_and_traverses_like_the_tree_level(src, "FnBVH", 3);
}

#[test]
fn arrays_of_children_pack_and_traverse_like_the_binary_tree() {
    // `Interior(children: BVH4[4])`: the runtime collapses the binary tree to four slots (empty
    // slots are empty leaves with empty boxes), `build children` builds the four and gives their
    // references, and the traversal reads the children's boxes through `ch[k]`; the closest hits
    // are the binary tree's.
    let src = include_str!("../../../../lit-tests/Inputs/wide4_layout.scion");
    packs_like_the_binary_tree(src, "Wide4", "closest_hit4", 3, 4);
}

/// Packs the scene into `layout` of `src` (`nbuf` buffers) as the runtime fills the layout's
/// tree type, and checks `entry(B, ray, root, best)` against the binary tree's closest hits on
/// rays that miss and rays at every triangle. The root's reference is `@L.node` of the root
/// again, with fresh counters (it places every node where the build did).
fn packs_like_the_binary_tree(src: &str, layout: &str, entry: &str, nbuf: usize, arity: u32) {
    let (nodes, root, prims) = scene();
    let all_rays: Vec<Val> = rays().into_iter().chain(rays_at(&prims)).collect();
    let want = reference_for(&nodes, root, prims.as_slice(), &all_rays);
    assert!(want.iter().filter(|h| h.1 != u32::MAX).count() >= prims.len());
    let (m, schema) = module_and_schema(src, Some(layout));
    let schema = schema.expect("the runtime fills the tree type");
    assert_eq!(schema.arity, arity);
    let mut it = Interp::new(&m);
    let tree = put_tree_as(&mut it, &nodes, root, &prims, &schema);
    let (b, _) = pack(&mut it, layout, nbuf, tree);
    let ptr = |a: u64| Val::Int(a as i128, IntTy::U64);
    let cells: Vec<Val> = (0..2).map(|_| it.alloc(Val::Int(0, IntTy::U32))).collect();
    let status = it.alloc(Val::Int(0, IntTy::I32));
    let root_ref = it
        .call(
            &format!("{layout}.node"),
            vec![
                ptr(tree),
                ptr(b),
                Val::Int(0, IntTy::U32),
                cells[0].clone(),
                cells[1].clone(),
                status,
            ],
        )
        .expect("node runs")
        .remove(0);
    let got = closest_hits(&mut it, entry, b, root_ref, all_rays);
    assert_eq!(got, want);
}

#[test]
fn eight_wide_nodes_with_child_boxes_pack_and_traverse_like_the_binary_tree() {
    // `Interior(child_bounds: AABB[8], children: BVH8[8])`: no box per node, the children's
    // boxes in the parent (the runtime's ChildBounds, empty slots `Aabb::EMPTY`); interior
    // records in an indirect group, leaves and empty slots as tagged references (the `Leaf`
    // build returns SENTINEL for an empty one); `foreach c, k in ch` tests `cb[k]` first.
    let src = include_str!("../../../../lit-tests/Inputs/bvh8_aos_layout.scion");
    packs_like_the_binary_tree(src, "Bvh8Aos", "closest_hit8", 3, 8);
}

#[test]
fn table1_bvh8_in_its_natural_form_packs_and_traverses_like_the_binary_tree() {
    // Catalog §4.1: 256-byte records, L64 links, six planes of eight floats decoded by a user
    // function in the layout (`child_bounds = boxes8(...)`) and encoded by array literals in
    // the build (`build lower_x = plane8(child_bounds, false, 0)`).
    let src = concat!(
        include_str!("../../../../library/algorithms/closest_hit8.scion"),
        include_str!("../../../../library/layouts/bvh8.scion")
    );
    packs_like_the_binary_tree(src, "Bvh8", "closest_hit8", 3, 8);
}

#[test]
fn table1_bvh8_q8_ci_packs_and_traverses_like_the_binary_tree() {
    // Catalog §4.5, §8.5: 104-byte records, eight-bit codes in a per-node frame decoded by a
    // user function (conservative boxes), L32 links whose count goes in with `this[28:32]`.
    let src = concat!(
        include_str!("../../../../library/algorithms/closest_hit8.scion"),
        include_str!("../../../../library/layouts/bvh8_q8_ci.scion")
    );
    packs_like_the_binary_tree(src, "Bvh8Q8CI", "closest_hit8", 3, 8);
}

#[test]
fn an_empty_tree_packs_to_zero_counts() {
    let m = module(PBRT, Some("LinearBVH"));
    let mut it = Interp::new(&m);
    let tree = put_tree(&mut it, &[], u32::MAX, &[]);
    let (_, bufs) = pack(&mut it, "LinearBVH", 3, tree);
    assert_eq!(u32_at(&it, bufs[0]), 0);
    assert_eq!(u32_at(&it, bufs[0] + 4), 0);
}

/// A post-order variant of pbrt: children first, the right child just before its parent.
const POST: &str = r#"
layout PostBVH(I: u32) {
  P: u32;
  N: u32;
  primitives: Triangle[P];
  group nodes[size=N, align=32] by I {
    bounds: AABB;
    split nprims {
      > 0 -> Leaf { p_o: u32; data = primitives[p_o : p_o + nprims]; };
      0 -> Interior { c_o: u32; left = I - c_o; right = I - 1; };
    };
    nprims: u16;
  };
};

build PostBVH[order=post] {
  build Interior(bounds: AABB, left: BVH, right: BVH) {
    build bounds;
    build nprims = 0;
    let L: u32 = build left;
    build right;
    build c_o = this - L;
    return this;
  };
  build Leaf(bounds: AABB, nprims: u16, data: Triangle[nprims]) {
    build bounds;
    build nprims;
    build p_o = append(data, nprims);
    return this;
  };
};
"#;

#[test]
fn post_order_builds_place_children_first() {
    let (nodes, root, prims) = scene();
    let want = reference(&nodes, root, prims.as_slice());
    let m = module(POST, Some("PostBVH"));
    let mut it = Interp::new(&m);
    let tree = put_tree(&mut it, &nodes, root, &prims);
    let (b, bufs) = pack(&mut it, "PostBVH", 3, tree);
    // The root is placed last; its right child just before it.
    let last = nodes.len() as u32 - 1;
    let root_nprims = u32_at(&it, bufs[2] + 32 * last as u64 + 28) & 0xFFFF;
    assert_eq!(root_nprims, 0, "the root is an interior node");
    let got: Vec<(u32, u32)> = rays()
        .into_iter()
        .map(|ray| {
            let cell = it.alloc(Val::Tuple(vec![
                Val::F32(f32::INFINITY),
                Val::Int(0xFFFF_FFFF, IntTy::U32),
            ]));
            let bv = Val::Int(b as i128, IntTy::U64);
            best_of(
                &mut it,
                "closest_hit",
                vec![bv, ray, Val::Int(last as i128, IntTy::U32)],
                cell,
            )
        })
        .collect();
    assert_eq!(got, want);
}
