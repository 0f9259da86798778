//! The `emit` API and the JIT's edges: linkage with and without `export`, PTX kernels and
//! `lo.global_id`, option errors, control flow LLVM needs special care for (a branch back to
//! the entry block, a conditional branch with one target twice), host function binding.

use scion_ir::interp::Val;
use scion_ir::types::IntTy;
use scion_llvm::{emit, JitModule, Options, Output, Target};

fn parse(text: &str) -> scion_ir::Module {
    let m =
        scion_ir::parse_module(text, scion_ir::diag::FileId(0)).unwrap_or_else(|e| panic!("{e:?}"));
    scion_ir::verify(&m).unwrap_or_else(|e| panic!("{e:?}"));
    m
}

fn text(m: &scion_ir::Module, target: Target, out: Output, level: u8) -> String {
    let opts = Options {
        target,
        cpu: None,
        opt_level: level,
    };
    String::from_utf8(emit(m, &opts, out).unwrap_or_else(|e| panic!("{e}"))).unwrap()
}

const KERNEL: &str = r#"
func @helper(%x: f32) -> (f32) {
  %y = "lo.add"(%x, %x) : (f32, f32) -> f32
  "lo.return"(%y) : (f32) -> ()
}

func @scion_double_kernel(%a: ptr, %n: u64) attributes {export, kernel} {
  %i = "lo.global_id"() : () -> u64
  %c = "lo.cmp"(%i, %n) {pred = "lt"} : (u64, u64) -> i1
  "lo.cond_br"(%c)[^body, ^exit] : (i1) -> ()
^body:
  %four = "lo.const"() {value = 4} : () -> u64
  %off = "lo.mul"(%i, %four) : (u64, u64) -> u64
  %p = "lo.ptr_add"(%a, %off) : (ptr, u64) -> ptr
  %x = "lo.load"(%p) {offset = 0} : (ptr) -> f32
  %y = "lo.call"(%x) {callee = @helper} : (f32) -> f32
  "lo.store"(%p, %y) {offset = 0} : (ptr, f32) -> ()
  "lo.br"()[^exit] : () -> ()
^exit:
  "lo.return"() : () -> ()
}
"#;

const EXPORTS: &str = r#"
func @helper.inner(%x: u32) -> (u32) {
  %y = "lo.add"(%x, %x) : (u32, u32) -> u32
  "lo.return"(%y) : (u32) -> ()
}

func @scion_entry(%x: u32) -> (u32) attributes {export} {
  %y = "lo.call"(%x) {callee = @helper.inner} : (u32) -> u32
  "lo.return"(%y) : (u32) -> ()
}
"#;

#[test]
fn a_kernel_becomes_a_ptx_entry_reading_the_thread_index() {
    let m = parse(KERNEL);
    let ir = text(&m, Target::Nvptx64, Output::LlvmIr, 0);
    assert!(
        ir.contains("target triple = \"nvptx64-nvidia-cuda\""),
        "{ir}"
    );
    assert!(
        ir.contains("define ptx_kernel void @scion_double_kernel("),
        "{ir}"
    );
    assert!(ir.contains("define internal float @helper("), "{ir}");
    for sreg in ["ctaid.x", "ntid.x", "tid.x"] {
        assert!(
            ir.contains(&format!("@llvm.nvvm.read.ptx.sreg.{sreg}()")),
            "{ir}"
        );
    }
    for level in [0, 3] {
        let ptx = text(&m, Target::Nvptx64, Output::Asm, level);
        assert!(ptx.contains(".target sm_90"), "{ptx}");
        assert!(ptx.contains(".address_size 64"), "{ptx}");
        assert!(
            ptx.contains(".visible .entry scion_double_kernel("),
            "{ptx}"
        );
        assert!(ptx.contains("%ctaid.x"), "{ptx}");
        assert!(!ptx.contains(".visible .func helper"), "{ptx}");
    }
    let sm80 = Options {
        target: Target::Nvptx64,
        cpu: Some("sm_80".into()),
        opt_level: 2,
    };
    let ptx = String::from_utf8(emit(&m, &sm80, Output::Asm).unwrap()).unwrap();
    assert!(ptx.contains(".target sm_80"), "{ptx}");
}

#[test]
fn global_id_and_objects_are_rejected_where_they_mean_nothing() {
    let m = parse(KERNEL);
    for t in [Target::X86_64, Target::Aarch64] {
        let e = emit(&m, &Options::new(t), Output::Object).unwrap_err();
        assert!(e.0.contains("`lo.global_id` is a GPU op"), "{e}");
    }
    let e = emit(&m, &Options::new(Target::Nvptx64), Output::Object).unwrap_err();
    assert!(e.0.contains("no object files"), "{e}");
    let e = JitModule::compile(&m, 0).err().unwrap();
    assert!(e.0.contains("`lo.global_id` is a GPU op"), "{e}");
    let bad_sm = Options {
        target: Target::Nvptx64,
        cpu: Some("gfx90a".into()),
        opt_level: 0,
    };
    let e = emit(&m, &bad_sm, Output::Asm).unwrap_err();
    assert!(
        e.0.contains("unknown NVPTX cpu `gfx90a` (e.g. sm_90"),
        "{e}"
    );
    let native_gpu = Options {
        target: Target::Nvptx64,
        cpu: Some("native".into()),
        opt_level: 0,
    };
    assert!(emit(&m, &native_gpu, Output::Asm).is_err());
}

#[test]
fn float_rem_is_rejected_on_nvptx_only() {
    let m = parse(
        r#"
func @r(%a: f64, %b: f64) -> (f64) {
  %r = "lo.rem"(%a, %b) : (f64, f64) -> f64
  "lo.return"(%r) : (f64) -> ()
}
"#,
    );
    let e = emit(&m, &Options::new(Target::Nvptx64), Output::Asm).unwrap_err();
    assert!(e.0.contains("no exact lowering on nvptx64"), "{e}");
    let asm = text(&m, Target::X86_64, Output::Asm, 2);
    assert!(asm.contains("fmod"), "{asm}");
}

#[test]
fn a_kernel_with_results_is_an_error() {
    let m = parse(
        r#"
func @k(%x: u32) -> (u32) attributes {kernel} {
  "lo.return"(%x) : (u32) -> ()
}
"#,
    );
    let e = emit(&m, &Options::new(Target::Nvptx64), Output::Asm).unwrap_err();
    assert!(e.0.contains("a PTX kernel returns nothing"), "{e}");
}

#[test]
fn exports_make_every_other_function_internal() {
    let m = parse(EXPORTS);
    for t in [Target::X86_64, Target::Aarch64] {
        let ir = text(&m, t, Output::LlvmIr, 0);
        assert!(ir.contains("define internal i32 @helper.inner("), "{ir}");
        assert!(ir.contains("define i32 @scion_entry("), "{ir}");
        let asm = text(&m, t, Output::Asm, 2);
        assert!(asm.contains(".globl\tscion_entry"), "{asm}");
        assert!(!asm.contains(".globl\thelper.inner"), "{asm}");
    }
    // Without exports every function is external under its lo name.
    let plain = parse(&EXPORTS.replace(" attributes {export}", ""));
    let ir = text(&plain, Target::X86_64, Output::LlvmIr, 0);
    assert!(ir.contains("define i32 @helper.inner("), "{ir}");
    // The JIT exposes what the object file does: the entry point (which runs the helper,
    // internal and inlined into it), not the helper, and says why when asked for it.
    let jit = JitModule::compile(&m, 3).unwrap();
    let out = jit
        .call("scion_entry", &[Val::Int(21, IntTy::U32)])
        .unwrap();
    assert!(matches!(out[0], Val::Int(42, IntTy::U32)));
    assert!(jit.get("scion_entry").is_some());
    assert!(jit.get("helper.inner").is_none());
    let e = jit
        .call("helper.inner", &[Val::Int(21, IntTy::U32)])
        .unwrap_err();
    assert!(e.0.contains("exposes only those"), "{e}");
    assert!(jit.get("nope").is_none());
    // Without exports the JIT reaches every function.
    let jit = JitModule::compile(&plain, 3).unwrap();
    let out = jit
        .call("helper.inner", &[Val::Int(21, IntTy::U32)])
        .unwrap();
    assert!(matches!(out[0], Val::Int(42, IntTy::U32)));
}

#[test]
fn objects_are_elf_for_each_cpu_target() {
    let m = parse(EXPORTS);
    for (t, machine) in [(Target::X86_64, 62u16), (Target::Aarch64, 183)] {
        let obj = emit(&m, &Options::new(t), Output::Object).unwrap();
        assert_eq!(&obj[..4], b"\x7fELF");
        assert_eq!(obj[4], 2, "64-bit");
        assert_eq!(u16::from_le_bytes([obj[18], obj[19]]), machine);
    }
}

#[test]
fn native_cpu_compiles_for_the_host() {
    let m = parse(EXPORTS);
    let host = Target::host().expect("an x86-64 or AArch64 test machine");
    let opts = Options {
        target: host,
        cpu: Some("native".into()),
        opt_level: 3,
    };
    let asm = String::from_utf8(emit(&m, &opts, Output::Asm).unwrap()).unwrap();
    assert!(asm.contains("scion_entry:"), "{asm}");
}

#[test]
fn a_conditional_branch_with_one_target_twice() {
    // Both edges go to ^join with different arguments: LLVM needs a phi entry per
    // predecessor, so the backend splits one edge.
    let m = parse(
        r#"
func @pick(%c: i1, %a: u32, %b: u32) -> (u32) {
  "lo.cond_br"(%c)[^join(%a : u32), ^join(%b : u32)] : (i1) -> ()
^join(%r: u32):
  "lo.return"(%r) : (u32) -> ()
}
"#,
    );
    for level in [0, 3] {
        let jit = JitModule::compile(&m, level).unwrap();
        for (c, want) in [(true, 7), (false, 9)] {
            let args = [
                Val::Bool(c),
                Val::Int(7, IntTy::U32),
                Val::Int(9, IntTy::U32),
            ];
            let out = jit.call("pick", &args).unwrap();
            assert!(
                matches!(out[0], Val::Int(w, IntTy::U32) if w == want),
                "{out:?}"
            );
        }
    }
    let e = JitModule::compile(&m, 0)
        .unwrap()
        .call("pick", &[Val::Bool(true)])
        .unwrap_err();
    assert!(e.0.contains("takes 3 arguments"), "{e}");
}

extern "C" fn host_twice(x: u32) -> u32 {
    2 * x
}

#[test]
fn declarations_bind_to_host_functions() {
    let m = parse(
        r#"
func @ext(%x: u32) -> (u32)

func @call_ext(%x: u32) -> (u32) {
  %y = "lo.call"(%x) {callee = @ext} : (u32) -> u32
  %z = "lo.add"(%y, %x) : (u32, u32) -> u32
  "lo.return"(%z) : (u32) -> ()
}
"#,
    );
    let e = JitModule::compile(&m, 2).err().unwrap();
    assert!(e.0.contains("no host function was given"), "{e}");
    let jit = JitModule::compile_with(&m, 2, &[("ext", host_twice as *const u8)]).unwrap();
    let out = jit.call("call_ext", &[Val::Int(5, IntTy::U32)]).unwrap();
    assert!(matches!(out[0], Val::Int(15, IntTy::U32)), "{out:?}");
}
