//! The `mem` ops in the interpreter: a flat little-endian byte memory that the host fills
//! ([`Interp::alloc_bytes`]) and reads back ([`Interp::bytes`]).
//!
//! A `ptr` is a [`Val::Int`] of type `u64` holding an address of that memory (address 0 is
//! never handed out). `mem.load` and `mem.store` decode and encode plain data with the layout
//! model's rules (scalars at their width, `i1` as one byte, `f32x3` as 12 bytes aligned to 4,
//! records and tuples field by field at natural alignment); `mem.view` reads its elements into
//! an array value, which is exact because a traversal never writes the layout it reads.
//! Accesses outside the allocated memory are errors, never panics.

use super::{err, Interp, InterpError, Val};
use crate::entity::{OpId, TypeId};
use crate::mem::Op;
use crate::types::{FloatTy, IntTy, Type};
use std::rc::Rc;

/// The first address handed out (so that 0 is never a valid pointer).
const BASE: u64 = 0x1000;

/// Size and alignment of a plain-data type, as `mem.load` lays it out
/// ([`crate::data_layout`], the same model as `mem-to-lo`'s).
pub use crate::data_layout::size_align;

fn round_up(x: u64, a: u64) -> u64 {
    x.div_ceil(a) * a
}

impl Interp<'_> {
    /// Copies `bytes` into fresh memory aligned to `align` (at least 16) and returns the address.
    pub fn alloc_bytes(&mut self, bytes: &[u8], align: u64) -> u64 {
        let align = align.max(16);
        let start = round_up(BASE + self.memory.len() as u64, align);
        let pad = (start - BASE) as usize - self.memory.len();
        self.memory.extend(std::iter::repeat_n(0u8, pad));
        self.memory.extend_from_slice(bytes);
        start
    }

    /// The whole byte memory, from its first address: what the host allocated and the program
    /// stored.
    pub fn memory(&self) -> &[u8] {
        &self.memory
    }

    /// Replaces the byte memory by `memory`, a copy of [`Interp::memory`] of an interpreter
    /// over the same module: a structure packed by one interpreter, read by others.
    pub fn set_memory(&mut self, memory: Vec<u8>) {
        self.memory = memory;
    }

    /// `len` bytes at `addr`, if they are allocated.
    pub fn bytes(&self, addr: u64, len: u64) -> Option<&[u8]> {
        let lo = usize::try_from(addr.checked_sub(BASE)?).ok()?;
        let hi = lo.checked_add(usize::try_from(len).ok()?)?;
        self.memory.get(lo..hi)
    }

    fn bytes_mut(&mut self, addr: u64, len: u64) -> Option<&mut [u8]> {
        let lo = usize::try_from(addr.checked_sub(BASE)?).ok()?;
        let hi = lo.checked_add(usize::try_from(len).ok()?)?;
        self.memory.get_mut(lo..hi)
    }

    /// Reads a value of `ty` at `addr`.
    pub fn read_value(&self, addr: u64, ty: TypeId) -> Result<Val, String> {
        let m = self.m;
        let (size, _) = size_align(m, ty).ok_or("not plain data")?;
        let b = self
            .bytes(addr, size)
            .ok_or_else(|| format!("read of {size} bytes at {addr:#x} outside memory"))?;
        let le = |n: usize| -> u128 {
            let mut v = 0u128;
            for (i, byte) in b[..n].iter().enumerate() {
                v |= (*byte as u128) << (8 * i);
            }
            v
        };
        Ok(match m.types.get(ty) {
            Type::Bool => Val::Bool(b[0] != 0),
            Type::Int(t) => Val::Int(t.wrap(le(size as usize) as i128), *t),
            Type::Float(FloatTy::F32) => Val::F32(f32::from_bits(le(4) as u32)),
            Type::Float(FloatTy::F64) => Val::F64(f64::from_bits(le(8) as u64)),
            Type::Float(FloatTy::F16) => return Err("f16 in memory".into()),
            Type::Ptr => Val::Int(le(8) as i128, IntTy::U64),
            Type::Vector { elem, lanes } => {
                let (s, _) = size_align(m, *elem).ok_or("bad lane")?;
                let lanes = (0..*lanes as u64)
                    .map(|i| self.read_value(addr + i * s, *elem))
                    .collect::<Result<_, _>>()?;
                Val::Vector(lanes)
            }
            Type::Array { elem, len: Some(n) } => {
                let (s, a) = size_align(m, *elem).ok_or("bad element")?;
                let items = (0..*n)
                    .map(|i| self.read_value(addr + i * round_up(s, a), *elem))
                    .collect::<Result<_, _>>()?;
                Val::Array(Rc::new(items))
            }
            Type::Tuple(fields) => Val::Tuple(self.read_fields(addr, fields)?),
            Type::Adt(name) => {
                let adt = m.adt(name).ok_or("unknown record")?;
                let fields: Vec<TypeId> = adt.shared.iter().map(|f| f.ty).collect();
                Val::Adt(Rc::new(super::AdtVal {
                    ty: name.clone(),
                    variant: None,
                    fields: self.read_fields(addr, &fields)?,
                }))
            }
            _ => return Err("not plain data".into()),
        })
    }

    fn read_fields(&self, addr: u64, fields: &[TypeId]) -> Result<Vec<Val>, String> {
        let mut off = 0;
        let mut out = Vec::new();
        for &f in fields {
            let (s, a) = size_align(self.m, f).ok_or("not plain data")?;
            off = round_up(off, a);
            out.push(self.read_value(addr + off, f)?);
            off += s;
        }
        Ok(out)
    }

    /// Writes `v` of type `ty` at `addr`.
    pub fn write_value(&mut self, addr: u64, ty: TypeId, v: &Val) -> Result<(), String> {
        let m = self.m;
        let (size, _) = size_align(m, ty).ok_or("not plain data")?;
        let raw: Option<u128> = match (m.types.get(ty), v) {
            (Type::Bool, Val::Bool(b)) => Some(*b as u128),
            (Type::Int(_) | Type::Ptr, Val::Int(x, _)) => Some(*x as u128),
            (Type::Float(FloatTy::F32), Val::F32(x)) => Some(x.to_bits() as u128),
            (Type::Float(FloatTy::F64), Val::F64(x)) => Some(x.to_bits() as u128),
            _ => None,
        };
        if let Some(raw) = raw {
            let b = self
                .bytes_mut(addr, size)
                .ok_or_else(|| format!("write of {size} bytes at {addr:#x} outside memory"))?;
            for (i, byte) in b.iter_mut().enumerate() {
                *byte = (raw >> (8 * i)) as u8;
            }
            return Ok(());
        }
        let parts: Vec<(TypeId, Val)> = match (m.types.get(ty), v) {
            (Type::Vector { elem, .. }, Val::Vector(l)) => {
                l.iter().map(|x| (*elem, x.clone())).collect()
            }
            (Type::Array { elem, .. }, Val::Array(l)) => {
                l.iter().map(|x| (*elem, x.clone())).collect()
            }
            (Type::Tuple(fs), Val::Tuple(l)) => fs.iter().copied().zip(l.iter().cloned()).collect(),
            (Type::Adt(name), Val::Adt(a)) => {
                let adt = m.adt(name).ok_or("unknown record")?;
                adt.shared
                    .iter()
                    .map(|f| f.ty)
                    .zip(a.fields.iter().cloned())
                    .collect()
            }
            _ => return Err(format!("cannot store {v} as {}", m.types.display(ty))),
        };
        let mut off = 0;
        for (t, x) in parts {
            let (s, a) = size_align(m, t).ok_or("not plain data")?;
            off = round_up(off, a);
            self.write_value(addr + off, t, &x)?;
            off += s;
        }
        Ok(())
    }

    /// Runs one `mem` op.
    pub(crate) fn exec_mem(
        &mut self,
        op: OpId,
        kind: Op,
        args: Vec<Val>,
    ) -> Result<Vec<Val>, InterpError> {
        let m = self.m;
        let o = &m.ops[op];
        let bad = |what: String| err(Some(op), format!("`mem.{}`: {what}", kind.mnemonic()));
        let int = |v: &Val| match v {
            Val::Int(x, _) => Ok(*x),
            other => Err(bad(format!("{other} is not an address or index"))),
        };
        let attr = |k: &str| o.int_attr(k).unwrap_or(0);
        let addr_of = |args: &[Val]| -> Result<u64, InterpError> {
            let base = int(&args[0])?;
            let index = if args.len() > 1 { int(&args[1])? } else { 0 };
            let a = base + index * attr("stride") + attr("offset");
            u64::try_from(a).map_err(|_| bad(format!("address {a} out of range")))
        };
        let u64v = |x: u64| Val::Int(x as i128, IntTy::U64);
        Ok(match kind {
            Op::Buffer => {
                let table = u64::try_from(int(&args[0])?).map_err(|_| bad("bad table".into()))?;
                let ptr = m
                    .types
                    .lookup(&Type::Ptr)
                    .ok_or_else(|| bad("no ptr type".into()))?;
                let v = self
                    .read_value(table + 8 * attr("index") as u64, ptr)
                    .map_err(bad)?;
                vec![v]
            }
            Op::Load => {
                let a = addr_of(&args)?;
                vec![self.read_value(a, m.values[o.results[0]].ty).map_err(bad)?]
            }
            Op::Store => {
                let (addr_args, v) = args.split_at(args.len() - 1);
                let a = addr_of(addr_args)?;
                let ty = m.values[o.operands[o.operands.len() - 1]].ty;
                self.write_value(a, ty, &v[0]).map_err(bad)?;
                vec![]
            }
            Op::Addr => vec![u64v(addr_of(&args)?)],
            Op::View => {
                let (base, start, len) = (int(&args[0])?, int(&args[1])?, int(&args[2])?);
                let Type::View(elem) = m.types.get(m.values[o.results[0]].ty) else {
                    return Err(bad("result is not a view".into()));
                };
                let stride = attr("stride");
                let mut items = Vec::new();
                for i in 0..len {
                    let a = u64::try_from(base + (start + i) * stride)
                        .map_err(|_| bad("address out of range".into()))?;
                    items.push(self.read_value(a, *elem).map_err(bad)?);
                }
                vec![Val::Array(Rc::new(items))]
            }
        })
    }
}
