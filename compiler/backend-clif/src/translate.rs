//! `lo` to Cranelift IR, one op to one (or a few) instructions, through `FunctionBuilder`.
//!
//! Types: `i1` is `i8` holding 0 or 1; integers keep their width (signedness picks `sdiv`/`udiv`,
//! `sshr`/`ushr`, signed or unsigned compares and extensions); `ptr` is the target's pointer
//! type. Float semantics match the interpreters bit for bit: arithmetic rounds to nearest in
//! the value's own precision; a NaN produced by `add sub mul div rem` is replaced by the
//! canonical quiet NaN (as [`scion_ir::tree::scalar`] does) wherever its bits can be observed
//! ([`scion_ir::lo::nan`]: where it is defined, when some use sees the payload, possibly through
//! `min`/`max`/`select` and block arguments, which pass an operand's bits on); Cranelift never contracts
//! `a*b+c`, and `fma` is emitted only for `lo.fma`; `min`/`max` are compare-and-select
//! (Cranelift's `fmin`/`fmax` propagate NaN, `lo` wants the non-NaN operand), one `minss`/`maxss`
//! when an operand is known never to be NaN ([`scion_ir::lo::nan::MinMaxForm`]); `rem` calls the C library's
//! `fmodf`/`fmod`; `next_up`/`next_down` step the bit pattern; directed rounding (`lo.add_rd`
//! ...) was expanded into round-to-nearest ops by the callers ([`scion_ir::lo::directed`]).
//! Blocks are translated in reverse
//! post-order so every definition is translated before its uses; a block entered by one branch
//! takes that branch's values as its arguments (no block parameters). The rest of an op's
//! translation lives beside this file: the multi-instruction scalar ops in [`crate::arith`],
//! the four-lane vector groups, their reductions and a float `select` without a branch in
//! [`crate::lanes`], the if-conversion of short diamonds in [`crate::ifconv`].

use cranelift_codegen::ir::condcodes::{FloatCC, IntCC};
use cranelift_codegen::ir::immediates::{Ieee32, Ieee64};
use cranelift_codegen::ir::{
    self, types, AbiParam, BlockArg, InstBuilder, MemFlags, Signature, StackSlotData, StackSlotKind,
};
use cranelift_frontend::{FunctionBuilder, FunctionBuilderContext};
use cranelift_module::{FuncId as ClFuncId, Linkage, Module as ClModule};
use scion_ir::entity::{BlockId, FuncId, TypeId, ValueId};
use scion_ir::lo::backend::reverse_post_order;
use scion_ir::lo::nan::NanFacts;
use scion_ir::lo::Op as L;
use scion_ir::op::OpKind;
use scion_ir::tree::CmpPred;
use scion_ir::types::{FloatTy, IntTy, Type};
use scion_ir::Module;
use std::collections::{HashMap, HashSet};

/// The Cranelift type of a `lo` type.
pub fn clif_type(m: &Module, ty: TypeId, ptr: ir::Type) -> Result<ir::Type, String> {
    Ok(match m.types.get(ty) {
        Type::Bool => types::I8,
        Type::Int(t) => match t.bits() {
            8 => types::I8,
            16 => types::I16,
            32 => types::I32,
            _ => types::I64,
        },
        Type::Float(FloatTy::F32) => types::F32,
        Type::Float(FloatTy::F64) => types::F64,
        Type::Ptr => ptr,
        _ => return Err(format!("{} is not a lo type", m.types.display(ty))),
    })
}

/// The Cranelift condition of a float `lo.cmp` (ordered, but `ne`), scalar or lane by lane.
pub(crate) fn float_cc(pred: CmpPred) -> FloatCC {
    match pred {
        CmpPred::Eq => FloatCC::Equal,
        CmpPred::Ne => FloatCC::NotEqual,
        CmpPred::Lt => FloatCC::LessThan,
        CmpPred::Le => FloatCC::LessThanOrEqual,
        CmpPred::Gt => FloatCC::GreaterThan,
        CmpPred::Ge => FloatCC::GreaterThanOrEqual,
    }
}

/// The Cranelift condition of an integer `lo.cmp` on operands of the given signedness.
pub(crate) fn int_cc(pred: CmpPred, signed: bool) -> IntCC {
    match (pred, signed) {
        (CmpPred::Eq, _) => IntCC::Equal,
        (CmpPred::Ne, _) => IntCC::NotEqual,
        (CmpPred::Lt, true) => IntCC::SignedLessThan,
        (CmpPred::Le, true) => IntCC::SignedLessThanOrEqual,
        (CmpPred::Gt, true) => IntCC::SignedGreaterThan,
        (CmpPred::Ge, true) => IntCC::SignedGreaterThanOrEqual,
        (CmpPred::Lt, false) => IntCC::UnsignedLessThan,
        (CmpPred::Le, false) => IntCC::UnsignedLessThanOrEqual,
        (CmpPred::Gt, false) => IntCC::UnsignedGreaterThan,
        (CmpPred::Ge, false) => IntCC::UnsignedGreaterThanOrEqual,
    }
}

/// The Cranelift signature of function `f`.
pub fn signature<M: ClModule>(cl: &M, m: &Module, f: FuncId) -> Result<Signature, String> {
    let ptr = cl.target_config().pointer_type();
    let mut sig = cl.make_signature();
    for &p in &m.funcs[f].params {
        sig.params.push(AbiParam::new(clif_type(m, p, ptr)?));
    }
    for &r in &m.funcs[f].results {
        sig.returns.push(AbiParam::new(clif_type(m, r, ptr)?));
    }
    Ok(sig)
}

/// Declares every function of `m` in `cl` (declarations imported), and the C library's
/// `fmodf`/`fmod` for float `rem`. Definitions are exported, except that when any function
/// carries the attribute `export` (the C entry points of docs/design/backends.md §1) only
/// those are, and every other definition is `Local`.
pub fn declare_all<M: ClModule>(cl: &mut M, m: &Module) -> Result<Symbols, String> {
    let mut funcs = HashMap::new();
    let exports_only = m
        .func_order
        .iter()
        .any(|&f| m.funcs[f].attrs.get("export").is_some());
    for &f in &m.func_order {
        let sig = signature(cl, m, f)?;
        let linkage = if m.is_declaration(f) {
            Linkage::Import
        } else if exports_only && m.funcs[f].attrs.get("export").is_none() {
            Linkage::Local
        } else {
            Linkage::Export
        };
        let id = cl
            .declare_function(&m.funcs[f].name, linkage, &sig)
            .map_err(|e| e.to_string())?;
        funcs.insert(m.funcs[f].name.clone(), id);
    }
    let mut fmod = |name: &str, t: ir::Type| -> Result<ClFuncId, String> {
        let mut sig = cl.make_signature();
        sig.params.push(AbiParam::new(t));
        sig.params.push(AbiParam::new(t));
        sig.returns.push(AbiParam::new(t));
        cl.declare_function(name, Linkage::Import, &sig)
            .map_err(|e| e.to_string())
    };
    let fmodf = fmod("fmodf", types::F32)?;
    let fmod64 = fmod("fmod", types::F64)?;
    Ok(Symbols {
        funcs,
        fmodf,
        fmod: fmod64,
    })
}

/// The Cranelift ids of a module's functions and helpers.
pub struct Symbols {
    /// Each `lo` function by name.
    pub funcs: HashMap<String, ClFuncId>,
    fmodf: ClFuncId,
    fmod: ClFuncId,
}

/// Builds the body of `lo` function `f` into `func` (whose signature is set).
pub fn translate_func<M: ClModule>(
    cl: &mut M,
    syms: &Symbols,
    m: &Module,
    f: FuncId,
    func: &mut ir::Function,
    fctx: &mut FunctionBuilderContext,
) -> Result<(), String> {
    let ptr = cl.target_config().pointer_type();
    let mut b = FunctionBuilder::new(func, fctx);
    let body = &m.regions[m.funcs[f].body].blocks;
    let order = reverse_post_order(m, body);
    let mut blocks = HashMap::new();
    let mut vals: HashMap<ValueId, ir::Value> = HashMap::new();
    let nan = NanFacts::of(m, body);
    let groups = crate::lanes::groups(m, body);
    // The groups' vectors, kept across blocks: a lane used in another block is defined in one
    // that dominates it (translated first, in reverse post-order), and so is its vector.
    let mut lane_vecs = HashMap::new();
    let mut lane_sets = HashMap::new();
    let preds = crate::ifconv::predecessors(m, f);
    // Blocks entered by one branch only take their arguments as the branch's values, bound when
    // the branch is translated (its block dominates them): no Cranelift parameters, so a value
    // passed along but not used there (a leaf's 36 triangle floats into the inlined
    // `nearest_lane`) is not kept alive to the jump, and lanes keep their vectors.
    let direct: HashSet<BlockId> = order
        .iter()
        .skip(1)
        .filter(|b| preds.get(b) == Some(&1))
        .copied()
        .collect();
    let mut vector_params = crate::lanes::vector_params(m, body, &groups);
    vector_params.retain(|b, _| !direct.contains(b));
    let no_runs: Vec<usize> = Vec::new();
    // Blocks an if-conversion computed inline: unreachable, so not translated (their values
    // are the inline ones).
    let mut converted = HashSet::new();
    let dead = crate::lanes::dead_direct_params(m, f, &direct);
    let deferrable = crate::loads::deferrable_loads(m, f, &groups, &direct, &dead);
    let pure_loads = crate::loads::pure_loads(m, f, &deferrable);
    let mut load_of: HashMap<ValueId, scion_ir::OpId> = HashMap::new();
    // Deferred loads still pending at a jump into a block entered by that jump alone, for that
    // block (see `Fx::op`).
    let mut carried: HashMap<BlockId, Vec<(ValueId, scion_ir::OpId)>> = HashMap::new();
    let position: HashMap<BlockId, usize> =
        order.iter().enumerate().map(|(i, &b)| (b, i)).collect();
    for (i, &lb) in order.iter().enumerate() {
        let cb = b.create_block();
        if i == 0 {
            b.append_block_params_for_function_params(cb);
        } else if !direct.contains(&lb) {
            let runs = vector_params.get(&lb).unwrap_or(&no_runs);
            let args = &m.blocks[lb].args;
            let mut j = 0;
            while j < args.len() {
                let ty = m.values[args[j]].ty;
                if runs.contains(&j) {
                    let vt = crate::lanes::param_vector_type(m, ty).ok_or("a vector run's type")?;
                    b.append_block_param(cb, vt);
                    j += 4;
                } else {
                    b.append_block_param(cb, clif_type(m, ty, ptr)?);
                    j += 1;
                }
            }
        }
        blocks.insert(lb, cb);
    }
    for (i, &lb) in order.iter().enumerate() {
        if converted.contains(&lb) {
            continue;
        }
        let cb = blocks[&lb];
        b.switch_to_block(cb);
        let params = b.block_params(cb).to_vec();
        let mut fx = Fx {
            b: &mut b,
            m,
            ptr,
            vals: &mut vals,
            nan: &nan,
            groups: &groups,
            grouped: HashSet::new(),
            lane_vecs: &mut lane_vecs,
            lane_sets: &mut lane_sets,
            vector_params: &vector_params,
            preds: &preds,
            converted: &mut converted,
            deferrable: &deferrable,
            deferred: carried.remove(&lb).unwrap_or_default(),
            carried: &mut carried,
            carried_params: HashSet::new(),
            dead: &dead,
            pure_loads: &pure_loads,
            loaded_vectors: HashMap::new(),
            load_of: &mut load_of,
            position: &position,
            direct: &direct,
        };
        let runs = match i {
            0 => &no_runs,
            _ => vector_params.get(&lb).unwrap_or(&no_runs),
        };
        if !direct.contains(&lb) {
            fx.bind_params(&m.blocks[lb].args, runs, &params)?;
        }
        for &op in &m.blocks[lb].ops {
            fx.op(cl, syms, op, &blocks)?;
        }
    }
    if !carried.is_empty() {
        return Err("deferred loads carried into a block that was not translated".into());
    }
    b.seal_all_blocks();
    b.finalize();
    Ok(())
}

pub(crate) struct Fx<'a, 'b> {
    pub(crate) b: &'a mut FunctionBuilder<'b>,
    pub(crate) m: &'a Module,
    ptr: ir::Type,
    pub(crate) vals: &'a mut HashMap<ValueId, ir::Value>,
    /// Which NaNs to canonicalize, which values are never NaN ([`scion_ir::lo::nan`]).
    pub(crate) nan: &'a NanFacts,
    /// The function's lane groups ([`crate::lanes`]), keyed by their first op.
    groups: &'a HashMap<scion_ir::OpId, Vec<scion_ir::OpId>>,
    /// The other ops of the groups met so far in this block (translated with their first).
    grouped: HashSet<scion_ir::OpId>,
    /// The vector and lane of each value a group defined.
    pub(crate) lane_vecs: &'a mut HashMap<ValueId, (ir::Value, u8)>,
    /// Booleans that are the `and` or the `or` of some lanes of one mask vector: the vector,
    /// the lanes (bits), and whether it is an `and` ([`crate::lanes`], "reductions").
    pub(crate) lane_sets: &'a mut HashMap<ValueId, (ir::Value, u8, bool)>,
    /// The runs of block arguments passed as one vector ([`crate::lanes::vector_params`]).
    vector_params: &'a HashMap<BlockId, Vec<usize>>,
    /// The number of branch edges into each block ([`crate::ifconv`]).
    pub(crate) preds: &'a HashMap<BlockId, usize>,
    /// The blocks if-conversions computed inline ([`crate::ifconv`]).
    pub(crate) converted: &'a mut HashSet<BlockId>,
    /// Loads whose one use is a lane of a vector group ([`crate::loads::deferrable_loads`]).
    deferrable: &'a HashSet<scion_ir::OpId>,
    /// Such loads of this block not emitted yet, in order, with their results.
    pub(crate) deferred: Vec<(ValueId, scion_ir::OpId)>,
    /// Deferred loads passed on at a jump, by the block jumped to, each under the name it
    /// has there (the parameter it is passed as, or its own result).
    carried: &'a mut HashMap<BlockId, Vec<(ValueId, scion_ir::OpId)>>,
    /// The parameters of the block this block jumps to that are carried loads (bound when the
    /// load is emitted there, not at the jump).
    carried_params: HashSet<ValueId>,
    /// Parameters of direct blocks that nothing reads ([`crate::lanes::dead_direct_params`]).
    dead: &'a HashSet<ValueId>,
    /// Loads of layout buffers Cranelift may move ([`crate::loads::pure_loads`]).
    pub(crate) pure_loads: &'a HashSet<scion_ir::OpId>,
    /// Each block's place in the translation order.
    position: &'a HashMap<BlockId, usize>,
    /// Blocks whose arguments are bound at their one branch ([`translate_func`]).
    direct: &'a HashSet<BlockId>,
    /// The vector loads of the lane group being translated, by the lanes they load
    /// ([`Fx::vector_load`]).
    pub(crate) loaded_vectors: HashMap<Vec<ValueId>, ir::Value>,
    /// The load each emitted deferred load's name (its result, or the parameter it was carried
    /// as) stands for.
    pub(crate) load_of: &'a mut HashMap<ValueId, scion_ir::OpId>,
}

impl Fx<'_, '_> {
    /// Binds the argument `param` of a block entered by one branch to `v`, the value of `x`
    /// (with its vector lane, if it has one) when the argument is a `lo` value.
    pub(crate) fn bind_direct(&mut self, param: ValueId, v: ir::Value, x: Option<ValueId>) {
        self.vals.insert(param, v);
        match x.and_then(|x| self.lane_vecs.get(&x).copied()) {
            Some(lv) => self.lane_vecs.insert(param, lv),
            None => self.lane_vecs.remove(&param),
        };
        match x.and_then(|x| self.lane_sets.get(&x).copied()) {
            Some(ls) => self.lane_sets.insert(param, ls),
            None => self.lane_sets.remove(&param),
        };
    }

    /// Whether block `b` is entered by one branch (its arguments bound there).
    pub(crate) fn is_direct(&self, b: BlockId) -> bool {
        self.direct.contains(&b)
    }

    /// Whether block `b` takes a run of its arguments as one vector.
    pub(crate) fn has_vector_params(&self, b: BlockId) -> bool {
        self.vector_params.get(&b).is_some_and(|r| !r.is_empty())
    }

    pub(crate) fn v(&self, x: ValueId) -> Result<ir::Value, String> {
        self.vals
            .get(&x)
            .copied()
            .ok_or_else(|| "a value is used before its definition is translated".to_string())
    }

    fn int_ty(&self, x: ValueId) -> Option<IntTy> {
        self.m.types.as_int(self.m.values[x].ty)
    }

    pub(crate) fn cty(&self, ty: TypeId) -> Result<ir::Type, String> {
        clif_type(self.m, ty, self.ptr)
    }

    /// `r` (the value of `lo` value `x`), canonicalized when [`NanFacts::canonicalize`] says so.
    fn canon_if_needed(&mut self, x: ValueId, r: ir::Value) -> ir::Value {
        if self.nan.canonicalize(x) {
            let t = self.b.func.dfg.value_type(r);
            self.canon(r, t)
        } else {
            r
        }
    }

    /// The canonical quiet NaN in place of any NaN `v`.
    fn canon(&mut self, v: ir::Value, t: ir::Type) -> ir::Value {
        let nan = self.b.ins().fcmp(FloatCC::Unordered, v, v);
        let c = if t == types::F32 {
            self.b.ins().f32const(Ieee32::with_bits(0x7fc0_0000))
        } else {
            self.b
                .ins()
                .f64const(Ieee64::with_bits(scion_ir::attr::CANONICAL_NAN_BITS))
        };
        self.b.ins().select(nan, c, v)
    }

    pub(crate) fn op<M: ClModule>(
        &mut self,
        cl: &mut M,
        syms: &Symbols,
        op: scion_ir::OpId,
        blocks: &HashMap<BlockId, ir::Block>,
    ) -> Result<(), String> {
        if self.grouped.contains(&op) {
            return Ok(());
        }
        let m = self.m;
        if self.deferrable.contains(&op) {
            self.deferred.push((m.ops[op].results[0], op));
            return Ok(());
        }
        if let Some(ops) = self.groups.get(&op) {
            // The group's deferred loads, just before it: four lanes that read consecutive
            // words from one address as one vector load, or one word of four records as a
            // column of their transposed rows ([`crate::transpose`]).
            for j in 0..m.ops[op].operands.len() {
                let xs: Vec<ValueId> = ops.iter().map(|&o| m.ops[o].operands[j]).collect();
                self.vector_load(&xs)?;
                self.transposed_load(&xs)?;
            }
            for &o in ops {
                for &x in &m.ops[o].operands {
                    if let Some(i) = self.deferred.iter().position(|d| d.0 == x) {
                        let (name, load) = self.deferred.remove(i);
                        self.emit_deferred(cl, syms, name, load, blocks)?;
                    }
                }
            }
            self.grouped.extend(ops[1..].iter().copied());
            let vectorized = self.group(ops)?;
            self.loaded_vectors.clear();
            if vectorized {
                return Ok(());
            }
            for &o in ops {
                self.scalar_op(cl, syms, o, blocks)?;
            }
            return Ok(());
        }
        // Anything else that reads a deferred load, or writes memory, or leaves the block:
        // the deferred loads first, in their order.
        let o = &m.ops[op];
        let effect = matches!(
            o.kind,
            OpKind::Lo(L::Store | L::Call | L::Br | L::CondBr | L::Return)
        );
        // A jump into a block that only it enters (translated later, in reverse post-order)
        // passes them on, renamed to the parameters they are passed as: the chain of blocks
        // an inlined call leaves between a leaf's loads and the lanes that gather them.
        if o.kind == OpKind::Lo(L::Br) && !self.deferred.is_empty() {
            let s = &o.successors[0];
            let here = o.parent.and_then(|b| self.position.get(&b));
            if self.direct.contains(&s.block)
                && here.is_some_and(|h| self.position.get(&s.block).is_some_and(|t| t > h))
            {
                let mut pending = std::mem::take(&mut self.deferred);
                let params = &m.blocks[s.block].args;
                for d in &mut pending {
                    // The live parameter it is passed as (a dead one binds nothing).
                    let live = s
                        .args
                        .iter()
                        .zip(params)
                        .find(|(&x, p)| x == d.0 && !self.dead.contains(p));
                    if let Some((_, &p)) = live {
                        d.0 = p;
                        self.carried_params.insert(p);
                    }
                }
                self.carried.insert(s.block, pending);
            }
        }
        if !self.deferred.is_empty()
            && (effect
                || o.operands
                    .iter()
                    .any(|x| self.deferred.iter().any(|d| d.0 == *x)))
        {
            for (name, load) in std::mem::take(&mut self.deferred) {
                self.emit_deferred(cl, syms, name, load, blocks)?;
            }
        }
        self.scalar_op(cl, syms, op, blocks)
    }

    /// `op` translated on its own, one lane's scalar op for the ops of a lane group.
    pub(crate) fn scalar_op<M: ClModule>(
        &mut self,
        cl: &mut M,
        syms: &Symbols,
        op: scion_ir::OpId,
        blocks: &HashMap<BlockId, ir::Block>,
    ) -> Result<(), String> {
        let m = self.m;
        let o = &m.ops[op];
        let OpKind::Lo(kind) = o.kind else {
            return Err(format!("`{}` is not a lo op", o.kind.name()));
        };
        if kind == L::CondBr && self.if_convert(cl, syms, op, blocks)? {
            return Ok(());
        }
        let args: Vec<ir::Value> = o
            .operands
            .iter()
            .map(|&x| self.v(x))
            .collect::<Result<_, _>>()?;
        let rty = o.results.first().map(|&r| m.values[r].ty);
        let rct = match rty {
            Some(t) => Some(self.cty(t)?),
            None => None,
        };
        let ct = || rct.ok_or_else(|| "op without a result".to_string());
        let is_float = |t: ir::Type| t == types::F32 || t == types::F64;
        let signed = o
            .operands
            .first()
            .and_then(|&x| self.int_ty(x))
            .is_some_and(|t| t.is_signed());
        let out: Option<ir::Value> = match kind {
            L::Const => {
                let t = ct()?;
                let a = o.attr("value").ok_or("constant without value")?;
                Some(match a {
                    scion_ir::attr::Attr::Bool(x) => self.b.ins().iconst(t, i64::from(*x)),
                    scion_ir::attr::Attr::Int(v) => {
                        let bits = t.bits();
                        let raw = if bits >= 64 {
                            *v as u64
                        } else {
                            (*v as u64) & ((1u64 << bits) - 1)
                        };
                        self.b.ins().iconst(t, raw as i64)
                    }
                    scion_ir::attr::Attr::Float(bits) => {
                        let x = f64::from_bits(*bits);
                        if t == types::F32 {
                            self.b
                                .ins()
                                .f32const(Ieee32::with_bits((x as f32).to_bits()))
                        } else {
                            self.b.ins().f64const(Ieee64::with_bits(*bits))
                        }
                    }
                    _ => return Err("bad constant".into()),
                })
            }
            L::Add | L::Sub | L::Mul | L::Div | L::Rem if is_float(ct()?) => {
                let t = ct()?;
                let (x, y) = (args[0], args[1]);
                let r = match kind {
                    L::Add => self.b.ins().fadd(x, y),
                    L::Sub => self.b.ins().fsub(x, y),
                    L::Mul => self.b.ins().fmul(x, y),
                    L::Div => self.b.ins().fdiv(x, y),
                    _ => {
                        let id = if t == types::F32 {
                            syms.fmodf
                        } else {
                            syms.fmod
                        };
                        let fref = cl.declare_func_in_func(id, self.b.func);
                        let call = self.b.ins().call(fref, &[x, y]);
                        self.b.inst_results(call)[0]
                    }
                };
                Some(self.canon_if_needed(o.results[0], r))
            }
            L::Add => Some(self.b.ins().iadd(args[0], args[1])),
            L::Sub => Some(self.b.ins().isub(args[0], args[1])),
            L::Mul => Some(self.b.ins().imul(args[0], args[1])),
            L::Div | L::Rem => Some(self.int_div(kind == L::Div, signed, args[0], args[1])),
            L::And | L::Or => Some(match self.lane_reduction(op)? {
                Some(v) => v,
                None if kind == L::And => self.b.ins().band(args[0], args[1]),
                None => self.b.ins().bor(args[0], args[1]),
            }),
            L::Xor => Some(self.b.ins().bxor(args[0], args[1])),
            L::Shl => Some(self.b.ins().ishl(args[0], args[1])),
            L::Shr if signed => Some(self.b.ins().sshr(args[0], args[1])),
            L::Shr => Some(self.b.ins().ushr(args[0], args[1])),
            L::BitNot => Some(self.b.ins().bnot(args[0])),
            L::Not => Some(self.b.ins().bxor_imm(args[0], 1)),
            L::Neg if is_float(ct()?) => Some(self.b.ins().fneg(args[0])),
            L::Neg => Some(self.b.ins().ineg(args[0])),
            L::Abs if is_float(ct()?) => Some(self.b.ins().fabs(args[0])),
            L::Abs if signed => Some(self.b.ins().iabs(args[0])),
            L::Abs => Some(args[0]),
            L::Sqrt => Some(self.b.ins().sqrt(args[0])),
            L::Floor => Some(self.b.ins().floor(args[0])),
            L::Ceil => Some(self.b.ins().ceil(args[0])),
            L::Trunc => Some(self.b.ins().trunc(args[0])),
            L::Fma => Some(self.b.ins().fma(args[0], args[1], args[2])),
            L::Popcount => Some(self.b.ins().popcnt(args[0])),
            L::Clz => Some(self.b.ins().clz(args[0])),
            L::Ctz => Some(self.b.ins().ctz(args[0])),
            L::Min | L::Max => {
                let form = self.nan.min_max_form(o.operands[0], o.operands[1]);
                Some(self.min_max(kind == L::Max, args[0], args[1], ct()?, signed, form))
            }
            L::NextUp | L::NextDown => Some(self.next(kind == L::NextUp, args[0], ct()?)),
            L::AddRd | L::AddRu | L::MulRd | L::MulRu => {
                return Err(format!(
                    "`lo.{}` reached Cranelift unexpanded (scion_ir::lo::directed::expanded)",
                    kind.mnemonic()
                ))
            }
            L::Cmp => {
                let pred = o.pred().ok_or("bad predicate")?;
                let t = self.b.func.dfg.value_type(args[0]);
                Some(if is_float(t) {
                    self.b.ins().fcmp(float_cc(pred), args[0], args[1])
                } else {
                    self.b.ins().icmp(int_cc(pred, signed), args[0], args[1])
                })
            }
            L::Select => Some(self.select(o.operands[0], args[0], args[1], args[2])?),
            L::Cast => {
                let from = m.values[o.operands[0]].ty;
                Some(self.cast(args[0], from, rty.ok_or("cast without result")?)?)
            }
            L::Bitcast => {
                let t = ct()?;
                let from = self.b.func.dfg.value_type(args[0]);
                Some(if from == t {
                    args[0]
                } else {
                    self.b.ins().bitcast(t, MemFlags::new(), args[0])
                })
            }
            L::Load => {
                let off = o.int_attr("offset").unwrap_or(0) as i32;
                // A layout buffer's address (`global = true`) is read from the buffer table,
                // which nothing writes while generated code runs and which is valid wherever
                // the function may run: a pure value that Cranelift may share and hoist out of
                // the traversal loop.
                let flags = crate::loads::flags(
                    o.attr("global") == Some(&scion_ir::attr::Attr::Bool(true))
                        || self.pure_loads.contains(&op),
                );
                Some(self.b.ins().load(ct()?, flags, args[0], off))
            }
            L::Store => {
                let off = o.int_attr("offset").unwrap_or(0) as i32;
                self.b.ins().store(MemFlags::new(), args[1], args[0], off);
                None
            }
            L::PtrAdd => {
                let t = self.b.func.dfg.value_type(args[1]);
                let signed = o
                    .operands
                    .get(1)
                    .and_then(|&x| self.int_ty(x))
                    .is_some_and(|t| t.is_signed());
                let d = if t == self.ptr {
                    args[1]
                } else if signed {
                    self.b.ins().sextend(self.ptr, args[1])
                } else {
                    self.b.ins().uextend(self.ptr, args[1])
                };
                Some(self.b.ins().iadd(args[0], d))
            }
            L::GlobalId => {
                return Err("`lo.global_id` is a GPU op: Cranelift targets CPUs only".into())
            }
            L::StackSlot => {
                let size = o.int_attr("size").unwrap_or(1) as u32;
                let align = o.int_attr("align").unwrap_or(8).max(1) as u32;
                let slot = self.b.create_sized_stack_slot(StackSlotData::new(
                    StackSlotKind::ExplicitSlot,
                    size,
                    align.trailing_zeros() as u8,
                ));
                Some(self.b.ins().stack_addr(self.ptr, slot, 0))
            }
            L::Call => {
                let callee = o.callee().ok_or("call without callee")?;
                let id = *syms
                    .funcs
                    .get(callee)
                    .ok_or_else(|| format!("unknown callee @{callee}"))?;
                let fref = cl.declare_func_in_func(id, self.b.func);
                let call = self.b.ins().call(fref, &args);
                let res = self.b.inst_results(call).to_vec();
                for (&r, v) in o.results.iter().zip(res) {
                    self.vals.insert(r, v);
                }
                None
            }
            L::Br | L::CondBr => {
                let mut target = |i: usize| -> Result<(ir::Block, Vec<BlockArg>), String> {
                    let s = &o.successors[i];
                    let bl = *blocks.get(&s.block).ok_or("branch to a missing block")?;
                    if self.direct.contains(&s.block) {
                        let params = &m.blocks[s.block].args;
                        for (&param, &x) in params.iter().zip(&s.args) {
                            if self.carried_params.contains(&param) || self.dead.contains(&param) {
                                continue;
                            }
                            let v = self.v(x)?;
                            self.bind_direct(param, v, Some(x));
                        }
                        return Ok((bl, Vec::new()));
                    }
                    let runs = self.vector_params.get(&s.block).map_or(&[][..], |r| &r[..]);
                    let a = self.jump_args(&s.args, runs)?;
                    Ok((bl, a.into_iter().map(BlockArg::Value).collect()))
                };
                if kind == L::Br {
                    let (bl, a) = target(0)?;
                    self.b.ins().jump(bl, &a);
                } else {
                    let (t, ta) = target(0)?;
                    let (e, ea) = target(1)?;
                    self.b.ins().brif(args[0], t, &ta, e, &ea);
                }
                None
            }
            L::Return => {
                self.b.ins().return_(&args);
                None
            }
        };
        if let (Some(v), Some(&r)) = (out, o.results.first()) {
            self.vals.insert(r, v);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cranelift_jit::{JITBuilder, JITModule};
    use scion_ir::interp::Val;

    fn linkages(text: &str) -> HashMap<String, Linkage> {
        let mut sources = scion_ir::diag::SourceMap::new();
        let file = sources.add("<test>", text.to_string());
        let m = scion_ir::parse_module(text, file).expect("parses");
        let builder = JITBuilder::with_isa(
            crate::host_isa().expect("host ISA"),
            cranelift_module::default_libcall_names(),
        );
        let mut cl = JITModule::new(builder);
        let syms = declare_all(&mut cl, &m).expect("declares");
        syms.funcs
            .iter()
            .map(|(name, id)| {
                let d = cl.declarations().get_function_decl(*id);
                (name.clone(), d.linkage)
            })
            .collect()
    }

    const HELPER: &str = "func @helper(%0: i32) -> (i32) {\n  \"lo.return\"(%0) : (i32) -> ()\n}\n";

    #[test]
    fn only_export_functions_are_exported_when_there_are_any() {
        let entry = "func @api(%0: i32) -> (i32) attributes {export} {\n  \
                     %1 = \"lo.call\"(%0) {callee = @helper} : (i32) -> i32\n  \
                     \"lo.return\"(%1) : (i32) -> ()\n}\n";
        let l = linkages(&format!("{HELPER}{entry}"));
        assert_eq!(l["api"], Linkage::Export);
        assert_eq!(l["helper"], Linkage::Local);
    }

    #[test]
    fn the_jit_runs_export_functions_over_local_helpers() {
        let entry = "func @api(%0: i32) -> (i32) attributes {export} {\n  \
                     %1 = \"lo.call\"(%0) {callee = @helper} : (i32) -> i32\n  \
                     %2 = \"lo.add\"(%1, %0) : (i32, i32) -> i32\n  \
                     \"lo.return\"(%2) : (i32) -> ()\n}\n";
        let text = format!("{HELPER}{entry}");
        let mut sources = scion_ir::diag::SourceMap::new();
        let file = sources.add("<test>", text.clone());
        let m = scion_ir::parse_module(&text, file).expect("parses");
        let jit = crate::JitModule::compile(&m).expect("compiles");
        assert!(
            jit.function_ptr("api").is_some(),
            "the export has an address"
        );
        assert!(
            jit.function_ptr("helper").is_some(),
            "so has the local helper"
        );
        for x in [21, -4, i32::MAX] {
            let v = jit
                .call("api", &[Val::Int(x.into(), IntTy::I32)])
                .expect("runs");
            let want = Val::Int(x.wrapping_add(x).into(), IntTy::I32);
            assert_eq!(format!("{v:?}"), format!("{:?}", [want]));
        }
    }

    #[test]
    fn without_export_functions_every_definition_is_exported() {
        let l = linkages(HELPER);
        assert_eq!(l["helper"], Linkage::Export);
    }
}
