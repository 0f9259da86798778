//! Two idioms of the eight-wide traversals that `lo`, having no vector types, spells with
//! scalars, translated on CPUs as the vector operations they are (NVPTX keeps the scalars).
//!
//! **A dynamic index into a value array.** `mem-to-lo` lowers `a[i]` for an array `a` of `n`
//! values held in registers (no layout memory behind it) as a chain of selects, each keyed on
//! one position: `select(i == n-1, a[n-1], select(i == n-2, a[n-2], ... select(i == 1, a[1],
//! a[0])))` (an index out of range gives `a[0]`). LLVM keeps such a chain as compares and
//! blends, or turns it into a jump tree (`d[ctz(m)]` of eight distances: about 30 instructions
//! and several branches on the index). The root of a chain of four or more positions becomes
//! `extractelement <n x T> a, (i <u n ? i : 0)`, the same value, which the code generators lower
//! to one store of the vector and one load of the lane ([`Fn::index_chain`]).
//!
//! **The bits of several conditions.** `(c0 as u32) | ((c1 as u32) << 1) | ... | ((cN-1 as u32)
//! << N-1)`, every position once, becomes `zext(bitcast <N x i1> [c0, ..., cN-1] to iN)`: the
//! SLP vectorizer then makes the N compares one vector compare and the bits one `vmovmskps` or
//! `kmovb`, where it otherwise vectorizes such an `or` tree piecewise (lanes 1-4 as a vector,
//! the others one by one: about 30 instructions for eight bits) ([`Fn::lane_bits`]).

use super::*;

/// The shortest chain worth a vector: four positions (three selects).
const MIN_POSITIONS: usize = 4;

impl<'a, 'c> Fn<'a, 'c> {
    /// The op that defines `v`, when an op does (not a block argument).
    fn defining(&self, v: ValueId) -> Option<(scion_ir::OpId, &'a scion_ir::Operation)> {
        let d = self.m.def_op(v)?;
        Some((d, &self.m.ops[d]))
    }

    /// The position `k` that select condition `c` tests (`x == k`, `x` returned too).
    fn position_test(&self, c: ValueId) -> Option<(ValueId, i128)> {
        let (_, o) = self.defining(c)?;
        if o.kind != OpKind::Lo(L::Cmp) || o.pred() != Some(CmpPred::Eq) {
            return None;
        }
        Some((o.operands[0], self.int_constant(o.operands[1])?))
    }

    /// The value of `v` when a `lo.const` integer defines it.
    fn int_constant(&self, v: ValueId) -> Option<i128> {
        let (_, o) = self.defining(v)?;
        if o.kind != OpKind::Lo(L::Const) {
            return None;
        }
        match o.attr("value") {
            Some(scion_ir::attr::Attr::Int(k)) => Some(*k),
            _ => None,
        }
    }

    /// `select` op `op` as a variable lane of a vector when it is the root of an index chain of
    /// at least [`MIN_POSITIONS`] positions whose elements are integers or floats; `None` to
    /// translate it as a select.
    pub(super) fn index_chain(&self, op: scion_ir::OpId) -> R<Option<BasicValueEnum<'c>>> {
        let m = self.m;
        if self.target == Target::Nvptx64 {
            return Ok(None);
        }
        let root = &m.ops[op];
        let Some((index, _)) = self.position_test(root.operands[0]) else {
            return Ok(None);
        };
        // Walk the else operands: (position, value) pairs, then the base.
        let mut lanes: Vec<Option<ValueId>> = Vec::new();
        let mut cur = op;
        let base = loop {
            let o = &m.ops[cur];
            let Some((x, k)) = self.position_test(o.operands[0]) else {
                break None;
            };
            if x != index || !(1..64).contains(&k) {
                break None;
            }
            let k = k as usize;
            if lanes.len() <= k {
                lanes.resize(k + 1, None);
            }
            if lanes[k].is_some() {
                break None;
            }
            lanes[k] = Some(o.operands[1]);
            let next = o.operands[2];
            match m.def_op(next) {
                Some(d)
                    if m.ops[d].kind == OpKind::Lo(L::Select)
                        && self.position_test(m.ops[d].operands[0]).map(|p| p.0) == Some(index) =>
                {
                    cur = d
                }
                _ => break Some(next),
            }
        };
        let Some(base) = base else {
            return Ok(None);
        };
        let n = lanes.len();
        if n < MIN_POSITIONS || lanes[1..].iter().any(Option::is_none) {
            return Ok(None);
        }
        lanes[0] = Some(base);
        let values: Vec<BasicValueEnum<'c>> = lanes
            .iter()
            .flatten()
            .map(|&v| self.v(v))
            .collect::<R<_>>()?;
        if values.iter().any(|v| v.get_type() != values[0].get_type()) {
            return Ok(None);
        }
        let b = self.b;
        let mut vector = match values[0] {
            BasicValueEnum::IntValue(i) => i.get_type().vec_type(n as u32).get_undef(),
            BasicValueEnum::FloatValue(f) => f.get_type().vec_type(n as u32).get_undef(),
            _ => return Ok(None),
        };
        let i32t = self.cx.i32_type();
        for (k, &v) in values.iter().enumerate() {
            vector = b
                .build_insert_element(vector, v, i32t.const_int(k as u64, false), "")
                .map_err(be)?;
        }
        let i = self.v(index)?.into_int_value();
        let it = i.get_type();
        let inside = b
            .build_int_compare(IntPredicate::ULT, i, it.const_int(n as u64, false), "")
            .map_err(be)?;
        let lane = b
            .build_select(inside, i, it.const_zero(), "")
            .map_err(be)?
            .into_int_value();
        let lane = b
            .build_int_cast_sign_flag(lane, i32t, false, "")
            .map_err(be)?;
        Ok(Some(b.build_extract_element(vector, lane, "").map_err(be)?))
    }
}

/// The values that some `lo.or` of function `f` reads.
pub(super) fn or_operands(m: &Module, f: FuncId) -> std::collections::HashSet<ValueId> {
    let mut out = std::collections::HashSet::new();
    for &b in &m.regions[m.funcs[f].body].blocks {
        for &o in &m.blocks[b].ops {
            if m.ops[o].kind == OpKind::Lo(L::Or) {
                out.extend(m.ops[o].operands.iter().copied());
            }
        }
    }
    out
}

/// The most conditions one tree of lane bits packs.
const MAX_LANES: usize = 64;

impl<'c> Fn<'_, 'c> {
    /// The condition and the position of one leaf of a tree of lane bits: `c as T` (position
    /// 0) or `(c as T) << k` for an `i1` value `c` and a constant `k`.
    fn lane_bit(&self, v: ValueId) -> Option<(ValueId, usize)> {
        let m = self.m;
        let (d, o) = self.defining(v)?;
        let (cast, k) = match o.kind {
            OpKind::Lo(L::Shl) => {
                let k = self.int_constant(o.operands[1])?;
                if !(0..MAX_LANES as i128).contains(&k) {
                    return None;
                }
                (m.def_op(o.operands[0])?, k as usize)
            }
            OpKind::Lo(L::Cast) => (d, 0),
            _ => return None,
        };
        let c = &m.ops[cast];
        if c.kind != OpKind::Lo(L::Cast)
            || !matches!(m.types.get(m.values[c.operands[0]].ty), Type::Bool)
        {
            return None;
        }
        Some((c.operands[0], k))
    }

    /// The leaves of the `or` tree under `op`, or `None` when one is not a lane bit.
    fn lane_bit_leaves(&self, op: scion_ir::OpId, out: &mut Vec<(ValueId, usize)>) -> Option<()> {
        let m = self.m;
        for &x in &m.ops[op].operands {
            match m.def_op(x) {
                Some(d) if m.ops[d].kind == OpKind::Lo(L::Or) => self.lane_bit_leaves(d, out)?,
                _ => out.push(self.lane_bit(x)?),
            }
            if out.len() > MAX_LANES {
                return None;
            }
        }
        Some(())
    }

    /// `or` op `op` as the bits of one `<N x i1>` vector when it is the root of a tree of lane
    /// bits (read by no other `or`) with every position `0..N` once, `N >= 4`; `None` to
    /// translate it as an `or`.
    pub(super) fn lane_bits(&self, op: scion_ir::OpId) -> R<Option<BasicValueEnum<'c>>> {
        let m = self.m;
        let root = &m.ops[op];
        if self.target == Target::Nvptx64 || self.or_operands.contains(&root.results[0]) {
            return Ok(None);
        }
        let mut leaves = Vec::new();
        if self.lane_bit_leaves(op, &mut leaves).is_none() {
            return Ok(None);
        }
        let n = leaves.len();
        let Type::Int(it) = m.types.get(m.values[root.results[0]].ty) else {
            return Ok(None);
        };
        let mut conds: Vec<Option<ValueId>> = vec![None; n];
        for &(c, k) in &leaves {
            if k >= n || conds[k].is_some() {
                return Ok(None);
            }
            conds[k] = Some(c);
        }
        if n < MIN_POSITIONS || n > it.bits() as usize {
            return Ok(None);
        }
        let b = self.b;
        let i32t = self.cx.i32_type();
        let mut vector = self.cx.bool_type().vec_type(n as u32).get_undef();
        for (k, c) in conds.iter().enumerate() {
            let c = self.v(c.ok_or("lane bits: a position twice")?)?;
            vector = b
                .build_insert_element(vector, c, i32t.const_int(k as u64, false), "")
                .map_err(be)?;
        }
        let bits_ty = self
            .cx
            .custom_width_int_type(
                std::num::NonZeroU32::new(n as u32).ok_or("lane bits of no lanes")?,
            )
            .map_err(|e| format!("lane bits: {e}"))?;
        let bits = b
            .build_bit_cast(vector, bits_ty, "")
            .map_err(be)?
            .into_int_value();
        let rt = llvm_type(self.cx, m, m.values[root.results[0]].ty)?.into_int_type();
        Ok(Some(
            b.build_int_z_extend_or_bit_cast(bits, rt, "")
                .map_err(be)?
                .into(),
        ))
    }
}
