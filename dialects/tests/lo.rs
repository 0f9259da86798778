//! The `lo` dialect: text round trip, verifier rules, and the `lo` interpreter on CFGs, memory,
//! stack slots and the float corner cases (minNum, directed rounding).

use scion_ir::diag::FileId;
use scion_ir::interp::lo::{next_f32, LoInterp};
use scion_ir::interp::Val;
use scion_ir::types::IntTy;
use scion_ir::{parse_module, print_module, verify};

const SUM: &str = r#"
func @sum(%p: ptr, %n: u32) -> (f32, i32) {
  %z = "lo.const"() {value = 0} : () -> u32
  %zf = "lo.const"() {value = 0.0} : () -> f32
  "lo.br"()[^head(%z, %zf : u32, f32)] : () -> ()
^head(%i: u32, %acc: f32):
  %c = "lo.cmp"(%i, %n) {pred = "lt"} : (u32, u32) -> i1
  "lo.cond_br"(%c)[^body, ^exit] : (i1) -> ()
^body:
  %four = "lo.const"() {value = 4} : () -> u32
  %off = "lo.mul"(%i, %four) : (u32, u32) -> u32
  %a = "lo.ptr_add"(%p, %off) : (ptr, u32) -> ptr
  %x = "lo.load"(%a) {offset = 0} : (ptr) -> f32
  %acc2 = "lo.add"(%acc, %x) : (f32, f32) -> f32
  %one = "lo.const"() {value = 1} : () -> u32
  %i2 = "lo.add"(%i, %one) : (u32, u32) -> u32
  "lo.br"()[^head(%i2, %acc2 : u32, f32)] : () -> ()
^exit:
  %s = "lo.stack_slot"() {align = 4, size = 8} : () -> ptr
  "lo.store"(%s, %acc) {offset = 4} : (ptr, f32) -> ()
  %back = "lo.load"(%s) {offset = 4} : (ptr) -> f32
  %st = "lo.const"() {value = 0} : () -> i32
  "lo.return"(%back, %st) : (f32, i32) -> ()
}
"#;

#[test]
fn cfg_round_trips_verifies_and_runs() {
    let m = parse_module(SUM, FileId(0)).unwrap();
    verify(&m).unwrap();
    let text = print_module(&m);
    let back = parse_module(&text, FileId(0)).unwrap();
    assert_eq!(print_module(&back), text);
    let mut it = LoInterp::new(&m);
    let data: Vec<u8> = [1.5f32, 2.0, -0.25]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let p = it.alloc(&data, 4);
    let out = it
        .call(
            "sum",
            vec![Val::Int(p as i128, IntTy::U64), Val::Int(3, IntTy::U32)],
        )
        .unwrap();
    assert!(matches!(out[0], Val::F32(x) if x == 3.25));
    assert!(matches!(out[1], Val::Int(0, IntTy::I32)));
}

#[test]
fn out_of_bounds_load_is_an_error() {
    let m = parse_module(SUM, FileId(0)).unwrap();
    let mut it = LoInterp::new(&m);
    let p = it.alloc(&[0u8; 4], 4);
    let e = it
        .call(
            "sum",
            vec![Val::Int(p as i128, IntTy::U64), Val::Int(2, IntTy::U32)],
        )
        .unwrap_err();
    assert!(e.message.contains("out of bounds"), "{}", e.message);
}

#[test]
fn verifier_rejects_bad_lo() {
    let bad = r#"
func @f(%a: f32, %b: u32) -> (f32) {
  %c = "lo.add"(%a, %b) : (f32, u32) -> f32
  "lo.return"(%c) : (f32) -> ()
}
"#;
    let m = parse_module(bad, FileId(0)).unwrap();
    let e = verify(&m).unwrap_err();
    assert!(format!("{e:?}").contains("lo.add"));
    let bad_succ = r#"
func @g(%a: i1) -> () {
  "lo.cond_br"(%a)[^x] : (i1) -> ()
^x:
  "lo.return"() : () -> ()
}
"#;
    let m = parse_module(bad_succ, FileId(0)).unwrap();
    assert!(verify(&m).is_err());
}

#[test]
fn min_max_and_directed_rounding() {
    let src = r#"
func @mm(%a: f32, %b: f32) -> (f32, f32, f32, f32) {
  %lo = "lo.min"(%a, %b) : (f32, f32) -> f32
  %hi = "lo.max"(%a, %b) : (f32, f32) -> f32
  %s = "lo.add"(%a, %b) : (f32, f32) -> f32
  %d = "lo.next_down"(%s) : (f32) -> f32
  %u = "lo.next_up"(%s) : (f32) -> f32
  "lo.return"(%lo, %hi, %d, %u) : (f32, f32, f32, f32) -> ()
}
"#;
    let m = parse_module(src, FileId(0)).unwrap();
    verify(&m).unwrap();
    let mut it = LoInterp::new(&m);
    let out = it
        .call("mm", vec![Val::F32(f32::NAN), Val::F32(2.0)])
        .unwrap();
    assert!(matches!(out[0], Val::F32(x) if x == 2.0));
    assert!(matches!(out[1], Val::F32(x) if x == 2.0));
    let out = it.call("mm", vec![Val::F32(0.0), Val::F32(-0.0)]).unwrap();
    assert!(matches!(out[0], Val::F32(x) if x.to_bits() == 0));
    assert!(matches!(out[2], Val::F32(x) if x.to_bits() == 0x8000_0001));
    assert!(matches!(out[3], Val::F32(x) if x.to_bits() == 1));
    assert_eq!(next_f32(1.0, true), 1.0000001);
    assert_eq!(next_f32(f32::INFINITY, false), f32::MAX);
    assert!(next_f32(f32::NAN, true).is_nan());
}
