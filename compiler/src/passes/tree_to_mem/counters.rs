//! Placement counters of a layout's generated constructor: which counter each variant takes
//! its record's index from (one for all, or one per indirect group), the counters' cell type
//! and its initial value, and the attribute through which the entries learn how many there are.

use super::LayoutSpec;
use crate::layout::plan::{BufferKind, Count};
use scion_ir::tree::Op;
use scion_ir::{Builder, Module, TypeId, ValueId};

/// The attribute of `@L.node` giving the number of placement counters its counter cell holds
/// (1: one `u32`; more: a tuple of `u32`s, one per indirect group), which the entry that
/// recomputes the root's reference allocates.
pub const COUNTERS_ATTR: &str = "counters";

/// Which placement counter each variant takes its record's index from. A layout with two or
/// more indirect groups (the hair BVH's axis-aligned and oriented records) counts each group's
/// records apart, so each group holds its own variants' records only and its indices are dense;
/// otherwise one counter serves every placing variant (`count` 1, no slots).
pub(crate) struct CounterSlots {
    /// Variant name and its counter.
    slot: Vec<(String, usize)>,
    /// Counters (0 or 1: the single shared counter).
    pub(super) count: usize,
}

impl CounterSlots {
    pub(super) fn slot_of(&self, variant: &str) -> Option<usize> {
        if self.count <= 1 {
            return None;
        }
        self.slot
            .iter()
            .find(|(v, _)| v == variant)
            .map(|&(_, k)| k)
    }
}

pub(super) fn counter_slots(spec: &LayoutSpec) -> CounterSlots {
    let mut groups: Vec<usize> = Vec::new();
    let mut slot: Vec<(String, usize)> = Vec::new();
    for b in &spec.plan.buffers {
        if let (Count::VariantNodes { variants }, BufferKind::GroupArray { group, .. }) =
            (&b.count, &b.kind)
        {
            let k = match groups.iter().position(|g| g == group) {
                Some(k) => k,
                None => {
                    groups.push(*group);
                    groups.len() - 1
                }
            };
            for v in variants {
                if !slot.iter().any(|(w, _)| w == v) {
                    slot.push((v.clone(), k));
                }
            }
        }
    }
    // Direct groups index every node: one counter for all then.
    let direct = spec
        .plan
        .buffers
        .iter()
        .any(|b| matches!(b.count, Count::Nodes { .. }));
    if groups.len() < 2 || direct {
        return CounterSlots {
            slot: Vec::new(),
            count: 1,
        };
    }
    CounterSlots {
        slot,
        count: groups.len(),
    }
}

/// The type of the counters' tuple, `None` for a single `u32` counter.
pub(super) fn counter_type(m: &mut Module, slots: &CounterSlots) -> Option<TypeId> {
    if slots.count <= 1 {
        return None;
    }
    let u32t = m.types.u32();
    Some(m.types.tuple(vec![u32t; slots.count]))
}

/// The initial counters (all zero) for a build entry: a `u32`, or the tuple of them.
pub(super) fn zero_counters(bd: &mut Builder<'_>, count: usize) -> ValueId {
    let u32t = bd.m.types.u32();
    let zero = bd.const_int(u32t, 0);
    if count <= 1 {
        return zero;
    }
    let ty = bd.m.types.tuple(vec![u32t; count]);
    bd.build1(Op::Tuple, &vec![zero; count], ty)
}
