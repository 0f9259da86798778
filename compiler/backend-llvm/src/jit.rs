//! The JIT: compiles a `lo` module with LLVM (MCJIT) for this machine's CPU and calls its
//! functions in this process. Input: a verified `lo` module and an `-O` level; output: the
//! machine-code address of each function.
//!
//! As in `scion-clif`, every function `@f` the module exposes gets a companion trampoline
//! `f$entry(args: ptr, results: ptr)` (in LLVM IR) that loads parameter `i` from `args[8*i]` and
//! stores result `i` to `results[8*i]` (the low bytes of a `u64` slot), so [`JitModule::call`]
//! runs any signature from [`Val`]s. A module with entry points (functions marked `export`, the
//! C ABI's) exposes only those, as its object file does: the others are internal, so that LLVM
//! inlines them where it would in `scionc --emit=obj` (a traversal into the batch loop that calls
//! it once per query: a real call per ray otherwise, docs/performance.md "Twenty-second
//! session"). A module without entry points exposes every function. Every address is resolved
//! when the module is compiled; afterwards the execution engine is never touched again until it
//! is dropped, which is what makes a `JitModule` shareable between threads. All `unsafe` of the
//! JIT is in this file.

#![allow(unsafe_code)]

use crate::target::{self, Target};
use crate::translate::{self, llvm_type};
use crate::LlvmError;
use inkwell::attributes::AttributeLoc;
use inkwell::context::Context;
use inkwell::execution_engine::ExecutionEngine;
use inkwell::module::Linkage;
use inkwell::values::{BasicMetadataValueEnum, BasicValueEnum, ValueKind};
use scion_ir::interp::Val;
use scion_ir::lo::backend::{call_through_slots, is_called, Trampoline};
use scion_ir::types::Type;
use scion_ir::Module;
use std::collections::HashMap;

struct Entry {
    func: usize,
    entry: usize,
    params: Vec<Type>,
    results: Vec<Type>,
}

/// A compiled `lo` module living in executable memory.
pub struct JitModule {
    entries: HashMap<String, Entry>,
    /// Owns the machine code; dropped before the context it borrows (field order).
    _engine: ExecutionEngine<'static>,
    /// The LLVM context of the module, boxed so its address never changes.
    _context: Box<Context>,
}

// SAFETY: after `compile_with` returns, the execution engine and its context are only dropped,
// never used (every address is resolved in `compile_with` and kept in `entries`), and the
// compiled code is immutable, so sharing the module or moving it between threads cannot race
// on LLVM's (single-threaded) data structures.
unsafe impl Send for JitModule {}
// SAFETY: as for `Send`: `&JitModule` only reads `entries` and calls the finished code.
unsafe impl Sync for JitModule {}

impl JitModule {
    /// Compiles every function of the verified `lo` module `m` at `-O{opt_level}` for this
    /// machine's CPU. Declarations it calls must be given to [`JitModule::compile_with`].
    pub fn compile(m: &Module, opt_level: u8) -> Result<JitModule, LlvmError> {
        JitModule::compile_with(m, opt_level, &[])
    }

    /// Compiles `m`, binding each called declaration to a host function: `(name, address)`,
    /// the address of an `extern "C"` function whose signature matches the declaration.
    pub fn compile_with(
        m: &Module,
        opt_level: u8,
        symbols: &[(&str, *const u8)],
    ) -> Result<JitModule, LlvmError> {
        let host = Target::host()
            .ok_or_else(|| LlvmError("the JIT needs an x86-64 or AArch64 host".into()))?;
        for &f in &m.func_order {
            let name = &m.funcs[f].name;
            if m.is_declaration(f) && is_called(m, name) && !symbols.iter().any(|(s, _)| s == name)
            {
                return Err(LlvmError(format!(
                    "`@{name}` is declared and called but no host function was given for it"
                )));
            }
        }
        let tm = target::target_machine(host, Some("native"), opt_level)?;
        let context = Box::new(Context::create());
        // SAFETY: the context lives in a box owned by the returned `JitModule`, which drops
        // the engine (and with it the module and code) before the box (field order); the box
        // is never moved out of or replaced, so the reference stays valid as long as anything
        // that borrows it.
        let cx: &'static Context = unsafe { &*(&*context as *const Context) };
        let (lm, funcs) =
            translate::translate(cx, m, "scion_jit", host, true).map_err(LlvmError)?;
        lm.set_triple(&tm.get_triple());
        lm.set_data_layout(&tm.get_target_data().get_data_layout());
        let mut trampolines = HashMap::new();
        let builder = cx.create_builder();
        let ptr = cx.ptr_type(Default::default());
        for &f in &m.func_order {
            if m.is_declaration(f) {
                continue;
            }
            let name = &m.funcs[f].name;
            let callee = funcs[name];
            if callee.get_linkage() == Linkage::Internal {
                // Not an entry point: callable from the module only (and inlined there).
                continue;
            }
            let ft = cx.void_type().fn_type(&[ptr.into(), ptr.into()], false);
            let tr = lm.add_function(&format!("{name}$entry"), ft, Some(Linkage::External));
            let bb = cx.append_basic_block(tr, "entry");
            builder.position_at_end(bb);
            let args = tr
                .get_nth_param(0)
                .ok_or_else(|| LlvmError("trampoline without params".into()))?
                .into_pointer_value();
            let res = tr
                .get_nth_param(1)
                .ok_or_else(|| LlvmError("trampoline without params".into()))?
                .into_pointer_value();
            let slot = |base, i: usize| -> Result<_, LlvmError> {
                // SAFETY: a GEP over `i64` with one integer index is address arithmetic.
                unsafe {
                    builder.build_gep(
                        cx.i64_type(),
                        base,
                        &[cx.i64_type().const_int(i as u64, false)],
                        "",
                    )
                }
                .map_err(|e| LlvmError(e.to_string()))
            };
            let multi = translate::results_struct(cx, m, f).map_err(LlvmError)?;
            let mut vals: Vec<BasicMetadataValueEnum> = Vec::new();
            let out = match multi {
                Some(st) => {
                    let p = builder
                        .build_alloca(st, "results")
                        .map_err(|e| LlvmError(e.to_string()))?;
                    vals.push(p.into());
                    Some((p, st))
                }
                None => None,
            };
            for (i, &p) in m.funcs[f].params.iter().enumerate() {
                let t = llvm_type(cx, m, p).map_err(LlvmError)?;
                let at = slot(args, i)?;
                let v = load_slot(&builder, cx, t, at)?;
                vals.push(v.into());
            }
            let call = builder
                .build_call(callee, &vals, "")
                .map_err(|e| LlvmError(e.to_string()))?;
            let outs: Vec<BasicValueEnum> = match (out, call.try_as_basic_value()) {
                (Some((p, st)), _) => (0..st.count_fields())
                    .map(|i| {
                        let at = builder.build_struct_gep(st, p, i, "")?;
                        let ty = st.get_field_type_at_index(i).unwrap_or(cx.i8_type().into());
                        builder.build_load(ty, at, "")
                    })
                    .collect::<Result<_, _>>()
                    .map_err(|e| LlvmError(e.to_string()))?,
                (None, ValueKind::Basic(v)) if m.funcs[f].results.len() == 2 => (0..2)
                    .map(|i| builder.build_extract_value(v.into_struct_value(), i, ""))
                    .collect::<Result<_, _>>()
                    .map_err(|e| LlvmError(e.to_string()))?,
                (None, ValueKind::Basic(v)) => vec![v],
                (None, ValueKind::Instruction(_)) => Vec::new(),
            };
            for (i, o) in outs.into_iter().enumerate() {
                let at = slot(res, i)?;
                store_slot(&builder, cx, o, at)?;
            }
            builder
                .build_return(None)
                .map_err(|e| LlvmError(e.to_string()))?;
            trampolines.insert(name.clone(), tr);
        }
        // The host CPU's name and features on every function: MCJIT's own target machine
        // would compile for the baseline CPU.
        let (cpu, features) = target::jit_cpu();
        for f in lm.get_functions() {
            if f.count_basic_blocks() > 0 {
                f.add_attribute(
                    AttributeLoc::Function,
                    cx.create_string_attribute("target-cpu", &cpu),
                );
                f.add_attribute(
                    AttributeLoc::Function,
                    cx.create_string_attribute("target-features", &features),
                );
            }
        }
        lm.verify()
            .map_err(|e| LlvmError(format!("invalid LLVM module (a backend bug): {e}")))?;
        target::optimize(&lm, &tm, opt_level, false)?;
        let engine = lm
            .create_jit_execution_engine(target::llvm_level(opt_level))
            .map_err(|e| LlvmError(format!("JIT: {e}")))?;
        for &(name, addr) in symbols {
            if let Some(f) = lm.get_function(name) {
                engine.add_global_mapping(&f, addr as usize);
            }
        }
        let mut entries = HashMap::new();
        for &f in &m.func_order {
            if m.is_declaration(f) {
                continue;
            }
            let name = &m.funcs[f].name;
            if !trampolines.contains_key(name) {
                continue;
            }
            let addr = |sym: &str| {
                engine
                    .get_function_address(sym)
                    .map_err(|e| LlvmError(format!("JIT: no address for `{sym}`: {e}")))
            };
            let func = addr(&funcs[name].get_name().to_string_lossy())?;
            let entry = addr(&format!("{name}$entry"))?;
            let ty = |t: &scion_ir::TypeId| m.types.get(*t).clone();
            entries.insert(
                name.clone(),
                Entry {
                    func,
                    entry,
                    params: m.funcs[f].params.iter().map(ty).collect(),
                    results: m.funcs[f].results.iter().map(ty).collect(),
                },
            );
        }
        drop(lm);
        Ok(JitModule {
            entries,
            _engine: engine,
            _context: context,
        })
    }

    /// The machine-code address of `@name` (C calling convention of the host), if the module
    /// defines and exposes it (in a module with entry points, only those).
    /// A function with two results returns them as a struct of two (in two registers); one
    /// with more takes the address of a struct of them (C layout) as a hidden first parameter
    /// and returns nothing.
    pub fn get(&self, name: &str) -> Option<*const u8> {
        self.entries.get(name).map(|e| e.func as *const u8)
    }

    /// The same as [`JitModule::get`], under `scion_clif::JitModule`'s name.
    pub fn function_ptr(&self, name: &str) -> Option<*const u8> {
        self.get(name)
    }

    /// Calls `@name` on scalar arguments (`ptr` as a `u64` integer) and returns its results.
    /// The types of `args` must match the parameters (checked).
    pub fn call(&self, name: &str, args: &[Val]) -> Result<Vec<Val>, LlvmError> {
        let e = self.entries.get(name).ok_or_else(|| {
            LlvmError(format!(
                "no function `@{name}` (a module with entry points exposes only those)"
            ))
        })?;
        // SAFETY: `e.entry` is the address of the trampoline `name$entry`, compiled with the
        // signature `void (ptr, ptr)` in the host's C calling convention. It reads exactly
        // `params.len()` u64 slots from its first argument and writes `results.len()` slots
        // (at least one) through the second, as `call_through_slots` provides; the code lives
        // as long as `self`.
        let f: Trampoline = unsafe { std::mem::transmute(e.entry) };
        call_through_slots(name, &e.params, &e.results, args, f).map_err(LlvmError)
    }
}

/// Loads a value of type `t` from the low bytes of the `u64` slot at `at`.
fn load_slot<'c>(
    b: &inkwell::builder::Builder<'c>,
    cx: &'c Context,
    t: inkwell::types::BasicTypeEnum<'c>,
    at: inkwell::values::PointerValue<'c>,
) -> Result<BasicValueEnum<'c>, LlvmError> {
    let err = |e: inkwell::builder::BuilderError| LlvmError(e.to_string());
    if t.is_int_type() && t.into_int_type().get_bit_width() == 1 {
        let raw = b.build_load(cx.i8_type(), at, "").map_err(err)?;
        return Ok(b
            .build_int_truncate(raw.into_int_value(), cx.bool_type(), "")
            .map_err(err)?
            .into());
    }
    b.build_load(t, at, "").map_err(err)
}

/// Stores `v` to the `u64` slot at `at` (booleans as one byte).
fn store_slot<'c>(
    b: &inkwell::builder::Builder<'c>,
    cx: &'c Context,
    v: BasicValueEnum<'c>,
    at: inkwell::values::PointerValue<'c>,
) -> Result<(), LlvmError> {
    let err = |e: inkwell::builder::BuilderError| LlvmError(e.to_string());
    let v = if v.get_type().is_int_type() && v.into_int_value().get_type().get_bit_width() == 1 {
        b.build_int_z_extend(v.into_int_value(), cx.i8_type(), "")
            .map_err(err)?
            .into()
    } else {
        v
    };
    b.build_store(at, v).map_err(err)?;
    Ok(())
}

/// LLVM's JIT at an `-O` level as a [`scion_ir::backend::Backend`]: [`JitModule::compile`].
#[derive(Clone, Copy, Debug)]
pub struct Llvm {
    /// LLVM's pipeline `default<O{opt_level}>` (0 to 3).
    pub opt_level: u8,
}

impl scion_ir::backend::Backend for Llvm {
    fn name(&self) -> String {
        format!("llvm -O{}", self.opt_level)
    }

    fn jit(&self, m: &Module) -> Result<Box<dyn scion_ir::backend::JitCode>, String> {
        Ok(Box::new(
            JitModule::compile(m, self.opt_level).map_err(|e| e.to_string())?,
        ))
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
