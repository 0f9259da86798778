//! The op kinds of the `tree` dialect and their static properties (name, purity, terminator).
//!
//! Each variant documents its operands, attributes, regions and results; the verifier in
//! [`super::verify`] checks exactly what is written here, and `docs/ir.md` repeats the table.

/// One `tree` operation kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Op {
    /// `tree.const {value}` `() -> T`: a scalar constant (`Int`, `Float` or `Bool` attribute).
    Const,
    /// `tree.add` `(T, T) -> T`, integers (wrapping) or floats, scalar or vector.
    Add,
    /// `tree.sub` `(T, T) -> T`.
    Sub,
    /// `tree.mul` `(T, T) -> T`.
    Mul,
    /// `tree.div` `(T, T) -> T`; integer division truncates toward zero.
    Div,
    /// `tree.rem` `(T, T) -> T`; the sign follows the dividend (floats: C `fmod`).
    Rem,
    /// `tree.neg` `(T) -> T`.
    Neg,
    /// `tree.and` `(T, T) -> T`, integers or `i1`.
    And,
    /// `tree.or` `(T, T) -> T`.
    Or,
    /// `tree.xor` `(T, T) -> T`.
    Xor,
    /// `tree.shl` `(T, U) -> T`, integers; the amount is taken modulo the width.
    Shl,
    /// `tree.shr` `(T, U) -> T`: arithmetic for signed, logical for unsigned types.
    Shr,
    /// `tree.bitnot` `(T) -> T`, integers.
    BitNot,
    /// `tree.not` `(i1) -> i1`, logical negation.
    Not,
    /// `tree.cmp {pred}` `(T, T) -> i1` (or a vector of `i1`); `pred` is one of
    /// `"eq" "ne" "lt" "le" "gt" "ge"`, ordered on floats except `ne`, which is true on NaN.
    Cmp,
    /// `tree.select` `(i1, T, T) -> T`.
    Select,
    /// `tree.cast` `(A) -> B`: value conversion (`as`) between numeric scalars or vectors of the
    /// same lane count: integer wrap or extension, float rounding, float to integer saturating
    /// (NaN gives 0), to `i1` is `!= 0`.
    Cast,
    /// `tree.bitcast` `(A) -> B`: reinterpretation (`to`) between types of equal bit width.
    Bitcast,
    /// `tree.tuple` `(A, B, ...) -> tuple<A, B, ...>`.
    Tuple,
    /// `tree.array` `(T, T, ...) -> array<N x T>` with N operands (N at least 1).
    Array,
    /// `tree.extract {index}` `(tuple<...>) -> T_index`.
    Extract,
    /// `tree.insert {index}` `(tuple<...>, T_index) -> tuple<...>`.
    Insert,
    /// `tree.vector` `(T, T, ...) -> vector<NxT>` with N operands.
    Vector,
    /// `tree.lane {index}` `(vector<NxT>) -> T`: a constant lane (`.x`, `.y`, ...).
    Lane,
    /// `tree.field {name, index}` `(!tree.adt<"R">) -> T`: reads shared field `index` (a record's
    /// fields are all shared); `name` must be that field's name.
    Field,
    /// `tree.ctor {variant?}` `(fields...) -> !tree.adt<"S">`: builds a record (no `variant`) or a
    /// variant of a sum, taking the shared fields then the variant's own.
    Ctor,
    /// `tree.is {variant}` `(!tree.adt<"S">) -> i1`: the variant test.
    Is,
    /// `tree.match {arms}` `(!tree.adt<"S">) -> (results...)`, one region per arm. `arms` is a
    /// list of variant names, `"_"` for a wildcard arm. A variant arm's block arguments are the
    /// variant's fields, shared first; a wildcard arm takes none or the shared fields. Each arm
    /// ends with `tree.yield` of the results or with `tree.return`.
    Match,
    /// `tree.if` `(i1) -> (results...)`, regions then and else, each ending with `tree.yield` of
    /// the results or with `tree.return`.
    If,
    /// `tree.foreach` `(array<N x T> | set<T>) -> ()`, one region whose block arguments are the
    /// element and optionally its index (an integer type); it ends with `tree.yield()`. Sets
    /// are visited in ascending order.
    Foreach,
    /// `tree.index` `(array<N x T> | vector<NxT>, integer) -> T`.
    Index,
    /// `tree.slice` `(array<N x T>, integer, integer) -> array<? x T>`: elements `[lo, hi)`.
    Slice,
    /// `tree.bits {lo, hi}` `(integer) -> integer`, or with operands `(integer, lo, hi)`: bits
    /// `[lo, hi)` of the operand, shifted down, zero-extended or truncated to the result type.
    Bits,
    /// `tree.call {callee = @f}` `(args...) -> (results...)` of the function `@f`.
    Call,
    /// `tree.intrinsic {name}` `(args...) -> (T)`: a builtin such as `min`, `sqrt`, `dot`; see
    /// [`super::Intrinsic`] for the list.
    Intrinsic,
    /// `tree.var` `(T) -> !tree.ref<T>`: a fresh mutable cell holding the operand.
    Var,
    /// `tree.load` `(!tree.ref<T>) -> T`.
    Load,
    /// `tree.store` `(!tree.ref<T>, T) -> ()`.
    Store,
    /// `tree.yield` `(values...) -> ()`: ends a region of `if`, `match` or `foreach`, giving the
    /// enclosing op its results.
    Yield,
    /// `tree.return` `(values...) -> ()`: returns from the enclosing function, from any depth.
    Return,
    /// `tree.this` `() -> R`: the reference of the node a build function is placing (its index,
    /// or its address for pointer-referenced groups). Build functions only.
    This,
    /// `tree.build_store {field}` `(T) -> ()`: stores the value into stored field `field` of
    /// the node being placed. Build functions only.
    BuildStore,
    /// `tree.build_store_bits {lo, hi}` `(integer) -> ()`: `this[lo:hi] = value`, bits of the
    /// node's reference; the constructor reports a value that does not fit.
    BuildStoreBits,
    /// `tree.build_child {field}` `(u32) -> (R)`: builds the subtree whose logical node index is
    /// the operand (the recursive field `field`) and yields its reference.
    BuildChild,
    /// `tree.build_load {field}` `() -> T`: reads layout member `field` (a global, or a stored
    /// field of the node being placed) inside a build function.
    BuildLoad,
    /// `tree.child_field {field}` `(integer) -> T`: reads shared logical field `field` (e.g.
    /// `bounds`) of the logical child whose index is the operand, inside a build function
    /// (`left.bounds` in `build Interior(bounds, left, right)`).
    ChildField,
    /// `tree.append {field}` `(array<? x T>, integer) -> (integer)`: copies the first `n`
    /// elements of the logical array into the global array behind `field` at the running
    /// cursor and yields the start index.
    Append,
}

impl Op {
    /// Every op, in declaration order.
    pub const ALL: [Op; 47] = [
        Op::Const,
        Op::Add,
        Op::Sub,
        Op::Mul,
        Op::Div,
        Op::Rem,
        Op::Neg,
        Op::And,
        Op::Or,
        Op::Xor,
        Op::Shl,
        Op::Shr,
        Op::BitNot,
        Op::Not,
        Op::Cmp,
        Op::Select,
        Op::Cast,
        Op::Bitcast,
        Op::Tuple,
        Op::Array,
        Op::Extract,
        Op::Insert,
        Op::Vector,
        Op::Lane,
        Op::Field,
        Op::Ctor,
        Op::Is,
        Op::Match,
        Op::If,
        Op::Foreach,
        Op::Index,
        Op::Slice,
        Op::Bits,
        Op::Call,
        Op::Intrinsic,
        Op::Var,
        Op::Load,
        Op::Store,
        Op::Yield,
        Op::Return,
        Op::This,
        Op::BuildStore,
        Op::BuildStoreBits,
        Op::BuildChild,
        Op::BuildLoad,
        Op::ChildField,
        Op::Append,
    ];

    /// The name without the dialect prefix (`add`).
    pub fn mnemonic(self) -> &'static str {
        match self {
            Op::Const => "const",
            Op::Add => "add",
            Op::Sub => "sub",
            Op::Mul => "mul",
            Op::Div => "div",
            Op::Rem => "rem",
            Op::Neg => "neg",
            Op::And => "and",
            Op::Or => "or",
            Op::Xor => "xor",
            Op::Shl => "shl",
            Op::Shr => "shr",
            Op::BitNot => "bitnot",
            Op::Not => "not",
            Op::Cmp => "cmp",
            Op::Select => "select",
            Op::Cast => "cast",
            Op::Bitcast => "bitcast",
            Op::Tuple => "tuple",
            Op::Array => "array",
            Op::Extract => "extract",
            Op::Insert => "insert",
            Op::Vector => "vector",
            Op::Lane => "lane",
            Op::Field => "field",
            Op::Ctor => "ctor",
            Op::Is => "is",
            Op::Match => "match",
            Op::If => "if",
            Op::Foreach => "foreach",
            Op::Index => "index",
            Op::Slice => "slice",
            Op::Bits => "bits",
            Op::Call => "call",
            Op::Intrinsic => "intrinsic",
            Op::Var => "var",
            Op::Load => "load",
            Op::Store => "store",
            Op::Yield => "yield",
            Op::Return => "return",
            Op::This => "this",
            Op::BuildStore => "build_store",
            Op::BuildStoreBits => "build_store_bits",
            Op::BuildChild => "build_child",
            Op::BuildLoad => "build_load",
            Op::ChildField => "child_field",
            Op::Append => "append",
        }
    }

    /// The op with mnemonic `s`.
    pub fn from_mnemonic(s: &str) -> Option<Op> {
        Op::ALL.iter().copied().find(|op| op.mnemonic() == s)
    }

    /// True for ops that end a block.
    pub fn is_terminator(self) -> bool {
        matches!(self, Op::Yield | Op::Return)
    }

    /// True for ops without side effects (their only effect is their results), which may be
    /// removed when unused and reordered freely. Region ops are pure when their regions are;
    /// see [`crate::walk::is_removable`].
    pub fn is_pure(self) -> bool {
        !matches!(
            self,
            Op::Call
                | Op::Store
                | Op::Yield
                | Op::Return
                | Op::Match
                | Op::If
                | Op::Foreach
                | Op::This
                | Op::BuildStore
                | Op::BuildStoreBits
                | Op::BuildChild
                | Op::BuildLoad
                | Op::ChildField
                | Op::Append
        )
    }

    /// True for the binary arithmetic and bitwise ops `(T, T) -> T`.
    pub fn is_binary(self) -> bool {
        matches!(
            self,
            Op::Add
                | Op::Sub
                | Op::Mul
                | Op::Div
                | Op::Rem
                | Op::And
                | Op::Or
                | Op::Xor
                | Op::Shl
                | Op::Shr
        )
    }

    /// True for ops carrying regions.
    pub fn has_regions(self) -> bool {
        matches!(self, Op::Match | Op::If | Op::Foreach)
    }
}

/// The predicates of `tree.cmp`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CmpPred {
    /// `==`
    Eq,
    /// `!=` (true when either float operand is NaN)
    Ne,
    /// `<`
    Lt,
    /// `<=`
    Le,
    /// `>`
    Gt,
    /// `>=`
    Ge,
}

impl CmpPred {
    /// The attribute spelling.
    pub fn name(self) -> &'static str {
        match self {
            CmpPred::Eq => "eq",
            CmpPred::Ne => "ne",
            CmpPred::Lt => "lt",
            CmpPred::Le => "le",
            CmpPred::Gt => "gt",
            CmpPred::Ge => "ge",
        }
    }

    /// Parses the attribute spelling.
    pub fn from_name(s: &str) -> Option<CmpPred> {
        Some(match s {
            "eq" => CmpPred::Eq,
            "ne" => CmpPred::Ne,
            "lt" => CmpPred::Lt,
            "le" => CmpPred::Le,
            "gt" => CmpPred::Gt,
            "ge" => CmpPred::Ge,
            _ => return None,
        })
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
    }

    #[test]
    fn build_ops_round_trip_and_verify() {
        let text = r#"tree.type @Triangle(p0: vector<3xf32>, p1: vector<3xf32>, p2: vector<3xf32>, id: u32)

func @L.build.Leaf(%0: u16, %1: array<? x !tree.adt<"Triangle">>, %2: u32) -> (u32) {
  %3 = "tree.this"() : () -> u32
  "tree.build_store"(%0) {field = "nprims"} : (u16) -> ()
  %4 = "tree.append"(%1, %0) {field = "data"} : (array<? x !tree.adt<"Triangle">>, u16) -> u32
  "tree.build_store"(%4) {field = "p_o"} : (u32) -> ()
  %5 = "tree.build_child"(%2) {field = "left"} : (u32) -> u32
  %6 = "tree.build_load"() {field = "wlo"} : () -> vector<3xf32>
  "tree.build_store_bits"(%5) {hi = 32, lo = 28} : (u32) -> ()
  "tree.return"(%3) : (u32) -> ()
}
"#;
        let m = crate::parse_module(text, crate::diag::FileId(0)).expect("parses");
        crate::verify(&m).expect("verifies");
        assert_eq!(crate::print_module(&m), text);
        let bad = text.replace("{hi = 32, lo = 28}", "{hi = 28, lo = 28}");
        let m = crate::parse_module(&bad, crate::diag::FileId(0)).expect("parses");
        assert!(crate::verify(&m).is_err());
        let bad = text.replace(r#"{field = "nprims"} "#, "");
        let m = crate::parse_module(&bad, crate::diag::FileId(0)).expect("parses");
        assert!(crate::verify(&m).is_err());
    }
}
