//! The quantization builtins (`frame_origin`, `frame_step`, `quant_lo`, `quant_hi`, layout
//! catalog §2.4, and the snapped-grid `sg_bins`, `sg_code_up`, `sg_code_down`, §3.8):
//!
//! * differential: the `tree` interpreter (which calls `scion_ir::tree::quant`), the `lo`
//!   interpreter after `mem-to-lo`, the Cranelift JIT and LLVM at -O0 and -O3 give the same bits
//!   on random and adversarial inputs (NaN, infinities, subnormals, signed zeros, huge and tiny
//!   magnitudes, far-from-origin frames), with the code bound both a constant (the unrolled
//!   search stops at its top bit) and a parameter (all 32 bits);
//! * conservative: for a frame built from a world box and any box inside it, the decoded box
//!   encloses the box on every lane and the low code never passes the high one; the same for
//!   the snapped grid's codes of the box against the world (decoded with directed rounding);
//! * tight: each code is the tightest one the decoder allows (the next code inward decodes past
//!   the plane, or the plane is hit exactly), so a decoded plane is at most one step plus
//!   rounding away from the original, and the step itself is the smallest that reaches the
//!   frame's high corner, up to one ulp.

use crate::common;

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use scion_clif::JitModule;
use scion_compiler::passes::mem_to_lo::lower_module;
use scion_ir::diag::FileId;
use scion_ir::interp::lo::LoInterp;
use scion_ir::interp::{Interp, Val};
use scion_ir::tree::quant::{decode, frame_origin, frame_step, quant_hi, quant_lo, MIN_STEP};
use scion_ir::tree::snapped;
use scion_ir::types::IntTy;
use scion_ir::Module;

const M: u32 = 65535;
/// The snapped grid's code bound in the `sgb`/`sgc` functions below (sg-eq's ten bits).
const SG_M: u32 = 1023;

const TREE: &str = r#"
func @fo(%x: vector<3xf32>) -> vector<3xf32> {
  %r = "tree.intrinsic"(%x) {name = "frame_origin"} : (vector<3xf32>) -> vector<3xf32>
  "tree.return"(%r) : (vector<3xf32>) -> ()
}
func @fs(%o: vector<3xf32>, %h: vector<3xf32>) -> vector<3xf32> {
  %m = "tree.const"() {value = 65535} : () -> u32
  %r = "tree.intrinsic"(%o, %h, %m) {name = "frame_step"} : (vector<3xf32>, vector<3xf32>, u32) -> vector<3xf32>
  "tree.return"(%r) : (vector<3xf32>) -> ()
}
func @fsm(%o: vector<3xf32>, %h: vector<3xf32>, %m: u32) -> vector<3xf32> {
  %r = "tree.intrinsic"(%o, %h, %m) {name = "frame_step"} : (vector<3xf32>, vector<3xf32>, u32) -> vector<3xf32>
  "tree.return"(%r) : (vector<3xf32>) -> ()
}
func @q(%v: vector<3xf32>, %o: vector<3xf32>, %s: vector<3xf32>) -> (vector<3xu32>, vector<3xu32>) {
  %m = "tree.const"() {value = 65535} : () -> i32
  %a = "tree.intrinsic"(%v, %o, %s, %m) {name = "quant_lo"} : (vector<3xf32>, vector<3xf32>, vector<3xf32>, i32) -> vector<3xu32>
  %b = "tree.intrinsic"(%v, %o, %s, %m) {name = "quant_hi"} : (vector<3xf32>, vector<3xf32>, vector<3xf32>, i32) -> vector<3xu32>
  "tree.return"(%a, %b) : (vector<3xu32>, vector<3xu32>) -> ()
}
func @qm(%v: vector<3xf32>, %o: vector<3xf32>, %s: vector<3xf32>, %m: u32) -> (vector<3xu32>, vector<3xu32>) {
  %a = "tree.intrinsic"(%v, %o, %s, %m) {name = "quant_lo"} : (vector<3xf32>, vector<3xf32>, vector<3xf32>, u32) -> vector<3xu32>
  %b = "tree.intrinsic"(%v, %o, %s, %m) {name = "quant_hi"} : (vector<3xf32>, vector<3xf32>, vector<3xf32>, u32) -> vector<3xu32>
  "tree.return"(%a, %b) : (vector<3xu32>, vector<3xu32>) -> ()
}
func @sgb(%lo: vector<3xf32>, %hi: vector<3xf32>) -> vector<3xf32> {
  %m = "tree.const"() {value = 1023} : () -> u32
  %r = "tree.intrinsic"(%lo, %hi, %m) {name = "sg_bins"} : (vector<3xf32>, vector<3xf32>, u32) -> vector<3xf32>
  "tree.return"(%r) : (vector<3xf32>) -> ()
}
func @sgbm(%lo: vector<3xf32>, %hi: vector<3xf32>, %m: u32) -> vector<3xf32> {
  %r = "tree.intrinsic"(%lo, %hi, %m) {name = "sg_bins"} : (vector<3xf32>, vector<3xf32>, u32) -> vector<3xf32>
  "tree.return"(%r) : (vector<3xf32>) -> ()
}
func @sgc(%v: vector<3xf32>, %lo: vector<3xf32>, %hi: vector<3xf32>) -> (vector<3xu32>, vector<3xu32>) {
  %m = "tree.const"() {value = 1023} : () -> u32
  %a = "tree.intrinsic"(%v, %lo, %hi, %m) {name = "sg_code_up"} : (vector<3xf32>, vector<3xf32>, vector<3xf32>, u32) -> vector<3xu32>
  %b = "tree.intrinsic"(%v, %lo, %hi, %m) {name = "sg_code_down"} : (vector<3xf32>, vector<3xf32>, vector<3xf32>, u32) -> vector<3xu32>
  "tree.return"(%a, %b) : (vector<3xu32>, vector<3xu32>) -> ()
}
func @sgcm(%v: vector<3xf32>, %lo: vector<3xf32>, %hi: vector<3xf32>, %m: u32) -> (vector<3xu32>, vector<3xu32>) {
  %a = "tree.intrinsic"(%v, %lo, %hi, %m) {name = "sg_code_up"} : (vector<3xf32>, vector<3xf32>, vector<3xf32>, u32) -> vector<3xu32>
  %b = "tree.intrinsic"(%v, %lo, %hi, %m) {name = "sg_code_down"} : (vector<3xf32>, vector<3xf32>, vector<3xf32>, u32) -> vector<3xu32>
  "tree.return"(%a, %b) : (vector<3xu32>, vector<3xu32>) -> ()
}
"#;

/// Every engine that runs the lowered code.
struct Engines {
    tree: Module,
    lo: Module,
    clif: JitModule,
    llvm: Vec<scion_llvm::JitModule>,
}

fn engines() -> Engines {
    let tree = scion_ir::parse_module(TREE, FileId(0)).expect("parses");
    scion_ir::verify(&tree).expect("tree verifies");
    let (lo, skipped) = lower_module(&tree, false).expect("lowers");
    assert!(skipped.is_empty());
    scion_ir::verify(&lo).expect("lo verifies");
    let clif = JitModule::compile(&lo).expect("Cranelift compiles");
    let llvm = [0, 3]
        .iter()
        .map(|&o| scion_llvm::JitModule::compile(&lo, o).expect("LLVM compiles"))
        .collect();
    Engines {
        tree,
        lo,
        clif,
        llvm,
    }
}

fn v3(x: [f32; 3]) -> Val {
    Val::Vector(x.iter().map(|&f| Val::F32(f)).collect())
}

fn flatten(v: &Val, out: &mut Vec<Val>) {
    match v {
        Val::Vector(l) | Val::Tuple(l) => l.iter().for_each(|x| flatten(x, out)),
        other => out.push(other.clone()),
    }
}

impl Engines {
    /// Runs `name` everywhere; the flattened results of the tree interpreter, after checking
    /// that every other engine gives the same bits.
    fn agree(&self, name: &str, args: Vec<Val>) -> Result<Vec<Val>, String> {
        let mut flat = Vec::new();
        args.iter().for_each(|a| flatten(a, &mut flat));
        let want = Interp::new(&self.tree)
            .call(name, args)
            .map_err(|e| format!("{name}: tree interpreter: {e}"))?;
        let mut want_flat = Vec::new();
        want.iter().for_each(|v| flatten(v, &mut want_flat));
        let want_keys: Vec<_> = want_flat.iter().map(Val::bits_key).collect();
        let mut got = vec![(
            "lo interpreter",
            LoInterp::new(&self.lo)
                .call(name, flat.clone())
                .map_err(|e| e.to_string()),
        )];
        got.push((
            "Cranelift",
            self.clif.call(name, &flat).map_err(|e| e.to_string()),
        ));
        for (l, label) in self.llvm.iter().zip(["LLVM -O0", "LLVM -O3"]) {
            got.push((label, l.call(name, &flat).map_err(|e| e.to_string())));
        }
        for (label, out) in got {
            let out = out.map_err(|e| format!("{name}: {label}: {e}"))?;
            let keys: Vec<_> = out.iter().map(Val::bits_key).collect();
            if keys != want_keys {
                return Err(format!(
                    "{name}({flat:?}): tree interpreter {want_flat:?} but {label} {out:?}"
                ));
            }
        }
        Ok(want_flat)
    }
}

/// Floats rich in edge cases: NaN (with payloads), infinities, signed zeros, subnormals,
/// `FLT_MIN` neighbours, huge and far-from-origin values.
fn special_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        4 => -8.0f32..8.0,
        1 => Just(0.0f32),
        1 => Just(-0.0f32),
        1 => Just(f32::INFINITY),
        1 => Just(f32::NEG_INFINITY),
        1 => Just(f32::NAN),
        1 => Just(f32::from_bits(0xffc0_0001)),
        1 => Just(f32::from_bits(1)),
        1 => Just(-f32::MIN_POSITIVE / 3.0),
        1 => Just(f32::MIN_POSITIVE),
        1 => Just(-f32::MIN_POSITIVE),
        1 => Just(f32::MAX),
        1 => Just(-f32::MAX),
        2 => 1e6f32..1e6 + 2.0,
        2 => -3e38f32..3e38,
        3 => any::<f32>(),
    ]
}

/// A world interval `[lo, hi]` with `lo ≤ hi`, finite, at one of several scales.
fn world() -> impl Strategy<Value = (f32, f32)> {
    let scale = prop_oneof![
        Just((0.0f64, 1.0f64)),
        Just((0.0, 1e-3)),
        Just((1e6, 1.0)),
        Just((-1e6, 1e-2)),
        Just((0.0, 3e38)),
        Just((-2e38, 1e38)),
        Just((0.0, 1e-38)),
        Just((1e-39, 1e-40)),
        Just((-7.0, 0.0)),
    ];
    (scale, -1.0f64..1.0, -1.0f64..1.0).prop_map(|((c, r), a, b)| {
        let (x, y) = ((c + r * a) as f32, (c + r * b) as f32);
        (x.min(y), x.max(y))
    })
}

/// A point of `[lo, hi]` at fraction `t`, snapped to an end sometimes.
fn inside(lo: f32, hi: f32, t: f64) -> f32 {
    if t < 0.05 {
        return lo;
    }
    if t > 0.95 {
        return hi;
    }
    ((lo as f64 + (hi as f64 - lo as f64) * t) as f32).clamp(lo, hi)
}

fn code(v: &Val) -> u32 {
    match v {
        Val::Int(x, _) => *x as u32,
        other => panic!("not a code: {other:?}"),
    }
}

#[test]
fn builtins_agree_in_every_engine_on_adversarial_inputs() {
    let e = engines();
    let cases = common::cases(if cfg!(debug_assertions) { 200 } else { 2000 });
    let mut runner = TestRunner::new(Config {
        cases,
        ..Config::default()
    });
    let bound = prop_oneof![
        Just(65535u32),
        Just(0),
        Just(1),
        Just(255),
        Just(u32::MAX),
        any::<u32>()
    ];
    let strategy = (
        prop::collection::vec(special_f32(), 9),
        prop::collection::vec(world(), 3),
        bound,
        any::<bool>(),
    );
    let result = runner.run(&strategy, |(f, w, m, real_frame)| {
        let check = || -> Result<(), String> {
            let (a, b, c) = ([f[0], f[1], f[2]], [f[3], f[4], f[5]], [f[6], f[7], f[8]]);
            e.agree("fo", vec![v3(a)])?;
            e.agree("fs", vec![v3(a), v3(b)])?;
            e.agree("fsm", vec![v3(a), v3(b), Val::Int(m as i128, IntTy::U32)])?;
            // Codes against either nonsense or a real frame (where the search does work).
            let (o, s) = if real_frame {
                let o = [0, 1, 2].map(|i| frame_origin(w[i].0));
                let s = [0, 1, 2].map(|i| frame_step(o[i], w[i].1, m));
                (o, s)
            } else {
                (b, c)
            };
            e.agree("q", vec![v3(a), v3(o), v3(s)])?;
            e.agree(
                "qm",
                vec![v3(a), v3(o), v3(s), Val::Int(m as i128, IntTy::U32)],
            )?;
            // Snapped grid (sg-eq): frames from nonsense and from real worlds, codes of any
            // value against them.
            let mu = Val::Int(m as i128, IntTy::U32);
            e.agree("sgb", vec![v3(a), v3(b)])?;
            e.agree("sgbm", vec![v3(a), v3(b), mu.clone()])?;
            let (wlo, whi) = if real_frame {
                ([0, 1, 2].map(|i| w[i].0), [0, 1, 2].map(|i| w[i].1))
            } else {
                (b, c)
            };
            e.agree("sgc", vec![v3(a), v3(wlo), v3(whi)])?;
            e.agree("sgcm", vec![v3(a), v3(wlo), v3(whi), mu])?;
            Ok(())
        };
        check().map_err(TestCaseError::fail)
    });
    if let Err(err) = result {
        panic!("{err}");
    }
}

/// One ulp of `x` as an `f64` (the gap to the next float away from zero).
fn ulp(x: f32) -> f64 {
    let a = x.abs();
    if a == f32::MAX {
        return a as f64 - f32::from_bits(a.to_bits() - 1) as f64;
    }
    f32::from_bits(a.to_bits() + 1) as f64 - a as f64
}

#[test]
fn decoded_boxes_enclose_and_are_tight() {
    let e = engines();
    let cases = common::cases(if cfg!(debug_assertions) { 1000 } else { 20000 });
    let mut runner = TestRunner::new(Config {
        cases,
        ..Config::default()
    });
    let strategy = (
        prop::collection::vec(world(), 3),
        prop::collection::vec((0.0f64..1.0, 0.0f64..1.0), 3),
    );
    let checked = std::cell::Cell::new(0usize);
    let result = runner.run(&strategy, |(w, ts)| {
        let check = || -> Result<(), String> {
            let wlo = [0, 1, 2].map(|i| w[i].0);
            let whi = [0, 1, 2].map(|i| w[i].1);
            let o = e.agree("fo", vec![v3(wlo)])?;
            let o = [0, 1, 2].map(|i| match o[i] {
                Val::F32(x) => x,
                _ => unreachable!("frame_origin gives f32"),
            });
            let s = e.agree("fs", vec![v3(o), v3(whi)])?;
            let s = [0, 1, 2].map(|i| match s[i] {
                Val::F32(x) => x,
                _ => unreachable!("frame_step gives f32"),
            });
            let mut lo = [0.0; 3];
            let mut hi = [0.0; 3];
            for i in 0..3 {
                let (x, y) = (
                    inside(wlo[i], whi[i], ts[i].0),
                    inside(wlo[i], whi[i], ts[i].1),
                );
                (lo[i], hi[i]) = (x.min(y), x.max(y));
            }
            let ql = e.agree("q", vec![v3(lo), v3(o), v3(s)])?;
            let qh = e.agree("q", vec![v3(hi), v3(o), v3(s)])?;
            for i in 0..3 {
                let ctx = format!(
                    "lane {i}: box [{:e}, {:e}] in world [{:e}, {:e}], frame o={:e} s={:e}",
                    lo[i], hi[i], wlo[i], whi[i], o[i], s[i]
                );
                // The frame: origin at or below the world, D(M) at or above it, and the
                // smallest such step up to one ulp.
                if o[i] > wlo[i] || decode(M, o[i], s[i]) < whi[i] {
                    return Err(format!("{ctx}: the frame misses the world"));
                }
                let need = ((whi[i] as f64 - o[i] as f64) / M as f64).max(MIN_STEP);
                if s[i] as f64 > need + 2.0 * ulp(need as f32) {
                    return Err(format!("{ctx}: step larger than needed ({need:e})"));
                }
                let (a, b) = (code(&ql[i]), code(&qh[i + 3]));
                let (da, db) = (decode(a, o[i], s[i]), decode(b, o[i], s[i]));
                // Conservative: the decoded box encloses the box; codes ordered and in range.
                if a > b || b > M {
                    return Err(format!("{ctx}: codes {a} > {b} (or above M)"));
                }
                if da > lo[i] || db < hi[i] {
                    return Err(format!("{ctx}: decoded [{da:e}, {db:e}] misses the box"));
                }
                // Tight: the next code inward passes the plane unless the plane is hit.
                if da != lo[i] && a < M && decode(a + 1, o[i], s[i]) <= lo[i] {
                    return Err(format!("{ctx}: low code {a} is not the tightest"));
                }
                if db != hi[i] && b > 0 && decode(b - 1, o[i], s[i]) >= hi[i] {
                    return Err(format!("{ctx}: high code {b} is not the tightest"));
                }
                // Hence each plane moves out by at most one step plus rounding.
                let slack = s[i] as f64 + 2.0 * ulp(lo[i].abs().max(da.abs()).max(o[i].abs()));
                if (lo[i] as f64 - da as f64) > slack {
                    return Err(format!("{ctx}: low plane moved out by more than a step"));
                }
                let slack = s[i] as f64 + 2.0 * ulp(hi[i].abs().max(db.abs()).max(o[i].abs()));
                if (db as f64 - hi[i] as f64) > slack {
                    return Err(format!("{ctx}: high plane moved out by more than a step"));
                }
            }
            // The snapped grid (sg-eq, 1023 bins) on the same world and box: every engine
            // gives the same codes, in range, and the directed-rounding decode encloses.
            let bins = e.agree("sgb", vec![v3(wlo), v3(whi)])?;
            let ql = e.agree("sgc", vec![v3(lo), v3(wlo), v3(whi)])?;
            let qh = e.agree("sgc", vec![v3(hi), v3(wlo), v3(whi)])?;
            for i in 0..3 {
                let Val::F32(b) = bins[i] else {
                    unreachable!("sg_bins gives f32")
                };
                let (a, c) = (code(&ql[i]), code(&qh[i + 3]));
                let (da, dc) = (
                    snapped::decode_lo(a, wlo[i], b),
                    snapped::decode_hi(c, whi[i], b),
                );
                if a > SG_M || c > SG_M || da > lo[i] || dc < hi[i] {
                    return Err(format!(
                        "lane {i}: box [{:e}, {:e}] in world [{:e}, {:e}], bins {b:e}: \
                         sg codes {a}, {c} decode to [{da:e}, {dc:e}]",
                        lo[i], hi[i], wlo[i], whi[i]
                    ));
                }
            }
            Ok(())
        };
        checked.set(checked.get() + 1);
        check().map_err(TestCaseError::fail)
    });
    if let Err(err) = result {
        panic!("{err}");
    }
    assert!(checked.get() >= cases as usize);
}

/// The reference functions and the lowered code agree on the fixed corner cases of the
/// catalog's edge-case table, and those cases enclose.
#[test]
fn catalog_edge_cases() {
    let e = engines();
    let cases: &[[[f32; 3]; 4]] = &[
        // [world lo, world hi, box lo, box hi]: flat frame, frame-touching box, far from the
        // origin with a tiny extent, huge extents, subnormal origins.
        [[5.0; 3], [5.0; 3], [5.0; 3], [5.0; 3]],
        [
            [-2.0, 0.0, 1.0],
            [3.0, 1.0, 2.0],
            [-2.0, 0.0, 1.0],
            [3.0, 1.0, 2.0],
        ],
        [[1e6; 3], [1e6 + 1.0; 3], [1e6 + 0.25; 3], [1e6 + 0.25; 3]],
        [
            [-f32::MAX; 3],
            [f32::MAX; 3],
            [-1.0, 0.0, 3e38],
            [1.0, 0.0, f32::MAX],
        ],
        [
            [1e-40, -1e-40, -0.0],
            [1e-39, 1e-41, 1e-45],
            [1e-40, -1e-40, 0.0],
            [1e-39, 0.0, 1e-45],
        ],
    ];
    for &[wlo, whi, lo, hi] in cases {
        let o = wlo.map(frame_origin);
        let s = [0, 1, 2].map(|i| frame_step(o[i], whi[i], M));
        e.agree("fo", vec![v3(wlo)]).unwrap();
        e.agree("fs", vec![v3(o), v3(whi)]).unwrap();
        e.agree("q", vec![v3(lo), v3(o), v3(s)]).unwrap();
        e.agree("q", vec![v3(hi), v3(o), v3(s)]).unwrap();
        for i in 0..3 {
            let (a, b) = (
                quant_lo(lo[i], o[i], s[i], M),
                quant_hi(hi[i], o[i], s[i], M),
            );
            assert!(a <= b, "{wlo:?} {whi:?}: {a} > {b}");
            assert!(decode(a, o[i], s[i]) <= lo[i], "{wlo:?} {whi:?} lane {i}");
            assert!(decode(b, o[i], s[i]) >= hi[i], "{wlo:?} {whi:?} lane {i}");
        }
        if wlo == lo && whi == hi && wlo[0] < whi[0] {
            assert_eq!(
                quant_lo(lo[0], o[0], s[0], M),
                0,
                "the root box starts at 0"
            );
            assert_eq!(quant_hi(hi[0], o[0], s[0], M), M, "the root box ends at M");
        }
    }
}
