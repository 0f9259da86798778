//! The `lo` ops whose MLIR takes more than one op: casts with Rust's `as` semantics and the
//! one-ulp steps (`next_up`, `next_down`).

use super::Emitter;
use scion_ir::diag::Diagnostic;
use scion_ir::op::Operation;
use scion_ir::types::{FloatTy, Type};
use std::fmt::Write;

impl Emitter<'_> {
    /// `lo.cast`: Rust `as` semantics between scalars.
    pub(super) fn cast(&self, o: &Operation, out: &mut String) -> Result<(), Diagnostic> {
        let (x, r) = (self.v(o.operands[0]), self.v(o.results[0]));
        let (ft, tt) = (self.ty(o.operands[0])?, self.ty(o.results[0])?);
        let from = self.m.types.get(self.m.values[o.operands[0]].ty).clone();
        let to = self.m.types.get(self.m.values[o.results[0]].ty).clone();
        let w = |out: &mut String, line: String| {
            let _ = writeln!(out, "    {line}");
        };
        let width = |t: &Type| match t {
            Type::Int(i) => i.bits(),
            Type::Bool => 1,
            Type::Float(FloatTy::F32) => 32,
            _ => 64,
        };
        match (&from, &to) {
            (Type::Float(_), Type::Bool) => {
                let zero = self.fresh();
                w(out, format!("{zero} = arith.constant 0.0 : {ft}"));
                w(out, format!("{r} = arith.cmpf une, {x}, {zero} : {ft}"));
            }
            (Type::Int(_), Type::Bool) => {
                let zero = self.int_const(out, 0, &ft);
                w(out, format!("{r} = arith.cmpi ne, {x}, {zero} : {ft}"));
            }
            (Type::Int(_) | Type::Bool, Type::Int(_)) | (Type::Bool, Type::Bool) => {
                let (a, b) = (width(&from), width(&to));
                let s = matches!(from, Type::Int(i) if i.is_signed());
                let op = if a == b {
                    // The same width: the bits (a no-op MLIR still wants spelled).
                    let z = self.int_const(out, 0, &tt);
                    w(out, format!("{r} = arith.addi {x}, {z} : {tt}"));
                    return Ok(());
                } else if a < b {
                    if s {
                        "extsi"
                    } else {
                        "extui"
                    }
                } else {
                    "trunci"
                };
                w(out, format!("{r} = arith.{op} {x} : {ft} to {tt}"));
            }
            (Type::Int(_) | Type::Bool, Type::Float(_)) => {
                let s = matches!(from, Type::Int(i) if i.is_signed());
                let op = if s { "sitofp" } else { "uitofp" };
                w(out, format!("{r} = arith.{op} {x} : {ft} to {tt}"));
            }
            (Type::Float(fw), Type::Int(i)) => {
                // Saturating, NaN to 0 (Rust's `as`): `fpto[su]i` of the value when it is in
                // range (of 0 otherwise, never poison), then the bound or 0 selected.
                let bits = i.bits();
                let (lo, hi) = if i.is_signed() {
                    (-(2f64.powi(bits as i32 - 1)), 2f64.powi(bits as i32 - 1))
                } else {
                    (-1.0, 2f64.powi(bits as i32))
                };
                let fconst = |x: f64| {
                    if *fw == FloatTy::F32 {
                        format!("0x{:08X}", (x as f32).to_bits())
                    } else {
                        format!("0x{:016X}", x.to_bits())
                    }
                };
                let (lo_c, hi_c, zero_f) = (self.fresh(), self.fresh(), self.fresh());
                w(
                    out,
                    format!("{lo_c} = arith.constant {} : {ft}", fconst(lo)),
                );
                w(
                    out,
                    format!("{hi_c} = arith.constant {} : {ft}", fconst(hi)),
                );
                w(out, format!("{zero_f} = arith.constant 0.0 : {ft}"));
                let (above_lo, below_hi, in_range) = (self.fresh(), self.fresh(), self.fresh());
                let lo_pred = if i.is_signed() { "oge" } else { "ogt" };
                w(
                    out,
                    format!("{above_lo} = arith.cmpf {lo_pred}, {x}, {lo_c} : {ft}"),
                );
                w(
                    out,
                    format!("{below_hi} = arith.cmpf olt, {x}, {hi_c} : {ft}"),
                );
                w(
                    out,
                    format!("{in_range} = arith.andi {above_lo}, {below_hi} : i1"),
                );
                let safe = self.fresh();
                w(
                    out,
                    format!("{safe} = arith.select {in_range}, {x}, {zero_f} : {ft}"),
                );
                let conv = self.fresh();
                let name = if i.is_signed() { "fptosi" } else { "fptoui" };
                w(out, format!("{conv} = arith.{name} {safe} : {ft} to {tt}"));
                let (max, min) = if i.is_signed() {
                    ((1i128 << (bits - 1)) - 1, -(1i128 << (bits - 1)))
                } else {
                    (-1, 0)
                };
                let max_c = self.int_const(out, max, &tt);
                let min_c = self.int_const(out, min, &tt);
                let zero_i = self.int_const(out, 0, &tt);
                let (high, nan, low_or_nan, out_of_range) =
                    (self.fresh(), self.fresh(), self.fresh(), self.fresh());
                w(out, format!("{high} = arith.cmpf oge, {x}, {hi_c} : {ft}"));
                w(out, format!("{nan} = arith.cmpf uno, {x}, {x} : {ft}"));
                w(
                    out,
                    format!("{low_or_nan} = arith.select {nan}, {zero_i}, {min_c} : {tt}"),
                );
                w(
                    out,
                    format!("{out_of_range} = arith.select {high}, {max_c}, {low_or_nan} : {tt}"),
                );
                w(
                    out,
                    format!("{r} = arith.select {in_range}, {conv}, {out_of_range} : {tt}"),
                );
            }
            (Type::Float(a), Type::Float(b)) if a == b => {
                // The same type: `x + -0.0` is `x` (bits and all, NaN payloads aside).
                let z = self.fresh();
                w(out, format!("{z} = arith.constant -0.0 : {tt}"));
                w(out, format!("{r} = arith.addf {x}, {z} : {tt}"));
            }
            (Type::Float(_), Type::Float(FloatTy::F64)) => {
                w(out, format!("{r} = arith.extf {x} : {ft} to {tt}"))
            }
            (Type::Float(_), Type::Float(_)) => {
                w(out, format!("{r} = arith.truncf {x} : {ft} to {tt}"))
            }
            _ => {
                return Err(Diagnostic::error(
                    "E0925",
                    format!("--emit=mlir: no cast from {ft} to {tt}"),
                ))
            }
        }
        Ok(())
    }

    /// `lo.next_up` / `next_down`: one ulp toward +inf / -inf by the bits; NaN and that
    /// infinity stay, zeros step to the smallest subnormal.
    pub(super) fn next(&self, up: bool, o: &Operation, out: &mut String) -> Result<(), Diagnostic> {
        let (x, r) = (self.v(o.operands[0]), self.v(o.results[0]));
        let ft = self.ty(o.operands[0])?;
        let wide = ft == "f64";
        let it = if wide { "i64" } else { "i32" };
        let (zero_step, inf): (i128, &str) = match (wide, up) {
            (false, true) => (1, "0x7F800000"),
            (false, false) => (0x8000_0001u32 as i32 as i128, "0xFF800000"),
            (true, true) => (1, "0x7FF0000000000000"),
            (true, false) => (
                0x8000_0000_0000_0001u64 as i64 as i128,
                "0xFFF0000000000000",
            ),
        };
        let w = |out: &mut String, line: String| {
            let _ = writeln!(out, "    {line}");
        };
        let bits = self.fresh();
        w(out, format!("{bits} = arith.bitcast {x} : {ft} to {it}"));
        let one = self.int_const(out, 1, it);
        let inc = self.fresh();
        w(out, format!("{inc} = arith.addi {bits}, {one} : {it}"));
        let dec = self.fresh();
        w(out, format!("{dec} = arith.subi {bits}, {one} : {it}"));
        let zero = self.fresh();
        w(out, format!("{zero} = arith.constant 0.0 : {ft}"));
        let pos = self.fresh();
        w(out, format!("{pos} = arith.cmpf ogt, {x}, {zero} : {ft}"));
        let stepped = self.fresh();
        let (a, b) = if up { (&inc, &dec) } else { (&dec, &inc) };
        w(
            out,
            format!("{stepped} = arith.select {pos}, {a}, {b} : {it}"),
        );
        let is_zero = self.fresh();
        w(
            out,
            format!("{is_zero} = arith.cmpf oeq, {x}, {zero} : {ft}"),
        );
        let zs = self.int_const(out, zero_step, it);
        let s2 = self.fresh();
        w(
            out,
            format!("{s2} = arith.select {is_zero}, {zs}, {stepped} : {it}"),
        );
        let back = self.fresh();
        w(out, format!("{back} = arith.bitcast {s2} : {it} to {ft}"));
        let nan = self.fresh();
        w(out, format!("{nan} = arith.cmpf uno, {x}, {x} : {ft}"));
        let infc = self.fresh();
        w(out, format!("{infc} = arith.constant {inf} : {ft}"));
        let at_inf = self.fresh();
        w(
            out,
            format!("{at_inf} = arith.cmpf oeq, {x}, {infc} : {ft}"),
        );
        let keep = self.fresh();
        w(out, format!("{keep} = arith.ori {nan}, {at_inf} : i1"));
        w(
            out,
            format!("{r} = arith.select {keep}, {x}, {back} : {ft}"),
        );
        Ok(())
    }
}
