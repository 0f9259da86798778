//! Four records' fields gathered into lanes as four 16-byte loads and a transpose.
//!
//! A leaf's four triangles (`block_of`: lane `k` of each field is triangle `k`'s) are four
//! records at four addresses, each field a 32-bit word at the same offset in every record. Lane
//! by lane, a field's vector is four scalar loads and three insertions; Cranelift merges no load
//! into the insertion (it merges a load only where the loaded value is used once transitively,
//! and a triangle's lanes feed products used several times), so the nine fields of four
//! triangles took 36 `vmovss` and 27 `vinsertps`. When the block also loads the three words
//! after a field's word from each of the four records (`x`, `y`, `z` of a corner and the next
//! word), the four fields are one 16-byte load per record and a 4 × 4 transpose: four loads and
//! eight interleaving shuffles (`punpckldq`, `punpckhdq`, `punpcklqdq`, `punpckhqdq`) for four
//! fields' lanes.
//!
//! Only loads not yet emitted are taken ([`Fx::deferred`]: the block reads them, and no store,
//! call or branch has come since, so reading them here reads what the block reads); the rows
//! read exactly the sixteen words that those loads name. Their lanes are bound as
//! [`crate::loads`]' vector loads bind theirs, so each field's group later finds its vector.

use crate::translate::Fx;
use cranelift_codegen::ir::{self, types, InstBuilder};
use scion_ir::entity::{OpId, ValueId};
use scion_ir::lo::Op as L;
use scion_ir::op::OpKind;
use scion_ir::types::{FloatTy, Type};

/// The interleaving shuffles' byte masks: 32-bit lanes low and high, 64-bit lanes low and high.
const LO32: [u8; 16] = [0, 1, 2, 3, 16, 17, 18, 19, 4, 5, 6, 7, 20, 21, 22, 23];
const HI32: [u8; 16] = [8, 9, 10, 11, 24, 25, 26, 27, 12, 13, 14, 15, 28, 29, 30, 31];
const LO64: [u8; 16] = [0, 1, 2, 3, 4, 5, 6, 7, 16, 17, 18, 19, 20, 21, 22, 23];
const HI64: [u8; 16] = [8, 9, 10, 11, 12, 13, 14, 15, 24, 25, 26, 27, 28, 29, 30, 31];

impl Fx<'_, '_> {
    /// The deferred loads of the 32-bit word at `addr` + `offset`, as (name, op, lane type).
    fn deferred_words(&self, addr: ValueId, offset: i128) -> Vec<(ValueId, OpId, ir::Type)> {
        let m = self.m;
        self.deferred
            .iter()
            .filter_map(|&(name, op)| {
                let o = &m.ops[op];
                let vt = word_type(m, m.values[o.results[0]].ty)?;
                (o.operands[0] == addr
                    && o.int_attr("offset").unwrap_or(0) == offset
                    && o.attr("global").is_none())
                .then_some((name, op, vt))
            })
            .collect()
    }

    /// When the four lanes `xs` are deferred loads of a 32-bit word at one offset from four
    /// addresses, and the block's deferred loads also read the three words after some such
    /// word from each (the lowest such start), the four records' sixteen words loaded as four
    /// rows and transposed, every lane of the four columns bound to its load.
    pub(crate) fn transposed_load(&mut self, xs: &[ValueId]) -> Result<(), String> {
        let m = self.m;
        if xs.len() != 4 {
            return Ok(());
        }
        let mut addrs = Vec::with_capacity(4);
        let mut offset = None;
        for x in xs {
            let Some(&(_, op)) = self.deferred.iter().find(|d| d.0 == *x) else {
                return Ok(());
            };
            let o = &m.ops[op];
            let off = o.int_attr("offset").unwrap_or(0);
            if o.kind != OpKind::Lo(L::Load)
                || o.attr("global").is_some()
                || offset.is_some_and(|c| c != off)
                || word_type(m, m.values[o.results[0]].ty).is_none()
            {
                return Ok(());
            }
            offset = Some(off);
            addrs.push(o.operands[0]);
        }
        let Some(c) = offset else {
            return Ok(());
        };
        // The lowest start whose 16 bytes the block reads from every record (record k's row
        // is its words start .. start + 16).
        let mut found = None;
        for start in [c - 12, c - 8, c - 4, c] {
            // Each column's lane type: the type the block reads the word as, the same in every
            // record (a word read as `f32` in one and as an integer in another is left to the
            // scalar gathers).
            let types: Option<Vec<ir::Type>> = (0..4)
                .map(|i| {
                    let ty = |a: ValueId| Some(self.deferred_words(a, start + 4 * i).first()?.2);
                    let t = ty(addrs[0])?;
                    addrs[1..].iter().all(|&a| ty(a) == Some(t)).then_some(t)
                })
                .collect();
            if let Some(types) = types {
                found = Some((start, types));
                break;
            }
        }
        let Some((start, types)) = found else {
            return Ok(());
        };
        let all_pure = addrs.iter().all(|&a| {
            (0..4).all(|i| {
                self.deferred_words(a, start + 4 * i)
                    .iter()
                    .all(|(_, op, _)| self.pure_loads.contains(op))
            })
        });
        let flags = crate::loads::flags(all_pure);
        let mut row_vals = Vec::with_capacity(4);
        for &a in &addrs {
            let base = self.v(a)?;
            row_vals.push(self.b.ins().load(types::I8X16, flags, base, start as i32));
        }
        let t0 = self.shuffle(row_vals[0], row_vals[1], &LO32);
        let t1 = self.shuffle(row_vals[2], row_vals[3], &LO32);
        let t2 = self.shuffle(row_vals[0], row_vals[1], &HI32);
        let t3 = self.shuffle(row_vals[2], row_vals[3], &HI32);
        let cols = [
            self.shuffle(t0, t1, &LO64),
            self.shuffle(t0, t1, &HI64),
            self.shuffle(t2, t3, &LO64),
            self.shuffle(t2, t3, &HI64),
        ];
        for (i, (&col, &vt)) in cols.iter().zip(&types).enumerate() {
            let v = self.b.ins().bitcast(vt, crate::lanes::lanes_flags(), col);
            for (k, &a) in addrs.iter().enumerate() {
                // Every deferred load of this word as this lane type (a field read twice is one
                // word; read as another type, it stays a scalar load).
                let lane = self.b.ins().extractlane(v, k as u8);
                for (name, op, t) in self.deferred_words(a, start + 4 * i as i128) {
                    if t == vt {
                        self.bind_lane(name, op, v, k as u8, lane);
                    }
                }
            }
        }
        Ok(())
    }

    /// `a` and `b` (16 bytes each) shuffled by byte mask `mask`.
    fn shuffle(&mut self, a: ir::Value, b: ir::Value, mask: &[u8; 16]) -> ir::Value {
        let imm = self
            .b
            .func
            .dfg
            .immediates
            .push(ir::ConstantData::from(mask.to_vec()));
        self.b.ins().shuffle(a, b, imm)
    }
}

/// The four-lane vector type of a 32-bit word of `lo` type `ty`: `f32` or a 32-bit integer.
fn word_type(m: &scion_ir::Module, ty: scion_ir::TypeId) -> Option<ir::Type> {
    match m.types.get(ty) {
        Type::Float(FloatTy::F32) => Some(types::F32X4),
        Type::Int(t) if t.bits() == 32 => Some(types::I32X4),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use crate::JitModule;
    use scion_ir::interp::lo::LoInterp;
    use scion_ir::interp::Val;
    use scion_ir::types::IntTy;

    /// Four records of four words, word 1 an `i32`: three lane groups read words 0, 1 and 3 of
    /// the four records (word 0 twice), and the block also reads word 2, so the groups' lanes
    /// are the transposed rows' columns.
    const GATHER: &str = r#"
func @gather(%p0: ptr, %p1: ptr, %p2: ptr, %p3: ptr) -> (f32, f32, f32, f32, i32, i32, i32, i32, f32, f32, f32, f32) {
  %a0 = "lo.load"(%p0) {offset = 0} : (ptr) -> f32
  %a1 = "lo.load"(%p1) {offset = 0} : (ptr) -> f32
  %a2 = "lo.load"(%p2) {offset = 0} : (ptr) -> f32
  %a3 = "lo.load"(%p3) {offset = 0} : (ptr) -> f32
  %b0 = "lo.load"(%p0) {offset = 4} : (ptr) -> i32
  %b1 = "lo.load"(%p1) {offset = 4} : (ptr) -> i32
  %b2 = "lo.load"(%p2) {offset = 4} : (ptr) -> i32
  %b3 = "lo.load"(%p3) {offset = 4} : (ptr) -> i32
  %c0 = "lo.load"(%p0) {offset = 8} : (ptr) -> f32
  %c1 = "lo.load"(%p1) {offset = 8} : (ptr) -> f32
  %c2 = "lo.load"(%p2) {offset = 8} : (ptr) -> f32
  %c3 = "lo.load"(%p3) {offset = 8} : (ptr) -> f32
  %d0 = "lo.load"(%p0) {offset = 12} : (ptr) -> f32
  %d1 = "lo.load"(%p1) {offset = 12} : (ptr) -> f32
  %d2 = "lo.load"(%p2) {offset = 12} : (ptr) -> f32
  %d3 = "lo.load"(%p3) {offset = 12} : (ptr) -> f32
  %s0 = "lo.sub"(%d0, %a0) {lane = [0, 0, 4]} : (f32, f32) -> f32
  %s1 = "lo.sub"(%d1, %a1) {lane = [0, 1, 4]} : (f32, f32) -> f32
  %s2 = "lo.sub"(%d2, %a2) {lane = [0, 2, 4]} : (f32, f32) -> f32
  %s3 = "lo.sub"(%d3, %a3) {lane = [0, 3, 4]} : (f32, f32) -> f32
  %t0 = "lo.add"(%b0, %b0) {lane = [1, 0, 4]} : (i32, i32) -> i32
  %t1 = "lo.add"(%b1, %b1) {lane = [1, 1, 4]} : (i32, i32) -> i32
  %t2 = "lo.add"(%b2, %b2) {lane = [1, 2, 4]} : (i32, i32) -> i32
  %t3 = "lo.add"(%b3, %b3) {lane = [1, 3, 4]} : (i32, i32) -> i32
  %u0 = "lo.mul"(%c0, %a0) {lane = [2, 0, 4]} : (f32, f32) -> f32
  %u1 = "lo.mul"(%c1, %a1) {lane = [2, 1, 4]} : (f32, f32) -> f32
  %u2 = "lo.mul"(%c2, %a2) {lane = [2, 2, 4]} : (f32, f32) -> f32
  %u3 = "lo.mul"(%c3, %a3) {lane = [2, 3, 4]} : (f32, f32) -> f32
  "lo.return"(%s0, %s1, %s2, %s3, %t0, %t1, %t2, %t3, %u0, %u1, %u2, %u3) : (f32, f32, f32, f32, i32, i32, i32, i32, f32, f32, f32, f32) -> ()
}
"#;

    fn bits(v: &Val) -> u64 {
        match v {
            Val::F32(x) => u64::from(x.to_bits()),
            Val::Int(i, _) => *i as u64,
            other => panic!("unexpected {other:?}"),
        }
    }

    #[test]
    fn four_records_words_are_transposed_rows_and_give_the_interpreters_lanes() {
        let m = scion_ir::parse_module(GATHER, scion_ir::diag::FileId(0)).expect("parses");
        let clif = crate::print_clif(&m).expect("translates");
        assert_eq!(clif.matches("load.i8x16").count(), 4, "{clif}");
        assert!(!clif.contains("insertlane"), "{clif}");
        // Records with special values: NaN payloads, signed zeros, infinities, subnormals and
        // integers at their extremes, each in its own word and record.
        let words: [[u32; 4]; 4] = [
            [0x7fc0_0001, 0x8000_0000, 0x3f80_0000, 0xff80_0000],
            [0x8000_0000, 0x7fff_ffff, 0x0000_0001, 0x7f7f_ffff],
            [0x4049_0fdb, 0xffff_ffff, 0xffc1_2345, 0x0000_0000],
            [0xc2f6_e979, 0x0000_0001, 0x7f80_0000, 0x807f_ffff],
        ];
        let bytes: Vec<Vec<u8>> = words
            .iter()
            .map(|r| r.iter().flat_map(|w| w.to_le_bytes()).collect())
            .collect();
        let mut it = LoInterp::new(&m);
        let args: Vec<Val> = bytes
            .iter()
            .map(|b| Val::Int(i128::from(it.alloc(b, 16)), IntTy::U64))
            .collect();
        let want = it.call("gather", args).expect("interprets");
        let jit = JitModule::compile(&m).expect("compiles");
        let host: Vec<Val> = bytes
            .iter()
            .map(|b| Val::Int(i128::from(b.as_ptr() as u64), IntTy::U64))
            .collect();
        let got = jit.call("gather", &host).expect("runs");
        assert_eq!(want.len(), 12);
        for (k, (w, g)) in want.iter().zip(&got).enumerate() {
            assert_eq!(
                bits(w),
                bits(g),
                "result {k}: interpreter {w:?}, Cranelift {g:?}"
            );
        }
    }
}
