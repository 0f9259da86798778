//! `recursion-to-stack` keeps the recursion's visit order and reports overflow: a traversal of
//! an implicit binary tree (lit-tests/recursion-to-stack/implicit-bvh.tree, tree IR with lo
//! memory ops, and mem-bvh.mem, the same at the mem level with a buffer table) run recursively and
//! as a stack loop, in the `lo` interpreter and JIT-compiled, must write the same visit log;
//! with a stack too small for the tree, it must return status 1 in both engines, after the
//! same prefix of visits.

use scion_clif::JitModule;
use scion_compiler::passes;
use scion_ir::diag::FileId;
use scion_ir::interp::lo::LoInterp;
use scion_ir::interp::Val;
use scion_ir::pass::{PassCx, PassManager};
use scion_ir::types::IntTy;
use scion_ir::Module;

const LO_SRC: &str = include_str!("../../lit-tests/recursion-to-stack/implicit-bvh.tree");
const MEM_SRC: &str = include_str!("../../lit-tests/recursion-to-stack/mem-bvh.mem");

thread_local! {
    /// Which input the helpers use: false the lo-memory one, true the mem one.
    static MEM: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

fn is_mem() -> bool {
    MEM.with(|c| c.get())
}

fn lowered(pipeline: &str, stack_size: Option<u32>) -> Module {
    let src = if is_mem() { MEM_SRC } else { LO_SRC };
    let mut m = scion_ir::parse_module(src, FileId(0)).expect("parses");
    let reg = passes::registry();
    let mut pm = PassManager::parse(&reg, pipeline).expect("pipeline");
    pm.options.verify_each = true;
    let mut cx = PassCx::new();
    if let Some(n) = stack_size {
        cx.set_option("recursion-to-stack", "stack-size", &n.to_string());
    }
    let mut dumps = String::new();
    pm.run(&mut m, &mut cx, &mut dumps)
        .unwrap_or_else(|e| panic!("{pipeline}: {e}"));
    m
}

/// 2^depth - 1 nodes; node i's interval is [lo, hi] from a small deterministic generator.
fn nodes(depth: u32, seed: u32) -> (Vec<u8>, u32) {
    let n = (1u32 << depth) - 1;
    let mut x = seed;
    let mut bytes = Vec::new();
    for _ in 0..n {
        x = x.wrapping_mul(1_103_515_245).wrapping_add(12345);
        let lo = (x >> 16) % 10;
        x = x.wrapping_mul(1_103_515_245).wrapping_add(12345);
        let hi = lo + (x >> 16) % 10;
        bytes.extend_from_slice(&(lo as f32).to_le_bytes());
        bytes.extend_from_slice(&(hi as f32).to_le_bytes());
    }
    (bytes, n)
}

fn ptr(a: u64) -> Val {
    Val::Int(i128::from(a), IntTy::U64)
}

/// Runs `@run` in the lo interpreter: (results, visit log).
fn interp(m: &Module, tree: &[u8], n: u32, q: f32) -> (Vec<Val>, Vec<u32>) {
    let mut it = LoInterp::new(m);
    let mut np = it.alloc(tree, 8);
    if is_mem() {
        np = it.alloc(&np.to_le_bytes(), 8);
    }
    let lp = it.alloc(&vec![0u8; 4 + 4 * n as usize], 4);
    let out = it
        .call(
            "run",
            vec![
                ptr(np),
                Val::Int(i128::from(n), IntTy::U32),
                Val::F32(q),
                ptr(lp),
            ],
        )
        .expect("runs");
    let log = it.bytes(lp, 4 + 4 * n as usize).expect("log").to_vec();
    (out, decode(&log))
}

/// Runs `@run` JIT-compiled on host memory.
fn jit(m: &Module, tree: &[u8], n: u32, q: f32) -> (Vec<Val>, Vec<u32>) {
    let j = JitModule::compile(m).expect("compiles");
    let tree = tree.to_vec();
    let table = [tree.as_ptr() as u64];
    let base = if is_mem() {
        table.as_ptr() as u64
    } else {
        tree.as_ptr() as u64
    };
    let mut log = vec![0u8; 4 + 4 * n as usize];
    let out = j
        .call(
            "run",
            &[
                ptr(base),
                Val::Int(i128::from(n), IntTy::U32),
                Val::F32(q),
                ptr(log.as_mut_ptr() as u64),
            ],
        )
        .expect("runs");
    (out, decode(&log))
}

fn decode(log: &[u8]) -> Vec<u32> {
    let word = |i: usize| u32::from_le_bytes(log[4 * i..4 * i + 4].try_into().unwrap());
    let k = word(0) as usize;
    (0..k).map(|i| word(i + 1)).collect()
}

fn status(out: &[Val]) -> i128 {
    match out.last() {
        Some(Val::Int(s, IntTy::I32)) => *s,
        other => panic!("no status: {other:?}"),
    }
}

#[test]
fn the_stack_loop_visits_in_recursion_order() {
    visits_in_order();
}

#[test]
fn the_mem_level_traversal_visits_in_recursion_order() {
    MEM.with(|c| c.set(true));
    visits_in_order();
}

#[test]
fn the_mem_level_traversal_overflows_like_the_lo_one() {
    MEM.with(|c| c.set(true));
    overflow();
}

fn visits_in_order() {
    let rec = lowered("mem-to-lo", None);
    let looped = lowered("mem-to-lo,recursion-to-stack", None);
    let mut longest = 0;
    for seed in 0..20 {
        let (tree, n) = nodes(6, seed);
        for q in [0.0f32, 3.5, 7.0, 12.0] {
            let (r_out, r_log) = interp(&rec, &tree, n, q);
            let (l_out, l_log) = interp(&looped, &tree, n, q);
            longest = longest.max(r_log.len());
            assert_eq!(r_log, l_log, "seed {seed}, q {q}");
            assert_eq!(r_out.len(), usize::from(!is_mem()));
            assert_eq!(status(&l_out), 0);
            let (j_out, j_log) = jit(&looped, &tree, n, q);
            assert_eq!(j_log, l_log, "JIT, seed {seed}, q {q}");
            assert_eq!(status(&j_out), 0);
            let (_, jr_log) = jit(&rec, &tree, n, q);
            assert_eq!(jr_log, r_log);
        }
    }
    assert!(
        longest > 3,
        "the generated trees should exercise the traversal"
    );
}

#[test]
fn a_full_stack_returns_status_1_after_the_same_visits() {
    overflow();
}

fn overflow() {
    // Every interval contains q, so the whole tree is visited and the stack must hold one
    // pending right child per level plus the two children just pushed: depth 6 needs 6
    // entries, 3 overflow.
    let n = 63u32;
    let tree: Vec<u8> = (0..n)
        .flat_map(|_| [0.0f32.to_le_bytes(), 10.0f32.to_le_bytes()].concat())
        .collect();
    let small = lowered("mem-to-lo,recursion-to-stack", Some(3));
    let (i_out, i_log) = interp(&small, &tree, n, 5.0);
    let (j_out, j_log) = jit(&small, &tree, n, 5.0);
    assert_eq!(status(&i_out), 1);
    assert_eq!(status(&j_out), 1);
    assert_eq!(i_log, j_log);
    assert!(!i_log.is_empty() && i_log.len() < n as usize);
    // The visits before the overflow are a prefix of the recursion's.
    let rec = lowered("mem-to-lo", None);
    let (_, r_log) = interp(&rec, &tree, n, 5.0);
    assert_eq!(r_log.len(), n as usize);
    assert_eq!(&r_log[..i_log.len()], &i_log[..]);
    // Enough room: the same pipeline with 6 entries completes.
    let fits = lowered("mem-to-lo,recursion-to-stack", Some(6));
    let (f_out, f_log) = jit(&fits, &tree, n, 5.0);
    assert_eq!(status(&f_out), 0);
    assert_eq!(f_log, r_log);
}
