//! Best-first functions (`order by k`): the recursive calls of `visit` below are queued and run
//! smallest key first, equal keys in the order they were queued, a NaN key as `+inf`
//! (docs/language.md, docs/ir.md). The order-sensitive visit log must be the same in a plain
//! Rust model of that rule, the `tree` interpreter, the `lo` interpreter after
//! `recursion-to-stack` (a binary heap in the frame) and the JIT-compiled code (Cranelift, LLVM
//! -O0 and -O3), for trees of every size up to 300 nodes and keys full of ties and NaNs (and
//! signed integer keys, the smallest `i32` among them); a queue too small returns status 1 in
//! every compiled engine.

use crate::common;

use scion_compiler::passes;
use scion_ir::backend::{Backend, JitCode};
use scion_ir::interp::lo::LoInterp;
use scion_ir::interp::{Interp, Val};
use scion_ir::pass::{PassCx, PassManager};
use scion_ir::types::IntTy;
use scion_ir::Module;

const SRC: &str = r#"
// Keys with many ties (five values) and NaNs (one in thirteen).
func key(i: u32, salt: u32) -> f32 = {
  let h: u32 = (i + salt) * 2654435761;
  if h % 13 == 0 { return 0.0 / 0.0; }
  return ((h >> 20) % 5) as f32 - 2.0;
}
"#;

/// The same with integer keys: ties, negative keys, and the smallest `i32` one in thirteen.
const INT_KEYS: &str = r#"
func key(i: u32, salt: u32) -> i32 = {
  let h: u32 = (i + salt) * 2654435761;
  if h % 13 == 0 { return -2147483648; }
  return ((h >> 20) % 5) as i32 - 2;
}
"#;

/// The traversal, over keys of type `K`.
const VISIT: &str = r#"
// Node i of an implicit binary tree of n nodes; the log records the visit order, and the body
// reads and writes it after queueing the children.
func visit(i: u32, k: K, n: u32, salt: u32, log: mut u64) order by k = {
  log = log * 1000003 + (i + 1) as u64;
  let c: u32 = 2 * i + 1;
  if c < n { visit(c, key(c, salt), n, salt, log); }
  if c + 1 < n && log % 17 != 3 { visit(c + 1, key(c + 1, salt), n, salt, log); }
  log = log + 7;
}

func run(n: u32, salt: u32) -> u64 = {
  let mut log: u64 = 0;
  visit(0, key(0, salt), n, salt, log);
  return log;
}
"#;

/// The program with float keys, or integer keys.
fn source(int_keys: bool) -> String {
    if int_keys {
        format!("{INT_KEYS}{}", VISIT.replace("k: K", "k: i32"))
    } else {
        format!("{SRC}{}", VISIT.replace("k: K", "k: f32"))
    }
}

/// The rule of docs/language.md written out: the log `run(n, salt)` must produce, and the
/// largest number of calls pending at once.
fn model(n: u32, salt: u32, int_keys: bool) -> (u64, usize) {
    // The key as the queue orders it: a float NaN is +inf.
    let order_key = |i: u32| -> f64 {
        let h = i.wrapping_add(salt).wrapping_mul(2_654_435_761);
        match (h.is_multiple_of(13), int_keys) {
            (true, true) => f64::from(i32::MIN),
            (true, false) => f64::INFINITY,
            (false, _) => f64::from((h >> 20) % 5) - 2.0,
        }
    };
    let mut log: u64 = 0;
    let mut queue: Vec<(f64, u64, u32)> = Vec::new();
    let mut seq = 0u64;
    let mut next = Some(0u32);
    let mut most = 0;
    while let Some(i) = next {
        log = log.wrapping_mul(1_000_003).wrapping_add(u64::from(i + 1));
        let c = 2 * i + 1;
        if c < n {
            queue.push((order_key(c), seq, c));
            seq += 1;
        }
        if c + 1 < n && log % 17 != 3 {
            queue.push((order_key(c + 1), seq, c + 1));
            seq += 1;
        }
        log = log.wrapping_add(7);
        most = most.max(queue.len());
        next = (0..queue.len())
            .min_by(|&a, &b| {
                let (x, y) = (&queue[a], &queue[b]);
                x.0.partial_cmp(&y.0).unwrap().then(x.1.cmp(&y.1))
            })
            .map(|j| queue.swap_remove(j).2);
    }
    (log, most)
}

fn lowered(stack_size: u32, int_keys: bool) -> (Module, Module) {
    let tree = common::tree_module_of(&[("best_first.scion", &source(int_keys))], false)
        .unwrap_or_else(|e| panic!("{e}"));
    let mut lo = tree.clone();
    let reg = passes::registry();
    let mut pm = PassManager::parse(&reg, "mem-to-lo,recursion-to-stack").expect("pipeline");
    pm.options.verify_each = true;
    let mut cx = PassCx::new();
    cx.set_option("recursion-to-stack", "stack-size", &stack_size.to_string());
    let mut dumps = String::new();
    pm.run(&mut lo, &mut cx, &mut dumps)
        .unwrap_or_else(|e| panic!("{e}"));
    (tree, lo)
}

fn u32v(x: u32) -> Val {
    Val::Int(i128::from(x), IntTy::U32)
}

fn as_u64(v: &Val) -> u64 {
    match v {
        Val::Int(x, _) => *x as u64,
        other => panic!("not an integer: {other:?}"),
    }
}

fn as_i32(v: &Val) -> i32 {
    match v {
        Val::Int(x, _) => *x as i32,
        other => panic!("not an integer: {other:?}"),
    }
}

fn engines(lo: &Module) -> Vec<(String, Box<dyn JitCode>)> {
    let backends: Vec<Box<dyn Backend>> = vec![
        Box::new(scion_clif::Cranelift),
        Box::new(scion_llvm::Llvm { opt_level: 0 }),
        Box::new(scion_llvm::Llvm { opt_level: 3 }),
    ];
    backends
        .iter()
        .map(|b| (b.name(), b.jit(lo).unwrap_or_else(|e| panic!("{e}"))))
        .collect()
}

#[test]
fn every_engine_visits_in_key_order() {
    visits_in_key_order(false);
}

#[test]
fn integer_keys_order_signed() {
    visits_in_key_order(true);
}

fn visits_in_key_order(int_keys: bool) {
    let (tree, lo) = lowered(64, int_keys);
    let visit = lo.func_by_name("visit").expect("visit");
    assert!(lo.funcs[visit].attrs.get("best_first").is_some());
    assert!(
        lo.funcs[visit].order_by().is_none(),
        "the queue replaced the attribute"
    );
    let jits = engines(&lo);
    let mut pending_seen = 0;
    for n in 0..300u32 {
        for salt in [0u32, 1, 7, 1234] {
            let (want, most) = model(n, salt, int_keys);
            pending_seen = pending_seen.max(most);
            let got = Interp::new(&tree)
                .call("run", vec![u32v(n), u32v(salt)])
                .unwrap_or_else(|e| panic!("tree interpreter, n = {n}: {e}"));
            assert_eq!(
                as_u64(&got[0]),
                want,
                "tree interpreter, n = {n}, salt {salt}"
            );
            let out = LoInterp::new(&lo)
                .call("run", vec![u32v(n), u32v(salt)])
                .unwrap_or_else(|e| panic!("lo interpreter, n = {n}: {e}"));
            assert_eq!(
                (as_u64(&out[0]), as_i32(&out[1])),
                (want, 0),
                "lo interpreter, n = {n}, salt {salt}"
            );
            for (name, code) in &jits {
                let out = code
                    .call("run", &[u32v(n), u32v(salt)])
                    .unwrap_or_else(|e| panic!("{name}: {e}"));
                assert_eq!(
                    (as_u64(&out[0]), as_i32(&out[1])),
                    (want, 0),
                    "{name}, n = {n}, salt {salt}"
                );
            }
        }
    }
    assert!(
        pending_seen > 20,
        "the queue held {pending_seen} calls at most"
    );
}

#[test]
fn a_full_queue_is_status_one() {
    let (_, lo) = lowered(4, false);
    let jits = engines(&lo);
    for n in [40u32, 100, 299] {
        let (_, most) = model(n, 7, false);
        assert!(most > 4, "n = {n} needs {most} entries");
        let out = LoInterp::new(&lo)
            .call("run", vec![u32v(n), u32v(7)])
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(as_i32(&out[1]), 1, "lo interpreter, n = {n}");
        for (name, code) in &jits {
            let out = code
                .call("run", &[u32v(n), u32v(7)])
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(as_i32(&out[1]), 1, "{name}, n = {n}");
        }
    }
    // Small trees fit.
    let (want, most) = model(6, 7, false);
    assert!(most <= 4);
    let out = LoInterp::new(&lo)
        .call("run", vec![u32v(6), u32v(7)])
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((as_u64(&out[0]), as_i32(&out[1])), (want, 0));
}
