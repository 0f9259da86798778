//! End to end below the tree level: closest-hit specialized to pbrt's LinearBVH (mem text from
//! destructor specialization, tests/data/pbrt-closest-hit.mem), lowered by `mem-to-lo` and
//! `recursion-to-stack`, run in the `lo` interpreter and JIT-compiled by Cranelift over
//! hand-packed LinearBVH buffers, must find exactly the hit the `tree` interpreter finds on the
//! same BVH as an algebraic value (paper Figure 4 / Figure 11).

use crate::common;

use scion_clif::JitModule;
use scion_compiler::driver::cli::Emit;
use scion_compiler::frontend::{compile, Frontend, PassOptions};
use scion_compiler::passes;
use scion_ir::diag::{FileId, SourceMap};
use scion_ir::interp::lo::LoInterp;
use scion_ir::interp::{AdtVal, Interp, Val};
use scion_ir::pass::{PassCx, PassManager};
use scion_ir::types::IntTy;
use scion_ir::Module;
use std::rc::Rc;

const MEM: &str = include_str!("data/pbrt-closest-hit.mem");
const PTR_MEM: &str = include_str!("data/ptr-closest-hit.mem");

type V3 = [f32; 3];
type Tri = (V3, V3, V3, u32);

fn tree_module() -> Module {
    let alg = std::fs::read_to_string(common::library_dir().join("algorithms/closest_hit.scion"))
        .expect("closest_hit.scion");
    common::tree_module_of(&[("closest_hit.scion", &alg)], true).unwrap_or_else(|e| panic!("{e}"))
}

fn lo_module() -> Module {
    lower_text(MEM)
}

fn lower_text(text: &str) -> Module {
    let mut m = scion_ir::parse_module(text, FileId(0)).expect("mem text parses");
    let reg = passes::registry();
    let mut pm = PassManager::parse(&reg, "mem-to-lo,recursion-to-stack,lo-inline").unwrap();
    pm.options.verify_each = true;
    let mut dumps = String::new();
    pm.run(&mut m, &mut PassCx::new(), &mut dumps)
        .unwrap_or_else(|e| panic!("{e}"));
    m
}

/// A BVH both as the tree interpreter's value and as pbrt's LinearBVH buffers.
struct Scene {
    adt: Val,
    nodes: Vec<u8>,
    prims: Vec<u8>,
    /// The logical nodes of the prelude's `BVH` (`scion_runtime::bvh::schema::binary_bvh`:
    /// kind @0, bounds @4, left @28 and right @32 or nprims: u16 @28 and data @32; 36 bytes),
    /// in the same pre-order; primitives are `prims`.
    logical: Vec<u8>,
}

/// Bytes of a logical node of `BVH`.
const LOGICAL: usize = 36;

#[test]
fn the_logical_node_is_the_runtimes() {
    assert_eq!(
        scion_runtime::bvh::schema::binary_bvh().node_size as usize,
        LOGICAL
    );
}

fn put(buf: &mut [u8], at: usize, bytes: &[u8]) {
    buf[at..at + bytes.len()].copy_from_slice(bytes);
}

fn v3(v: V3) -> Val {
    Val::Vector(v.iter().map(|&x| Val::F32(x)).collect())
}

fn rec(ty: &str, variant: Option<usize>, fields: Vec<Val>) -> Val {
    Val::Adt(Rc::new(AdtVal {
        ty: ty.into(),
        variant,
        fields,
    }))
}

fn bounds(tris: &[Tri]) -> (V3, V3) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for t in tris {
        for p in [t.0, t.1, t.2] {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
    }
    (lo, hi)
}

/// Builds the subtree of `tris` at the next node index (pre-order, left child at I + 1).
fn build(tris: &mut [Tri], depth: usize, s: &mut Scene) -> Val {
    let (lo, hi) = bounds(tris);
    let bounds_val = rec("AABB", None, vec![v3(lo), v3(hi)]);
    let me = s.nodes.len() / 32;
    s.nodes.extend_from_slice(&[0u8; 32]);
    s.logical.extend_from_slice(&[0u8; LOGICAL]);
    for (k, x) in lo.iter().chain(hi.iter()).enumerate() {
        s.nodes[me * 32 + 4 * k..me * 32 + 4 * k + 4].copy_from_slice(&x.to_le_bytes());
        put(&mut s.logical, me * LOGICAL + 4 + 4 * k, &x.to_le_bytes());
    }
    if tris.len() <= 3 {
        let p_o = (s.prims.len() / 40) as u32;
        let mut data = Vec::new();
        for t in tris.iter() {
            for x in t.0.iter().chain(&t.1).chain(&t.2) {
                s.prims.extend_from_slice(&x.to_le_bytes());
            }
            s.prims.extend_from_slice(&t.3.to_le_bytes());
            data.push(rec(
                "Triangle",
                None,
                vec![
                    v3(t.0),
                    v3(t.1),
                    v3(t.2),
                    Val::Int(i128::from(t.3), IntTy::U32),
                ],
            ));
        }
        s.nodes[me * 32 + 24..me * 32 + 28].copy_from_slice(&p_o.to_le_bytes());
        s.nodes[me * 32 + 28..me * 32 + 30].copy_from_slice(&(tris.len() as u16).to_le_bytes());
        put(&mut s.logical, me * LOGICAL, &1u32.to_le_bytes());
        put(&mut s.logical, me * LOGICAL + 32, &p_o.to_le_bytes());
        put(
            &mut s.logical,
            me * LOGICAL + 28,
            &(tris.len() as u16).to_le_bytes(),
        );
        return rec(
            "BVH",
            Some(1),
            vec![
                bounds_val,
                Val::Int(tris.len() as i128, IntTy::U16),
                Val::Array(Rc::new(data)),
            ],
        );
    }
    let axis = depth % 3;
    tris.sort_by(|a, b| {
        (a.0[axis] + a.1[axis] + a.2[axis]).total_cmp(&(b.0[axis] + b.1[axis] + b.2[axis]))
    });
    let mid = tris.len() / 2;
    let (l, r) = tris.split_at_mut(mid);
    let left = build(l, depth + 1, s);
    let right_index = s.nodes.len() / 32;
    let right = build(r, depth + 1, s);
    let c_o = (right_index - me) as u32;
    s.nodes[me * 32 + 24..me * 32 + 28].copy_from_slice(&c_o.to_le_bytes());
    put(
        &mut s.logical,
        me * LOGICAL + 28,
        &(me as u32 + 1).to_le_bytes(),
    );
    put(
        &mut s.logical,
        me * LOGICAL + 32,
        &(right_index as u32).to_le_bytes(),
    );
    rec("BVH", Some(0), vec![bounds_val, left, right])
}

struct Rng(u64);

impl Rng {
    fn f(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
}

fn scene(seed: u64, n: usize) -> Scene {
    let mut rng = Rng(seed);
    let mut tris: Vec<Tri> = (0..n)
        .map(|i| {
            let c = [rng.f() * 4.0, rng.f() * 4.0, rng.f() * 4.0];
            let mut p = || {
                [
                    c[0] + rng.f() - 0.5,
                    c[1] + rng.f() - 0.5,
                    c[2] + rng.f() - 0.5,
                ]
            };
            (p(), p(), p(), i as u32)
        })
        .collect();
    let mut s = Scene {
        adt: Val::Bool(false),
        nodes: Vec::new(),
        prims: Vec::new(),
        logical: Vec::new(),
    };
    s.adt = build(&mut tris, 0, &mut s);
    s
}

fn ray_leaves(o: V3, d: V3) -> Vec<Val> {
    o.iter()
        .chain(d.iter())
        .map(|&x| Val::F32(x))
        .chain([Val::F32(0.0), Val::F32(f32::INFINITY)])
        .collect()
}

fn u64v(x: u64) -> Val {
    Val::Int(i128::from(x), IntTy::U64)
}

fn best_bits(v: &Val) -> (u32, u32) {
    match v {
        Val::Tuple(t) => match (&t[0], &t[1]) {
            (Val::F32(d), Val::Int(id, _)) => (d.to_bits(), *id as u32),
            other => panic!("{other:?}"),
        },
        other => panic!("{other:?}"),
    }
}

/// The `lo` module `scionc --emit=lo --layout LinearBVH` produces today (the live front end,
/// specialization and lowering), as opposed to the fixed mem snapshot.
fn live_lo_module() -> Module {
    let mut sources = SourceMap::new();
    let lib = concat!(env!("CARGO_MANIFEST_DIR"), "/../library");
    let read = |p: &str| std::fs::read_to_string(format!("{lib}/{p}")).unwrap();
    let p = sources.add("prelude.scion", read("prelude.scion"));
    let a = sources.add("closest_hit.scion", read("algorithms/closest_hit.scion"));
    let l = sources.add("pbrt.scion", read("layouts/pbrt.scion"));
    let fe = Frontend {
        sources: &sources,
        prelude: &[p],
        inputs: &[a, l],
    };
    let popts = PassOptions {
        layout: Some("LinearBVH".into()),
        ..PassOptions::default()
    };
    let pipeline: Vec<String> = [
        "destructor-specialize",
        "constructor-specialize",
        "const-fold",
        "dce",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let out = compile(&fe, Emit::Lo, &pipeline, &popts);
    assert!(
        !out.diagnostics.has_errors() && out.internal_error.is_none(),
        "{}{:?}",
        out.diagnostics.render(&sources),
        out.internal_error
    );
    scion_ir::parse_module(&out.output.unwrap(), FileId(0)).unwrap()
}

#[test]
fn closest_hit_over_linear_bvh_matches_the_tree_interpreter() {
    closest_hit_linear_bvh(&lo_module());
}

#[test]
fn the_live_pipeline_closest_hit_matches_the_tree_interpreter() {
    closest_hit_linear_bvh(&live_lo_module());
}

fn closest_hit_linear_bvh(lo: &Module) {
    let tree = tree_module();
    let lo = lo.clone();
    let jit = JitModule::compile(&lo).expect("the whole pbrt module compiles");
    let mut hits = 0;
    for seed in 1..6u64 {
        let s = scene(seed, 100);
        let mut rng = Rng(seed * 77);
        for k in 0..40 {
            let o = [rng.f() * 6.0 - 1.0, rng.f() * 6.0 - 1.0, -2.0];
            let target = [rng.f() * 4.0, rng.f() * 4.0, rng.f() * 4.0];
            let mut d = [target[0] - o[0], target[1] - o[1], target[2] - o[2]];
            if k % 10 == 0 {
                d = [0.0, 0.0, 1.0];
            }
            // tree interpreter on the algebraic BVH
            let mut it = Interp::new(&tree);
            let ray = rec(
                "Ray",
                None,
                vec![v3(o), v3(d), Val::F32(0.0), Val::F32(f32::INFINITY)],
            );
            let cell = it.alloc(Val::Tuple(vec![
                Val::F32(f32::INFINITY),
                Val::Int(0xFFFF_FFFF, IntTy::U32),
            ]));
            it.call("closest_hit", vec![ray, s.adt.clone(), cell.clone()])
                .expect("tree run");
            let want = best_bits(it.read(&cell).unwrap());
            // lo interpreter on the packed buffers
            let mut li = LoInterp::new(&lo);
            let g = li.alloc(&[0u8; 8], 8);
            let pr = li.alloc(&s.prims, 8);
            let nd = li.alloc(&s.nodes, 8);
            let table: Vec<u8> = [g, pr, nd].iter().flat_map(|a| a.to_le_bytes()).collect();
            let b = li.alloc(&table, 8);
            let mut best = f32::INFINITY.to_le_bytes().to_vec();
            best.extend_from_slice(&0xFFFF_FFFFu32.to_le_bytes());
            let bp = li.alloc(&best, 8);
            let mut args = vec![u64v(b)];
            args.extend(ray_leaves(o, d));
            args.push(Val::Int(0, IntTy::U32));
            args.push(u64v(bp));
            let st = li.call("closest_hit", args.clone()).expect("lo run");
            assert!(matches!(st[0], Val::Int(0, IntTy::I32)));
            let got = li.bytes(bp, 8).unwrap();
            let lo_best = (
                u32::from_le_bytes(got[0..4].try_into().unwrap()),
                u32::from_le_bytes(got[4..8].try_into().unwrap()),
            );
            assert_eq!(lo_best, want, "lo interpreter, seed {seed} ray {k}");
            // JIT on host memory
            let g = [0u64];
            let table = [
                g.as_ptr() as u64,
                s.prims.as_ptr() as u64,
                s.nodes.as_ptr() as u64,
            ];
            let mut best = [f32::INFINITY.to_bits(), 0xFFFF_FFFF];
            args[0] = u64v(table.as_ptr() as u64);
            *args.last_mut().unwrap() = u64v(best.as_mut_ptr() as u64);
            let st = jit.call("closest_hit", &args).expect("jit run");
            assert!(matches!(st[0], Val::Int(0, IntTy::I32)));
            assert_eq!((best[0], best[1]), want, "JIT, seed {seed} ray {k}");
            if want.1 != 0xFFFF_FFFF {
                hits += 1;
            }
        }
    }
    assert!(hits > 40, "the scenes should be hit often ({hits})");
}

#[test]
fn lowered_modules_print_and_parse_back_identically() {
    let lo = lo_module();
    let text = scion_ir::print_module(&lo);
    let back = scion_ir::parse_module(&text, FileId(0)).expect("lo text parses");
    scion_ir::verify(&back).expect("and verifies");
    assert_eq!(scion_ir::print_module(&back), text);
    let clif = scion_clif::print_clif(&lo).expect("clif");
    assert!(clif.contains("function %closest_hit("));
}

/// The JIT-compiled constructor (`@LinearBVH.sizes`, `@LinearBVH.build`) packs the runtime's
/// logical tree into exactly the bytes of the hand-packed LinearBVH, and closest-hit over its
/// output finds the tree interpreter's hits.
#[test]
fn the_jit_compiled_constructor_packs_linear_bvh() {
    let lo = lo_module();
    let jit = JitModule::compile(&lo).expect("compiles");
    for seed in 1..4u64 {
        let s = scene(seed, 60);
        let n_nodes = (s.nodes.len() / 32) as u32;
        let n_prims = (s.prims.len() / 40) as u32;
        // LogicalTree: nodes ptr @0, node count @8, root @12, primitives ptr @16, count @24.
        let mut tree = [0u64; 4];
        tree[0] = s.logical.as_ptr() as u64;
        tree[1] = u64::from(n_nodes);
        tree[2] = s.prims.as_ptr() as u64;
        tree[3] = u64::from(n_prims);
        let tp = u64v(tree.as_ptr() as u64);
        let mut sizes = [0u64; 3];
        jit.call(
            "LinearBVH.sizes",
            &[tp.clone(), u64v(sizes.as_mut_ptr() as u64)],
        )
        .expect("sizes");
        assert_eq!(sizes[1], u64::from(n_prims) * 40);
        assert_eq!(sizes[2], u64::from(n_nodes) * 32);
        let mut bufs: Vec<Vec<u64>> = sizes
            .iter()
            .map(|&b| vec![0u64; (b as usize).div_ceil(8).max(1)])
            .collect();
        let table: Vec<u64> = bufs.iter_mut().map(|b| b.as_mut_ptr() as u64).collect();
        let st = jit
            .call("LinearBVH.build", &[tp, u64v(table.as_ptr() as u64)])
            .expect("build");
        assert!(matches!(st[0], Val::Int(0, IntTy::I32)), "{st:?}");
        let bytes = |b: &Vec<u64>, n: u64| -> Vec<u8> {
            b.iter()
                .flat_map(|w| w.to_le_bytes())
                .take(n as usize)
                .collect()
        };
        assert_eq!(bytes(&bufs[2], sizes[2]), s.nodes, "nodes, seed {seed}");
        assert_eq!(
            bytes(&bufs[1], sizes[1]),
            s.prims,
            "primitives, seed {seed}"
        );
    }
}

/// PtrBVH end to end: the JIT-compiled constructor packs the logical tree (absolute child
/// pointers into its own nodes buffer), and closest-hit from the root pointer (the first node,
/// pre-order) finds the tree interpreter's hits, also when both run in the lo interpreter.
#[test]
fn ptr_layout_built_and_traversed_by_the_jit_matches_the_tree_interpreter() {
    let tree_m = tree_module();
    let lo = lower_text(PTR_MEM);
    let jit = JitModule::compile(&lo).expect("compiles");
    for seed in 1..4u64 {
        let s = scene(seed, 80);
        let n_nodes = (s.nodes.len() / 32) as u32;
        let n_prims = (s.prims.len() / 40) as u32;
        let mut tree = [0u64; 4];
        tree[0] = s.logical.as_ptr() as u64;
        tree[1] = u64::from(n_nodes);
        tree[2] = s.prims.as_ptr() as u64;
        tree[3] = u64::from(n_prims);
        let tp = u64v(tree.as_ptr() as u64);
        let mut sizes = [0u64; 3];
        jit.call(
            "PtrBVH.sizes",
            &[tp.clone(), u64v(sizes.as_mut_ptr() as u64)],
        )
        .expect("sizes");
        assert_eq!(sizes[2], u64::from(n_nodes) * 48);
        let mut bufs: Vec<Vec<u64>> = sizes
            .iter()
            .map(|&b| vec![0u64; (b as usize).div_ceil(8).max(1)])
            .collect();
        let table: Vec<u64> = bufs.iter_mut().map(|b| b.as_mut_ptr() as u64).collect();
        let st = jit
            .call("PtrBVH.build", &[tp, u64v(table.as_ptr() as u64)])
            .expect("build");
        assert!(matches!(st[0], Val::Int(0, IntTy::I32)), "{st:?}");
        // The same build in the lo interpreter's memory.
        let mut li = LoInterp::new(&lo);
        let ln = li.alloc(&s.logical, 8);
        let lp = li.alloc(&s.prims, 8);
        let ltree: Vec<u8> = [ln, u64::from(n_nodes), lp, u64::from(n_prims)]
            .iter()
            .flat_map(|w| w.to_le_bytes())
            .collect();
        let ltp = li.alloc(&ltree, 8);
        let lb: Vec<u64> = sizes
            .iter()
            .map(|&b| li.alloc(&vec![0u8; b as usize], 8))
            .collect();
        let ltable: Vec<u8> = lb.iter().flat_map(|w| w.to_le_bytes()).collect();
        let ltab = li.alloc(&ltable, 8);
        let st = li
            .call("PtrBVH.build", vec![u64v(ltp), u64v(ltab)])
            .expect("lo build");
        assert!(matches!(st[0], Val::Int(0, IntTy::I32)));
        let mut rng = Rng(seed * 91);
        for k in 0..30 {
            let o = [rng.f() * 6.0 - 1.0, rng.f() * 6.0 - 1.0, -2.0];
            let t = [rng.f() * 4.0, rng.f() * 4.0, rng.f() * 4.0];
            let d = [t[0] - o[0], t[1] - o[1], t[2] - o[2]];
            let mut it = Interp::new(&tree_m);
            let ray = rec(
                "Ray",
                None,
                vec![v3(o), v3(d), Val::F32(0.0), Val::F32(f32::INFINITY)],
            );
            let cell = it.alloc(Val::Tuple(vec![
                Val::F32(f32::INFINITY),
                Val::Int(0xFFFF_FFFF, IntTy::U32),
            ]));
            it.call("closest_hit", vec![ray, s.adt.clone(), cell.clone()])
                .expect("tree run");
            let want = best_bits(it.read(&cell).unwrap());
            let mut best = [f32::INFINITY.to_bits(), 0xFFFF_FFFF];
            let mut args = vec![u64v(table.as_ptr() as u64)];
            args.extend(ray_leaves(o, d));
            args.push(u64v(table[2]));
            args.push(u64v(best.as_mut_ptr() as u64));
            let st = jit.call("closest_hit", &args).expect("jit run");
            assert!(matches!(st[0], Val::Int(0, IntTy::I32)));
            assert_eq!((best[0], best[1]), want, "JIT, seed {seed} ray {k}");
            let mut init = f32::INFINITY.to_le_bytes().to_vec();
            init.extend_from_slice(&0xFFFF_FFFFu32.to_le_bytes());
            let bp = li.alloc(&init, 8);
            args[0] = u64v(ltab);
            let n = args.len();
            args[n - 2] = u64v(lb[2]);
            args[n - 1] = u64v(bp);
            li.call("closest_hit", args).expect("lo run");
            let got = li.bytes(bp, 8).unwrap();
            let lo_best = (
                u32::from_le_bytes(got[0..4].try_into().unwrap()),
                u32::from_le_bytes(got[4..8].try_into().unwrap()),
            );
            assert_eq!(lo_best, want, "lo interpreter, seed {seed} ray {k}");
        }
    }
}
