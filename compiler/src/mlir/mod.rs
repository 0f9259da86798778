//! `--emit=mlir`: a `lo` module as upstream MLIR text, for MLIR-based tools (docs/backends.md,
//! "MLIR"). Dialects: `func` (functions, calls, returns), `arith` (integer and float arithmetic,
//! comparisons, selects, casts), `math` (sqrt, floor, ceil, trunc, fma, absf, counts), `cf`
//! (branches with block arguments) and `llvm` (the opaque `!llvm.ptr`, `alloca`, `load`,
//! `store`, byte-offset `getelementptr`, `inttoptr` and the saturating float-to-int
//! intrinsics). The text is checked by MLIR's own verifier (`mlir-opt`, lit-tests/mlir/).
//!
//! Each `lo` op becomes the MLIR ops with its semantics (docs/ir.md, "The lo dialect"): integer
//! types are signless, so an op's signedness picks the signed or unsigned MLIR op (`divsi` or
//! `divui`, `extsi` or `extui`, `cmpi slt` or `ult`); integer division never traps (a zero
//! divisor divides by 1 and `MIN / -1` wraps, as the other backends compute it); shift amounts are
//! masked to the width; float `min`/`max` are minNum/maxNum with the first operand on ties
//! (compares and selects); float-to-integer casts saturate, NaN giving 0 (range compares
//! around `arith.fpto[su]i`);
//! `next_up`/`next_down` step the bits; booleans are stored as bytes. Directed rounding
//! (`add_rd` ...) is expanded first as the CPU backends do (`scion_ir::lo::directed`). Stack
//! slots become `llvm.alloca`s at the top of the entry block. Not kept: the canonical quiet NaN
//! of `lo`'s arithmetic (MLIR leaves NaN payloads to the target), and GPU thread indices
//! (`lo.global_id`: the kernels of `--target=nvptx64`), which are an error here.

use scion_ir::attr::Attr;
use scion_ir::diag::Diagnostic;
use scion_ir::entity::{raw_index, FuncId, TypeId, ValueId};
use scion_ir::lo::Op as L;
use scion_ir::op::{OpKind, Operation, Successor};
use scion_ir::tree::CmpPred;
use scion_ir::types::{FloatTy, IntTy, Type};
use scion_ir::Module;
use std::fmt::Write;

mod scalar;

/// The MLIR text of the `lo` module `m`.
pub fn print_mlir(m: &Module) -> Result<String, Diagnostic> {
    let m = scion_ir::lo::directed::expanded(m);
    let mut out = String::from("module {\n");
    for &f in &m.func_order {
        Emitter::new(&m).func(f, &mut out)?;
    }
    out.push_str("}\n");
    Ok(out)
}

/// The MLIR type of a `lo` type.
fn mlir_type(m: &Module, t: TypeId) -> Result<String, Diagnostic> {
    Ok(match m.types.get(t) {
        Type::Bool => "i1".into(),
        Type::Int(i) => format!("i{}", i.bits()),
        Type::Float(FloatTy::F32) => "f32".into(),
        Type::Float(FloatTy::F64) => "f64".into(),
        Type::Ptr => "!llvm.ptr".into(),
        other => {
            return Err(Diagnostic::error(
                "E0925",
                format!("--emit=mlir: `{}` is not a type of lo", m.types.display(t)),
            )
            .with_note(format!("found {other:?}")))
        }
    })
}

struct Emitter<'m> {
    m: &'m Module,
    /// Fresh names for the values an op expands into.
    tmp: std::cell::Cell<usize>,
}

impl<'m> Emitter<'m> {
    fn new(m: &'m Module) -> Emitter<'m> {
        Emitter {
            m,
            tmp: std::cell::Cell::new(0),
        }
    }

    fn v(&self, v: ValueId) -> String {
        format!("%v{}", raw_index(v))
    }

    fn fresh(&self) -> String {
        self.tmp.set(self.tmp.get() + 1);
        format!("%t{}", self.tmp.get())
    }

    fn ty(&self, v: ValueId) -> Result<String, Diagnostic> {
        mlir_type(self.m, self.m.values[v].ty)
    }

    fn int_ty(&self, v: ValueId) -> Option<IntTy> {
        match self.m.types.get(self.m.values[v].ty) {
            Type::Int(i) => Some(*i),
            _ => None,
        }
    }

    fn is_float(&self, v: ValueId) -> bool {
        matches!(self.m.types.get(self.m.values[v].ty), Type::Float(_))
    }

    fn is_bool(&self, v: ValueId) -> bool {
        matches!(self.m.types.get(self.m.values[v].ty), Type::Bool)
    }

    fn signed(&self, v: ValueId) -> bool {
        self.int_ty(v).is_some_and(|i| i.is_signed())
    }

    fn func(&self, f: FuncId, out: &mut String) -> Result<(), Diagnostic> {
        let m = self.m;
        let func = &m.funcs[f];
        let results: Vec<String> = func
            .results
            .iter()
            .map(|&t| mlir_type(m, t))
            .collect::<Result<_, _>>()?;
        let res = if results.is_empty() {
            String::new()
        } else {
            format!(" -> ({})", results.join(", "))
        };
        if m.is_declaration(f) {
            let params: Vec<String> = func
                .params
                .iter()
                .map(|&t| mlir_type(m, t))
                .collect::<Result<_, _>>()?;
            let _ = writeln!(
                out,
                "  func.func private @{}({}){res}",
                func.name,
                params.join(", ")
            );
            return Ok(());
        }
        let blocks = &m.regions[func.body].blocks;
        let entry = blocks[0];
        // MLIR's entry block cannot be branched to: when `lo`'s is, the function's parameters
        // get their own names and a new entry jumps to `lo`'s with them.
        let entry_targeted = blocks.iter().any(|&b| {
            m.blocks[b]
                .ops
                .last()
                .is_some_and(|&t| m.ops[t].successors.iter().any(|s| s.block == entry))
        });
        let param_name = |a: ValueId| {
            if entry_targeted {
                format!("%p{}", raw_index(a))
            } else {
                self.v(a)
            }
        };
        let params: Vec<String> = m.blocks[entry]
            .args
            .iter()
            .map(|&a| Ok(format!("{}: {}", param_name(a), self.ty(a)?)))
            .collect::<Result<_, Diagnostic>>()?;
        let _ = writeln!(
            out,
            "  func.func @{}({}){res} {{",
            func.name,
            params.join(", ")
        );
        // Stack slots: allocas at the top of the entry block.
        let mut slots = String::new();
        for &b in blocks {
            for &o in &m.blocks[b].ops {
                let op = &m.ops[o];
                if op.kind == OpKind::Lo(L::StackSlot) {
                    let size = op.int_attr("size").unwrap_or(1).max(1);
                    let align = op.int_attr("align").unwrap_or(8).max(1);
                    let one = self.fresh();
                    let _ = writeln!(slots, "    {one} = arith.constant 1 : i64");
                    let _ = writeln!(
                        slots,
                        "    {} = llvm.alloca {one} x !llvm.array<{size} x i8> {{alignment = {align} : i64}} : (i64) -> !llvm.ptr",
                        self.v(op.results[0])
                    );
                }
            }
        }
        let label = |b: scion_ir::entity::BlockId| format!("^bb{}", raw_index(b));
        if entry_targeted {
            out.push_str(&slots);
            let args: Vec<String> = m.blocks[entry]
                .args
                .iter()
                .map(|&a| param_name(a))
                .collect();
            let tys: Vec<String> = m.blocks[entry]
                .args
                .iter()
                .map(|&a| self.ty(a))
                .collect::<Result<_, _>>()?;
            let _ = writeln!(
                out,
                "    cf.br {}{}",
                label(entry),
                if args.is_empty() {
                    String::new()
                } else {
                    format!("({} : {})", args.join(", "), tys.join(", "))
                }
            );
        }
        for (k, &b) in blocks.iter().enumerate() {
            if k == 0 && !entry_targeted {
                out.push_str(&slots);
            } else {
                let args: Vec<String> = m.blocks[b]
                    .args
                    .iter()
                    .map(|&a| Ok(format!("{}: {}", self.v(a), self.ty(a)?)))
                    .collect::<Result<_, Diagnostic>>()?;
                let _ = writeln!(
                    out,
                    "  {}{}:",
                    label(b),
                    if args.is_empty() {
                        String::new()
                    } else {
                        format!("({})", args.join(", "))
                    }
                );
            }
            for &o in &m.blocks[b].ops {
                self.op(&m.ops[o], out)?;
            }
        }
        out.push_str("  }\n");
        Ok(())
    }

    /// The values' names and their types, each joined by commas.
    fn names_and_types(&self, vals: &[ValueId]) -> Result<(String, String), Diagnostic> {
        let names: Vec<String> = vals.iter().map(|&a| self.v(a)).collect();
        let tys: Vec<String> = vals.iter().map(|&a| self.ty(a)).collect::<Result<_, _>>()?;
        Ok((names.join(", "), tys.join(", ")))
    }

    fn succ(&self, s: &Successor) -> Result<String, Diagnostic> {
        let label = format!("^bb{}", raw_index(s.block));
        if s.args.is_empty() {
            return Ok(label);
        }
        let (args, tys) = self.names_and_types(&s.args)?;
        Ok(format!("{label}({args} : {tys})"))
    }

    /// `%name = arith.constant V : T` for an integer of type `t`.
    fn int_const(&self, out: &mut String, value: i128, ty: &str) -> String {
        let name = self.fresh();
        let _ = writeln!(out, "    {name} = arith.constant {value} : {ty}");
        name
    }

    fn op(&self, o: &Operation, out: &mut String) -> Result<(), Diagnostic> {
        let OpKind::Lo(kind) = o.kind else {
            return Err(Diagnostic::error(
                "E0925",
                format!("--emit=mlir: `{}` is not a lo op", o.kind.name()),
            ));
        };
        let a = |i: usize| self.v(o.operands[i]);
        let r = o.results.first().map(|&x| self.v(x));
        let rt = match o.results.first() {
            Some(&x) => self.ty(x)?,
            None => String::new(),
        };
        let r0 = || r.clone().unwrap_or_default();
        let float = o.results.first().is_some_and(|&x| self.is_float(x));
        let signed = o.operands.first().is_some_and(|&x| self.signed(x));
        let w = |out: &mut String, line: String| {
            let _ = writeln!(out, "    {line}");
        };
        match kind {
            L::StackSlot => {}
            L::Const => {
                let x = o.results[0];
                match (o.attr("value"), self.m.types.get(self.m.values[x].ty)) {
                    (Some(Attr::Bool(b)), _) => w(out, format!("{} = arith.constant {b}", r0())),
                    (Some(Attr::Int(v)), Type::Ptr) => {
                        let c = self.int_const(out, *v as i64 as i128, "i64");
                        w(
                            out,
                            format!("{} = llvm.inttoptr {c} : i64 to !llvm.ptr", r0()),
                        );
                    }
                    (Some(Attr::Int(v)), Type::Int(i)) => {
                        // Signless: the bits, as the signed value of the width.
                        let bits = i.bits();
                        let raw = (*v as u128) & (u128::MAX >> (128 - bits));
                        let signed = if bits < 128 && raw >> (bits - 1) == 1 {
                            raw as i128 - (1i128 << bits)
                        } else {
                            raw as i128
                        };
                        w(out, format!("{} = arith.constant {signed} : {rt}", r0()));
                    }
                    (Some(Attr::Int(v)), Type::Bool) => {
                        w(out, format!("{} = arith.constant {}", r0(), *v != 0))
                    }
                    (Some(Attr::Float(bits)), Type::Float(ft)) => {
                        let hex = if *ft == FloatTy::F32 {
                            format!("0x{:08X}", (f64::from_bits(*bits) as f32).to_bits())
                        } else {
                            format!("0x{bits:016X}")
                        };
                        w(out, format!("{} = arith.constant {hex} : {rt}", r0()));
                    }
                    _ => {
                        return Err(Diagnostic::error(
                            "E0925",
                            "--emit=mlir: a lo.const without a value of its type",
                        ))
                    }
                }
            }
            L::Add | L::Sub | L::Mul if float => {
                let name = match kind {
                    L::Add => "addf",
                    L::Sub => "subf",
                    _ => "mulf",
                };
                w(
                    out,
                    format!("{} = arith.{name} {}, {} : {rt}", r0(), a(0), a(1)),
                );
            }
            L::Div | L::Rem if float => {
                let name = if kind == L::Div { "divf" } else { "remf" };
                w(
                    out,
                    format!("{} = arith.{name} {}, {} : {rt}", r0(), a(0), a(1)),
                );
            }
            L::Add | L::Sub | L::Mul | L::And | L::Or | L::Xor => {
                let name = match kind {
                    L::Add => "addi",
                    L::Sub => "subi",
                    L::Mul => "muli",
                    L::And => "andi",
                    L::Or => "ori",
                    _ => "xori",
                };
                w(
                    out,
                    format!("{} = arith.{name} {}, {} : {rt}", r0(), a(0), a(1)),
                );
            }
            L::Div | L::Rem => {
                // Never trapping, as the other backends compute it: a zero divisor divides by
                // 1 (`lo` leaves division by zero to the program; the interpreters stop), and
                // a signed MIN / -1 wraps (its remainder 0).
                let (x, y) = (a(0), a(1));
                let zero = self.int_const(out, 0, &rt);
                let one = self.int_const(out, 1, &rt);
                let is_zero = self.fresh();
                w(
                    out,
                    format!("{is_zero} = arith.cmpi eq, {y}, {zero} : {rt}"),
                );
                if !signed {
                    let safe = self.fresh();
                    w(
                        out,
                        format!("{safe} = arith.select {is_zero}, {one}, {y} : {rt}"),
                    );
                    let name = if kind == L::Div { "divui" } else { "remui" };
                    w(out, format!("{} = arith.{name} {x}, {safe} : {rt}", r0()));
                } else {
                    let m1 = self.int_const(out, -1, &rt);
                    let is_m1 = self.fresh();
                    w(out, format!("{is_m1} = arith.cmpi eq, {y}, {m1} : {rt}"));
                    let bad = self.fresh();
                    w(out, format!("{bad} = arith.ori {is_zero}, {is_m1} : i1"));
                    let safe = self.fresh();
                    w(
                        out,
                        format!("{safe} = arith.select {bad}, {one}, {y} : {rt}"),
                    );
                    let q = self.fresh();
                    let special = self.fresh();
                    if kind == L::Div {
                        w(out, format!("{q} = arith.divsi {x}, {safe} : {rt}"));
                        w(out, format!("{special} = arith.subi {zero}, {x} : {rt}"));
                    } else {
                        w(out, format!("{q} = arith.remsi {x}, {safe} : {rt}"));
                        w(out, format!("{special} = arith.addi {zero}, {zero} : {rt}"));
                    }
                    w(
                        out,
                        format!("{} = arith.select {is_m1}, {special}, {q} : {rt}", r0()),
                    );
                }
            }
            L::Shl | L::Shr => {
                let amt_ty = self.ty(o.operands[1])?;
                let bits = self.int_ty(o.results[0]).map_or(1, |i| i.bits());
                let amt_bits = self.int_ty(o.operands[1]).map_or(1, |i| i.bits());
                let amt = if amt_bits == bits {
                    a(1)
                } else {
                    let c = self.fresh();
                    let op = if amt_bits < bits { "extui" } else { "trunci" };
                    w(out, format!("{c} = arith.{op} {} : {amt_ty} to {rt}", a(1)));
                    c
                };
                let mask = self.int_const(out, i128::from(bits - 1), &rt);
                let masked = self.fresh();
                w(out, format!("{masked} = arith.andi {amt}, {mask} : {rt}"));
                let name = match (kind, signed) {
                    (L::Shl, _) => "shli",
                    (_, true) => "shrsi",
                    _ => "shrui",
                };
                w(
                    out,
                    format!("{} = arith.{name} {}, {masked} : {rt}", r0(), a(0)),
                );
            }
            L::BitNot | L::Not => {
                let ones = if self.is_bool(o.operands[0]) {
                    let c = self.fresh();
                    w(out, format!("{c} = arith.constant true"));
                    c
                } else {
                    self.int_const(out, -1, &rt)
                };
                w(
                    out,
                    format!("{} = arith.xori {}, {ones} : {rt}", r0(), a(0)),
                );
            }
            L::Neg if float => w(out, format!("{} = arith.negf {} : {rt}", r0(), a(0))),
            L::Neg => {
                let zero = self.int_const(out, 0, &rt);
                w(
                    out,
                    format!("{} = arith.subi {zero}, {} : {rt}", r0(), a(0)),
                );
            }
            L::Abs if float => w(out, format!("{} = math.absf {} : {rt}", r0(), a(0))),
            L::Abs if signed => w(out, format!("{} = math.absi {} : {rt}", r0(), a(0))),
            L::Abs => {
                let z = self.int_const(out, 0, &rt);
                w(out, format!("{} = arith.addi {}, {z} : {rt}", r0(), a(0)));
            }
            L::Sqrt | L::Floor | L::Ceil | L::Trunc => {
                let name = match kind {
                    L::Sqrt => "sqrt",
                    L::Floor => "floor",
                    L::Ceil => "ceil",
                    _ => "trunc",
                };
                w(out, format!("{} = math.{name} {} : {rt}", r0(), a(0)));
            }
            L::Fma => w(
                out,
                format!("{} = math.fma {}, {}, {} : {rt}", r0(), a(0), a(1), a(2)),
            ),
            L::Popcount | L::Clz | L::Ctz => {
                // `math.ctlz`/`cttz` of 0 is the width, as `lo` defines it.
                let name = match kind {
                    L::Popcount => "ctpop",
                    L::Clz => "ctlz",
                    _ => "cttz",
                };
                w(out, format!("{} = math.{name} {} : {rt}", r0(), a(0)));
            }
            L::Min | L::Max if float => {
                // minNum/maxNum, `p` on ties: select(q better than p, q, p), then q when p is NaN.
                let (p, q) = (a(0), a(1));
                let pred = if kind == L::Max { "ogt" } else { "olt" };
                let better = self.fresh();
                w(
                    out,
                    format!("{better} = arith.cmpf {pred}, {q}, {p} : {rt}"),
                );
                let s = self.fresh();
                w(out, format!("{s} = arith.select {better}, {q}, {p} : {rt}"));
                let p_nan = self.fresh();
                w(out, format!("{p_nan} = arith.cmpf uno, {p}, {p} : {rt}"));
                w(
                    out,
                    format!("{} = arith.select {p_nan}, {q}, {s} : {rt}", r0()),
                );
            }
            L::Min | L::Max => {
                let name = match (kind, signed) {
                    (L::Min, true) => "minsi",
                    (L::Min, false) => "minui",
                    (_, true) => "maxsi",
                    _ => "maxui",
                };
                w(
                    out,
                    format!("{} = arith.{name} {}, {} : {rt}", r0(), a(0), a(1)),
                );
            }
            L::NextUp | L::NextDown => self.next(kind == L::NextUp, o, out)?,
            L::Cmp => {
                let pred = o.pred().ok_or_else(|| {
                    Diagnostic::error("E0925", "--emit=mlir: a lo.cmp without a predicate")
                })?;
                let t = self.ty(o.operands[0])?;
                let (op, p) = if self.is_float(o.operands[0]) {
                    (
                        "cmpf",
                        match pred {
                            CmpPred::Eq => "oeq",
                            CmpPred::Ne => "une",
                            CmpPred::Lt => "olt",
                            CmpPred::Le => "ole",
                            CmpPred::Gt => "ogt",
                            CmpPred::Ge => "oge",
                        },
                    )
                } else {
                    (
                        "cmpi",
                        match (pred, signed) {
                            (CmpPred::Eq, _) => "eq",
                            (CmpPred::Ne, _) => "ne",
                            (CmpPred::Lt, true) => "slt",
                            (CmpPred::Le, true) => "sle",
                            (CmpPred::Gt, true) => "sgt",
                            (CmpPred::Ge, true) => "sge",
                            (CmpPred::Lt, false) => "ult",
                            (CmpPred::Le, false) => "ule",
                            (CmpPred::Gt, false) => "ugt",
                            (CmpPred::Ge, false) => "uge",
                        },
                    )
                };
                w(
                    out,
                    format!("{} = arith.{op} {p}, {}, {} : {t}", r0(), a(0), a(1)),
                );
            }
            L::Select => w(
                out,
                format!(
                    "{} = arith.select {}, {}, {} : {rt}",
                    r0(),
                    a(0),
                    a(1),
                    a(2)
                ),
            ),
            L::Cast => self.cast(o, out)?,
            L::Bitcast => {
                let ft = self.ty(o.operands[0])?;
                w(
                    out,
                    format!("{} = arith.bitcast {} : {ft} to {rt}", r0(), a(0)),
                );
            }
            L::Load => {
                let p = self.offset(out, &a(0), o.int_attr("offset").unwrap_or(0));
                if self.is_bool(o.results[0]) {
                    let byte = self.fresh();
                    w(
                        out,
                        format!("{byte} = llvm.load {p} {{alignment = 1 : i64}} : !llvm.ptr -> i8"),
                    );
                    let zero = self.int_const(out, 0, "i8");
                    w(
                        out,
                        format!("{} = arith.cmpi ne, {byte}, {zero} : i8", r0()),
                    );
                } else {
                    w(
                        out,
                        format!(
                            "{} = llvm.load {p} {{alignment = 1 : i64}} : !llvm.ptr -> {rt}",
                            r0()
                        ),
                    );
                }
            }
            L::Store => {
                let p = self.offset(out, &a(0), o.int_attr("offset").unwrap_or(0));
                let (mut v, mut t) = (a(1), self.ty(o.operands[1])?);
                if self.is_bool(o.operands[1]) {
                    let byte = self.fresh();
                    w(out, format!("{byte} = arith.extui {v} : i1 to i8"));
                    (v, t) = (byte, "i8".into());
                }
                w(
                    out,
                    format!("llvm.store {v}, {p} {{alignment = 1 : i64}} : {t}, !llvm.ptr"),
                );
            }
            L::PtrAdd => {
                let off_ty = self.ty(o.operands[1])?;
                let off = if off_ty == "i64" {
                    a(1)
                } else {
                    let c = self.fresh();
                    let ext = if self.signed(o.operands[1]) {
                        "extsi"
                    } else {
                        "extui"
                    };
                    w(out, format!("{c} = arith.{ext} {} : {off_ty} to i64", a(1)));
                    c
                };
                w(
                    out,
                    format!(
                        "{} = llvm.getelementptr {}[{off}] : (!llvm.ptr, i64) -> !llvm.ptr, i8",
                        r0(),
                        a(0)
                    ),
                );
            }
            L::GlobalId => {
                return Err(Diagnostic::error(
                    "E0925",
                    "--emit=mlir: a GPU thread index (`lo.global_id`) has no host MLIR form",
                )
                .with_note("emit MLIR for the host entries (no --target=nvptx64)"))
            }
            L::Call => {
                let callee = o.callee().unwrap_or("?");
                let (args, tys) = self.names_and_types(&o.operands)?;
                let (rs, rts) = self.names_and_types(&o.results)?;
                let lhs = if rs.is_empty() {
                    String::new()
                } else {
                    format!("{rs} = ")
                };
                w(
                    out,
                    format!("{lhs}func.call @{callee}({args}) : ({tys}) -> ({rts})"),
                );
            }
            L::Br => w(out, format!("cf.br {}", self.succ(&o.successors[0])?)),
            L::CondBr => w(
                out,
                format!(
                    "cf.cond_br {}, {}, {}",
                    a(0),
                    self.succ(&o.successors[0])?,
                    self.succ(&o.successors[1])?
                ),
            ),
            L::Return => {
                if o.operands.is_empty() {
                    w(out, "func.return".into());
                } else {
                    let (args, tys) = self.names_and_types(&o.operands)?;
                    w(out, format!("func.return {args} : {tys}"));
                }
            }
            L::AddRd | L::AddRu | L::MulRd | L::MulRu => {
                return Err(Diagnostic::error(
                    "E0925",
                    "--emit=mlir: directed rounding left after its expansion",
                ))
            }
        }
        Ok(())
    }

    /// `p + offset` as a byte address (`p` itself for 0).
    fn offset(&self, out: &mut String, p: &str, offset: i128) -> String {
        if offset == 0 {
            return p.to_string();
        }
        let q = self.fresh();
        let _ = writeln!(
            out,
            "    {q} = llvm.getelementptr {p}[{offset}] : (!llvm.ptr) -> !llvm.ptr, i8"
        );
        q
    }
}
