//! Differential property test of `mem-to-lo` and the JIT on random `tree` modules (the
//! generator of scion-ir's own property tests: arithmetic on every scalar type with special
//! float values, `if` with yields and early returns, `foreach`, calls, tuples, vectors, records,
//! references). Every function that lowers must verify, compile, and give the `tree`
//! interpreter's results bit for bit, in the `lo` interpreter and as machine code from
//! Cranelift and from LLVM (`scion-llvm`'s JIT at -O2), including what it leaves in its `mut`
//! cells.

#[path = "../../dialects/tests/common/mod.rs"]
mod common;

use scion_clif::JitModule;
use scion_compiler::passes::mem_to_lo::{layout, lower_module};
use scion_ir::entity::TypeId;
use scion_ir::interp::lo::LoInterp;
use scion_ir::interp::{AdtVal, Interp, Val};
use scion_ir::types::{FloatTy, IntTy, Type};
use scion_ir::Module;
use std::rc::Rc;

extern "C" fn ext(x: f32, _n: u32) -> f32 {
    x
}

fn arbitrary(m: &Module, ty: TypeId, rng: &mut common::Rng) -> Val {
    match m.types.get(ty).clone() {
        Type::Bool => Val::Bool(rng.chance(50)),
        Type::Int(t) => {
            let (lo, hi) = t.range();
            let v = match rng.below(4) {
                0 => lo,
                1 => hi,
                _ => (rng.next() as i128 % 2000 - 1000).clamp(lo, hi),
            };
            Val::Int(v, t)
        }
        Type::Float(FloatTy::F32) => Val::F32(
            [
                0.0,
                -0.0,
                1.5,
                -2.25,
                f32::INFINITY,
                f32::NAN,
                1e-40,
                3.0e38,
            ][rng.below(8)],
        ),
        Type::Float(_) => {
            Val::F64([0.0, -0.0, 1.5, -2.25, f64::INFINITY, f64::NAN, 1e-310][rng.below(7)])
        }
        Type::Vector { elem, lanes } => {
            Val::Vector((0..lanes).map(|_| arbitrary(m, elem, rng)).collect())
        }
        Type::Tuple(elems) => Val::Tuple(elems.iter().map(|&e| arbitrary(m, e, rng)).collect()),
        Type::Adt(name) => {
            let adt = m.adt(&name).unwrap();
            Val::Adt(Rc::new(AdtVal {
                ty: name.clone(),
                variant: None,
                fields: adt.shared.iter().map(|f| arbitrary(m, f.ty, rng)).collect(),
            }))
        }
        other => panic!("no generator for {other:?}"),
    }
}

fn flatten(v: &Val, out: &mut Vec<Val>) {
    match v {
        Val::Vector(l) | Val::Tuple(l) => l.iter().for_each(|x| flatten(x, out)),
        Val::Adt(a) => a.fields.iter().for_each(|x| flatten(x, out)),
        other => out.push(other.clone()),
    }
}

/// The bytes of `v` (type `ty`) laid out as `mem-to-lo` lays out a `mut` cell.
fn encode(m: &Module, ty: TypeId, v: &Val) -> Vec<u8> {
    let (size, _, offs) = layout(m, ty).unwrap();
    let mut leaves = Vec::new();
    flatten(v, &mut leaves);
    let mut bytes = vec![0u8; size as usize];
    for (&o, l) in offs.iter().zip(&leaves) {
        let b: Vec<u8> = match *l {
            Val::Bool(x) => vec![u8::from(x)],
            Val::Int(x, t) => (x as u64).to_le_bytes()[..t.bits() as usize / 8].to_vec(),
            Val::F32(x) => x.to_le_bytes().to_vec(),
            Val::F64(x) => x.to_le_bytes().to_vec(),
            _ => panic!("not a leaf"),
        };
        bytes[o as usize..o as usize + b.len()].copy_from_slice(&b);
    }
    bytes
}

fn check_seed(seed: u64) -> Result<usize, String> {
    let m = common::random_module(seed);
    let (lo, _skipped) = lower_module(&m, true).map_err(|e| format!("lowering failed: {e:?}"))?;
    scion_ir::verify(&lo)
        .map_err(|e| format!("lo does not verify: {e:?}\n{}", scion_ir::print_module(&lo)))?;
    // The JIT runs the module after lo-inline, the lo interpreter the one before.
    let mut inlined = lo.clone();
    scion_compiler::passes::lo::inline::run(&mut inlined, 48);
    scion_ir::verify(&inlined).map_err(|e| format!("inlined lo does not verify: {e:?}"))?;
    let jit = JitModule::compile_with(&inlined, &[("ext", ext as *const u8)])
        .map_err(|e| format!("{e}\n{}", scion_ir::print_module(&inlined)))?;
    let llvm = scion_llvm::JitModule::compile_with(&inlined, 2, &[("ext", ext as *const u8)])
        .map_err(|e| format!("{e}\n{}", scion_ir::print_module(&inlined)))?;
    let mut rng = common::Rng(seed.rotate_left(23) | 1);
    let mut compared = 0;
    for &g in &lo.func_order {
        if lo.is_declaration(g) {
            continue;
        }
        let name = lo.funcs[g].name.clone();
        let f = m.func_by_name(&name).unwrap();
        let params = m.funcs[f].params.clone();
        let args: Vec<Val> = params
            .iter()
            .map(|&p| match m.types.get(p) {
                Type::Ref(inner) => arbitrary(&m, *inner, &mut rng),
                _ => arbitrary(&m, p, &mut rng),
            })
            .collect();
        // The tree interpreter.
        let mut it = Interp::new(&m);
        it.max_depth = 12;
        it.max_steps = 200_000;
        it.define_extern("ext", Box::new(|a: &[Val]| Ok(vec![a[0].clone()])));
        let mut cells = Vec::new();
        let targs: Vec<Val> = params
            .iter()
            .zip(&args)
            .map(|(&p, a)| match m.types.get(p) {
                Type::Ref(_) => {
                    let r = it.alloc(a.clone());
                    cells.push(r.clone());
                    r
                }
                _ => a.clone(),
            })
            .collect();
        let Ok(want) = it.call(&name, targs) else {
            continue; // division by zero or a limit: undefined or unsupported, not compared
        };
        let mut want_flat = Vec::new();
        want.iter().for_each(|v| flatten(v, &mut want_flat));
        let mut want_cells = Vec::new();
        for c in &cells {
            flatten(it.read(c).unwrap(), &mut want_cells);
        }
        // The lo interpreter and the JIT, with each cell in memory.
        let mut li = LoInterp::new(&lo);
        li.define_extern("ext", Box::new(|a: &[Val]| Ok(vec![a[0].clone()])));
        let mut host_cells: Vec<Vec<u64>> = Vec::new();
        let mut ptr_args = Vec::new();
        let mut lo_cells = Vec::new();
        let (mut largs, mut jargs) = (Vec::new(), Vec::new());
        for (&p, a) in params.iter().zip(&args) {
            match m.types.get(p) {
                Type::Ref(inner) => {
                    let bytes = encode(&m, *inner, a);
                    let at = li.alloc(&bytes, 8);
                    lo_cells.push((at, *inner, bytes.len()));
                    largs.push(Val::Int(i128::from(at), IntTy::U64));
                    let mut words = vec![0u64; bytes.len().div_ceil(8).max(1)];
                    for (i, b) in bytes.iter().enumerate() {
                        words[i / 8] |= u64::from(*b) << (8 * (i % 8));
                    }
                    host_cells.push(words);
                    let ptr = host_cells.last_mut().unwrap().as_mut_ptr() as u64;
                    ptr_args.push(jargs.len());
                    jargs.push(Val::Int(i128::from(ptr), IntTy::U64));
                }
                _ => {
                    let mut leaves = Vec::new();
                    flatten(a, &mut leaves);
                    largs.extend(leaves.iter().cloned());
                    jargs.extend(leaves);
                }
            }
        }
        let lo_out = li.call(&name, largs).map_err(|e| {
            format!(
                "@{name}: lo interpreter: {e}\n{}",
                scion_ir::print_module(&lo)
            )
        })?;
        // LLVM gets its own copy of the cells.
        let mut llvm_cells = host_cells.clone();
        let mut llvm_args = jargs.clone();
        for (&i, cell) in ptr_args.iter().zip(llvm_cells.iter_mut()) {
            llvm_args[i] = Val::Int(i128::from(cell.as_mut_ptr() as u64), IntTy::U64);
        }
        let jit_out = jit.call(&name, &jargs).map_err(|e| e.to_string())?;
        let llvm_out = llvm.call(&name, &llvm_args).map_err(|e| e.to_string())?;
        let keys = |v: &[Val]| v.iter().map(Val::bits_key).collect::<Vec<_>>();
        if keys(&lo_out) != keys(&want_flat)
            || keys(&jit_out) != keys(&want_flat)
            || keys(&llvm_out) != keys(&want_flat)
        {
            return Err(format!(
                "@{name}({args:?}): tree {want_flat:?}, lo {lo_out:?}, jit {jit_out:?}, \
                 llvm {llvm_out:?}\n{}\n{}",
                scion_ir::print_module(&m),
                scion_ir::print_module(&lo)
            ));
        }
        // The cells after the call, decoded through the same layout.
        let mut lo_bytes = Vec::new();
        for (at, _, len) in &lo_cells {
            lo_bytes.push(li.bytes(*at, *len).unwrap().to_vec());
        }
        let mut want_bytes = Vec::new();
        for (c, (_, inner, _)) in cells.iter().zip(&lo_cells) {
            want_bytes.push(encode(&m, *inner, it.read(c).unwrap()));
        }
        let bytes_of = |cells: &[Vec<u64>]| -> Vec<Vec<u8>> {
            cells
                .iter()
                .zip(&lo_cells)
                .map(|(w, (_, _, len))| w.iter().flat_map(|x| x.to_le_bytes()).take(*len).collect())
                .collect()
        };
        let jit_bytes = bytes_of(&host_cells);
        let llvm_bytes = bytes_of(&llvm_cells);
        if lo_bytes != want_bytes || jit_bytes != want_bytes || llvm_bytes != want_bytes {
            return Err(format!(
                "@{name}: mut cells differ\n{}",
                scion_ir::print_module(&m)
            ));
        }
        compared += 1;
    }
    Ok(compared)
}

#[test]
fn random_modules_agree_in_tree_lo_cranelift_and_llvm() {
    let n: usize = std::env::var("SCION_LOWER_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(if cfg!(debug_assertions) { 150 } else { 1500 });
    let mut compared = 0;
    for seed in 1..=n as u64 {
        match check_seed(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)) {
            Ok(c) => compared += c,
            Err(e) => panic!("seed {seed}: {e}"),
        }
    }
    eprintln!("compared {compared} functions of {n} modules");
    assert!(compared > n / 2, "only {compared} functions were compared");
}
