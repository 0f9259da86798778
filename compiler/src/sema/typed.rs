//! The output of semantic analysis: the AST's meaning, in side tables keyed by [`NodeId`].
//!
//! Input: produced by [`super::check_program`]. Output: what `irgen` reads: the declared types
//! ([`AdtTable`]), the function table with overload-disambiguated names, the type of every
//! expression, the resolution of every name and call, the bindings introduced by `let`,
//! `foreach` and patterns, and for layouts and builds the types of their members (paper §3-§6).
//! No [`Ty::Var`] remains in a `TypedProgram`; where a type could not be found it is
//! [`Ty::Error`] and a diagnostic was reported.
//!
//! Reading it (for `irgen`), by AST node:
//!
//! * every `Expr`: `expr_types[id]`; `Name`, `Call`, `Parent` and `Build` expressions also have
//!   `resolutions[id]` ([`Resolution`]). A `Call` resolved to `Ctor`/`Variant`/`Func` may omit
//!   trailing arguments whose field or parameter has a default: the default is the expression in
//!   the declaring AST node (typed like any other expression).
//! * `StmtKind::Let` and `StmtKind::Foreach`: `binders[stmt.id]` is the binding; a
//!   `PatternKind::Bind`: `binders[pattern.id]`, whose [`BindingKind::Pattern`] says which field
//!   (shared fields first) it binds; a `PatternKind::Variant`: `pattern_variants[pattern.id]`.
//! * an arithmetic or comparison operand in `widenings` is converted to the wider integer type
//!   before the operation (its own `expr_types` entry is the narrow type).
//! * a `mut` parameter is passed by reference: an argument for a `mut` parameter is always a
//!   `Name` resolving to a `mut` [`Resolution::Param`] of the caller.
//! * the function declared by item `i` is `funcs[func_of_item(i)]`; its `unique_name` tells
//!   overloads apart.
//! * layouts: [`LayoutInfo::members`] in pre-order of named members; builds: `build x` statements
//!   have `build_targets[stmt.id]`.

use super::types::{AdtId, AdtTable, Prim, Ty};
use crate::syntax::ast::NodeId;
use rustc_hash::FxHashMap;
use scion_ir::diag::Span;
pub use scion_ir::tree::Intrinsic;

/// Identifies a function in [`TypedProgram::funcs`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct FuncId(pub u32);

/// Identifies a local binding (`let`, `foreach` variable, pattern binding) in
/// [`TypedProgram::bindings`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BindingId(pub u32);

/// Identifies a layout in [`TypedProgram::layouts`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct LayoutId(pub u32);

/// Identifies a named member of one layout: its position in the pre-order walk of the layout's
/// named members (stored fields, derived fields, lets, groups), descending into groups and split
/// arms in textual order. See [`LayoutInfo::members`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct MemberId(pub u32);

/// A builtin function (table in `docs/language.md`, "Builtins").
///
/// Most builtins are the `tree` level's own ([`Intrinsic`]: one list of names, type rules,
/// interpreter semantics and lowerings); the front end adds the few that are sugar over them or
/// belong to the build language.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Builtin {
    /// A builtin of the `tree` level, called under its own name (`min`, `sqrt`, `popcount`, ...;
    /// not `set_insert`, which the language spells `insert`).
    Intrinsic(Intrinsic),
    /// `clamp(x, lo, hi)` = `min(max(x, lo), hi)`.
    Clamp,
    /// `select(c, a, b)`: `a` where `c` holds, else `b`; lane by lane for a `bool` vector `c`.
    Select,
    /// `any(m)`: whether some lane of a `bool` vector holds.
    Any,
    /// `all(m)`: whether every lane of a `bool` vector holds.
    All,
    /// `insert(s, x)`: adds `x` to the set `s`, a `mut` parameter (passed by reference).
    Insert,
    /// Build language: `append(x, n)` appends `n` elements of logical array `x` to the array the
    /// layout maps it to and yields the start index (`u32`).
    Append,
}

impl Builtin {
    /// Every builtin of the traversal and layout languages (not `append`).
    pub fn traversal() -> impl Iterator<Item = Builtin> {
        Intrinsic::ALL
            .iter()
            .filter(|&&i| i != Intrinsic::SetInsert)
            .map(|&i| Builtin::Intrinsic(i))
            .chain([
                Builtin::Clamp,
                Builtin::Select,
                Builtin::Any,
                Builtin::All,
                Builtin::Insert,
            ])
    }

    /// The name as written.
    pub fn name(self) -> &'static str {
        match self {
            Builtin::Intrinsic(i) => i.name(),
            Builtin::Clamp => "clamp",
            Builtin::Select => "select",
            Builtin::Any => "any",
            Builtin::All => "all",
            Builtin::Insert => "insert",
            Builtin::Append => "append",
        }
    }

    /// The traversal builtin named `name`.
    pub fn from_name(name: &str) -> Option<Builtin> {
        Builtin::traversal().find(|b| b.name() == name)
    }

    /// Number of arguments.
    pub fn arity(self) -> usize {
        match self {
            Builtin::Intrinsic(i) => i.arity(),
            Builtin::Clamp | Builtin::Select => 3,
            Builtin::Any | Builtin::All => 1,
            Builtin::Insert | Builtin::Append => 2,
        }
    }
}

/// What a name, a call or a `parent.x` / `build x` expression refers to.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Resolution {
    /// A `let`, `foreach` or pattern binding.
    Local(BindingId),
    /// Parameter `i` of the enclosing function.
    Param(u32),
    /// A function (after overload resolution).
    Func(FuncId),
    /// A builtin.
    Builtin(Builtin),
    /// The constructor of a record type.
    Ctor(AdtId),
    /// A variant constructor (or a bare field-less variant used as a value): type, variant index.
    Variant(AdtId, u32),
    /// A vector constructor `f32x3(a, b, c)`.
    VectorCtor(Prim, u32),
    /// A conversion written as a call, `f32(x)` (same as `x as f32`).
    PrimConv(Prim),
    /// Component `i` of the enclosing layout's reference (a layout parameter).
    LayoutParam(u32),
    /// A member of the enclosing layout (in a build: of the build's layout).
    LayoutMember(MemberId),
    /// `parent.x` where `x` is a member.
    ParentMember(MemberId),
    /// `parent.x` where `x` is a reference component.
    ParentParam(u32),
    /// Logical field `i` (shared fields first) of the variant a build entry builds.
    BuildField(u32),
    /// `build x` in expression position: builds the child in logical field `i` of the variant.
    BuildChild(u32),
}

/// A function parameter after resolution.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamInfo {
    /// Name.
    pub name: String,
    /// Type.
    pub ty: Ty,
    /// `mut`: passed by reference.
    pub mutable: bool,
    /// Whether a default is written (the expression is in the AST and typed).
    pub has_default: bool,
}

/// A function of the traversal language.
#[derive(Clone, Debug, PartialEq)]
pub struct FuncInfo {
    /// Index of the declaring item in `Program::items`.
    pub item: usize,
    /// Name as written (shared by overloads).
    pub name: String,
    /// Unique name: `name` for the first declaration, `name.1`, `name.2`, ... for later
    /// overloads, in declaration order.
    pub unique_name: String,
    /// Parameters.
    pub params: Vec<ParamInfo>,
    /// Result type (declared or inferred).
    pub ret: Ty,
    /// `order by k`: the index of parameter `k`, whose value orders the function's queued
    /// recursive calls (smallest first).
    pub order_by: Option<u32>,
    /// The declaration's span.
    pub span: Span,
}

/// How a local binding was introduced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BindingKind {
    /// `let`
    Let,
    /// A `foreach` loop variable.
    Foreach,
    /// A binding in a match pattern: field `field` (shared fields first) of the matched variant,
    /// or the whole value when `field` is `None`.
    Pattern {
        /// Logical field index.
        field: Option<u32>,
    },
}

/// A local binding.
#[derive(Clone, Debug, PartialEq)]
pub struct BindingInfo {
    /// Name.
    pub name: String,
    /// Type.
    pub ty: Ty,
    /// Introduced by.
    pub kind: BindingKind,
    /// A `let mut` local: assignable, and passable to a `mut` parameter.
    pub mutable: bool,
    /// Where the name was written.
    pub span: Span,
}

/// The kind of a named layout member.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MemberKindInfo {
    /// `x: T`, a stored field (a global when at top level).
    Stored,
    /// `x = e`
    Derived,
    /// `let x = e`
    Let,
    /// `group g ...`
    Group,
    /// `indirect group g ...`
    IndirectGroup,
}

/// A named layout member with its type.
#[derive(Clone, Debug, PartialEq)]
pub struct MemberInfo {
    /// Name.
    pub name: String,
    /// Kind.
    pub kind: MemberKindInfo,
    /// Type (for groups: the unit type).
    pub ty: Ty,
    /// The enclosing group, if any.
    pub group: Option<MemberId>,
    /// The variant (index in the layout's ADT) of the enclosing split arm, if any.
    pub variant: Option<u32>,
    /// The member's span.
    pub span: Span,
}

/// One split arm of a layout, in pre-order.
#[derive(Clone, Debug, PartialEq)]
pub struct ArmInfo {
    /// The arm's span.
    pub span: Span,
    /// The variant it realizes (index in the layout's ADT), when it names one.
    pub variant: Option<u32>,
    /// For `V from g[e]`: the indirect group.
    pub from_group: Option<MemberId>,
}

/// A typed layout.
#[derive(Clone, Debug, PartialEq)]
pub struct LayoutInfo {
    /// Index of the declaring item.
    pub item: usize,
    /// Name.
    pub name: String,
    /// The sum type this layout realizes, when it could be determined.
    pub adt: Option<AdtId>,
    /// Reference components (the layout's parameters): name and type.
    pub params: Vec<(String, Ty)>,
    /// The reference type: the single component's type, or the tuple of all components.
    pub ref_ty: Ty,
    /// A child's reference as the layout's expression for it (`left = I + 1`) gives it: the
    /// components that are not tree-carried (the compiler adds `c: T = parent.x` itself).
    pub child_ty: Ty,
    /// The reference as a build places it: the first component's type. With several
    /// components the others are the traversal's (computed by the layout's expressions for a
    /// child, from their defaults at the root), so `this` and a built child are the first.
    pub build_ref_ty: Ty,
    /// Named members in pre-order ([`MemberId`] indexes this).
    pub members: Vec<MemberInfo>,
    /// Split arms in pre-order.
    pub arms: Vec<ArmInfo>,
}

/// One `build Variant(...) { ... }` entry.
#[derive(Clone, Debug, PartialEq)]
pub struct BuildVariantInfo {
    /// Index of the entry in `BuildDecl::variants`.
    pub entry: usize,
    /// The variant built (index in the ADT).
    pub variant: u32,
    /// Logical fields (shared first): name and type.
    pub fields: Vec<(String, Ty)>,
}

/// A typed build.
#[derive(Clone, Debug, PartialEq)]
pub struct BuildInfo {
    /// Index of the declaring item.
    pub item: usize,
    /// The layout populated.
    pub layout: Option<LayoutId>,
    /// The entries whose variant was resolved.
    pub variants: Vec<BuildVariantInfo>,
}

/// What a `build x` / `build x = e` statement writes.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BuildTarget {
    /// The stored layout field written, if there is one named `x`.
    pub member: Option<MemberId>,
    /// The logical field of the variant named `x` (copied, or built when recursive).
    pub field: Option<u32>,
    /// True when `x` is a recursive field: the statement builds the child.
    pub child: bool,
}

/// Everything semantic analysis learned about a program.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TypedProgram {
    /// Declared types.
    pub adts: AdtTable,
    /// Functions, in declaration order.
    pub funcs: Vec<FuncInfo>,
    /// Local bindings.
    pub bindings: Vec<BindingInfo>,
    /// Type of every expression (also default expressions of fields and parameters).
    pub expr_types: FxHashMap<NodeId, Ty>,
    /// Resolution of every `Name`, `Call`, `Parent` and `Build` expression.
    pub resolutions: FxHashMap<NodeId, Resolution>,
    /// Binding introduced by a `let` or `foreach` statement (keyed by the statement's id) or by
    /// a binding pattern (keyed by the pattern's id).
    pub binders: FxHashMap<NodeId, BindingId>,
    /// `foreach x, k in e`: the binding of `k`, by the statement's id.
    pub foreach_index: FxHashMap<NodeId, BindingId>,
    /// Variant matched by a variant pattern.
    pub pattern_variants: FxHashMap<NodeId, (AdtId, u32)>,
    /// Operands of arithmetic and comparisons that are implicitly widened (an unsigned or signed
    /// integer to a wider one of the same signedness): the operand's id and the wider type.
    pub widenings: FxHashMap<NodeId, Ty>,
    /// Layouts, in declaration order.
    pub layouts: Vec<LayoutInfo>,
    /// Builds, in declaration order.
    pub builds: Vec<BuildInfo>,
    /// What each `build x` statement writes (keyed by the statement's id).
    pub build_targets: FxHashMap<NodeId, BuildTarget>,
}

impl TypedProgram {
    /// The type of expression `id` ([`Ty::Error`] when it has none).
    pub fn expr_ty(&self, id: NodeId) -> &Ty {
        self.expr_types.get(&id).unwrap_or(&Ty::Error)
    }

    /// The resolution of name or call `id`.
    pub fn resolution(&self, id: NodeId) -> Option<&Resolution> {
        self.resolutions.get(&id)
    }

    /// The function declared by item `item`.
    pub fn func_of_item(&self, item: usize) -> Option<FuncId> {
        self.funcs
            .iter()
            .position(|f| f.item == item)
            .map(|i| FuncId(i as u32))
    }

    /// The function with id `id`.
    pub fn func(&self, id: FuncId) -> &FuncInfo {
        &self.funcs[id.0 as usize]
    }

    /// The layout named `name`.
    pub fn layout_named(&self, name: &str) -> Option<LayoutId> {
        self.layouts
            .iter()
            .position(|l| l.name == name)
            .map(|i| LayoutId(i as u32))
    }
}
