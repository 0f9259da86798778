//! A reference interpreter for the `tree` level, and for the `mem` ops over a byte memory
//! ([`mem`]): runs a function of a verified module on argument values and returns its results. Input: a [`Module`] and [`Val`]s; output: [`Val`]s
//! or an [`InterpError`].
//!
//! It is the oracle for the layout-free meaning of a program (paper §3: the traversal as
//! written against the algebraic data type), so irgen and the `tree` passes can be tested
//! before any layout exists, and later levels can be compared with it. Scalars follow
//! [`crate::tree::scalar`] (the semantics `const-fold` uses); intrinsics are listed in
//! [`intrinsics`]. Mutable state lives in a heap of cells addressed by [`Val::Ref`]. Calls to
//! declarations go to host functions registered with [`Interp::define_extern`].
//!
//! An ADT value can also be *lazy*: [`Val::Extern`] is a host handle that the interpreter
//! destructures on demand (`match`, `field`, `is`) through the provider installed with
//! [`Interp::set_adt_provider`], so a large host structure (a logical BVH of millions of
//! nodes) is never materialized as [`Val::Adt`] values; only the nodes a run visits are asked
//! for. Fields of a provided value may themselves be handles.
//!
//! Failures are values, never panics: division by zero, an index out of bounds, `unwrap` of
//! `none`, a call deeper than [`Interp::max_depth`], more than [`Interp::max_steps`] ops, or IR
//! the interpreter cannot run (which the verifier would have rejected).

pub mod intrinsics;
pub mod lo;
pub mod mem;
mod tree;

use crate::entity::{FuncId, OpId, ValueId};
use crate::module::Module;
use crate::tree::scalar::Scalar;
use crate::types::IntTy;
use rustc_hash::FxHashMap;
use std::cmp::Ordering;
use std::fmt;
use std::rc::Rc;

/// A run-time value.
#[derive(Clone, Debug)]
pub enum Val {
    /// `i1`
    Bool(bool),
    /// An integer of the given type, normalized to its range.
    Int(i128, IntTy),
    /// `f32`
    F32(f32),
    /// `f64`
    F64(f64),
    /// A vector's lanes (scalars).
    Vector(Vec<Val>),
    /// A tuple's elements.
    Tuple(Vec<Val>),
    /// An array or slice.
    Array(Rc<Vec<Val>>),
    /// A set, kept sorted by [`Val::total_cmp`] without duplicates.
    Set(Rc<Vec<Val>>),
    /// An option.
    Option(Option<Box<Val>>),
    /// A value of an algebraic data type.
    Adt(Rc<AdtVal>),
    /// A reference to a heap cell of the interpreter.
    Ref(usize),
    /// A lazy ADT value: a host handle resolved by the ADT provider
    /// ([`Interp::set_adt_provider`]) when the program looks inside it.
    Extern(u64),
}

/// The payload of an ADT value.
#[derive(Clone, Debug)]
pub struct AdtVal {
    /// The type's name.
    pub ty: String,
    /// The variant's position in the declaration (`None` for a record).
    pub variant: Option<usize>,
    /// All fields, shared first.
    pub fields: Vec<Val>,
}

impl Val {
    /// The scalar view of a `Bool`, `Int`, `F32` or `F64`.
    pub fn scalar(&self) -> Option<Scalar> {
        Some(match *self {
            Val::Bool(b) => Scalar::Bool(b),
            Val::Int(v, t) => Scalar::Int(v, t),
            Val::F32(x) => Scalar::F32(x),
            Val::F64(x) => Scalar::F64(x),
            _ => return None,
        })
    }

    /// A scalar's kind and bits, so that NaN payloads and signed zeros count: what the
    /// differential tests compare between engines. Anything else is `(9, 0)`.
    pub fn bits_key(&self) -> (u8, u64) {
        match *self {
            Val::Bool(b) => (0, u64::from(b)),
            Val::Int(x, _) => (1, x as u64),
            Val::F32(x) => (2, u64::from(x.to_bits())),
            Val::F64(x) => (3, x.to_bits()),
            _ => (9, 0),
        }
    }

    /// The value of a scalar.
    pub fn from_scalar(s: Scalar) -> Val {
        match s {
            Scalar::Bool(b) => Val::Bool(b),
            Scalar::Int(v, t) => Val::Int(v, t),
            Scalar::F32(x) => Val::F32(x),
            Scalar::F64(x) => Val::F64(x),
        }
    }

    /// A total order (floats by IEEE `totalOrder`, then structure), used for sets.
    pub fn total_cmp(&self, other: &Val) -> Ordering {
        fn rank(v: &Val) -> u8 {
            match v {
                Val::Bool(_) => 0,
                Val::Int(..) => 1,
                Val::F32(_) => 2,
                Val::F64(_) => 3,
                Val::Vector(_) => 4,
                Val::Tuple(_) => 5,
                Val::Array(_) => 6,
                Val::Set(_) => 7,
                Val::Option(_) => 8,
                Val::Adt(_) => 9,
                Val::Ref(_) => 10,
                Val::Extern(_) => 11,
            }
        }
        fn seq(a: &[Val], b: &[Val]) -> Ordering {
            for (x, y) in a.iter().zip(b) {
                let o = x.total_cmp(y);
                if o != Ordering::Equal {
                    return o;
                }
            }
            a.len().cmp(&b.len())
        }
        match (self, other) {
            (Val::Bool(a), Val::Bool(b)) => a.cmp(b),
            (Val::Int(a, _), Val::Int(b, _)) => a.cmp(b),
            (Val::F32(a), Val::F32(b)) => a.total_cmp(b),
            (Val::F64(a), Val::F64(b)) => a.total_cmp(b),
            (Val::Vector(a), Val::Vector(b)) | (Val::Tuple(a), Val::Tuple(b)) => seq(a, b),
            (Val::Array(a), Val::Array(b)) | (Val::Set(a), Val::Set(b)) => seq(a, b),
            (Val::Option(a), Val::Option(b)) => match (a, b) {
                (None, None) => Ordering::Equal,
                (None, Some(_)) => Ordering::Less,
                (Some(_), None) => Ordering::Greater,
                (Some(x), Some(y)) => x.total_cmp(y),
            },
            (Val::Adt(a), Val::Adt(b)) => {
                a.ty.cmp(&b.ty)
                    .then(a.variant.cmp(&b.variant))
                    .then_with(|| seq(&a.fields, &b.fields))
            }
            (Val::Ref(a), Val::Ref(b)) => a.cmp(b),
            (Val::Extern(a), Val::Extern(b)) => a.cmp(b),
            _ => rank(self).cmp(&rank(other)),
        }
    }

    /// Bit-exact equality (floats compare by bits, so `-0.0 != 0.0` and a NaN equals itself).
    pub fn same(&self, other: &Val) -> bool {
        self.total_cmp(other) == Ordering::Equal
    }
}

impl fmt::Display for Val {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fn list(f: &mut fmt::Formatter<'_>, open: &str, items: &[Val], close: &str) -> fmt::Result {
            write!(f, "{open}")?;
            for (i, v) in items.iter().enumerate() {
                if i > 0 {
                    write!(f, ", ")?;
                }
                write!(f, "{v}")?;
            }
            write!(f, "{close}")
        }
        match self {
            Val::Bool(b) => write!(f, "{b}"),
            Val::Int(v, t) => write!(f, "{v}_{}", t.name()),
            Val::F32(x) => write!(f, "{x:?}_f32"),
            Val::F64(x) => write!(f, "{x:?}_f64"),
            Val::Vector(l) => list(f, "<", l, ">"),
            Val::Tuple(l) => list(f, "(", l, ")"),
            Val::Array(l) => list(f, "[", l, "]"),
            Val::Set(l) => list(f, "set{", l, "}"),
            Val::Option(None) => write!(f, "none"),
            Val::Option(Some(v)) => write!(f, "some({v})"),
            Val::Adt(a) => {
                let name = a.variant.map_or(a.ty.clone(), |i| format!("{}#{i}", a.ty));
                list(f, &format!("{name}("), &a.fields, ")")
            }
            Val::Ref(i) => write!(f, "ref#{i}"),
            Val::Extern(h) => write!(f, "extern#{h}"),
        }
    }
}

/// Why a run failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InterpError {
    /// What happened.
    pub message: String,
    /// The op that failed, when there is one.
    pub op: Option<OpId>,
}

impl fmt::Display for InterpError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.message)
    }
}

/// A host function standing for a declared function.
pub type ExternFn = Box<dyn FnMut(&[Val]) -> Result<Vec<Val>, String>>;

/// The host side of lazy ADT values: given the handle of a [`Val::Extern`], the value it
/// stands for (type name, variant position, fields; fields may be handles again). Called each
/// time the program looks inside a handle, so a provider over a big structure should cache.
pub type AdtProvider<'p> = Box<dyn FnMut(u64) -> Result<Rc<AdtVal>, String> + 'p>;

/// An interpreter over one module.
pub struct Interp<'m> {
    m: &'m Module,
    heap: Vec<Val>,
    /// The byte memory of `mem` ops (see [`mem`]).
    memory: Vec<u8>,
    externs: FxHashMap<String, ExternFn>,
    provider: Option<AdtProvider<'m>>,
    steps: u64,
    depth: usize,
    /// The most ops one top-level [`Interp::call`] may execute.
    pub max_steps: u64,
    /// The deepest call nesting allowed. Each level costs native stack (up to about 32 KiB in
    /// debug builds when every level nests regions); the default of 64 fits a 2 MiB thread.
    /// Raise it only on a thread with a bigger stack.
    pub max_depth: usize,
    /// Calls of each defined function since counting was turned on ([`Interp::count_calls`]):
    /// the work profile of a traversal (node visits, box and primitive tests).
    calls: Option<FxHashMap<FuncId, u64>>,
    /// The functions whose bodies are running, innermost last.
    frames: Vec<FuncId>,
    /// The call queues of the best-first functions running, innermost last.
    queues: Vec<CallQueue>,
}

/// The pending calls of one outer call of a best-first function (attribute `order_by`): each
/// call the function makes of itself waits here; the smallest key runs next, and on equal keys
/// the call queued first (docs/ir.md, "Best-first functions").
struct CallQueue {
    func: FuncId,
    /// `(key, sequence number, arguments)`, in no particular order.
    pending: Vec<(Val, u64, Vec<Val>)>,
    next_seq: u64,
}

impl CallQueue {
    /// Removes and returns the entry that runs next.
    fn pop(&mut self) -> Option<Vec<Val>> {
        let mut best: Option<usize> = None;
        for (i, e) in self.pending.iter().enumerate() {
            if best.is_none_or(|b| key_before(e, &self.pending[b])) {
                best = Some(i);
            }
        }
        best.map(|i| self.pending.swap_remove(i).2)
    }
}

/// Whether queue entry `a` runs before `b`: a smaller key, or an equal key queued earlier. A NaN
/// key counts as `+inf` (every NaN alike), so the order is total.
fn key_before(a: &(Val, u64, Vec<Val>), b: &(Val, u64, Vec<Val>)) -> bool {
    let f = |v: &Val| -> Option<f64> {
        match v {
            Val::F32(x) if x.is_nan() => Some(f64::INFINITY),
            Val::F64(x) if x.is_nan() => Some(f64::INFINITY),
            Val::F32(x) => Some(f64::from(*x)),
            Val::F64(x) => Some(*x),
            _ => None,
        }
    };
    let ord = match (&a.0, &b.0) {
        (Val::Int(x, _), Val::Int(y, _)) => x.cmp(y),
        (x, y) => match (f(x), f(y)) {
            (Some(x), Some(y)) => x.partial_cmp(&y).unwrap_or(std::cmp::Ordering::Equal),
            _ => std::cmp::Ordering::Equal,
        },
    };
    ord.then(a.1.cmp(&b.1)) == std::cmp::Ordering::Less
}

/// How a region was left.
pub(crate) enum Flow {
    /// Through `tree.yield` with these values.
    Yield(Vec<Val>),
    /// Through `tree.return` with these values.
    Return(Vec<Val>),
}

pub(crate) type Env = FxHashMap<ValueId, Val>;

impl<'m> Interp<'m> {
    /// An interpreter over `m` with an empty heap.
    pub fn new(m: &'m Module) -> Interp<'m> {
        Interp {
            m,
            heap: Vec::new(),
            memory: Vec::new(),
            externs: FxHashMap::default(),
            provider: None,
            steps: 0,
            depth: 0,
            max_steps: 10_000_000,
            max_depth: 64,
            calls: None,
            frames: Vec::new(),
            queues: Vec::new(),
        }
    }

    /// Starts counting the calls of each function (from zero).
    pub fn count_calls(&mut self) {
        self.calls = Some(FxHashMap::default());
    }

    /// The calls counted since [`Interp::count_calls`], by function name, in the module's
    /// function order (functions never called are left out).
    pub fn call_counts(&self) -> Vec<(String, u64)> {
        let Some(calls) = &self.calls else {
            return Vec::new();
        };
        self.m
            .func_order
            .iter()
            .filter_map(|f| calls.get(f).map(|&n| (self.m.funcs[*f].name.clone(), n)))
            .collect()
    }

    /// Lets calls to the declaration `name` run `f`.
    pub fn define_extern(&mut self, name: &str, f: ExternFn) {
        self.externs.insert(name.to_string(), f);
    }

    /// Installs the provider that resolves [`Val::Extern`] handles (replacing any earlier one).
    pub fn set_adt_provider(&mut self, p: AdtProvider<'m>) {
        self.provider = Some(p);
    }

    /// The ADT value `v` is: itself for [`Val::Adt`], the provider's answer for
    /// [`Val::Extern`], `None` for anything else.
    pub fn resolve_adt(&mut self, v: &Val) -> Result<Option<Rc<AdtVal>>, String> {
        match v {
            Val::Adt(a) => Ok(Some(a.clone())),
            Val::Extern(h) => match &mut self.provider {
                Some(p) => p(*h).map(Some),
                None => Err(format!("lazy value extern#{h} without an ADT provider")),
            },
            _ => Ok(None),
        }
    }

    /// A new heap cell holding `v`; returns the reference (for `mut` arguments).
    pub fn alloc(&mut self, v: Val) -> Val {
        self.heap.push(v);
        Val::Ref(self.heap.len() - 1)
    }

    /// The value in the cell `r` refers to.
    pub fn read(&self, r: &Val) -> Option<&Val> {
        match r {
            Val::Ref(i) => self.heap.get(*i),
            _ => None,
        }
    }

    /// Runs the function called `name` on `args`.
    pub fn call(&mut self, name: &str, args: Vec<Val>) -> Result<Vec<Val>, InterpError> {
        let f = self
            .m
            .func_by_name(name)
            .ok_or_else(|| err(None, format!("no function `@{name}`")))?;
        self.steps = 0;
        self.call_func(f, args, None)
    }

    pub(crate) fn call_func(
        &mut self,
        f: FuncId,
        args: Vec<Val>,
        at: Option<OpId>,
    ) -> Result<Vec<Val>, InterpError> {
        let func = &self.m.funcs[f];
        if self.m.is_declaration(f) {
            let name = func.name.clone();
            let host = self.externs.get_mut(&name).ok_or_else(|| {
                err(
                    at,
                    format!("call to declaration `@{name}` without a host function"),
                )
            })?;
            return host(&args).map_err(|e| err(at, format!("`@{name}`: {e}")));
        }
        if let Some(k) = func.order_by() {
            return self.call_ordered(f, k, args, at);
        }
        self.run_body(f, args, at)
    }

    /// A call of a best-first function: from its own body, the call is queued; otherwise the
    /// call runs, then its queue until it is empty.
    fn call_ordered(
        &mut self,
        f: FuncId,
        k: usize,
        args: Vec<Val>,
        at: Option<OpId>,
    ) -> Result<Vec<Val>, InterpError> {
        if !self.m.funcs[f].results.is_empty() {
            return Err(err(at, "a best-first function (`order_by`) returns values"));
        }
        let key = args
            .get(k)
            .cloned()
            .ok_or_else(|| err(at, format!("`order_by = {k}`: no such parameter")))?;
        if self.frames.last() == Some(&f) {
            if let Some(q) = self.queues.last_mut().filter(|q| q.func == f) {
                let seq = q.next_seq;
                q.next_seq += 1;
                q.pending.push((key, seq, args));
                return Ok(Vec::new());
            }
        }
        self.queues.push(CallQueue {
            func: f,
            pending: Vec::new(),
            next_seq: 0,
        });
        let mut next = Some(args);
        let mut out = Ok(Vec::new());
        while let Some(args) = next {
            if let Err(e) = self.run_body(f, args, at) {
                out = Err(e);
                break;
            }
            next = self.queues.last_mut().and_then(CallQueue::pop);
        }
        self.queues.pop();
        out
    }

    /// Runs the body of the defined function `f`.
    fn run_body(
        &mut self,
        f: FuncId,
        args: Vec<Val>,
        at: Option<OpId>,
    ) -> Result<Vec<Val>, InterpError> {
        let func = &self.m.funcs[f];
        if self.depth >= self.max_depth {
            return Err(err(
                at,
                format!("call depth limit {} reached", self.max_depth),
            ));
        }
        if let Some(calls) = &mut self.calls {
            *calls.entry(f).or_default() += 1;
        }
        let entry = self.m.regions[func.body].blocks[0];
        if self.m.regions[func.body].blocks.len() != 1 {
            return Err(err(
                at,
                "the interpreter runs single-block (structured) bodies only",
            ));
        }
        self.depth += 1;
        self.frames.push(f);
        let mut env = Env::default();
        let flow = self.run_block(entry, args, &mut env);
        self.frames.pop();
        self.depth -= 1;
        match flow? {
            Flow::Return(vals) => Ok(vals),
            Flow::Yield(_) => Err(err(at, "function body left by `tree.yield`")),
        }
    }

    /// Runs a block with its arguments bound to `args`.
    pub(crate) fn run_block(
        &mut self,
        b: crate::entity::BlockId,
        args: Vec<Val>,
        env: &mut Env,
    ) -> Result<Flow, InterpError> {
        let block = &self.m.blocks[b];
        if block.args.len() != args.len() {
            return Err(err(
                None,
                format!(
                    "block takes {} arguments, given {}",
                    block.args.len(),
                    args.len()
                ),
            ));
        }
        for (&a, v) in block.args.iter().zip(args) {
            env.insert(a, v);
        }
        for &op in &block.ops {
            self.steps += 1;
            if self.steps > self.max_steps {
                return Err(err(
                    Some(op),
                    format!("step limit {} reached", self.max_steps),
                ));
            }
            if let Some(flow) = self.exec(op, env)? {
                return Ok(flow);
            }
        }
        Err(err(None, "block ended without a terminator"))
    }
}

pub(crate) fn err(op: Option<OpId>, message: impl Into<String>) -> InterpError {
    InterpError {
        message: message.into(),
        op,
    }
}
