//! The generic passes and the pass manager, text in and text out.

use expect_test::{expect, Expect};
use scion_ir::diag::FileId;
use scion_ir::pass::{Level, PassError};
use scion_ir::{
    parse_module, print_module, Module, Pass, PassCx, PassInfo, PassManager, PassRegistry,
};

fn run(pipeline: &str, text: &str) -> String {
    let mut m = parse_module(text, FileId(0)).unwrap_or_else(|d| panic!("{d:?}"));
    let reg = PassRegistry::with_builtin();
    let mut pm = PassManager::parse(&reg, pipeline).unwrap();
    pm.run(&mut m, &mut PassCx::new(), &mut String::new())
        .unwrap_or_else(|e| panic!("{e:?}"));
    print_module(&m)
}

fn check(pipeline: &str, text: &str, expect: Expect) {
    expect.assert_eq(&run(pipeline, text));
}

#[test]
fn const_fold_floats_exactly() {
    check(
        "const-fold,dce",
        r#"
func @f() -> (f32, f32, f32, f64, i1, i1, f32) {
  %a = "tree.const"() {value = 0.1} : () -> f64
  %one = "tree.const"() {value = 1.0} : () -> f32
  %three = "tree.const"() {value = 3.0} : () -> f32
  %z = "tree.const"() {value = 0.0} : () -> f32
  %nz = "tree.const"() {value = -0.0} : () -> f32
  %third = "tree.div"(%one, %three) : (f32, f32) -> f32
  %inf = "tree.div"(%one, %nz) : (f32, f32) -> f32
  %nan = "tree.div"(%z, %z) : (f32, f32) -> f32
  %d = "tree.add"(%a, %a) : (f64, f64) -> f64
  %eq = "tree.cmp"(%nan, %nan) {pred = "eq"} : (f32, f32) -> i1
  %ne = "tree.cmp"(%nan, %nan) {pred = "ne"} : (f32, f32) -> i1
  %neg = "tree.neg"(%z) : (f32) -> f32
  "tree.return"(%third, %inf, %nan, %d, %eq, %ne, %neg) : (f32, f32, f32, f64, i1, i1, f32) -> ()
}
"#,
        expect![[r#"
            func @f() -> (f32, f32, f32, f64, i1, i1, f32) {
              %0 = "tree.const"() {value = 0.33333334 : f32} : () -> f32
              %1 = "tree.const"() {value = -inf} : () -> f32
              %2 = "tree.const"() {value = nan} : () -> f32
              %3 = "tree.const"() {value = 0.2} : () -> f64
              %4 = "tree.const"() {value = false} : () -> i1
              %5 = "tree.const"() {value = true} : () -> i1
              %6 = "tree.const"() {value = -0.0} : () -> f32
              "tree.return"(%0, %1, %2, %3, %4, %5, %6) : (f32, f32, f32, f64, i1, i1, f32) -> ()
            }
        "#]],
    );
}

#[test]
fn const_fold_integers_wrap_and_casts_saturate() {
    check(
        "const-fold,dce",
        r#"
func @f(%x: i32) -> (u8, i8, i32, u32, i32, i32, u8, i32, i1, u32) {
  %a = "tree.const"() {value = 200} : () -> u8
  %b = "tree.const"() {value = 100} : () -> u8
  %s = "tree.add"(%a, %b) : (u8, u8) -> u8
  %m = "tree.const"() {value = -128} : () -> i8
  %n = "tree.neg"(%m) : (i8) -> i8
  %k = "tree.const"() {value = 7} : () -> i32
  %zero = "tree.const"() {value = 0} : () -> i32
  %dz = "tree.div"(%k, %zero) : (i32, i32) -> i32
  %big = "tree.const"() {value = 33} : () -> u32
  %one = "tree.const"() {value = 1} : () -> u32
  %sh = "tree.shl"(%one, %big) : (u32, u32) -> u32
  %mk = "tree.const"() {value = -7} : () -> i32
  %two = "tree.const"() {value = 2} : () -> i32
  %q = "tree.div"(%mk, %two) : (i32, i32) -> i32
  %r = "tree.rem"(%mk, %two) : (i32, i32) -> i32
  %f = "tree.const"() {value = 1e10} : () -> f32
  %sat = "tree.cast"(%f) : (f32) -> u8
  %nan = "tree.const"() {value = nan} : () -> f32
  %nz = "tree.cast"(%nan) : (f32) -> i32
  %c = "tree.cmp"(%mk, %two) {pred = "lt"} : (i32, i32) -> i1
  %fb = "tree.const"() {value = -1.0} : () -> f32
  %bits = "tree.bitcast"(%fb) : (f32) -> u32
  "tree.return"(%s, %n, %dz, %sh, %q, %r, %sat, %nz, %c, %bits) : (u8, i8, i32, u32, i32, i32, u8, i32, i1, u32) -> ()
}
"#,
        expect![[r#"
            func @f(%0: i32) -> (u8, i8, i32, u32, i32, i32, u8, i32, i1, u32) {
              %1 = "tree.const"() {value = 44} : () -> u8
              %2 = "tree.const"() {value = -128} : () -> i8
              %3 = "tree.const"() {value = 7} : () -> i32
              %4 = "tree.const"() {value = 0} : () -> i32
              %5 = "tree.div"(%3, %4) : (i32, i32) -> i32
              %6 = "tree.const"() {value = 2} : () -> u32
              %7 = "tree.const"() {value = -3} : () -> i32
              %8 = "tree.const"() {value = -1} : () -> i32
              %9 = "tree.const"() {value = 255} : () -> u8
              %10 = "tree.const"() {value = 0} : () -> i32
              %11 = "tree.const"() {value = true} : () -> i1
              %12 = "tree.const"() {value = 3212836864} : () -> u32
              "tree.return"(%1, %2, %5, %6, %7, %8, %9, %10, %11, %12) : (u8, i8, i32, u32, i32, i32, u8, i32, i1, u32) -> ()
            }
        "#]],
    );
}

#[test]
fn select_folds_and_dead_ifs_go() {
    check(
        "const-fold,dce",
        r#"
func @f(%a: f32, %b: f32, %c: i1) -> (f32) {
  %t = "tree.const"() {value = true} : () -> i1
  %s = "tree.select"(%t, %a, %b) : (i1, f32, f32) -> f32
  %unused = "tree.if"(%c) ({
    %x = "tree.mul"(%a, %b) : (f32, f32) -> f32
    "tree.yield"(%x) : (f32) -> ()
  }, {
    "tree.yield"(%b) : (f32) -> ()
  }) : (i1) -> f32
  %kept = "tree.if"(%c) ({
    "tree.return"(%a) : (f32) -> ()
  }, {
    "tree.yield"(%b) : (f32) -> ()
  }) : (i1) -> f32
  "tree.return"(%s) : (f32) -> ()
}
"#,
        expect![[r#"
            func @f(%0: f32, %1: f32, %2: i1) -> (f32) {
              %3 = "tree.if"(%2) ({
              ^bb1:
                "tree.return"(%0) : (f32) -> ()
              }, {
              ^bb2:
                "tree.yield"(%1) : (f32) -> ()
              }) : (i1) -> f32
              "tree.return"(%0) : (f32) -> ()
            }
        "#]],
    );
}

const SMALL: &str = r#"
func @f(%a: f32) -> (f32) {
  %one = "tree.const"() {value = 1.0} : () -> f32
  %two = "tree.add"(%one, %one) : (f32, f32) -> f32
  "tree.return"(%two) : (f32) -> ()
}
"#;

#[test]
fn print_after_all_and_stop_after() {
    let mut m = parse_module(SMALL, FileId(0)).unwrap();
    let reg = PassRegistry::with_builtin();
    let mut pm = PassManager::parse(&reg, "const-fold, dce, const-fold").unwrap();
    pm.options.print_after_all = true;
    pm.options.stop_after = Some("dce".into());
    pm.options.time_passes = true;
    let mut sink = String::new();
    let report = pm.run(&mut m, &mut PassCx::new(), &mut sink).unwrap();
    expect![[r#"
        // -----// IR Dump After const-fold //----- //
        func @f(%0: f32) -> (f32) {
          %1 = "tree.const"() {value = 1.0} : () -> f32
          %2 = "tree.const"() {value = 2.0} : () -> f32
          "tree.return"(%2) : (f32) -> ()
        }

        // -----// IR Dump After dce //----- //
        func @f(%0: f32) -> (f32) {
          %1 = "tree.const"() {value = 2.0} : () -> f32
          "tree.return"(%1) : (f32) -> ()
        }

    "#]]
    .assert_eq(&sink);
    assert!(report.stopped_early);
    let names: Vec<_> = report.passes.iter().map(|p| (p.name, p.changed)).collect();
    assert_eq!(names, [("const-fold", true), ("dce", true)]);
    assert!(report.passes.iter().all(|p| p.time.is_some()));
    let table = report.timing_table();
    assert!(
        table.contains("const-fold") && table.contains("Total"),
        "{table}"
    );
}

#[test]
fn unknown_pass_is_a_user_error() {
    let reg = PassRegistry::with_builtin();
    let err = PassManager::parse(&reg, "dce,frobnicate").err().unwrap();
    assert_eq!(err.to_string(), "error[E0961]: unknown pass `frobnicate`");
    assert_eq!(err.notes, ["known passes: const-fold, dce"]);
    assert_eq!(
        reg.help(),
        "  const-fold  Evaluate tree arithmetic, comparisons and casts on scalar constants (exact IEEE semantics)\n  \
         dce         Remove operations without side effects whose results are unused\n"
    );
}

/// A pass that breaks the IR: it erases every function's terminator.
struct Vandal;

impl Pass for Vandal {
    fn name(&self) -> &'static str {
        "vandal"
    }
    fn summary(&self) -> &'static str {
        "Erase terminators (to test the verifier between passes)"
    }
    fn run(&mut self, m: &mut Module, _cx: &mut PassCx) -> Result<bool, PassError> {
        for f in m.func_order.clone() {
            let entry = m.entry_block(f).unwrap();
            if let Some(&last) = m.blocks[entry].ops.last() {
                scion_ir::rewrite::erase_op(m, last);
            }
        }
        Ok(true)
    }
}

#[test]
fn verifier_failure_after_a_pass_is_an_internal_error_naming_it() {
    let mut reg = PassRegistry::with_builtin();
    reg.register(PassInfo {
        name: "vandal",
        summary: "Erase terminators",
        input: Level::Any,
        output: Level::Any,
        create: || Box::new(Vandal),
    });
    let mut m = parse_module(SMALL, FileId(0)).unwrap();
    let mut pm = PassManager::parse(&reg, "dce,vandal").unwrap();
    let err = pm
        .run(&mut m, &mut PassCx::new(), &mut String::new())
        .unwrap_err();
    let PassError::Internal(ie) = err else {
        panic!("expected an internal error")
    };
    expect![[r#"
        internal compiler error: after pass `vandal`: IR verification failed: block does not end with a terminator
        func @f(%0: f32) -> (f32) {
          %1 = "tree.const"() {value = 1.0} : () -> f32
          // error: block does not end with a terminator
          %2 = "tree.add"(%1, %1) : (f32, f32) -> f32
        }

        note: this is a bug in scionc; please report it with the input that caused it"#]]
    .assert_eq(&ie.to_string());
}

#[test]
fn invalid_input_is_a_user_diagnostic() {
    let text = "func @f(%a: f32) -> (i32) {\n  \"tree.return\"(%a) : (f32) -> ()\n}\n";
    let mut m = parse_module(text, FileId(0)).unwrap();
    let reg = PassRegistry::with_builtin();
    let mut pm = PassManager::parse(&reg, "dce").unwrap();
    let err = pm
        .run(&mut m, &mut PassCx::new(), &mut String::new())
        .unwrap_err();
    let PassError::Diagnostics(d) = err else {
        panic!("expected diagnostics")
    };
    assert_eq!(
        d.list[0].to_string(),
        "error[E0960]: invalid IR: returned types do not match the function's results"
    );
    assert!(d.list[0].primary_span().is_some());
}

#[test]
fn pass_options_and_extensions() {
    let mut cx = PassCx::new();
    cx.parse_option("inline:threshold=40").unwrap();
    assert_eq!(
        cx.parse_option("inline=3").unwrap_err().to_string(),
        "error[E0962]: malformed pass option `inline=3`"
    );
    assert_eq!(cx.option("inline", "threshold"), Some("40"));
    assert_eq!(cx.option("inline", "depth"), None);
    cx.insert_ext(vec![1u32, 2]);
    cx.ext_mut::<Vec<u32>>().unwrap().push(3);
    assert_eq!(cx.ext::<Vec<u32>>(), Some(&vec![1, 2, 3]));
    assert_eq!(cx.ext::<String>(), None);
}

#[test]
fn registry_entries_match_their_passes() {
    for info in PassRegistry::with_builtin().infos() {
        let pass = (info.create)();
        assert_eq!(pass.name(), info.name);
        assert_eq!(pass.summary(), info.summary);
    }
}

#[test]
fn print_before_writes_the_input_of_the_pass() {
    let mut m = parse_module(SMALL, FileId(0)).unwrap();
    let reg = PassRegistry::with_builtin();
    let mut pm = PassManager::parse(&reg, "const-fold,dce").unwrap();
    pm.options.print_before = vec!["dce".into()];
    let mut sink = String::new();
    pm.run(&mut m, &mut PassCx::new(), &mut sink).unwrap();
    assert!(
        sink.starts_with("// -----// IR Dump Before dce //----- //\nfunc @f"),
        "{sink}"
    );
    assert_eq!(sink.matches("IR Dump").count(), 1);
    assert_eq!(pm.names(), ["const-fold", "dce"]);
    let mut m = parse_module(SMALL, FileId(0)).unwrap();
    pm.options.print_before = Vec::new();
    pm.options.print_before_all = true;
    let mut sink = String::new();
    pm.run(&mut m, &mut PassCx::new(), &mut sink).unwrap();
    assert_eq!(
        sink.matches("// -----// IR Dump Before ").count(),
        2,
        "{sink}"
    );
}
