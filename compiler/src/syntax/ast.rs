//! The abstract syntax tree of the three Scion languages (paper Figures 3, 6 and 10).
//!
//! One source file is a list of [`Item`]s: `type` and `func` declarations of the traversal
//! language, `layout` declarations of the layout language and `build` declarations of the build
//! language. Every node carries the [`Span`] it was parsed from. Expressions, statements and
//! patterns carry a [`NodeId`], unique within one [`Program`], so that later phases (name
//! resolution, type inference) keep their results in side tables instead of mutating the tree.
//!
//! The tree is exactly what was written: no desugaring happens here. `T(e*)` and `f(e*)` are
//! both [`ExprKind::Call`]; whether the callee is a constructor or a function is decided by
//! `sema`. Likewise `e[a:b]` is a [`ExprKind::Slice`] whether it slices an array or takes a bit
//! range of an integer.

use scion_ir::diag::Span;

/// Identifies an expression, statement or pattern node inside one [`Program`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeId(pub u32);

/// A name as written, with its position.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Ident {
    /// The text of the name.
    pub name: String,
    /// Where it was written.
    pub span: Span,
}

/// All items of a compilation (every input file, the prelude first).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Program {
    /// Items in input order.
    pub items: Vec<Item>,
    /// One more than the largest [`NodeId`] handed out.
    pub node_count: u32,
}

/// A top-level declaration.
// Items are few (one per declaration), so boxing the larger variants would buy nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub enum Item {
    /// `type ...;`
    Type(TypeDecl),
    /// `func ...`
    Func(FuncDecl),
    /// `layout ... { ... }`
    Layout(LayoutDecl),
    /// `build ... { ... }`
    Build(BuildDecl),
}

impl Item {
    /// The span of the whole item.
    pub fn span(&self) -> Span {
        match self {
            Item::Type(d) => d.span,
            Item::Func(d) => d.span,
            Item::Layout(d) => d.span,
            Item::Build(d) => d.span,
        }
    }

    /// The declared name.
    pub fn name(&self) -> &Ident {
        match self {
            Item::Type(d) => &d.name,
            Item::Func(d) => &d.name,
            Item::Layout(d) => &d.name,
            Item::Build(d) => &d.name,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Types

/// A written type.
#[derive(Clone, Debug, PartialEq)]
pub struct TypeExpr {
    /// What kind of type.
    pub kind: TypeExprKind,
    /// Where it was written.
    pub span: Span,
}

/// The forms of a written type (Figure 3, `T`).
#[derive(Clone, Debug, PartialEq)]
pub enum TypeExprKind {
    /// A named type: a primitive (`f32`, `u16`, `bool`, `ptr`) or a declared `type`.
    Named(Ident),
    /// A vector `f32x3`: element primitive and lane count (written as one token).
    Vector {
        /// The element type's name (`f32`, `u8`, ...).
        elem: Ident,
        /// Number of lanes (≥ 1).
        lanes: u32,
    },
    /// `T[n]` (statically sized) or `T[x]` (sized by a field or global named `x`).
    Array {
        /// Element type.
        elem: Box<TypeExpr>,
        /// The length.
        len: ArrayLen,
    },
    /// `(T1, ..., Tn)` with n ≠ 1; `()` is the unit type.
    Tuple(Vec<TypeExpr>),
    /// `set[T]`
    Set(Box<TypeExpr>),
    /// `option[T]`
    Option(Box<TypeExpr>),
}

/// The length of an array type.
#[derive(Clone, Debug, PartialEq)]
pub enum ArrayLen {
    /// A literal length, `T[8]`.
    Const(u64, Span),
    /// A length given by a name, `Triangle[nprims]`, `Triangle[P]`.
    Name(Ident),
}

// ---------------------------------------------------------------------------------------------
// Traversal language declarations

/// `type R(a: T, b: U = d);` (a record) or `type S(shared: T) = A(...) | B(...);` (a sum whose
/// variants carry the shared fields first).
#[derive(Clone, Debug, PartialEq)]
pub struct TypeDecl {
    /// The type's name.
    pub name: Ident,
    /// Record fields, or the fields shared by every variant of a sum.
    pub fields: Vec<FieldDecl>,
    /// `None` for a record; the variants of a sum otherwise.
    pub variants: Option<Vec<VariantDecl>>,
    /// The whole declaration.
    pub span: Span,
}

/// `name: T` or `name: T = default` in a type declaration.
#[derive(Clone, Debug, PartialEq)]
pub struct FieldDecl {
    /// Field name.
    pub name: Ident,
    /// Field type.
    pub ty: TypeExpr,
    /// Default value used when a constructor call omits the field.
    pub default: Option<Expr>,
    /// The whole field.
    pub span: Span,
}

/// One variant of a sum type: `Leaf(nprims: u16, data: Triangle[nprims])`.
#[derive(Clone, Debug, PartialEq)]
pub struct VariantDecl {
    /// Variant name.
    pub name: Ident,
    /// Fields after the shared ones.
    pub fields: Vec<FieldDecl>,
    /// The whole variant.
    pub span: Span,
}

/// `func name(params) -> T order by k = body` (the `-> T` is optional and inferred when absent;
/// `order by k` is optional).
#[derive(Clone, Debug, PartialEq)]
pub struct FuncDecl {
    /// Function name (overloads share a name).
    pub name: Ident,
    /// Parameters.
    pub params: Vec<Param>,
    /// Declared result type.
    pub ret: Option<TypeExpr>,
    /// `order by k`: the function's recursive calls are queued and run smallest `k` first
    /// (best-first traversal); `k` names a parameter.
    pub order_by: Option<Ident>,
    /// The body: `= stmt` (a block, a `match`, or any statement).
    pub body: Stmt,
    /// The whole declaration.
    pub span: Span,
}

/// `x: mut? T (= e)?`
#[derive(Clone, Debug, PartialEq)]
pub struct Param {
    /// Parameter name.
    pub name: Ident,
    /// `mut` parameters are passed by reference; assignment writes through.
    pub mutable: bool,
    /// Parameter type.
    pub ty: TypeExpr,
    /// Default argument.
    pub default: Option<Expr>,
    /// The whole parameter.
    pub span: Span,
}

// ---------------------------------------------------------------------------------------------
// Statements

/// A statement.
#[derive(Clone, Debug, PartialEq)]
pub struct Stmt {
    /// Side-table key.
    pub id: NodeId,
    /// What kind of statement.
    pub kind: StmtKind,
    /// Where.
    pub span: Span,
}

/// The statement forms of Figures 3 and 10.
#[derive(Clone, Debug, PartialEq)]
pub enum StmtKind {
    /// An expression evaluated for its effect or, as the last statement of a body, its value.
    Expr(Expr),
    /// `target = value`: a `mut` variable, a tuple component, or `this[a:b]` in a build.
    Assign {
        /// Where to store.
        target: Expr,
        /// What to store.
        value: Expr,
    },
    /// `{ s; s; ... }`
    Block(Vec<Stmt>),
    /// `return e?`
    Return(Option<Expr>),
    /// `match e { | p -> s ... }`
    Match {
        /// The matched value.
        scrutinee: Expr,
        /// Arms, tested in order.
        arms: Vec<MatchArm>,
    },
    /// `let x: T = e` (the type may be omitted and is then inferred), or `let mut x: T = e`, a
    /// local that later statements may assign.
    Let {
        /// Bound name.
        name: Ident,
        /// Declared type.
        ty: Option<TypeExpr>,
        /// Initial value.
        value: Expr,
        /// Written `let mut`.
        mutable: bool,
    },
    /// `if e { s } elif e { s } ... else { s }`
    If {
        /// Conditions with their branches, in order (the `if` first, then each `elif`).
        branches: Vec<(Expr, Stmt)>,
        /// The `else` branch.
        otherwise: Option<Box<Stmt>>,
    },
    /// `foreach x in e { s }`
    Foreach {
        /// Loop variable.
        var: Ident,
        /// `foreach x, k in e`: the element's index (a `u32`).
        index: Option<Ident>,
        /// The iterated array, slice or set.
        iter: Expr,
        /// Body.
        body: Box<Stmt>,
    },
    /// Build language: `build x` (copy logical field `x`, or build child `x`) or `build x = e`.
    Build {
        /// The layout field (or recursive logical field) being built.
        field: Ident,
        /// The stored value, for `build x = e`.
        value: Option<Expr>,
    },
}

/// `| pattern -> stmt`
#[derive(Clone, Debug, PartialEq)]
pub struct MatchArm {
    /// What the arm matches.
    pub pattern: Pattern,
    /// What it runs.
    pub body: Stmt,
    /// The whole arm.
    pub span: Span,
}

/// A pattern (Figure 3, `q`).
#[derive(Clone, Debug, PartialEq)]
pub struct Pattern {
    /// Side-table key.
    pub id: NodeId,
    /// What kind.
    pub kind: PatternKind,
    /// Where.
    pub span: Span,
}

/// Pattern forms.
#[derive(Clone, Debug, PartialEq)]
pub enum PatternKind {
    /// `_`
    Wildcard,
    /// A binding `x` or `x: T` (inside a variant pattern).
    Bind {
        /// Bound name.
        name: Ident,
        /// Optional type annotation.
        ty: Option<TypeExpr>,
    },
    /// `Variant(p, ...)`: the sub-patterns bind the shared fields first, then the variant's own,
    /// positionally. A bare `Variant` with no parentheses matches without binding.
    Variant {
        /// The variant's name.
        name: Ident,
        /// Sub-patterns (bindings or wildcards).
        fields: Vec<Pattern>,
    },
}

// ---------------------------------------------------------------------------------------------
// Expressions

/// An expression.
#[derive(Clone, Debug, PartialEq)]
pub struct Expr {
    /// Side-table key.
    pub id: NodeId,
    /// What kind.
    pub kind: ExprKind,
    /// Where.
    pub span: Span,
}

/// Expression forms of Figures 3, 6 and 10.
#[derive(Clone, Debug, PartialEq)]
pub enum ExprKind {
    /// A variable, parameter, field or global name.
    Name(Ident),
    /// An integer literal; its type is inferred from use (default `i32`).
    Int(u128),
    /// A float literal (including `inf`); its type is inferred from use (default `f32`).
    Float(f64),
    /// `true` / `false`.
    Bool(bool),
    /// `f(e, ...)` or `T(e, ...)`: a call or a constructor, resolved by `sema`.
    Call {
        /// The called function, type or variant name.
        callee: Ident,
        /// Arguments, positional.
        args: Vec<Expr>,
    },
    /// `e.x`: a record field, or a vector component (`.x .y .z .w`).
    Field {
        /// The record or vector.
        base: Box<Expr>,
        /// The field or component name.
        name: Ident,
    },
    /// `e[i]`: array element, tuple component (literal index), vector lane.
    Index {
        /// Indexed value.
        base: Box<Expr>,
        /// The index.
        index: Box<Expr>,
    },
    /// `e[a:b]`: an array slice, or bits `a..b` of an integer (half-open, low bit 0).
    Slice {
        /// Sliced value.
        base: Box<Expr>,
        /// Start (inclusive).
        lo: Box<Expr>,
        /// End (exclusive).
        hi: Box<Expr>,
    },
    /// `(a, b, ...)` with at least two components; `()` is the unit value.
    Tuple(Vec<Expr>),
    /// `[a, b, ...]`: an array of at least one element, all of one type.
    Array(Vec<Expr>),
    /// A prefix operator.
    Unary {
        /// Which.
        op: UnaryOp,
        /// Operand.
        operand: Box<Expr>,
    },
    /// An infix operator.
    Binary {
        /// Which.
        op: BinaryOp,
        /// Left operand.
        lhs: Box<Expr>,
        /// Right operand.
        rhs: Box<Expr>,
    },
    /// `e as T`: a value conversion (int↔float, widening, narrowing).
    Cast {
        /// Converted value.
        expr: Box<Expr>,
        /// Target type.
        ty: TypeExpr,
    },
    /// `e to T`: reinterpret the bits (sizes must agree).
    BitCast {
        /// Reinterpreted value.
        expr: Box<Expr>,
        /// Target type.
        ty: TypeExpr,
    },
    /// Build language: the reference of the node being built.
    This,
    /// Layout language: `parent.x`, the parent's value of `x` (a tree-carried dependency).
    Parent(Ident),
    /// Build language: `build x` in expression position: builds child `x`, yields its reference.
    Build(Ident),
    /// `if c { s } elif c { s } else { s }` as an expression: the taken branch's value (the
    /// tail of its block, as in a function body). The `else` is required, and every branch
    /// must end in a value or leave the function.
    If {
        /// Conditions with their branches, in order (the `if` first, then each `elif`).
        branches: Vec<(Expr, Stmt)>,
        /// The `else` branch.
        otherwise: Box<Stmt>,
    },
}

/// Prefix operators.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum UnaryOp {
    /// `-e`
    Neg,
    /// `!e` (logical not)
    Not,
    /// `~e` (bitwise not)
    BitNot,
}

/// Infix operators, loosest first: `||`, `&&`, comparisons, `|`, `^`, `&`, shifts, `+ -`, `* / %`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BinaryOp {
    /// `||`
    Or,
    /// `&&`
    And,
    /// `==`
    Eq,
    /// `!=`
    Ne,
    /// `<`
    Lt,
    /// `<=`
    Le,
    /// `>`
    Gt,
    /// `>=`
    Ge,
    /// `|`
    BitOr,
    /// `^`
    BitXor,
    /// `&`
    BitAnd,
    /// `<<`
    Shl,
    /// `>>`
    Shr,
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `*`
    Mul,
    /// `/`
    Div,
    /// `%`
    Rem,
}

impl BinaryOp {
    /// The operator as written.
    pub fn as_str(self) -> &'static str {
        use BinaryOp::*;
        match self {
            Or => "||",
            And => "&&",
            Eq => "==",
            Ne => "!=",
            Lt => "<",
            Le => "<=",
            Gt => ">",
            Ge => ">=",
            BitOr => "|",
            BitXor => "^",
            BitAnd => "&",
            Shl => "<<",
            Shr => ">>",
            Add => "+",
            Sub => "-",
            Mul => "*",
            Div => "/",
            Rem => "%",
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Layout language (Figure 6)

/// `layout Name(I: u32, ...) { members }`
#[derive(Clone, Debug, PartialEq)]
pub struct LayoutDecl {
    /// Layout name; the build of the same name populates it.
    pub name: Ident,
    /// The components of the reference type. A parameter with a default `parent.x` is a
    /// tree-carried component, filled from the parent when descending.
    pub params: Vec<LayoutParam>,
    /// Top-level members: globals, groups, derived fields.
    pub members: Vec<Member>,
    /// The whole declaration.
    pub span: Span,
}

/// `x: T (= e)?` in a layout signature.
#[derive(Clone, Debug, PartialEq)]
pub struct LayoutParam {
    /// Component name (`I`).
    pub name: Ident,
    /// Component type (`u32`, `ptr`, `AABB`, ...).
    pub ty: TypeExpr,
    /// Default value, e.g. `parent.bounds`.
    pub default: Option<Expr>,
    /// The whole parameter.
    pub span: Span,
}

/// A layout member.
#[derive(Clone, Debug, PartialEq)]
pub struct Member {
    /// What kind.
    pub kind: MemberKind,
    /// Where.
    pub span: Span,
}

/// Member forms (Figure 6, `M`).
#[derive(Clone, Debug, PartialEq)]
pub enum MemberKind {
    /// `x: T` — a stored field occupying `sizeof(T)` bytes.
    Field {
        /// Field name.
        name: Ident,
        /// Physical type.
        ty: TypeExpr,
    },
    /// `n` — `n` bytes of padding.
    Padding {
        /// Byte count.
        bytes: u64,
    },
    /// `x = e` — a derived field, evaluated at most once per destruction.
    Derived {
        /// Field name.
        name: Ident,
        /// Definition.
        value: Expr,
    },
    /// `let x: T = e` — a local binding visible to later members.
    Let {
        /// Bound name.
        name: Ident,
        /// Declared type.
        ty: Option<TypeExpr>,
        /// Value.
        value: Expr,
    },
    /// `group g[attrs] by e { ... }` or `indirect group g { ... }`.
    Group(GroupDecl),
    /// `---`: ends one array of the enclosing group and starts the next (SoA).
    Separator,
    /// `split e { pattern -> ... }` — a tagged union overlaying its arms.
    Split {
        /// The discriminant.
        discriminant: Expr,
        /// Arms, tested in order.
        arms: Vec<SplitArm>,
    },
}

/// A group declaration.
#[derive(Clone, Debug, PartialEq)]
pub struct GroupDecl {
    /// Group name.
    pub name: Ident,
    /// `indirect group` (auxiliary storage reached through `from`).
    pub indirect: bool,
    /// `[size=N, align=A]` or `[4]` (tile count of a nested group).
    pub attrs: Vec<GroupAttr>,
    /// `by e`: the index (a reference component or an expression over it).
    pub by: Option<Expr>,
    /// Members (with `---` separators).
    pub members: Vec<Member>,
    /// The whole group.
    pub span: Span,
}

/// A group attribute.
#[derive(Clone, Debug, PartialEq)]
pub struct GroupAttr {
    /// Which attribute.
    pub kind: GroupAttrKind,
    /// Where.
    pub span: Span,
}

/// Group attribute forms.
#[derive(Clone, Debug, PartialEq)]
pub enum GroupAttrKind {
    /// A bare count `[4]`: tile size of a nested group.
    Count(u64),
    /// `size = e`: number of elements (an expression over globals).
    Size(Expr),
    /// `align = n`: element alignment in bytes (a power of two).
    Align(u64),
}

/// `pattern -> Variant { members }` or `pattern -> Variant from g[e]`.
#[derive(Clone, Debug, PartialEq)]
pub struct SplitArm {
    /// When the arm applies.
    pub pattern: SplitPattern,
    /// The variant it realizes and how.
    pub body: SplitArmBody,
    /// The whole arm.
    pub span: Span,
}

/// A split pattern (Figure 6, `p`).
#[derive(Clone, Debug, PartialEq)]
pub struct SplitPattern {
    /// What kind.
    pub kind: SplitPatternKind,
    /// Where.
    pub span: Span,
}

/// Split pattern forms.
#[derive(Clone, Debug, PartialEq)]
pub enum SplitPatternKind {
    /// `n`: equal to the literal.
    Eq(i128),
    /// `~ n`: not equal to the literal.
    Ne(i128),
    /// `< n`
    Lt(i128),
    /// `<= n`
    Le(i128),
    /// `> n`
    Gt(i128),
    /// `>= n`
    Ge(i128),
    /// `_`: anything not matched by an earlier arm.
    Wildcard,
}

/// The right-hand side of a split arm.
#[derive(Clone, Debug, PartialEq)]
pub enum SplitArmBody {
    /// `Variant { members }`: the arm's members overlay the split's bytes.
    Members {
        /// Which variant of the ADT this arm realizes.
        variant: Ident,
        /// Its members.
        members: Vec<Member>,
    },
    /// `Variant from g[e]`: a foreign key into indirect group `g`, whose members realize the
    /// variant.
    From {
        /// Which variant.
        variant: Ident,
        /// The indirect group.
        group: Ident,
        /// The key.
        key: Expr,
    },
}

// ---------------------------------------------------------------------------------------------
// Build language (Figure 10)

/// `build Name[order=pre] { build root { ... }; build Variant(params) { ... }; ... }`
#[derive(Clone, Debug, PartialEq)]
pub struct BuildDecl {
    /// The layout this build populates (same name).
    pub name: Ident,
    /// `pre` (node before its subtrees) or `post`; `pre` when not written.
    pub order: BuildOrder,
    /// Where `order=...` was written, if it was.
    pub order_span: Option<Span>,
    /// `build root { ... }`, run once before the tree.
    pub root: Option<BuildRoot>,
    /// One per variant.
    pub variants: Vec<BuildVariant>,
    /// The whole declaration.
    pub span: Span,
}

/// Placement of a node relative to its subtrees.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BuildOrder {
    /// Parent first.
    Pre,
    /// Children first.
    Post,
}

/// `build root { stmts }`
#[derive(Clone, Debug, PartialEq)]
pub struct BuildRoot {
    /// Statements.
    pub body: Vec<Stmt>,
    /// Where.
    pub span: Span,
}

/// `build Variant(x: T, ...) { stmts }`
#[derive(Clone, Debug, PartialEq)]
pub struct BuildVariant {
    /// The variant built.
    pub name: Ident,
    /// The variant's logical fields as the build names them (shared fields first).
    pub params: Vec<FieldDecl>,
    /// Statements.
    pub body: Vec<Stmt>,
    /// Where.
    pub span: Span,
}
