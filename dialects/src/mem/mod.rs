//! The `mem` dialect: reads and writes of a physical layout's buffers (paper §7.1-§7.2).
//!
//! Destructor specialization turns a traversal's tree values into *references* of a layout and
//! its field reads into [`Op::Load`]s at resolved byte offsets; constructor specialization writes
//! a layout with [`Op::Store`]s. `mem` is a dialect *added* to `tree` (as in MLIR): control flow,
//! arithmetic and calls stay `tree` ops. The op table and the layout-instance convention (one
//! `%B: ptr` to a table of `u64` buffer addresses, in `BufferPlan` order) are fixed by
//! `docs/design/specialization.md` §2; the verifier rules are in [`verify`].

pub mod verify;

/// One `mem` operation kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Op {
    /// `mem.buffer {index, name}` `(ptr) -> ptr`: the base address of buffer `index` of the
    /// layout instance `%B` (the `u64` at byte `8 * index` of the table `%B` points to).
    Buffer,
    /// `mem.load {offset, stride?}` `(ptr) -> T` or `(ptr, integer) -> T`: the value at
    /// `base + index * stride + offset`. `stride` is required with an index. `T` is a scalar, a
    /// vector, `ptr`, or a record ADT laid out with the layout model's rules (fields in order at
    /// natural alignment).
    Load,
    /// `mem.store {offset, stride?}` `(ptr, T) -> ()` or `(ptr, integer, T) -> ()`: writes the
    /// value at `base + index * stride + offset` (the constructor's writes).
    Store,
    /// `mem.addr {offset, stride?}` `(ptr) -> ptr` or `(ptr, integer) -> ptr`: the address
    /// `base + index * stride + offset` itself (pointer references, `this` of `ptr` layouts).
    Addr,
    /// `mem.view {stride}` `(ptr, integer, integer) -> !mem.view<T>`: `len` elements of `T`
    /// from element `start` of the array at `base` (operands `base, start, len`). `tree.foreach`,
    /// `tree.index` and the `len` intrinsic accept views like slices.
    View,
}

impl Op {
    /// Every op, in declaration order.
    pub const ALL: [Op; 5] = [Op::Buffer, Op::Load, Op::Store, Op::Addr, Op::View];

    /// The name without the dialect prefix (`load`).
    pub fn mnemonic(self) -> &'static str {
        match self {
            Op::Buffer => "buffer",
            Op::Load => "load",
            Op::Store => "store",
            Op::Addr => "addr",
            Op::View => "view",
        }
    }

    /// The op with mnemonic `s`.
    pub fn from_mnemonic(s: &str) -> Option<Op> {
        Op::ALL.iter().copied().find(|op| op.mnemonic() == s)
    }

    /// True for ops without side effects apart from their results. Loads count as pure: within
    /// one traversal the layout is read-only, so an unused load may be removed.
    pub fn is_pure(self) -> bool {
        !matches!(self, Op::Store)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for op in Op::ALL {
            assert_eq!(Op::from_mnemonic(op.mnemonic()), Some(op));
        }
        assert_eq!(Op::from_mnemonic("nope"), None);
        assert!(!Op::Store.is_pure());
        assert!(Op::Load.is_pure());
    }
}

#[cfg(test)]
mod text_tests {
    use crate::diag::FileId;
    use crate::{parse_module, print_module, verify};

    const SAMPLE: &str = r#"tree.type @AABB(low: vector<3xf32>, high: vector<3xf32>)

func @f(%0: ptr, %1: u32) -> (f32) {
  %2 = "mem.buffer"(%0) {index = 1, name = "nodes"} : (ptr) -> ptr
  %3 = "mem.load"(%2, %1) {offset = 0, stride = 32} : (ptr, u32) -> !tree.adt<"AABB">
  %4 = "mem.load"(%2, %1) {offset = 28, stride = 32} : (ptr, u32) -> u16
  %5 = "mem.addr"(%2, %1) {offset = 24, stride = 32} : (ptr, u32) -> ptr
  %6 = "mem.load"(%5) {offset = 0} : (ptr) -> u32
  %7 = "mem.view"(%2, %6, %6) {stride = 32} : (ptr, u32, u32) -> !mem.view<!tree.adt<"AABB">>
  %8 = "tree.intrinsic"(%7) {name = "len"} : (!mem.view<!tree.adt<"AABB">>) -> u32
  "mem.store"(%2, %1, %8) {offset = 24, stride = 32} : (ptr, u32, u32) -> ()
  "mem.store"(%5, %4) {offset = 0} : (ptr, u16) -> ()
  "tree.foreach"(%7) ({
  ^bb1(%9: !tree.adt<"AABB">):
    "tree.yield"() : () -> ()
  }) : (!mem.view<!tree.adt<"AABB">>) -> ()
  %10 = "tree.index"(%7, %1) : (!mem.view<!tree.adt<"AABB">>, u32) -> !tree.adt<"AABB">
  %11 = "tree.field"(%10) {index = 0, name = "low"} : (!tree.adt<"AABB">) -> vector<3xf32>
  %12 = "tree.lane"(%11) {index = 0} : (vector<3xf32>) -> f32
  "tree.return"(%12) : (f32) -> ()
}
"#;

    #[test]
    fn every_op_round_trips_and_verifies() {
        let m = parse_module(SAMPLE, FileId(0)).expect("parses");
        verify(&m).expect("verifies");
        assert_eq!(print_module(&m), SAMPLE);
    }

    fn rejects(from: &str, to: &str, why: &str) {
        let text = SAMPLE.replace(from, to);
        assert_ne!(text, SAMPLE, "the edit `{from}` applies");
        let m = parse_module(&text, FileId(0)).expect("parses");
        let errs = verify(&m).expect_err("must be rejected");
        let all = format!("{errs:?}");
        assert!(all.contains(why), "expected `{why}` in {all}");
    }

    #[test]
    fn verifier_rules() {
        rejects(
            "{offset = 28, stride = 32}",
            "{offset = 28}",
            "needs a `stride`",
        );
        rejects(
            "{offset = 0} : (ptr) -> u32",
            "{stride = 4} : (ptr) -> u32",
            "needs an `offset`",
        );
        rejects(
            "{index = 1, name = \"nodes\"}",
            "{name = \"nodes\"}",
            "needs an `index`",
        );
        rejects(
            "{stride = 32} : (ptr, u32, u32)",
            "{stride = 0} : (ptr, u32, u32)",
            "positive `stride`",
        );
        rejects(
            "%3 = \"mem.load\"(%2, %1) {offset = 0, stride = 32} : (ptr, u32) -> !tree.adt<\"AABB\">",
            "%3 = \"mem.load\"(%1, %1) {offset = 0, stride = 32} : (u32, u32) -> !tree.adt<\"AABB\">",
            "base must be ptr",
        );
    }
}
