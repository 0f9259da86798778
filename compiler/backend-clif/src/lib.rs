//! `scion-clif`: Scion's Cranelift backend (paper §7.3). Input: a verified module of the `lo`
//! dialect; output: Cranelift IR text ([`print_clif`], for `scionc --emit=clif`) or machine code
//! in memory ([`JitModule`]).
//!
//! The translation ([`translate`]) is one-to-one: a `lo` block is a Cranelift block with the
//! same parameters, a `lo` op one instruction or a short fixed sequence (NaN canonicalization,
//! minNum/maxNum, ulp steps, saturating casts). Float results are bit-identical to the `tree`
//! and `lo` interpreters of `scion-ir`; the differential tests check it on random inputs with
//! NaNs, signed zeros, infinities and subnormals.
//!
//! ```
//! use scion_ir::interp::Val;
//! let m = scion_ir::parse_module(r#"
//! func @twice(%x: f32) -> (f32) {
//!   %y = "lo.add"(%x, %x) : (f32, f32) -> f32
//!   "lo.return"(%y) : (f32) -> ()
//! }
//! "#, scion_ir::diag::FileId(0)).unwrap();
//! let jit = scion_clif::JitModule::compile(&m).unwrap();
//! let out = jit.call("twice", &[Val::F32(1.5)]).unwrap();
//! assert!(matches!(out[0], Val::F32(x) if x == 3.0));
//! assert!(scion_clif::print_clif(&m).unwrap().contains("fadd"));
//! ```

mod arith;
pub mod flatten;
mod ifconv;
pub mod jit;
mod lanes;
mod loads;
pub mod remat;
pub mod translate;
mod transpose;

pub use jit::{ClifError, Cranelift, JitModule};

use cranelift_codegen::settings::{self, Configurable};
use cranelift_frontend::FunctionBuilderContext;
use cranelift_module::Module as _;

/// The target ISA of this machine, with Scion's settings: optimizing, verifier on, and several
/// return values allowed (through a hidden return area when they exceed the registers).
pub fn host_isa() -> Result<std::sync::Arc<dyn cranelift_codegen::isa::TargetIsa>, ClifError> {
    isa_with("speed")
}

/// The host's ISA at `opt_level`: `speed`, or `none` for the JIT's code generation after its
/// own optimization ([`remat`] between the two).
pub(crate) fn isa_with(
    opt_level: &str,
) -> Result<std::sync::Arc<dyn cranelift_codegen::isa::TargetIsa>, ClifError> {
    let mut flags = settings::builder();
    let set = |f: &mut settings::Builder, k: &str, v: &str| {
        f.set(k, v)
            .map_err(|e| ClifError(format!("setting {k}={v}: {e}")))
    };
    set(&mut flags, "opt_level", opt_level)?;
    set(&mut flags, "enable_verifier", "true")?;
    set(&mut flags, "enable_multi_ret_implicit_sret", "true")?;
    set(&mut flags, "use_colocated_libcalls", "false")?;
    set(&mut flags, "is_pic", "false")?;
    let isa = cranelift_native::builder()
        .map_err(|e| ClifError(format!("host ISA: {e}")))?
        .finish(settings::Flags::new(flags))
        .map_err(|e| ClifError(format!("host ISA: {e}")))?;
    Ok(isa)
}

/// `m` as the translation takes it: directed rounding expanded into round-to-nearest ops
/// ([`scion_ir::lo::directed`]) and short-circuit conditions flattened ([`flatten`]).
pub fn prepared(m: &scion_ir::Module) -> scion_ir::Module {
    let mut owned = scion_ir::lo::directed::expanded(m).into_owned();
    flatten::flatten(&mut owned);
    owned
}

/// The Cranelift IR of every function of the `lo` module `m`, as text (one `function` each, in
/// module order; declarations are left out).
pub fn print_clif(m: &scion_ir::Module) -> Result<String, ClifError> {
    let prepared = prepared(m);
    let m = &prepared;
    let builder =
        cranelift_jit::JITBuilder::with_isa(host_isa()?, cranelift_module::default_libcall_names());
    let mut cl = cranelift_jit::JITModule::new(builder);
    let syms = translate::declare_all(&mut cl, m).map_err(ClifError)?;
    let mut fctx = FunctionBuilderContext::new();
    let mut out = String::new();
    for &f in &m.func_order {
        if m.is_declaration(f) {
            continue;
        }
        let mut ctx = cl.make_context();
        ctx.func.signature = translate::signature(&cl, m, f).map_err(ClifError)?;
        ctx.func.name = cranelift_codegen::ir::UserFuncName::testcase(&m.funcs[f].name);
        translate::translate_func(&mut cl, &syms, m, f, &mut ctx.func, &mut fctx)
            .map_err(|e| ClifError(format!("@{}: {e}", m.funcs[f].name)))?;
        out.push_str(&ctx.func.display().to_string());
        out.push('\n');
    }
    Ok(out)
}
