//! The JIT: compiles a `lo` module to machine code in this process and calls its functions.
//!
//! Every function `@f` gets a companion trampoline `f$entry(args: ptr, results: ptr)` that
//! loads each parameter from `args[8*i]` and stores each result to `results[8*i]` (the low
//! bytes of a `u64` slot, little-endian), so [`JitModule::call`] can run any signature from
//! [`Val`]s without a Rust function type per signature. [`JitModule::function_ptr`] gives the
//! raw entry of `@f` (platform C calling convention) for callers that know its type.
//! All `unsafe` of the backend is in this file, at the call boundary.

#![allow(unsafe_code)]

use crate::translate::{self, clif_type};
use cranelift_codegen::ir::{AbiParam, InstBuilder, MemFlags, UserFuncName};
use cranelift_frontend::{FunctionBuilder, FunctionBuilderContext};
use cranelift_jit::{JITBuilder, JITModule};
use cranelift_module::{FuncId as ClFuncId, Linkage, Module as _};
use scion_ir::interp::Val;
use scion_ir::lo::backend::{call_through_slots, is_called, Trampoline};
use scion_ir::types::Type;
use scion_ir::{FuncId, Module};
use std::collections::HashMap;
use std::fmt;

/// A backend failure (a translation or code generation error: a compiler bug or unsupported IR).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ClifError(pub String);

impl fmt::Display for ClifError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "cranelift backend: {}", self.0)
    }
}

impl std::error::Error for ClifError {}

struct Entry {
    entry: ClFuncId,
    func: ClFuncId,
    params: Vec<Type>,
    results: Vec<Type>,
}

/// A compiled `lo` module living in executable memory.
pub struct JitModule {
    module: JITModule,
    entries: HashMap<String, Entry>,
}

impl JitModule {
    /// Compiles every function of the verified `lo` module `m`. Declarations it calls must be
    /// given to [`JitModule::compile_with`].
    pub fn compile(m: &Module) -> Result<JitModule, ClifError> {
        JitModule::compile_with(m, &[])
    }

    /// Compiles `m`, binding each called declaration to a host function: `(name, address)`,
    /// the address of an `extern "C"` function whose signature matches the declaration.
    pub fn compile_with(m: &Module, symbols: &[(&str, *const u8)]) -> Result<JitModule, ClifError> {
        // No per-instruction rounding modes (directed rounding becomes round-to-nearest ops), and
        // no if-conversion in Cranelift (short-circuit conditions become `and`/`or`).
        let prepared = crate::prepared(m);
        let m = &prepared;
        for &f in &m.func_order {
            let name = &m.funcs[f].name;
            if m.is_declaration(f) && is_called(m, name) && !symbols.iter().any(|(s, _)| s == name)
            {
                return Err(ClifError(format!(
                    "`@{name}` is declared and called but no host function was given for it"
                )));
            }
        }
        // Cranelift optimizes each function with `opt` (the egraph: GVN, loop-invariant code
        // motion); `crate::remat` then gives the vectors a loop reads but does not change their
        // frame homes, and the module generates code with the egraph off, so that nothing is
        // hoisted again. `SCION_CLIF_REMAT=0` leaves the homes out (for measuring them).
        let homes = std::env::var("SCION_CLIF_REMAT").map_or(true, |v| v.trim() != "0");
        let opt = crate::isa_with("speed")?;
        let code_isa = if homes {
            crate::isa_with("none")?
        } else {
            opt.clone()
        };
        let mut builder = JITBuilder::with_isa(code_isa, cranelift_module::default_libcall_names());
        for &(name, addr) in symbols {
            builder.symbol(name, addr);
        }
        let mut cl = JITModule::new(builder);
        let syms = translate::declare_all(&mut cl, m).map_err(ClifError)?;
        let mut fctx = FunctionBuilderContext::new();
        let mut ctx = cl.make_context();
        let mut entries = HashMap::new();
        for &f in &m.func_order {
            if m.is_declaration(f) {
                continue;
            }
            let name = &m.funcs[f].name;
            let id = syms.funcs[name];
            ctx.func.signature = translate::signature(&cl, m, f).map_err(ClifError)?;
            ctx.func.name = UserFuncName::user(0, id.as_u32());
            translate::translate_func(&mut cl, &syms, m, f, &mut ctx.func, &mut fctx)
                .map_err(|e| ClifError(format!("@{name}: {e}")))?;
            // For reading the Cranelift IR as translated and the machine code (docs/backends.md,
            // "In-process execution").
            let dump = std::env::var("SCION_CLIF_DUMP").ok();
            if let Some(dir) = &dump {
                let _ =
                    std::fs::write(format!("{dir}/{name}.clif"), ctx.func.display().to_string());
            }
            if homes {
                ctx.optimize(&*opt, &mut Default::default())
                    .map_err(|e| ClifError(format!("@{name}: {e:?}")))?;
                crate::remat::rematerialize(&mut ctx.func);
            }
            cl.define_function(id, &mut ctx)
                .map_err(|e| ClifError(format!("@{name}: {e:?}")))?;
            if let Some(dir) = &dump {
                if let Some(c) = ctx.compiled_code() {
                    let _ = std::fs::write(format!("{dir}/{name}.bin"), c.code_buffer());
                }
            }
            cl.clear_context(&mut ctx);
            let entry = trampoline(&mut cl, m, f, id, &mut fctx)?;
            let ty = |t: &scion_ir::TypeId| m.types.get(*t).clone();
            entries.insert(
                name.clone(),
                Entry {
                    entry,
                    func: id,
                    params: m.funcs[f].params.iter().map(ty).collect(),
                    results: m.funcs[f].results.iter().map(ty).collect(),
                },
            );
        }
        cl.finalize_definitions()
            .map_err(|e| ClifError(format!("finalize: {e:?}")))?;
        // Where each function's code landed, so that a profile of the process (callgrind's
        // instruction addresses) can be read against the dumped code
        // (scripts/count-instructions-jit.sh).
        if let Ok(dir) = std::env::var("SCION_CLIF_DUMP") {
            for (name, e) in &entries {
                let addr = cl.get_finalized_function(e.func) as usize;
                let _ = std::fs::write(format!("{dir}/{name}.addr"), format!("{addr:#x}\n"));
            }
        }
        Ok(JitModule {
            module: cl,
            entries,
        })
    }

    /// The machine-code address of `@name` (C calling convention of the host), if defined.
    pub fn function_ptr(&self, name: &str) -> Option<*const u8> {
        let e = self.entries.get(name)?;
        Some(self.module.get_finalized_function(e.func))
    }

    /// Calls `@name` on scalar arguments (`ptr` as a `u64` integer) and returns its results.
    /// The types of `args` must match the parameters (checked).
    pub fn call(&self, name: &str, args: &[Val]) -> Result<Vec<Val>, ClifError> {
        let e = self
            .entries
            .get(name)
            .ok_or_else(|| ClifError(format!("no function `@{name}`")))?;
        let code = self.module.get_finalized_function(e.entry);
        // SAFETY: `code` is the finalized trampoline built by `trampoline` with the signature
        // `(ptr, ptr) -> ()` in the host's default (C) calling convention. It reads exactly
        // `params.len()` u64 slots from its first argument and writes `results.len()` slots (at
        // least one) through the second, as `call_through_slots` provides; the module, hence
        // the code, lives as long as `self`.
        let f: Trampoline = unsafe { std::mem::transmute(code) };
        call_through_slots(name, &e.params, &e.results, args, f).map_err(ClifError)
    }
}

/// Defines `name$entry(args: ptr, results: ptr)` calling `@name` with unpacked arguments.
fn trampoline(
    cl: &mut JITModule,
    m: &Module,
    f: FuncId,
    callee: ClFuncId,
    fctx: &mut FunctionBuilderContext,
) -> Result<ClFuncId, ClifError> {
    let ptr = cl.target_config().pointer_type();
    let mut ctx = cl.make_context();
    ctx.func.signature.params.push(AbiParam::new(ptr));
    ctx.func.signature.params.push(AbiParam::new(ptr));
    let name = format!("{}$entry", m.funcs[f].name);
    let id = cl
        .declare_function(&name, Linkage::Local, &ctx.func.signature)
        .map_err(|e| ClifError(e.to_string()))?;
    ctx.func.name = UserFuncName::user(1, id.as_u32());
    {
        let mut b = FunctionBuilder::new(&mut ctx.func, fctx);
        let block = b.create_block();
        b.append_block_params_for_function_params(block);
        b.switch_to_block(block);
        let (args, res) = (b.block_params(block)[0], b.block_params(block)[1]);
        let mut vals = Vec::new();
        for (i, &p) in m.funcs[f].params.iter().enumerate() {
            let t = clif_type(m, p, ptr).map_err(ClifError)?;
            vals.push(b.ins().load(t, MemFlags::trusted(), args, (8 * i) as i32));
        }
        let fref = cl.declare_func_in_func(callee, b.func);
        let call = b.ins().call(fref, &vals);
        let outs = b.inst_results(call).to_vec();
        for (i, v) in outs.into_iter().enumerate() {
            b.ins().store(MemFlags::trusted(), v, res, (8 * i) as i32);
        }
        b.ins().return_(&[]);
        b.seal_all_blocks();
        b.finalize();
    }
    cl.define_function(id, &mut ctx)
        .map_err(|e| ClifError(format!("{name}: {e:?}")))?;
    Ok(id)
}

/// Cranelift as a [`scion_ir::backend::Backend`]: [`JitModule::compile`].
#[derive(Clone, Copy, Debug, Default)]
pub struct Cranelift;

impl scion_ir::backend::Backend for Cranelift {
    fn name(&self) -> String {
        "cranelift".to_string()
    }

    fn jit(&self, m: &Module) -> Result<Box<dyn scion_ir::backend::JitCode>, String> {
        Ok(Box::new(JitModule::compile(m).map_err(|e| e.to_string())?))
    }
}

impl scion_ir::backend::JitCode for JitModule {
    fn function_ptr(&self, name: &str) -> Option<*const u8> {
        JitModule::function_ptr(self, name)
    }

    fn call(&self, name: &str, args: &[Val]) -> Result<Vec<Val>, String> {
        JitModule::call(self, name, args).map_err(|e| e.to_string())
    }
}
