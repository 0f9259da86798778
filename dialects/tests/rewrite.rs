//! Rewriting utilities: aliases, erasure, region inlining and cloning, as a pass would use them.

use expect_test::expect;
use rustc_hash::FxHashMap;
use scion_ir::diag::FileId;
use scion_ir::module::RegionParent;
use scion_ir::rewrite::{
    clone_region, inline_region_before, replace_all_uses, resolve_aliases, resolve_value,
};
use scion_ir::tree::Op;
use scion_ir::{parse_module, print_func, print_module, verify, Builder, Module};

const CALLEE: &str = r#"
func @twice_neg(%a: f32, %c: i1) -> (f32) {
  %n = "tree.neg"(%a) : (f32) -> f32
  %r = "tree.if"(%c) ({
    %m = "tree.add"(%n, %n) : (f32, f32) -> f32
    "tree.yield"(%m) : (f32) -> ()
  }, {
    "tree.yield"(%a) : (f32) -> ()
  }) : (i1) -> f32
  "tree.return"(%r) : (f32) -> ()
}

func @caller(%x: f32, %y: i1) -> (f32) {
  %k = "tree.call"(%x, %y) {callee = @twice_neg} : (f32, i1) -> f32
  %z = "tree.mul"(%k, %x) : (f32, f32) -> f32
  "tree.return"(%z) : (f32) -> ()
}
"#;

#[test]
fn alias_chains_resolve() {
    let mut m = parse_module(CALLEE, FileId(0)).unwrap();
    let f = m.func_by_name("caller").unwrap();
    let entry = m.entry_block(f).unwrap();
    let (x, call) = (m.blocks[entry].args[0], m.blocks[entry].ops[0]);
    let k = m.ops[call].results[0];
    let neg = {
        let mut b = Builder::new(&mut m);
        b.set_insertion_point(scion_ir::InsertPoint::Before(call));
        b.unary(Op::Neg, x)
    };
    let negneg = {
        let mut b = Builder::new(&mut m);
        b.set_insertion_point(scion_ir::InsertPoint::Before(call));
        b.unary(Op::Neg, x)
    };
    replace_all_uses(&mut m, k, neg);
    replace_all_uses(&mut m, neg, negneg);
    assert_eq!(resolve_value(&m, k), negneg);
    scion_ir::rewrite::erase_op(&mut m, call);
    assert!(resolve_aliases(&mut m));
    assert!(m.aliases.is_empty());
    verify(&m).unwrap();
    expect![[r#"
        func @caller(%0: f32, %1: i1) -> (f32) {
          %2 = "tree.neg"(%0) : (f32) -> f32
          %3 = "tree.neg"(%0) : (f32) -> f32
          %4 = "tree.mul"(%3, %0) : (f32, f32) -> f32
          "tree.return"(%4) : (f32) -> ()
        }
    "#]]
    .assert_eq(&print_func(&m, f));
}

/// Inlining a call whose callee ends in a single top-level return: clone the callee's body,
/// splice it before the call with the call's operands for the parameters, and alias the call's
/// results to the returned values.
#[test]
fn clone_and_inline_a_call() {
    let mut m = parse_module(CALLEE, FileId(0)).unwrap();
    let callee = m.func_by_name("twice_neg").unwrap();
    let caller = m.func_by_name("caller").unwrap();
    let entry = m.entry_block(caller).unwrap();
    let call = m.blocks[entry].ops[0];
    let mut map = FxHashMap::default();
    let body = m.funcs[callee].body;
    let copy = clone_region(&mut m, body, &mut map);
    let args = m.ops[call].operands.clone();
    let ret = inline_region_before(&mut m, copy, call, &args).unwrap();
    let returned = m.ops[ret].operands.clone();
    scion_ir::rewrite::replace_op(&mut m, call, &returned);
    resolve_aliases(&mut m);
    verify(&m).unwrap_or_else(|e| panic!("{e}"));
    expect![[r#"
        func @caller(%0: f32, %1: i1) -> (f32) {
          %2 = "tree.neg"(%0) : (f32) -> f32
          %3 = "tree.if"(%1) ({
          ^bb1:
            %4 = "tree.add"(%2, %2) : (f32, f32) -> f32
            "tree.yield"(%4) : (f32) -> ()
          }, {
          ^bb2:
            "tree.yield"(%0) : (f32) -> ()
          }) : (i1) -> f32
          %5 = "tree.mul"(%3, %0) : (f32, f32) -> f32
          "tree.return"(%5) : (f32) -> ()
        }
    "#]]
    .assert_eq(&print_func(&m, caller));
    // The callee itself is untouched.
    let original = parse_module(CALLEE, FileId(0)).unwrap();
    let f0 = original.func_by_name("twice_neg").unwrap();
    assert_eq!(print_func(&m, callee), print_func(&original, f0));
}

#[test]
fn cloned_body_makes_an_equal_function() {
    let mut m = parse_module(CALLEE, FileId(0)).unwrap();
    let f = m.func_by_name("twice_neg").unwrap();
    let (params, results) = (m.funcs[f].params.clone(), m.funcs[f].results.clone());
    let (g, _) = m.add_func("copy", &params, &results);
    let body = m.funcs[f].body;
    let copy = clone_region(&mut m, body, &mut FxHashMap::default());
    m.funcs[g].body = copy;
    m.regions[copy].parent = Some(RegionParent::Func(g));
    verify(&m).unwrap_or_else(|e| panic!("{e}"));
    let printed = print_func(&m, g).replacen("@copy", "@twice_neg", 1);
    assert_eq!(printed, print_func(&m, f));
    // Spans come along.
    let orig_entry = m.entry_block(f).unwrap();
    let copy_entry = m.entry_block(g).unwrap();
    assert_eq!(
        m.span(m.blocks[orig_entry].ops[0]),
        m.span(m.blocks[copy_entry].ops[0])
    );
    assert!(m.span(m.blocks[copy_entry].ops[0]).is_some());
}

#[test]
fn constant_if_is_inlined_by_const_fold() {
    let text = r#"
func @f(%a: f32) -> (f32) {
  %t = "tree.const"() {value = false} : () -> i1
  %r = "tree.if"(%t) ({
    "tree.return"(%a) : (f32) -> ()
  }, {
    %n = "tree.neg"(%a) : (f32) -> f32
    "tree.yield"(%n) : (f32) -> ()
  }) : (i1) -> f32
  "tree.return"(%r) : (f32) -> ()
}
"#;
    let mut m = parse_module(text, FileId(0)).unwrap();
    let reg = scion_ir::PassRegistry::with_builtin();
    let mut pm = scion_ir::PassManager::parse(&reg, "const-fold,dce").unwrap();
    pm.run(&mut m, &mut scion_ir::PassCx::new(), &mut String::new())
        .unwrap();
    expect![[r#"
        func @f(%0: f32) -> (f32) {
          %1 = "tree.neg"(%0) : (f32) -> f32
          "tree.return"(%1) : (f32) -> ()
        }
    "#]]
    .assert_eq(&print_module(&m));
    let _ = Module::new();
}
