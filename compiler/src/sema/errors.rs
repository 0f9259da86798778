//! Every diagnostic that name resolution and type checking report, with its wording.
//!
//! Input: a [`SemaError`] built by `resolve`, `infer`, `layout_types` or `build_types` (types
//! already rendered to text). Output: a [`Diagnostic`] with a stable code, a primary span with a
//! label, and notes. Codes: `E02xx` names and types of the traversal language, `E0350`-`E0369`
//! typing of layouts, `E0450`-`E0499` typing of builds (paper §3, §5, §6). Structural mistakes
//! in layouts and builds (unknown variants, groups or targets, duplicate members, ...) are
//! reported by `check_layout` (`E0301`-`E0349`) and `check_build` (`E0401`-`E0449`) instead, so
//! each mistake is reported once; the codes this module gave up are not reused.

use scion_ir::diag::{Diagnostic, Span};

/// One semantic error (or warning), one variant per code.
#[derive(Clone, Debug, PartialEq)]
pub enum SemaError {
    /// E0201
    UnknownName { name: String, span: Span },
    /// E0202
    UnknownType { name: String, span: Span },
    /// E0203
    Duplicate {
        what: &'static str,
        name: String,
        span: Span,
        previous: Span,
    },
    /// E0204
    UnknownCallee { name: String, span: Span },
    /// E0205
    ArgCount {
        callee: String,
        min: usize,
        max: usize,
        found: usize,
        span: Span,
    },
    /// E0206
    Mismatch {
        expected: String,
        found: String,
        span: Span,
        context: &'static str,
    },
    /// E0207
    NoOverload {
        name: String,
        args: String,
        candidates: Vec<String>,
        span: Span,
    },
    /// E0208
    AmbiguousOverload {
        name: String,
        candidates: Vec<String>,
        span: Span,
    },
    /// E0209
    CannotInfer { what: &'static str, span: Span },
    /// E0210
    DuplicateOverload {
        name: String,
        params: String,
        span: Span,
        previous: Span,
    },
    /// E0211
    UnknownVariant {
        name: String,
        ty: String,
        span: Span,
    },
    /// E0212
    PatternArity {
        variant: String,
        expected: usize,
        found: usize,
        fields: String,
        span: Span,
    },
    /// E0213
    NotASum { ty: String, span: Span },
    /// E0214
    NonExhaustive { missing: Vec<String>, span: Span },
    /// E0215 (warning)
    UnreachableArm { span: Span },
    /// E0216
    NoSuchField {
        ty: String,
        name: String,
        span: Span,
    },
    /// E0217
    BadOperand {
        op: String,
        ty: String,
        expected: &'static str,
        span: Span,
    },
    /// E0218
    BadCast {
        from: String,
        to: String,
        span: Span,
    },
    /// E0219
    BadBitCast {
        from: String,
        to: String,
        from_bits: String,
        to_bits: String,
        span: Span,
    },
    /// E0220
    MissingValue {
        func: String,
        ret: String,
        span: Span,
    },
    /// E0221
    AssignImmutable { name: String, span: Span },
    /// E0222
    BadAssignTarget { span: Span },
    /// E0222: a shared field of a sum's value (which variant to rebuild is not known).
    SumFieldAssign {
        field: String,
        ty: String,
        span: Span,
    },
    /// E0223
    MutArgNotPlace { param: String, span: Span },
    /// E0224
    TupleIndexNotLiteral { span: Span },
    /// E0225
    TupleIndexRange { index: u128, len: usize, span: Span },
    /// E0226
    NotIndexable { ty: String, span: Span },
    /// E0227
    NotSliceable { ty: String, span: Span },
    /// E0228
    NotIterable { ty: String, span: Span },
    /// E0229
    LiteralRange { value: u128, ty: String, span: Span },
    /// E0230
    NotCallable {
        name: String,
        span: Span,
        why: &'static str,
    },
    /// E0231
    BuiltinArg {
        name: String,
        ty: String,
        expected: &'static str,
        span: Span,
    },
    /// E0232
    WrongContext {
        what: &'static str,
        span: Span,
        allowed: &'static str,
    },
    /// E0233
    UnknownArrayLen { name: String, span: Span },
    /// E0234
    VariantNeedsArgs { name: String, span: Span },
    /// E0235
    InfiniteType { span: Span },
    /// E0236
    ReturnValueInUnit { span: Span },
    /// E0237
    RecursiveRecord { name: String, span: Span },
    /// E0238
    IndexRange { index: u128, len: u64, span: Span },
    /// E0239
    BitRange {
        lo: u128,
        hi: u128,
        ty: String,
        span: Span,
    },
    /// E0240
    IfWithoutValue { span: Span },
    /// E0241
    EmptyArray { span: Span },
    /// E0242
    OrderByNotParam {
        func: String,
        name: String,
        span: Span,
    },
    /// E0243
    OrderByType {
        name: String,
        ty: String,
        span: Span,
        param: Span,
    },
    /// E0244
    OrderByResult {
        func: String,
        ret: String,
        span: Span,
    },
    /// E0353
    DiscriminantNotInt { ty: String, span: Span },
    /// E0354
    GroupSizeNotInt { ty: String, span: Span },
    /// E0355
    GroupByNotIndex { ty: String, span: Span },
    /// E0357
    PhysicalType {
        field: String,
        logical: String,
        expected: String,
        found: String,
        span: Span,
    },
    /// E0359
    FromKeyNotInt { ty: String, span: Span },
    /// E0361
    LayoutArrayLen { name: String, span: Span },
    /// E0452
    BuildParamCount {
        variant: String,
        expected: usize,
        found: usize,
        fields: String,
        span: Span,
    },
    /// E0453
    BuildParamName {
        expected: String,
        found: String,
        span: Span,
    },
    /// E0454
    BuildParamType {
        name: String,
        expected: String,
        found: String,
        span: Span,
    },
    /// E0456
    BuildValueType {
        field: String,
        expected: String,
        found: String,
        span: Span,
    },
    /// E0457
    BuildLiteralFit {
        field: String,
        value: u128,
        ty: String,
        span: Span,
    },
    /// E0461
    BuildReturnType {
        expected: String,
        found: String,
        span: Span,
    },
}

fn list(names: &[String]) -> String {
    names
        .iter()
        .map(|n| format!("`{n}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

impl SemaError {
    /// The stable error code.
    pub fn code(&self) -> &'static str {
        use SemaError::*;
        match self {
            UnknownName { .. } => "E0201",
            UnknownType { .. } => "E0202",
            Duplicate { .. } => "E0203",
            UnknownCallee { .. } => "E0204",
            ArgCount { .. } => "E0205",
            Mismatch { .. } => "E0206",
            NoOverload { .. } => "E0207",
            AmbiguousOverload { .. } => "E0208",
            CannotInfer { .. } => "E0209",
            DuplicateOverload { .. } => "E0210",
            UnknownVariant { .. } => "E0211",
            PatternArity { .. } => "E0212",
            NotASum { .. } => "E0213",
            NonExhaustive { .. } => "E0214",
            UnreachableArm { .. } => "E0215",
            NoSuchField { .. } => "E0216",
            BadOperand { .. } => "E0217",
            BadCast { .. } => "E0218",
            BadBitCast { .. } => "E0219",
            MissingValue { .. } => "E0220",
            AssignImmutable { .. } => "E0221",
            BadAssignTarget { .. } | SumFieldAssign { .. } => "E0222",
            MutArgNotPlace { .. } => "E0223",
            TupleIndexNotLiteral { .. } => "E0224",
            TupleIndexRange { .. } => "E0225",
            NotIndexable { .. } => "E0226",
            NotSliceable { .. } => "E0227",
            NotIterable { .. } => "E0228",
            LiteralRange { .. } => "E0229",
            NotCallable { .. } => "E0230",
            BuiltinArg { .. } => "E0231",
            WrongContext { .. } => "E0232",
            UnknownArrayLen { .. } => "E0233",
            VariantNeedsArgs { .. } => "E0234",
            InfiniteType { .. } => "E0235",
            ReturnValueInUnit { .. } => "E0236",
            RecursiveRecord { .. } => "E0237",
            IndexRange { .. } => "E0238",
            BitRange { .. } => "E0239",
            IfWithoutValue { .. } => "E0240",
            EmptyArray { .. } => "E0241",
            OrderByNotParam { .. } => "E0242",
            OrderByType { .. } => "E0243",
            OrderByResult { .. } => "E0244",
            DiscriminantNotInt { .. } => "E0353",
            GroupSizeNotInt { .. } => "E0354",
            GroupByNotIndex { .. } => "E0355",
            PhysicalType { .. } => "E0357",
            FromKeyNotInt { .. } => "E0359",
            LayoutArrayLen { .. } => "E0361",
            BuildParamCount { .. } => "E0452",
            BuildParamName { .. } => "E0453",
            BuildParamType { .. } => "E0454",
            BuildValueType { .. } => "E0456",
            BuildLiteralFit { .. } => "E0457",
            BuildReturnType { .. } => "E0461",
        }
    }

    /// The user-facing diagnostic.
    pub fn to_diagnostic(&self) -> Diagnostic {
        use SemaError::*;
        let code = self.code();
        let e = |msg: String| Diagnostic::error(code, msg);
        match self {
            UnknownName { name, span } => e(format!("unknown name `{name}`"))
                .with_primary(*span, "not found in this scope")
                .with_note("names are looked up in the enclosing scopes, then among globals"),
            UnknownType { name, span } => e(format!("unknown type `{name}`"))
                .with_primary(*span, "no such type")
                .with_note("types are primitives (`u32`, `f32`, ...), vectors (`f32x3`), `ptr`, or declared with `type`"),
            Duplicate { what, name, span, previous } => e(format!("{what} `{name}` is defined twice"))
                .with_primary(*span, "redefined here")
                .with_secondary(*previous, "first defined here"),
            UnknownCallee { name, span } => e(format!("unknown function or constructor `{name}`"))
                .with_primary(*span, "no function, type, variant or builtin has this name"),
            ArgCount { callee, min, max, found, span } => {
                let want = if min == max { format!("{min}") } else { format!("{min} to {max}") };
                e(format!("`{callee}` takes {want} argument(s) but {found} were given"))
                    .with_primary(*span, format!("{found} argument(s)"))
            }
            Mismatch { expected, found, span, context } => e(format!("mismatched types: expected `{expected}`, found `{found}`"))
                .with_primary(*span, format!("expected `{expected}`"))
                .with_note(format!("required by {context}")),
            NoOverload { name, args, candidates, span } => e(format!("no overload of `{name}` accepts arguments {args}"))
                .with_primary(*span, "no matching candidate")
                .with_note(format!("candidates: {}", candidates.join("; "))),
            AmbiguousOverload { name, candidates, span } => e(format!("ambiguous call to `{name}`"))
                .with_primary(*span, "more than one candidate accepts these arguments")
                .with_note(format!("candidates: {}", candidates.join("; ")))
                .with_note("annotate the arguments' types to pick one"),
            CannotInfer { what, span } => e(format!("cannot infer the type of this {what}"))
                .with_primary(*span, "type annotations needed")
                .with_note("add a type to a `let` or a conversion `as T`"),
            DuplicateOverload { name, params, span, previous } => e(format!("function `{name}{params}` is defined twice with the same parameter types"))
                .with_primary(*span, "redefined here")
                .with_secondary(*previous, "first defined here")
                .with_note("overloads must differ in their parameter types"),
            UnknownVariant { name, ty, span } => e(format!("`{name}` is not a variant of `{ty}`"))
                .with_primary(*span, "unknown variant"),
            PatternArity { variant, expected, found, fields, span } => e(format!("pattern `{variant}` binds {found} field(s) but the variant has {expected}"))
                .with_primary(*span, format!("expected {expected} sub-pattern(s)"))
                .with_note(format!("fields, shared ones first: {fields}")),
            NotASum { ty, span } => e(format!("cannot match on a value of type `{ty}`"))
                .with_primary(*span, "not a sum type")
                .with_note("`match` takes a value of a `type S(...) = A(...) | B(...)`"),
            NonExhaustive { missing, span } => e(format!("non-exhaustive match: {} not covered", list(missing)))
                .with_primary(*span, "missing variant(s)")
                .with_note("add an arm for each missing variant, or a `_` arm"),
            UnreachableArm { span } => Diagnostic::warning(code, "unreachable match arm")
                .with_primary(*span, "an earlier arm already matches every value this arm matches"),
            NoSuchField { ty, name, span } => e(format!("type `{ty}` has no field `{name}`"))
                .with_primary(*span, "unknown field"),
            BadOperand { op, ty, expected, span } => e(format!("operator `{op}` cannot be applied to `{ty}`"))
                .with_primary(*span, format!("expected {expected}")),
            BadCast { from, to, span } => e(format!("cannot convert `{from}` to `{to}` with `as`"))
                .with_primary(*span, "invalid conversion")
                .with_note("`as` converts between numeric types, and between vectors with the same lane count"),
            BadBitCast { from, to, from_bits, to_bits, span } => e(format!("cannot reinterpret `{from}` as `{to}`"))
                .with_primary(*span, format!("{from_bits} bits to {to_bits} bits"))
                .with_note("`to` reinterprets the bits of a scalar or vector as another of the same size"),
            MissingValue { func, ret, span } => e(format!("function `{func}` may end without a value of type `{ret}`"))
                .with_primary(*span, "this body can fall off its end")
                .with_note("end every path with `return e` or a tail expression"),
            AssignImmutable { name, span } => e(format!("cannot assign to `{name}`"))
                .with_primary(*span, "not a `mut` parameter or a `let mut` local")
                .with_note("only `mut` parameters, `let mut` locals and their components can be assigned"),
            BadAssignTarget { span } => e("invalid assignment target".to_string())
                .with_primary(*span, "cannot assign to this expression")
                .with_note("assign to a `mut` parameter, a component of one, or (in a build) `this[a:b]`"),
            SumFieldAssign { field, ty, span } => e(format!("cannot assign to shared field `{field}` of a `{ty}` value"))
                .with_primary(*span, "a field of a sum's value")
                .with_note("a sum's value is one of its variants: build the new value with the variant's constructor (`match` on it) and assign that"),
            MutArgNotPlace { param, span } => e(format!("argument for `mut` parameter `{param}` must be a `mut` parameter or a `let mut` local"))
                .with_primary(*span, "not passable by reference"),
            TupleIndexNotLiteral { span } => e("a tuple index must be an integer literal".to_string())
                .with_primary(*span, "not a literal"),
            TupleIndexRange { index, len, span } => e(format!("tuple index {index} out of range for a tuple of {len}"))
                .with_primary(*span, "no such component"),
            NotIndexable { ty, span } => e(format!("cannot index a value of type `{ty}`"))
                .with_primary(*span, "not an array, slice, vector or tuple"),
            NotSliceable { ty, span } => e(format!("cannot slice a value of type `{ty}`"))
                .with_primary(*span, "not an array, slice or integer"),
            NotIterable { ty, span } => e(format!("cannot iterate over a value of type `{ty}`"))
                .with_primary(*span, "not an array, slice or set"),
            LiteralRange { value, ty, span } => e(format!("literal {value} does not fit in `{ty}`"))
                .with_primary(*span, "out of range"),
            NotCallable { name, span, why } => e(format!("`{name}` cannot be called"))
                .with_primary(*span, *why),
            BuiltinArg { name, ty, expected, span } => e(format!("builtin `{name}` cannot take `{ty}`"))
                .with_primary(*span, format!("expected {expected}")),
            WrongContext { what, span, allowed } => e(format!("{what} is not allowed here"))
                .with_primary(*span, "not allowed here")
                .with_note(format!("{what} is only allowed {allowed}")),
            UnknownArrayLen { name, span } => e(format!("array length `{name}` is not a field of this declaration"))
                .with_primary(*span, "unknown length")
                .with_note("a dependent-length array `T[x]` needs `x` to be an integer field declared before it"),
            VariantNeedsArgs { name, span } => e(format!("variant `{name}` has fields and needs arguments"))
                .with_primary(*span, format!("write `{name}(...)`")),
            InfiniteType { span } => e("this expression would have an infinite type".to_string())
                .with_primary(*span, "type refers to itself"),
            ReturnValueInUnit { span } => e("`return` without a value in a function that returns a value".to_string())
                .with_primary(*span, "missing value"),
            RecursiveRecord { name, span } => e(format!("record `{name}` contains itself"))
                .with_primary(*span, "infinitely large")
                .with_note("only sum types may be recursive; store the value through a sum type or a slice"),
            IndexRange { index, len, span } => e(format!("index {index} is out of range for {len} elements"))
                .with_primary(*span, "out of range"),
            BitRange { lo, hi, ty, span } => e(format!("bit range [{lo}:{hi}] does not fit `{ty}`"))
                .with_primary(*span, "bits outside the value")
                .with_note(format!("`e[a:b]` takes bits a..b-1 of an integer: it needs a < b <= {}", ty_bits(ty))),
            IfWithoutValue { span } => e("a branch of an `if` expression ends without a value".to_string())
                .with_primary(*span, "no value here")
                .with_note("an `if` used as a value needs a value at the end of every branch (or a `return`)"),
            EmptyArray { span } => e("an array literal needs at least one element".to_string())
                .with_primary(*span, "empty array")
                .with_note("its element type and length come from its elements"),
            OrderByNotParam { func, name, span } => e(format!("`order by {name}`: `{func}` has no parameter `{name}`"))
                .with_primary(*span, "not a parameter")
                .with_note("the calls of a best-first function are ordered by one of its parameters (docs/language.md)"),
            OrderByType { name, ty, span, param } => e(format!("`order by {name}`: the key has type `{ty}`, not a number passed by value"))
                .with_primary(*span, "expected an integer, `f32` or `f64` parameter")
                .with_secondary(*param, "declared here"),
            OrderByResult { func, ret, span } => e(format!("`{func}` is ordered by a parameter (`order by`) but returns `{ret}`"))
                .with_primary(*span, "a best-first function returns nothing")
                .with_note("its recursive calls are queued and run later, so no value can come back from them; write results through a `mut` parameter"),
            DiscriminantNotInt { ty, span } => e(format!("split discriminant has type `{ty}`, not an integer"))
                .with_primary(*span, "expected an integer"),
            GroupSizeNotInt { ty, span } => e(format!("group size has type `{ty}`, not an integer"))
                .with_primary(*span, "expected an integer"),
            GroupByNotIndex { ty, span } => e(format!("group index has type `{ty}`"))
                .with_primary(*span, "expected an integer or `ptr`"),
            PhysicalType { field, logical, expected, found, span } => e(format!("layout field `{field}` has type `{found}` but must have type `{expected}`"))
                .with_primary(*span, format!("expected `{expected}`"))
                .with_note(format!("physical types preserve logical types: logical field `{field}` has type `{logical}`")),
            FromKeyNotInt { ty, span } => e(format!("foreign key has type `{ty}`, not an integer"))
                .with_primary(*span, "expected an integer"),
            LayoutArrayLen { name, span } => e(format!("array length `{name}` is not a field of the layout"))
                .with_primary(*span, "unknown length"),
            BuildParamCount { variant, expected, found, fields, span } => e(format!("build of `{variant}` lists {found} field(s) but the variant has {expected}"))
                .with_primary(*span, "wrong number of fields")
                .with_note(format!("fields, shared ones first: {fields}")),
            BuildParamName { expected, found, span } => e(format!("build parameter `{found}` should be `{expected}`"))
                .with_primary(*span, format!("expected `{expected}`"))
                .with_note("build parameters name the variant's logical fields in order, shared ones first"),
            BuildParamType { name, expected, found, span } => e(format!("build parameter `{name}` has type `{found}` but the field has type `{expected}`"))
                .with_primary(*span, format!("expected `{expected}`")),
            BuildValueType { field, expected, found, span } => e(format!("`build {field} = ...` stores `{found}` into a field of type `{expected}`"))
                .with_primary(*span, format!("expected `{expected}`"))
                .with_note("convert explicitly with `as`"),
            BuildLiteralFit { field, value, ty, span } => e(format!("literal {value} does not fit field `{field}` of type `{ty}`"))
                .with_primary(*span, "out of range"),
            BuildReturnType { expected, found, span } => e(format!("a build returns the node's reference `{expected}`, found `{found}`"))
                .with_primary(*span, format!("expected `{expected}`")),
        }
    }
}

/// The width of an integer type named `ty` (for the note of E0239).
fn ty_bits(ty: &str) -> u32 {
    super::types::Prim::from_name(ty)
        .map(|p| p.bits())
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_error_has_code_and_primary_span() {
        let s = Span::default();
        let samples = vec![
            SemaError::UnknownName {
                name: "x".into(),
                span: s,
            },
            SemaError::NonExhaustive {
                missing: vec!["Leaf".into()],
                span: s,
            },
            SemaError::UnreachableArm { span: s },
            SemaError::BuildReturnType {
                expected: "u32".into(),
                found: "f32".into(),
                span: s,
            },
        ];
        for e in samples {
            let d = e.to_diagnostic();
            assert_eq!(d.code.as_deref(), Some(e.code()));
            assert!(d.primary_span().is_some());
        }
        let w = SemaError::UnreachableArm { span: s }.to_diagnostic();
        assert!(!w.is_error());
        let d = SemaError::NonExhaustive {
            missing: vec!["Leaf".into()],
            span: s,
        }
        .to_diagnostic();
        assert!(d.message.contains("`Leaf`"), "{}", d.message);
    }
}
