//! `lo` to LLVM IR: one `lo` function to one LLVM function, one op to one instruction or a short
//! fixed sequence. Input: a verified `lo` module; output: an LLVM module (not yet optimized).
//!
//! Types: `i1` is LLVM `i1` (a byte holding 0 or 1 in memory); integers keep their width and
//! their signedness picks `sdiv`/`udiv`, `ashr`/`lshr`, signed or unsigned compares and
//! extensions; `ptr` is the opaque `ptr` of address space 0 (on NVPTX the generic space, which
//! covers global, local and shared memory). Two results are returned as a literal struct (in
//! two registers). More than two are returned through memory: the function gets a hidden first
//! parameter, the address of a caller-allocated struct of the results ([`results_struct`]),
//! and returns `void`. (A first-class struct return would put a third `f32` result in x87's
//! `st(0)` on x86-64, which quiets signaling NaNs; after inlining, SROA removes the memory
//! traffic.)
//!
//! Float semantics are those of `scion-clif` and the interpreters, bit for bit: no fast-math
//! flags (so LLVM never contracts `a*b+c`; `llvm.fma` only for `lo.fma`); a NaN produced by
//! `add sub mul div rem` is replaced by the canonical quiet NaN wherever its bits can be
//! observed ([`scion_ir::lo::nan`]: where it is defined, when some use sees the payload,
//! possibly through `min`/`max`/`select` and block arguments, which pass an operand's bits on); `min`/`max` are
//! compare-and-select (minNum/maxNum, first operand on ties; `llvm.minnum`'s zero and
//! signaling-NaN cases are looser, so it is used only against a constant neither NaN nor zero
//! with an arithmetic result, never a signaling NaN, as the other operand; two-lane ones go
//! back to compare-and-select on x86-64 after optimization, [`crate::clamps`]), a single
//! compare-and-select (`minss`) when an operand is known never to be NaN
//! ([`scion_ir::lo::nan::MinMaxForm`]); `rem` is `frem` (C `fmod`; an error on NVPTX, whose
//! `frem` is not exact); float-to-int casts are the
//! saturating `llvm.fpto[su]i.sat`; `next_up`/`next_down` step the bit pattern; directed rounding
//! (`lo.add_rd` ...) is `llvm.nvvm.{add,mul}.{rm,rp}.f` on NVPTX and, for CPUs, expanded into
//! round-to-nearest ops before translation (`scion_ir::lo::directed`). Integer
//! division never traps (by zero divides by 1, `MIN / -1` wraps) and shift amounts are taken
//! modulo the width, as in `scion-clif`. Loads and stores: on CPUs `align 1` (x86-64 and
//! AArch64 access unaligned scalars at full speed, so nothing is assumed); on NVPTX, where an
//! unaligned access would be split into bytes, the scalar's natural alignment, which the
//! layout model guarantees (members at their natural alignment, buffers aligned to the
//! plan's largest alignment; query and result records likewise, `backends.md` §1).
//!
//! Blocks are translated in reverse post-order, block arguments become `phi`s; `lo.stack_slot`
//! is an `alloca` in the entry block; `lo.global_id` reads `%ctaid.x * %ntid.x + %tid.x` and
//! exists only on NVPTX.

mod groups;
mod lanes;
mod scalar;

use crate::target::Target;
use inkwell::basic_block::BasicBlock;
use inkwell::builder::Builder;
use inkwell::context::Context;
use inkwell::intrinsics::Intrinsic;
use inkwell::module::{Linkage, Module as LModule};
use inkwell::types::{BasicMetadataTypeEnum, BasicType, BasicTypeEnum};
use inkwell::values::{
    BasicMetadataValueEnum, BasicValue, BasicValueEnum, FloatValue, FunctionValue, IntValue,
    PhiValue, PointerValue,
};
use inkwell::{FloatPredicate, IntPredicate};
use scion_ir::entity::{BlockId, FuncId, TypeId, ValueId};
use scion_ir::lo::backend::reverse_post_order;
use scion_ir::lo::nan::{MinMaxForm, NanFacts};
use scion_ir::lo::Op as L;
use scion_ir::op::OpKind;
use scion_ir::tree::CmpPred;
use scion_ir::types::{FloatTy, Type};
use scion_ir::Module;
use std::collections::HashMap;

/// The PTX kernel calling convention (`ptx_kernel`).
const PTX_KERNEL_CC: u32 = 71;

type R<T> = Result<T, String>;

fn be<E: std::fmt::Display>(e: E) -> String {
    format!("LLVM builder: {e}")
}

/// The LLVM type of a `lo` scalar type.
pub fn llvm_type<'c>(cx: &'c Context, m: &Module, ty: TypeId) -> R<BasicTypeEnum<'c>> {
    Ok(match m.types.get(ty) {
        Type::Bool => cx.bool_type().into(),
        Type::Int(t) => int_type(cx, t.bits()).into(),
        Type::Float(FloatTy::F32) => cx.f32_type().into(),
        Type::Float(FloatTy::F64) => cx.f64_type().into(),
        Type::Ptr => cx.ptr_type(Default::default()).into(),
        _ => return Err(format!("{} is not a lo type", m.types.display(ty))),
    })
}

/// The LLVM integer type of `bits` (1, 8, 16, 32 or 64) bits.
pub fn int_type(cx: &Context, bits: u32) -> inkwell::types::IntType<'_> {
    match bits {
        1 => cx.bool_type(),
        8 => cx.i8_type(),
        16 => cx.i16_type(),
        32 => cx.i32_type(),
        _ => cx.i64_type(),
    }
}

/// The struct of `f`'s results when it has more than two (returned through a hidden first
/// pointer parameter), else `None`.
pub fn results_struct<'c>(
    cx: &'c Context,
    m: &Module,
    f: FuncId,
) -> R<Option<inkwell::types::StructType<'c>>> {
    let results = &m.funcs[f].results;
    if results.len() <= 2 {
        return Ok(None);
    }
    let tys = results
        .iter()
        .map(|&r| llvm_type(cx, m, r))
        .collect::<R<Vec<_>>>()?;
    Ok(Some(cx.struct_type(&tys, false)))
}

/// True when some function of `m` carries the `export` attribute: then every other function
/// gets internal linkage (design note `backends.md` §1).
pub fn has_exports(m: &Module) -> bool {
    m.func_order
        .iter()
        .any(|&f| m.funcs[f].attrs.get("export").is_some())
}

/// The symbol of `lo` function `f` on `target`: its name, except that on NVPTX a name that is
/// not a PTX identifier (`intersects(Ray,AABB)`) of a non-exported function is spelled with
/// `_` for each other character and `_<index>` appended to keep it unique.
pub fn symbol(m: &Module, f: FuncId, index: usize, target: Target) -> String {
    let name = &m.funcs[f].name;
    let valid = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '$';
    if target != Target::Nvptx64
        || m.funcs[f].attrs.get("export").is_some()
        || (name.chars().all(valid) && !name.starts_with(|c: char| c.is_ascii_digit()))
    {
        return name.clone();
    }
    let mut s: String = name
        .chars()
        .map(|c| if valid(c) { c } else { '_' })
        .collect();
    s.push_str(&format!("_{index}"));
    s
}

/// Translates the verified `lo` module `m` into a fresh LLVM module named `name` for `target`.
/// Returns the module and each `lo` function's LLVM function, by `lo` name. `internalize`
/// applies the `export` rule (the JIT turns it off to reach every function).
pub fn translate<'c>(
    cx: &'c Context,
    m: &Module,
    name: &str,
    target: Target,
    internalize: bool,
) -> R<(LModule<'c>, HashMap<String, FunctionValue<'c>>)> {
    // CPUs round per instruction only through a global mode: expand directed rounding into
    // round-to-nearest ops; NVPTX keeps it for `add.rp.f32` and friends.
    let expanded;
    let m = if target == Target::Nvptx64 {
        m
    } else {
        expanded = scion_ir::lo::directed::expanded(m);
        &*expanded
    };
    let lm = cx.create_module(name);
    let exports = internalize && has_exports(m);
    let mut funcs = HashMap::new();
    for (i, &f) in m.func_order.iter().enumerate() {
        let func = &m.funcs[f];
        let multi = results_struct(cx, m, f)?;
        let mut params: Vec<BasicMetadataTypeEnum> = Vec::new();
        if multi.is_some() {
            params.push(cx.ptr_type(Default::default()).into());
        }
        for &p in &func.params {
            params.push(llvm_type(cx, m, p)?.into());
        }
        let fty = match func.results.as_slice() {
            [one] => llvm_type(cx, m, *one)?.fn_type(&params, false),
            [a, b] => cx
                .struct_type(&[llvm_type(cx, m, *a)?, llvm_type(cx, m, *b)?], false)
                .fn_type(&params, false),
            _ => cx.void_type().fn_type(&params, false),
        };
        let linkage = if exports && !m.is_declaration(f) && func.attrs.get("export").is_none() {
            Linkage::Internal
        } else {
            Linkage::External
        };
        let fv = lm.add_function(&symbol(m, f, i, target), fty, Some(linkage));
        // `noalias = [k, ...]`: no other pointer reaches what parameter `k` points to while the
        // function runs (the entry points' buffer table, queries and results, docs/c-abi.md),
        // so stores of results do not make LLVM reload the tree's buffer addresses.
        if let Some(scion_ir::attr::Attr::List(ks)) = func.attrs.get("noalias") {
            let kind = inkwell::attributes::Attribute::get_named_enum_kind_id("noalias");
            let shift = u32::from(multi.is_some());
            for k in ks.iter().filter_map(scion_ir::attr::Attr::as_int) {
                let attr = cx.create_enum_attribute(kind, 0);
                fv.add_attribute(
                    inkwell::attributes::AttributeLoc::Param(k as u32 + shift),
                    attr,
                );
            }
        }
        if target == Target::Nvptx64 && func.attrs.get("kernel").is_some() {
            if !func.results.is_empty() {
                return Err(format!(
                    "kernel @{} returns values; a PTX kernel returns nothing",
                    func.name
                ));
            }
            fv.set_call_conventions(PTX_KERNEL_CC);
        }
        funcs.insert(func.name.clone(), fv);
    }
    let builder = cx.create_builder();
    for &f in &m.func_order {
        if m.is_declaration(f) {
            continue;
        }
        let fv = funcs[&m.funcs[f].name];
        let mut t = Fn {
            cx,
            lm: &lm,
            b: &builder,
            m,
            target,
            fv,
            funcs: &funcs,
            ret: results_struct(cx, m, f)?,
            vals: HashMap::new(),
            blocks: HashMap::new(),
            phis: HashMap::new(),
            entry: None,
            nan: NanFacts::of(m, &m.regions[m.funcs[f].body].blocks),
            or_operands: lanes::or_operands(m, f),
            groups: if target == Target::Nvptx64 {
                HashMap::new()
            } else {
                groups::groups(m, &m.regions[m.funcs[f].body].blocks)
            },
            grouped: Default::default(),
            lane_vecs: HashMap::new(),
            layout_readonly: !scion_ir::lo::layout_reads::writes_layout(m, f),
        };
        t.grouped = t
            .groups
            .values()
            .flat_map(|g| g[1..].iter().copied())
            .collect();
        t.body(f)
            .map_err(|e| format!("@{}: {e}", m.funcs[f].name))?;
    }
    Ok((lm, funcs))
}

/// The translation state of one function.
struct Fn<'a, 'c> {
    cx: &'c Context,
    lm: &'a LModule<'c>,
    b: &'a Builder<'c>,
    m: &'a Module,
    target: Target,
    fv: FunctionValue<'c>,
    funcs: &'a HashMap<String, FunctionValue<'c>>,
    /// The struct of this function's results when it returns several (through parameter 0).
    ret: Option<inkwell::types::StructType<'c>>,
    vals: HashMap<ValueId, BasicValueEnum<'c>>,
    blocks: HashMap<BlockId, BasicBlock<'c>>,
    phis: HashMap<BlockId, Vec<PhiValue<'c>>>,
    /// The LLVM entry block (allocas go to its start).
    entry: Option<BasicBlock<'c>>,
    /// Which NaNs to canonicalize, which values are never NaN ([`scion_ir::lo::nan`]).
    nan: NanFacts,
    /// The values some `lo.or` of this function reads ([`lanes`]: an `or` among them is inside
    /// a tree of lane bits, not its root).
    or_operands: std::collections::HashSet<ValueId>,
    /// The source's vector operations, each one LLVM vector instruction ([`groups`]): the ops
    /// of each, keyed by the first.
    groups: HashMap<scion_ir::OpId, Vec<scion_ir::OpId>>,
    /// The ops of a group after its first (translated with it).
    grouped: std::collections::HashSet<scion_ir::OpId>,
    /// The lane of a vector instruction each grouped value is.
    lane_vecs: HashMap<ValueId, (inkwell::values::VectorValue<'c>, u32)>,
    /// Whether the function writes no layout buffer (so a load of one reads the same words
    /// wherever it is placed; [`groups`]).
    layout_readonly: bool,
}

impl<'c> Fn<'_, 'c> {
    fn body(&mut self, f: FuncId) -> R<()> {
        let m = self.m;
        let order = reverse_post_order(m, &m.regions[m.funcs[f].body].blocks);
        let Some(&lo_entry) = order.first() else {
            return Err("function without blocks".into());
        };
        // A branch back to the lo entry block needs a separate LLVM entry block (LLVM's entry
        // block has no predecessors): the parameters then flow in through the entry's phis.
        let entry_targeted = order.iter().any(|&b| {
            m.blocks[b]
                .ops
                .last()
                .is_some_and(|&o| m.ops[o].successors.iter().any(|s| s.block == lo_entry))
        });
        let prologue = entry_targeted.then(|| self.cx.append_basic_block(self.fv, "entry"));
        self.entry = prologue;
        for (i, &lb) in order.iter().enumerate() {
            let bb = self.cx.append_basic_block(self.fv, &format!("bb{i}"));
            self.blocks.insert(lb, bb);
            if self.entry.is_none() {
                self.entry = Some(bb);
            }
            let mut phis = Vec::new();
            if i > 0 || entry_targeted {
                self.b.position_at_end(bb);
                for &a in &m.blocks[lb].args {
                    let ty = llvm_type(self.cx, m, m.values[a].ty)?;
                    let phi = self.b.build_phi(ty, "").map_err(be)?;
                    self.vals.insert(a, phi.as_basic_value());
                    phis.push(phi);
                }
            } else {
                for (&a, p) in m.blocks[lb].args.iter().zip(self.params()) {
                    self.vals.insert(a, p);
                }
            }
            self.phis.insert(lb, phis);
        }
        if let Some(pro) = prologue {
            self.b.position_at_end(pro);
            let target = self.blocks[&lo_entry];
            for (phi, p) in self.phis[&lo_entry].iter().zip(self.params()) {
                phi.add_incoming(&[(&p, pro)]);
            }
            self.b.build_unconditional_branch(target).map_err(be)?;
        }
        for &lb in &order {
            self.b.position_at_end(self.blocks[&lb]);
            for &op in &m.blocks[lb].ops {
                self.op(op)?;
            }
        }
        Ok(())
    }

    /// The LLVM parameters that are `lo` parameters (without the hidden results pointer).
    fn params(&self) -> impl Iterator<Item = BasicValueEnum<'c>> {
        self.fv
            .get_param_iter()
            .skip(usize::from(self.ret.is_some()))
    }

    /// An `alloca` of `ty` at the start of the entry block.
    fn entry_alloca(&self, ty: BasicTypeEnum<'c>, align: u32) -> R<PointerValue<'c>> {
        let entry = self.entry.ok_or("no entry block")?;
        let at = self.cx.create_builder();
        match entry.get_first_instruction() {
            Some(i) => at.position_before(&i),
            None => at.position_at_end(entry),
        }
        let slot = at.build_alloca(ty, "slot").map_err(be)?;
        if let Some(i) = slot.as_instruction_value() {
            i.set_alignment(align).map_err(be)?;
        }
        Ok(slot)
    }

    fn v(&self, x: ValueId) -> R<BasicValueEnum<'c>> {
        self.vals
            .get(&x)
            .copied()
            .ok_or_else(|| "a value is used before its definition is translated".to_string())
    }

    fn signed(&self, x: ValueId) -> bool {
        self.m
            .types
            .as_int(self.m.values[x].ty)
            .is_some_and(|t| t.is_signed())
    }

    fn intrinsic(&self, name: &str, tys: &[BasicTypeEnum<'c>]) -> R<FunctionValue<'c>> {
        Intrinsic::find(name)
            .and_then(|i| i.get_declaration(self.lm, tys))
            .ok_or_else(|| format!("LLVM has no intrinsic {name}"))
    }

    fn call_intr(
        &self,
        name: &str,
        tys: &[BasicTypeEnum<'c>],
        args: &[BasicValueEnum<'c>],
    ) -> R<BasicValueEnum<'c>> {
        let f = self.intrinsic(name, tys)?;
        let args: Vec<BasicMetadataValueEnum> = args.iter().map(|&a| a.into()).collect();
        let call = self.b.build_call(f, &args, "").map_err(be)?;
        match call.try_as_basic_value() {
            inkwell::values::ValueKind::Basic(v) => Ok(v),
            inkwell::values::ValueKind::Instruction(_) => Err(format!("{name} returns nothing")),
        }
    }

    /// The alignment of a load or store of `t` (see the module docs).
    fn mem_align(&self, t: BasicTypeEnum<'c>) -> u32 {
        if self.target != Target::Nvptx64 {
            return 1;
        }
        match t {
            BasicTypeEnum::IntType(i) => i.get_bit_width().div_ceil(8),
            BasicTypeEnum::FloatType(f) => f.get_bit_width() / 8,
            _ => 8,
        }
    }

    /// `p + off` bytes.
    fn byte_offset(&self, p: PointerValue<'c>, off: IntValue<'c>) -> R<PointerValue<'c>> {
        #[allow(unsafe_code)]
        // SAFETY: a `getelementptr` without `inbounds` over `i8` is plain address arithmetic;
        // it is well defined for every pointer and offset (inkwell marks every GEP `unsafe`
        // because wrong index lists for aggregate types can crash LLVM, which cannot happen
        // with one integer index over `i8`).
        let q = unsafe { self.b.build_gep(self.cx.i8_type(), p, &[off], "") };
        q.map_err(be)
    }

    fn offset_ptr(&self, p: BasicValueEnum<'c>, off: i128) -> R<PointerValue<'c>> {
        let p = p.into_pointer_value();
        if off == 0 {
            return Ok(p);
        }
        self.byte_offset(p, self.cx.i64_type().const_int(off as i64 as u64, true))
    }

    fn op(&mut self, op: scion_ir::OpId) -> R<()> {
        if self.grouped.contains(&op) {
            return Ok(());
        }
        if let Some(ops) = self.groups.get(&op).cloned() {
            return self.group(&ops);
        }
        let m = self.m;
        let o = &m.ops[op];
        let OpKind::Lo(kind) = o.kind else {
            return Err(format!("`{}` is not a lo op", o.kind.name()));
        };
        let args: Vec<BasicValueEnum<'c>> =
            o.operands.iter().map(|&x| self.v(x)).collect::<R<_>>()?;
        let rty = match o.results.first() {
            Some(&r) => Some(llvm_type(self.cx, m, m.values[r].ty)?),
            None => None,
        };
        let ty = || rty.ok_or_else(|| "op without a result".to_string());
        let is_float = rty.is_some_and(|t| t.is_float_type());
        let signed = o.operands.first().is_some_and(|&x| self.signed(x));
        let b = self.b;
        let int = |i: usize| args[i].into_int_value();
        let flt = |i: usize| args[i].into_float_value();
        let out: Option<BasicValueEnum<'c>> = match kind {
            L::Const => {
                let t = ty()?;
                let a = o.attr("value").ok_or("constant without value")?;
                Some(match (a, t) {
                    (scion_ir::attr::Attr::Bool(x), BasicTypeEnum::IntType(it)) => {
                        it.const_int(u64::from(*x), false).into()
                    }
                    (scion_ir::attr::Attr::Int(v), BasicTypeEnum::IntType(it)) => {
                        it.const_int(*v as u64, false).into()
                    }
                    (scion_ir::attr::Attr::Int(v), BasicTypeEnum::PointerType(pt)) => b
                        .build_int_to_ptr(self.cx.i64_type().const_int(*v as u64, false), pt, "")
                        .map_err(be)?
                        .into(),
                    (scion_ir::attr::Attr::Float(bits), BasicTypeEnum::FloatType(ft)) => {
                        let raw = if ft.get_bit_width() == 32 {
                            u64::from((f64::from_bits(*bits) as f32).to_bits())
                        } else {
                            *bits
                        };
                        self.fconst(t, raw)?.into()
                    }
                    _ => return Err("bad constant".into()),
                })
            }
            L::Rem if is_float && self.target == Target::Nvptx64 => {
                // NVPTX lowers `frem` to `x - trunc(x / y) * y`, which is not C `fmod` (it
                // rounds the quotient): rejected rather than silently inexact.
                return Err(
                    "float `lo.rem` (C fmod) has no exact lowering on nvptx64 (LLVM's frem \
                     rounds the quotient)"
                        .into(),
                );
            }
            L::Add | L::Sub | L::Mul | L::Div | L::Rem if is_float => {
                let (x, y) = (flt(0), flt(1));
                let r = match kind {
                    L::Add => b.build_float_add(x, y, ""),
                    L::Sub => b.build_float_sub(x, y, ""),
                    L::Mul => b.build_float_mul(x, y, ""),
                    L::Div => b.build_float_div(x, y, ""),
                    _ => b.build_float_rem(x, y, ""),
                }
                .map_err(be)?;
                Some(self.canon_if_needed(o.results[0], r.into())?)
            }
            L::AddRd | L::AddRu | L::MulRd | L::MulRu => {
                // Only NVPTX gets here (elsewhere `translate` expanded them): PTX rounds per
                // instruction, `add.rm.f32` ... (non-ftz, so subnormals are kept).
                let name = match kind {
                    L::AddRd => "llvm.nvvm.add.rm.f",
                    L::AddRu => "llvm.nvvm.add.rp.f",
                    L::MulRd => "llvm.nvvm.mul.rm.f",
                    _ => "llvm.nvvm.mul.rp.f",
                };
                let r = self.call_intr(name, &[], &args)?;
                Some(self.canon_if_needed(o.results[0], r)?)
            }
            L::Add => Some(b.build_int_add(int(0), int(1), "").map_err(be)?.into()),
            L::Sub => Some(b.build_int_sub(int(0), int(1), "").map_err(be)?.into()),
            L::Mul => Some(b.build_int_mul(int(0), int(1), "").map_err(be)?.into()),
            L::Div | L::Rem => Some(self.int_div(kind == L::Div, signed, int(0), int(1))?.into()),
            L::And => Some(b.build_and(int(0), int(1), "").map_err(be)?.into()),
            L::Or => Some(match self.lane_bits(op)? {
                Some(bits) => bits,
                None => b.build_or(int(0), int(1), "").map_err(be)?.into(),
            }),
            L::Xor => Some(b.build_xor(int(0), int(1), "").map_err(be)?.into()),
            L::Shl | L::Shr => {
                let x = int(0);
                let t = x.get_type();
                let amt = b
                    .build_int_cast_sign_flag(int(1), t, false, "")
                    .map_err(be)?;
                let mask = t.const_int(u64::from(t.get_bit_width() - 1), false);
                let amt = b.build_and(amt, mask, "").map_err(be)?;
                Some(
                    match kind {
                        L::Shl => b.build_left_shift(x, amt, ""),
                        _ => b.build_right_shift(x, amt, signed, ""),
                    }
                    .map_err(be)?
                    .into(),
                )
            }
            L::BitNot | L::Not => Some(b.build_not(int(0), "").map_err(be)?.into()),
            L::Neg if is_float => Some(b.build_float_neg(flt(0), "").map_err(be)?.into()),
            L::Neg => Some(b.build_int_neg(int(0), "").map_err(be)?.into()),
            L::Abs if is_float => Some(self.call_intr("llvm.fabs", &[ty()?], &args)?),
            L::Abs if signed => {
                let no_poison = self.cx.bool_type().const_int(0, false).into();
                Some(self.call_intr("llvm.abs", &[ty()?], &[args[0], no_poison])?)
            }
            L::Abs => Some(args[0]),
            L::Sqrt => Some(self.call_intr("llvm.sqrt", &[ty()?], &args)?),
            L::Floor => Some(self.call_intr("llvm.floor", &[ty()?], &args)?),
            L::Ceil => Some(self.call_intr("llvm.ceil", &[ty()?], &args)?),
            L::Trunc => Some(self.call_intr("llvm.trunc", &[ty()?], &args)?),
            L::Fma => Some(self.call_intr("llvm.fma", &[ty()?], &args)?),
            L::Popcount | L::Clz | L::Ctz => {
                let t = args[0].get_type();
                let r = if kind == L::Popcount {
                    self.call_intr("llvm.ctpop", &[t], &args)?
                } else {
                    let name = if kind == L::Clz {
                        "llvm.ctlz"
                    } else {
                        "llvm.cttz"
                    };
                    let no_poison = self.cx.bool_type().const_int(0, false).into();
                    self.call_intr(name, &[t], &[args[0], no_poison])?
                };
                let rt = ty()?.into_int_type();
                Some(
                    b.build_int_cast_sign_flag(r.into_int_value(), rt, false, "")
                        .map_err(be)?
                        .into(),
                )
            }
            L::Min | L::Max => {
                let form = self.nan.min_max_form(o.operands[0], o.operands[1]);
                let quiet = self.m.def_op(o.operands[0]).is_some_and(|d| {
                    matches!(
                        self.m.ops[d].kind,
                        OpKind::Lo(L::Add | L::Sub | L::Mul | L::Div | L::Fma | L::Sqrt)
                    )
                });
                if form == MinMaxForm::SelectSwapped && quiet {
                    // `q` a constant neither NaN nor zero, `p` an arithmetic result (never a
                    // signaling NaN): `llvm.maxnum` is exactly maxNum here (no signed-zero
                    // tie, a NaN `p` gives `q`), one instruction on every target, and unlike
                    // the compare-and-select no pass rewrites it into a form the vectorizer
                    // splits (`fcmp one` and a select apart).
                    let name = if kind == L::Max {
                        "llvm.maxnum"
                    } else {
                        "llvm.minnum"
                    };
                    Some(self.call_intr(name, &[args[0].get_type()], &[args[0], args[1]])?)
                } else {
                    Some(self.min_max(kind == L::Max, args[0], args[1], signed, form)?)
                }
            }
            L::NextUp | L::NextDown => Some(self.next(kind == L::NextUp, flt(0))?),
            L::Cmp => {
                let pred = o.pred().ok_or("bad predicate")?;
                Some(self.compare(pred, args[0], args[1], signed)?.into())
            }
            L::Select => Some(match self.index_chain(op)? {
                Some(lane) => lane,
                None => b.build_select(int(0), args[1], args[2], "").map_err(be)?,
            }),
            L::Cast => {
                let from = m.values[o.operands[0]].ty;
                let to = m.values[o.results[0]].ty;
                Some(self.cast(args[0], from, to)?)
            }
            L::Bitcast => {
                let t = ty()?;
                Some(if args[0].get_type() == t {
                    args[0]
                } else {
                    b.build_bit_cast(args[0], t, "").map_err(be)?
                })
            }
            L::Load => {
                let p = self.offset_ptr(args[0], o.int_attr("offset").unwrap_or(0))?;
                let is_bool = matches!(m.types.get(m.values[o.results[0]].ty), Type::Bool);
                let lt: BasicTypeEnum = if is_bool {
                    self.cx.i8_type().into()
                } else {
                    ty()?
                };
                // A layout buffer's base on NVPTX is loaded as a global-space pointer and cast
                // to a generic one: the cast keeps the buffer's address space visible to
                // LLVM's address-space inference however later passes merge or hoist the load,
                // so the accesses derived from it become `ld.global`/`st.global`.
                let global_base = self.target == Target::Nvptx64
                    && o.attr("global") == Some(&scion_ir::attr::Attr::Bool(true));
                let load_ty: BasicTypeEnum = if global_base {
                    self.cx.ptr_type(inkwell::AddressSpace::from(1u16)).into()
                } else {
                    lt
                };
                let v = b.build_load(load_ty, p, "").map_err(be)?;
                if let Some(i) = v.as_instruction_value() {
                    i.set_alignment(self.mem_align(lt)).map_err(be)?;
                }
                Some(if is_bool {
                    let zero = self.cx.i8_type().const_zero();
                    b.build_int_compare(IntPredicate::NE, v.into_int_value(), zero, "")
                        .map_err(be)?
                        .into()
                } else if global_base {
                    b.build_address_space_cast(v.into_pointer_value(), lt.into_pointer_type(), "")
                        .map_err(be)?
                        .into()
                } else {
                    v
                })
            }
            L::Store => {
                let p = self.offset_ptr(args[0], o.int_attr("offset").unwrap_or(0))?;
                let mut v = args[1];
                if matches!(m.types.get(m.values[o.operands[1]].ty), Type::Bool) {
                    v = b
                        .build_int_z_extend(v.into_int_value(), self.cx.i8_type(), "")
                        .map_err(be)?
                        .into();
                }
                let st = b.build_store(p, v).map_err(be)?;
                st.set_alignment(self.mem_align(v.get_type())).map_err(be)?;
                None
            }
            L::PtrAdd => {
                let off_signed = self.signed(o.operands[1]);
                let off = b
                    .build_int_cast_sign_flag(int(1), self.cx.i64_type(), off_signed, "")
                    .map_err(be)?;
                Some(self.byte_offset(args[0].into_pointer_value(), off)?.into())
            }
            L::GlobalId => Some(self.global_id()?.into()),
            L::StackSlot => {
                let size = o.int_attr("size").unwrap_or(1).max(1) as u32;
                let align = o.int_attr("align").unwrap_or(8).max(1) as u32;
                let ty = self.cx.i8_type().array_type(size).into();
                Some(self.entry_alloca(ty, align)?.into())
            }
            L::Call => {
                let callee = o.callee().ok_or("call without callee")?;
                let f = *self
                    .funcs
                    .get(callee)
                    .ok_or_else(|| format!("unknown callee @{callee}"))?;
                let fid = m.func_by_name(callee).ok_or("unknown callee")?;
                let multi = results_struct(self.cx, m, fid)?;
                let mut cargs: Vec<BasicMetadataValueEnum> = Vec::new();
                let out = match multi {
                    Some(st) => {
                        let p = self.entry_alloca(st.into(), 8)?;
                        cargs.push(p.into());
                        Some((p, st))
                    }
                    None => None,
                };
                cargs.extend(args.iter().map(|&a| BasicMetadataValueEnum::from(a)));
                let call = b.build_call(f, &cargs, "").map_err(be)?;
                call.set_call_convention(f.get_call_conventions());
                match (out, call.try_as_basic_value()) {
                    (Some((p, st)), _) => {
                        for (i, &r) in o.results.iter().enumerate() {
                            let at = b.build_struct_gep(st, p, i as u32, "").map_err(be)?;
                            let ty = st
                                .get_field_type_at_index(i as u32)
                                .ok_or("results struct too short")?;
                            let v = b.build_load(ty, at, "").map_err(be)?;
                            self.vals.insert(r, v);
                        }
                    }
                    (None, inkwell::values::ValueKind::Basic(v)) if o.results.len() == 2 => {
                        for (i, &r) in o.results.iter().enumerate() {
                            let e = b
                                .build_extract_value(v.into_struct_value(), i as u32, "")
                                .map_err(be)?;
                            self.vals.insert(r, e);
                        }
                    }
                    (None, inkwell::values::ValueKind::Basic(v)) => {
                        if let Some(&r) = o.results.first() {
                            self.vals.insert(r, v);
                        }
                    }
                    (None, inkwell::values::ValueKind::Instruction(_)) => {}
                }
                None
            }
            L::Br => {
                let t = self.edge(op, 0)?;
                b.build_unconditional_branch(t).map_err(be)?;
                None
            }
            L::CondBr => {
                let t = self.edge(op, 0)?;
                let e = if o.successors[0].block == o.successors[1].block {
                    // Two edges to one block would need two phi entries from one predecessor:
                    // the else edge goes through a block of its own.
                    let from = b.get_insert_block().ok_or("builder without a block")?;
                    let split = self.cx.append_basic_block(self.fv, "split");
                    b.position_at_end(split);
                    let e = self.edge(op, 1)?;
                    b.build_unconditional_branch(e).map_err(be)?;
                    b.position_at_end(from);
                    split
                } else {
                    self.edge(op, 1)?
                };
                b.build_conditional_branch(int(0), t, e).map_err(be)?;
                None
            }
            L::Return => {
                match (self.ret, args.as_slice()) {
                    (Some(st), many) => {
                        let p = self
                            .fv
                            .get_nth_param(0)
                            .ok_or("no results pointer")?
                            .into_pointer_value();
                        for (i, v) in many.iter().enumerate() {
                            let at = b.build_struct_gep(st, p, i as u32, "").map_err(be)?;
                            b.build_store(at, *v).map_err(be)?;
                        }
                        b.build_return(None)
                    }
                    (None, [one]) => b.build_return(Some(one)),
                    (None, [_, _]) => b.build_aggregate_return(&args),
                    (None, _) => b.build_return(None),
                }
                .map_err(be)?;
                None
            }
        };
        if let (Some(v), Some(&r)) = (out, o.results.first()) {
            self.vals.insert(r, v);
        }
        Ok(())
    }

    /// Adds the successor `i` of branch `op`'s arguments to its target's phis (coming from the
    /// builder's current block) and returns the target.
    fn edge(&self, op: scion_ir::OpId, i: usize) -> R<BasicBlock<'c>> {
        let s = &self.m.ops[op].successors[i];
        let target = *self
            .blocks
            .get(&s.block)
            .ok_or("branch to a missing block")?;
        let from = self.b.get_insert_block().ok_or("builder without a block")?;
        for (phi, &a) in self.phis[&s.block].iter().zip(&s.args) {
            let v = self.v(a)?;
            phi.add_incoming(&[(&v, from)]);
        }
        Ok(target)
    }
}
