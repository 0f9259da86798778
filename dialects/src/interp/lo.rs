//! A reference interpreter for the `lo` level: runs a function of a verified `lo` module on
//! scalar arguments over a byte-addressed memory, and returns its results. It is the oracle of
//! the backends' tests (`scion-clif` must return bit-identical results).
//!
//! Values are [`Val`] scalars; a `ptr` is a `Val::Int(address, u64)`. Memory is one flat byte
//! array starting at [`LoInterp::BASE`]: the host places data with [`LoInterp::alloc`] and
//! reads it back with [`LoInterp::bytes`]; `lo.stack_slot` allocates in the same memory and the
//! slot is released when its function returns. Every access is bounds-checked. Scalars follow
//! [`crate::tree::scalar`] and the intrinsics [`super::intrinsics`], so `tree` and `lo` agree by
//! construction. Failures (out-of-bounds access, division by zero, step or depth limits,
//! unverified IR) are [`InterpError`]s, never panics.

use super::{err, intrinsics, ExternFn, InterpError, Val};
use crate::entity::{BlockId, FuncId, OpId, TypeId, ValueId};
use crate::lo::Op;
use crate::module::Module;
use crate::op::OpKind;
use crate::tree::directed;
use crate::tree::scalar::{self, Scalar};

use crate::types::{FloatTy, IntTy, Type};
use rustc_hash::FxHashMap;

/// An interpreter of `lo` functions over one module.
pub struct LoInterp<'m> {
    m: &'m Module,
    mem: Vec<u8>,
    externs: FxHashMap<String, ExternFn>,
    steps: u64,
    depth: usize,
    /// The most ops one top-level [`LoInterp::call`] may execute.
    pub max_steps: u64,
    /// The deepest call nesting allowed.
    pub max_depth: usize,
}

type R<T> = Result<T, InterpError>;

impl<'m> LoInterp<'m> {
    /// The address of the first byte of memory (so that 0 is never valid).
    pub const BASE: u64 = 0x1000;

    /// An interpreter over `m` with empty memory.
    pub fn new(m: &'m Module) -> LoInterp<'m> {
        LoInterp {
            m,
            mem: Vec::new(),
            externs: FxHashMap::default(),
            steps: 0,
            depth: 0,
            max_steps: 50_000_000,
            max_depth: 256,
        }
    }

    /// Lets calls to the declaration `name` run `f` (on scalar arguments).
    pub fn define_extern(&mut self, name: &str, f: ExternFn) {
        self.externs.insert(name.to_string(), f);
    }

    /// Places `bytes` in memory at an address aligned to `align` (a power of two, at least 1)
    /// and returns the address.
    pub fn alloc(&mut self, bytes: &[u8], align: u64) -> u64 {
        let align = align.max(1);
        let mut at = Self::BASE + self.mem.len() as u64;
        at = at.div_ceil(align) * align;
        let start = (at - Self::BASE) as usize;
        self.mem.resize(start, 0);
        self.mem.extend_from_slice(bytes);
        at
    }

    /// The `len` bytes at `addr`, if in bounds.
    pub fn bytes(&self, addr: u64, len: usize) -> Option<&[u8]> {
        let start = addr.checked_sub(Self::BASE)? as usize;
        self.mem.get(start..start.checked_add(len)?)
    }

    /// Runs the function called `name` on `args` (pointers as `u64` integers).
    pub fn call(&mut self, name: &str, args: Vec<Val>) -> R<Vec<Val>> {
        let f = self
            .m
            .func_by_name(name)
            .ok_or_else(|| err(None, format!("no function `@{name}`")))?;
        self.steps = 0;
        self.call_func(f, args, None)
    }

    fn call_func(&mut self, f: FuncId, args: Vec<Val>, at: Option<OpId>) -> R<Vec<Val>> {
        let m = self.m;
        if m.is_declaration(f) {
            let name = &m.funcs[f].name;
            let host = self.externs.get_mut(name).ok_or_else(|| {
                err(
                    at,
                    format!("call to declaration `@{name}` without a host function"),
                )
            })?;
            return host(&args).map_err(|e| err(at, format!("`@{name}`: {e}")));
        }
        if m.funcs[f].order_by().is_some() {
            return Err(err(
                at,
                format!(
                    "`@{}` is best-first (`order_by`): it runs once `recursion-to-stack` has \
                     given it its queue",
                    m.funcs[f].name
                ),
            ));
        }
        if self.depth >= self.max_depth {
            return Err(err(
                at,
                format!("call depth limit {} reached", self.max_depth),
            ));
        }
        let mark = self.mem.len();
        self.depth += 1;
        let out = self.run(f, args);
        self.depth -= 1;
        self.mem.truncate(mark);
        out
    }

    fn run(&mut self, f: FuncId, args: Vec<Val>) -> R<Vec<Val>> {
        let m = self.m;
        let mut env: FxHashMap<ValueId, Val> = FxHashMap::default();
        let mut block = m.regions[m.funcs[f].body].blocks[0];
        let mut args = args;
        loop {
            let b = &m.blocks[block];
            if b.args.len() != args.len() {
                return Err(err(None, "block argument count mismatch"));
            }
            for (&a, v) in b.args.iter().zip(args.drain(..)) {
                env.insert(a, v);
            }
            let mut next: Option<(BlockId, Vec<Val>)> = None;
            for &op in &b.ops {
                self.steps += 1;
                if self.steps > self.max_steps {
                    return Err(err(
                        Some(op),
                        format!("step limit {} reached", self.max_steps),
                    ));
                }
                let o = &m.ops[op];
                let OpKind::Lo(kind) = o.kind else {
                    return Err(err(Some(op), "the lo interpreter runs only lo ops"));
                };
                let vals: Vec<Val> = o
                    .operands
                    .iter()
                    .map(|v| {
                        env.get(v)
                            .cloned()
                            .ok_or_else(|| err(Some(op), "operand has no value"))
                    })
                    .collect::<R<_>>()?;
                match kind {
                    Op::Return => return Ok(vals),
                    Op::Br | Op::CondBr => {
                        let i = match (kind, vals.first()) {
                            (Op::CondBr, Some(Val::Bool(c))) => usize::from(!*c),
                            (Op::Br, _) => 0,
                            _ => return Err(err(Some(op), "cond_br needs an i1")),
                        };
                        let s = &o.successors[i];
                        let a = s
                            .args
                            .iter()
                            .map(|v| env.get(v).cloned().ok_or_else(|| err(Some(op), "no value")))
                            .collect::<R<_>>()?;
                        next = Some((s.block, a));
                        break;
                    }
                    Op::Call => {
                        let callee = o
                            .callee()
                            .and_then(|c| m.func_by_name(c))
                            .ok_or_else(|| err(Some(op), "unknown callee"))?;
                        let res = self.call_func(callee, vals, Some(op))?;
                        if res.len() != o.results.len() {
                            return Err(err(Some(op), "callee returned the wrong count"));
                        }
                        for (&r, v) in o.results.iter().zip(res) {
                            env.insert(r, v);
                        }
                    }
                    _ => {
                        let v = self.data(op, kind, &vals)?;
                        if let (Some(&r), Some(v)) = (o.results.first(), v) {
                            env.insert(r, v);
                        }
                    }
                }
            }
            match next {
                Some((b, a)) => {
                    block = b;
                    args = a;
                }
                None => return Err(err(None, "block ended without a terminator")),
            }
        }
    }

    fn data(&mut self, op: OpId, kind: Op, vals: &[Val]) -> R<Option<Val>> {
        let m = self.m;
        let o = &m.ops[op];
        let rty = o.results.first().map(|&r| m.values[r].ty);
        let sc = |i: usize| -> R<Scalar> {
            vals.get(i)
                .and_then(Val::scalar)
                .ok_or_else(|| err(Some(op), "operand is not a scalar"))
        };
        let bad = || err(Some(op), format!("`lo.{}`: bad operands", kind.mnemonic()));
        let res_ty = || -> R<TypeId> { rty.ok_or_else(|| err(Some(op), "op has no result")) };
        let v = match kind {
            Op::Const => {
                let ty = res_ty()?;
                let a = o.attr("value").ok_or_else(bad)?;
                match m.types.get(ty) {
                    Type::Ptr => Val::Int(a.as_int().ok_or_else(bad)?, IntTy::U64),
                    _ => Val::from_scalar(Scalar::from_attr(m, a, ty).ok_or_else(bad)?),
                }
            }
            _ if kind.is_binary() => {
                let t = kind.tree_equivalent().ok_or_else(bad)?;
                let r = scalar::binary(t, sc(0)?, sc(1)?)
                    .ok_or_else(|| err(Some(op), "division by zero or bad operands"))?;
                Val::from_scalar(r)
            }
            Op::Neg | Op::BitNot | Op::Not => {
                let t = kind.tree_equivalent().ok_or_else(bad)?;
                Val::from_scalar(scalar::unary(t, sc(0)?).ok_or_else(bad)?)
            }
            Op::Cmp => {
                let pred = o.pred().ok_or_else(bad)?;
                let (a, b) = (ptr_as_scalar(&vals[0]), ptr_as_scalar(&vals[1]));
                Val::Bool(
                    scalar::compare(pred, a.ok_or_else(bad)?, b.ok_or_else(bad)?)
                        .ok_or_else(bad)?,
                )
            }
            Op::Select => match vals {
                [Val::Bool(c), a, b] => {
                    if *c {
                        a.clone()
                    } else {
                        b.clone()
                    }
                }
                _ => return Err(bad()),
            },
            Op::Cast => {
                let to = m.types.get(res_ty()?);
                Val::from_scalar(scalar::cast(sc(0)?, to).ok_or_else(bad)?)
            }
            Op::Bitcast => {
                let to = m.types.get(res_ty()?);
                Val::from_scalar(scalar::bitcast(sc(0)?, to).ok_or_else(bad)?)
            }
            Op::Min
            | Op::Max
            | Op::Abs
            | Op::Sqrt
            | Op::Floor
            | Op::Ceil
            | Op::Trunc
            | Op::Fma
            | Op::Popcount
            | Op::Clz
            | Op::Ctz => {
                use crate::tree::Intrinsic as I;
                // The same lane semantics as the `tree` builtin of the same name.
                let intrinsic = match kind {
                    Op::Min => I::Min,
                    Op::Max => I::Max,
                    Op::Abs => I::Abs,
                    Op::Sqrt => I::Sqrt,
                    Op::Floor => I::Floor,
                    Op::Ceil => I::Ceil,
                    Op::Trunc => I::Trunc,
                    Op::Fma => I::Fma,
                    Op::Popcount => I::Popcount,
                    Op::Clz => I::Clz,
                    _ => I::Ctz,
                };
                intrinsics::eval(m, intrinsic, vals, res_ty()?).map_err(|e| err(Some(op), e))?
            }
            Op::NextUp | Op::NextDown => {
                let up = kind == Op::NextUp;
                match sc(0)? {
                    Scalar::F32(x) => Val::F32(next_f32(x, up)),
                    Scalar::F64(x) => Val::F64(next_f64(x, up)),
                    _ => return Err(bad()),
                }
            }
            Op::AddRd | Op::AddRu | Op::MulRd | Op::MulRu => {
                let (mul, dir) = kind.directed().ok_or_else(bad)?;
                match (sc(0)?, sc(1)?) {
                    (Scalar::F32(a), Scalar::F32(b)) if mul => Val::F32(directed::mul(a, b, dir)),
                    (Scalar::F32(a), Scalar::F32(b)) => Val::F32(directed::add(a, b, dir)),
                    _ => return Err(bad()),
                }
            }
            Op::PtrAdd => match (&vals[0], &vals[1]) {
                (Val::Int(p, _), Val::Int(d, _)) => Val::Int(
                    (*p as u64).wrapping_add(*d as i64 as u64) as i128,
                    IntTy::U64,
                ),
                _ => return Err(bad()),
            },
            Op::GlobalId => {
                return Err(err(
                    Some(op),
                    "`lo.global_id` has no meaning outside a GPU kernel",
                ))
            }
            Op::StackSlot => {
                let size = o.int_attr("size").ok_or_else(bad)? as usize;
                let align = o.int_attr("align").unwrap_or(8).max(1) as u64;
                let at = self.alloc(&vec![0u8; size], align);
                Val::Int(at as i128, IntTy::U64)
            }
            Op::Load => {
                let addr = self.address(op, &vals[0])?;
                let ty = res_ty()?;
                let width = byte_width(m, ty).ok_or_else(bad)?;
                let bytes = self
                    .bytes(addr, width)
                    .ok_or_else(|| err(Some(op), format!("load out of bounds at {addr:#x}")))?;
                let mut raw = [0u8; 8];
                raw[..width].copy_from_slice(bytes);
                from_bits(m, ty, u64::from_le_bytes(raw)).ok_or_else(bad)?
            }
            Op::Store => {
                let addr = self.address(op, &vals[0])?;
                let ty = m.values[o.operands[1]].ty;
                let width = byte_width(m, ty).ok_or_else(bad)?;
                let bits = to_bits(&vals[1]).ok_or_else(bad)?;
                let start = (addr.checked_sub(Self::BASE))
                    .map(|s| s as usize)
                    .filter(|&s| s.checked_add(width).is_some_and(|e| e <= self.mem.len()))
                    .ok_or_else(|| err(Some(op), format!("store out of bounds at {addr:#x}")))?;
                self.mem[start..start + width].copy_from_slice(&bits.to_le_bytes()[..width]);
                return Ok(None);
            }
            _ => return Err(bad()),
        };
        Ok(Some(v))
    }

    fn address(&self, op: OpId, p: &Val) -> R<u64> {
        let off = self.m.ops[op].int_attr("offset").unwrap_or(0);
        match p {
            Val::Int(a, _) => Ok((*a as u64).wrapping_add(off as i64 as u64)),
            _ => Err(err(Some(op), "address is not a ptr")),
        }
    }
}

fn ptr_as_scalar(v: &Val) -> Option<Scalar> {
    v.scalar()
}

/// The size in bytes of a `lo` scalar type in memory (`i1` takes one byte).
pub fn byte_width(m: &Module, ty: TypeId) -> Option<usize> {
    Some(match m.types.get(ty) {
        Type::Bool => 1,
        Type::Int(t) => t.bits() as usize / 8,
        Type::Float(FloatTy::F32) => 4,
        Type::Float(FloatTy::F64) | Type::Ptr => 8,
        _ => return None,
    })
}

fn to_bits(v: &Val) -> Option<u64> {
    Some(match *v {
        Val::Bool(b) => b as u64,
        Val::Int(x, _) => x as u64,
        Val::F32(x) => x.to_bits() as u64,
        Val::F64(x) => x.to_bits(),
        _ => return None,
    })
}

fn from_bits(m: &Module, ty: TypeId, bits: u64) -> Option<Val> {
    Some(match m.types.get(ty) {
        Type::Bool => Val::Bool(bits & 1 != 0),
        Type::Int(t) => Val::Int(t.wrap(bits as i128), *t),
        Type::Float(FloatTy::F32) => Val::F32(f32::from_bits(bits as u32)),
        Type::Float(FloatTy::F64) => Val::F64(f64::from_bits(bits)),
        Type::Ptr => Val::Int(bits as i128, IntTy::U64),
        _ => return None,
    })
}

/// The next `f32` toward `+inf` (`up`) or `-inf`: NaN stays, an infinity in the direction
/// stays, `±0` steps to the smallest subnormal of that sign direction.
pub fn next_f32(x: f32, up: bool) -> f32 {
    if x.is_nan() || (up && x == f32::INFINITY) || (!up && x == f32::NEG_INFINITY) {
        return x;
    }
    if x == 0.0 {
        return f32::from_bits(if up { 1 } else { 0x8000_0001 });
    }
    let b = x.to_bits();
    f32::from_bits(if (x > 0.0) == up { b + 1 } else { b - 1 })
}

/// The next `f64` toward `+inf` (`up`) or `-inf`, as [`next_f32`].
pub fn next_f64(x: f64, up: bool) -> f64 {
    if x.is_nan() || (up && x == f64::INFINITY) || (!up && x == f64::NEG_INFINITY) {
        return x;
    }
    if x == 0.0 {
        return f64::from_bits(if up { 1 } else { 0x8000_0000_0000_0001 });
    }
    let b = x.to_bits();
    f64::from_bits(if (x > 0.0) == up { b + 1 } else { b - 1 })
}
