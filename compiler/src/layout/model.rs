//! The physical layout model: a `layout` declaration with every byte placed (paper §4.2,
//! docs/design/layout-catalog.md §2.3).
//!
//! Input: a [`LayoutDecl`] and the [`Program`] it belongs to (for `type` sizes and for the ADT
//! the layout realizes). Output: a [`LayoutModel`] holding the reference's components, the
//! globals block and the global arrays, every group with its arrays (a group cut by `---` has
//! several, all indexed alike), nested groups (tiles), splits (overlays) and, for every member,
//! its scope, its array and its byte offset. Problems found while placing bytes (unknown types,
//! bad group attributes, `---` outside a group, ...) are collected in
//! [`LayoutModel::diagnostics`]; building the model never fails and never panics.
//!
//! Sizing rules: members in textual order, each at its natural alignment; a split is as large
//! as its largest arm and every arm starts at the split's offset; an array element is aligned
//! to `max(natural, align attribute)` and its stride is its size rounded up to that alignment.

use crate::layout::types::Shape;
use crate::syntax::ast::{Expr, Ident, LayoutDecl, Program, SplitPattern, TypeExpr};
use scion_ir::diag::{Diagnostics, Span};

/// Index of a member in [`LayoutModel::members`].
pub type MemberId = usize;
/// Index of a group in [`LayoutModel::groups`].
pub type GroupId = usize;
/// Index of a split in [`LayoutModel::splits`].
pub type SplitId = usize;
/// Index of a scope in [`LayoutModel::scopes`]; scope 0 is the layout's top level.
pub type ScopeId = usize;

/// The physical model of one layout.
#[derive(Clone, Debug)]
pub struct LayoutModel {
    /// The layout's name.
    pub name: Ident,
    /// The whole declaration.
    pub span: Span,
    /// The components of the reference type, in order.
    pub components: Vec<Component>,
    /// Size and alignment of the reference (its components laid out as a record).
    pub reference: Shape,
    /// Every member, in textual (depth-first) order.
    pub members: Vec<MemberInfo>,
    /// Every scope: the top level, each group, each split arm with members.
    pub scopes: Vec<Scope>,
    /// Every group, top-level and nested.
    pub groups: Vec<Group>,
    /// Every split.
    pub splits: Vec<Split>,
    /// The block of fixed-size globals (top-level stored fields).
    pub globals: Shape,
    /// Globals whose length is a name (`primitives: Triangle[P]`): each is its own buffer.
    pub global_arrays: Vec<GlobalArray>,
    /// The algebraic data type this layout realizes, when it could be determined.
    pub adt: Option<Adt>,
    /// Problems found while building the model (codes E03xx).
    pub diagnostics: Diagnostics,
}

/// One component of the reference type: `I: u32`, or `lo: f32x3 = parent.lo`.
#[derive(Clone, Debug)]
pub struct Component {
    /// Its name.
    pub name: Ident,
    /// Its type.
    pub ty: TypeExpr,
    /// Its size, when the type is sized.
    pub shape: Option<Shape>,
    /// The default, e.g. `parent.lo`.
    pub default: Option<Expr>,
    /// `Some(x)` for a tree-carried component whose default is `parent.x`.
    pub carried: Option<Ident>,
    /// Byte offset inside the reference (components laid out as a record).
    pub offset: u64,
}

/// A member with the facts placement established.
#[derive(Clone, Debug)]
pub struct MemberInfo {
    /// What it is.
    pub kind: MemberModel,
    /// Where it was written.
    pub span: Span,
    /// The scope that declares it.
    pub scope: ScopeId,
    /// Which array of its group (0 unless after a `---`).
    pub part: usize,
}

/// Member forms of the model.
#[derive(Clone, Debug)]
pub enum MemberModel {
    /// A stored field.
    Stored(Stored),
    /// Padding bytes.
    Padding {
        /// Byte count.
        bytes: u64,
        /// Offset in its element (or in the globals block).
        offset: u64,
    },
    /// `x = e`.
    Derived {
        /// Name.
        name: Ident,
        /// Definition.
        value: Expr,
    },
    /// `let x: T = e`.
    Let {
        /// Name.
        name: Ident,
        /// Declared type.
        ty: Option<TypeExpr>,
        /// Value.
        value: Expr,
    },
    /// A group.
    Group(GroupId),
    /// A split.
    Split(SplitId),
    /// `---`.
    Separator,
}

impl MemberModel {
    /// The declared name of a stored field, derived field or let.
    pub fn value_name(&self) -> Option<&Ident> {
        match self {
            MemberModel::Stored(s) => Some(&s.name),
            MemberModel::Derived { name, .. } | MemberModel::Let { name, .. } => Some(name),
            _ => None,
        }
    }
}

/// A stored field.
#[derive(Clone, Debug)]
pub struct Stored {
    /// Name.
    pub name: Ident,
    /// Physical type.
    pub ty: TypeExpr,
    /// Size in bytes (0 when the type could not be sized; an error was reported).
    pub size: u64,
    /// Natural alignment.
    pub align: u64,
    /// Where its bytes are.
    pub storage: Storage,
}

/// Where a stored field's bytes are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Storage {
    /// At `offset` in the globals block.
    Globals {
        /// Byte offset.
        offset: u64,
    },
    /// It is global array number `n` of [`LayoutModel::global_arrays`].
    GlobalArray(usize),
    /// At `offset` in each element of array `array` of group `group`.
    Element {
        /// The group.
        group: GroupId,
        /// Which of its arrays.
        array: usize,
        /// Byte offset within one element.
        offset: u64,
    },
    /// Nowhere (an error was reported).
    None,
}

/// A lexical scope.
#[derive(Clone, Debug)]
pub struct Scope {
    /// What opens it.
    pub kind: ScopeKind,
    /// The enclosing scope (none for the top level).
    pub parent: Option<ScopeId>,
    /// Its members in order (the members of every array of a group share one scope).
    pub members: Vec<MemberId>,
}

/// What opens a scope.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScopeKind {
    /// The layout's top level: globals.
    Top,
    /// A group's body.
    Group(GroupId),
    /// The members of arm `arm` of split `split`.
    Arm {
        /// The split.
        split: SplitId,
        /// The arm's index.
        arm: usize,
    },
}

/// How a group's elements are addressed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GroupKind {
    /// Indexed `by` an expression over the reference (an array index).
    Direct,
    /// Indexed `by` a `ptr` component: the element is where the pointer points.
    Pointer,
    /// `indirect group`: reached only through `from g[key]`.
    Indirect,
    /// A group inside a group: a tile of `count` elements inside each outer element.
    Nested,
}

/// A group.
#[derive(Clone, Debug)]
pub struct Group {
    /// Name.
    pub name: Ident,
    /// Addressing.
    pub kind: GroupKind,
    /// Its body's scope.
    pub scope: ScopeId,
    /// The member that declares it.
    pub member: MemberId,
    /// `by e`.
    pub by: Option<Expr>,
    /// `size = e`.
    pub size: Option<Expr>,
    /// `align = n` (only when a power of two).
    pub align_attr: Option<u64>,
    /// `[n]` tile count of a nested group.
    pub count: Option<u64>,
    /// For a nested group: the outer group, the outer array and the tile's byte offset in it.
    pub parent: Option<(GroupId, usize, u64)>,
    /// One per `---`-separated part.
    pub arrays: Vec<ArrayShape>,
    /// The declaration.
    pub span: Span,
}

/// One contiguous array of a group.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ArrayShape {
    /// Bytes of members in one element.
    pub size: u64,
    /// Element alignment: `max(natural, align attribute)`.
    pub align: u64,
    /// Element stride: `size` rounded up to `align`.
    pub stride: u64,
    /// For a nested group, the byte offset of this array's block inside the tile; else 0.
    pub offset: u64,
}

/// A split (tagged union).
#[derive(Clone, Debug)]
pub struct Split {
    /// The member that declares it.
    pub member: MemberId,
    /// The enclosing scope.
    pub scope: ScopeId,
    /// The discriminant.
    pub discriminant: Expr,
    /// Its arms in order.
    pub arms: Vec<Arm>,
    /// Byte offset of the overlay in its element.
    pub offset: u64,
    /// Bytes the overlay occupies (its largest arm).
    pub size: u64,
    /// The declaration.
    pub span: Span,
}

/// A split arm.
#[derive(Clone, Debug)]
pub struct Arm {
    /// When it applies.
    pub pattern: SplitPattern,
    /// The variant it realizes.
    pub variant: Ident,
    /// How.
    pub body: ArmBody,
    /// The whole arm.
    pub span: Span,
}

/// How an arm realizes its variant.
#[derive(Clone, Debug)]
pub enum ArmBody {
    /// With members in this scope.
    Members(ScopeId),
    /// Through the indirect group named `group_name` at `key`.
    From {
        /// The name written.
        group_name: Ident,
        /// The indirect group, when the name denotes one.
        group: Option<GroupId>,
        /// The key.
        key: Expr,
    },
}

/// A global array (its own buffer).
#[derive(Clone, Debug)]
pub struct GlobalArray {
    /// The member.
    pub member: MemberId,
    /// Its name.
    pub name: Ident,
    /// The global that holds its length.
    pub len: Ident,
    /// Element type.
    pub elem: TypeExpr,
    /// Element size and alignment.
    pub shape: Shape,
}

/// The ADT a layout realizes.
#[derive(Clone, Debug)]
pub struct Adt {
    /// Its name.
    pub name: String,
    /// Its variants, each with the logical fields (shared first).
    pub variants: Vec<AdtVariant>,
}

/// One variant of the realized ADT.
#[derive(Clone, Debug)]
pub struct AdtVariant {
    /// Its declared name.
    pub name: Ident,
    /// Logical fields, shared ones first.
    pub fields: Vec<LogicalField>,
}

/// A logical field of a variant.
#[derive(Clone, Debug)]
pub struct LogicalField {
    /// Name.
    pub name: Ident,
    /// Logical type.
    pub ty: TypeExpr,
    /// Whether it holds children (its type is the ADT or an array of it).
    pub recursive: bool,
    /// Whether its type is an array.
    pub array: bool,
}

impl Adt {
    /// The variant called `name`.
    pub fn variant(&self, name: &str) -> Option<&AdtVariant> {
        self.variants.iter().find(|v| v.name.name == name)
    }
}

/// The type a layout realizes, as the type checker decided it.
#[derive(Clone, Copy, Debug)]
pub enum AdtChoice<'a> {
    /// The sum type of this name.
    Chosen(&'a str),
    /// None could be told (the model's search reports why, E0311).
    Undecided,
}

impl LayoutModel {
    /// Builds the model of `decl`, finding the type it realizes by itself (for tests of the
    /// layout checks without the type checker); `program` supplies the `type` declarations and
    /// the build of the same name.
    pub fn from_ast(decl: &LayoutDecl, program: &Program) -> LayoutModel {
        crate::layout::place::build(decl, program, None)
    }

    /// The model of `decl` realizing the type the type checker chose (`LayoutInfo::adt`).
    pub fn of(decl: &LayoutDecl, program: &Program, adt: AdtChoice<'_>) -> LayoutModel {
        crate::layout::place::build(decl, program, Some(adt))
    }

    /// The member's stored-field data, if it is a stored field.
    pub fn stored(&self, id: MemberId) -> Option<&Stored> {
        match &self.members[id].kind {
            MemberModel::Stored(s) => Some(s),
            _ => None,
        }
    }

    /// The top-level group called `name`.
    pub fn group_named(&self, name: &str) -> Option<GroupId> {
        self.groups
            .iter()
            .position(|g| g.parent.is_none() && g.name.name == name)
    }

    /// The component called `name`.
    pub fn component(&self, name: &str) -> Option<usize> {
        self.components.iter().position(|c| c.name.name == name)
    }

    /// Sum of the strides of every array of every direct top-level group: the bytes one node
    /// occupies (Table 1's "node size").
    pub fn node_bytes(&self) -> u64 {
        self.groups
            .iter()
            .filter(|g| matches!(g.kind, GroupKind::Direct | GroupKind::Pointer))
            .flat_map(|g| g.arrays.iter())
            .map(|a| a.stride)
            .sum()
    }

    /// The byte offset of the stored field `name` wherever it is declared (first match), with
    /// its group and array; for tests and dumps.
    pub fn offset_of(&self, name: &str) -> Option<Storage> {
        self.members.iter().find_map(|m| match &m.kind {
            MemberModel::Stored(s) if s.name.name == name => Some(s.storage),
            _ => None,
        })
    }
}

/// The layout models of a program: one per layout name (its first declaration), each built
/// once, realizing the type the type checker chose. The layout and build checks, the
/// specializations and the C ABI all read these.
#[derive(Clone, Debug, Default)]
pub struct Models {
    /// Each layout's declaration (with the components sema's types let the compiler declare,
    /// see [`Models::of`]) and its model.
    models: Vec<(LayoutDecl, LayoutModel)>,
}

impl Models {
    /// The models of `program`'s layouts, with `typed`'s choices of types. A `parent.x` of a
    /// derived field or let that no component carries gets a declared component typed by the
    /// checker (`parent.bounds` adds `parent_bounds: AABB = parent.bounds` to the reference).
    pub fn of(program: &Program, typed: &crate::sema::TypedProgram) -> Models {
        let mut models: Vec<(LayoutDecl, LayoutModel)> = Vec::new();
        let mut next_id = program.node_count;
        for item in &program.items {
            let crate::syntax::ast::Item::Layout(decl) = item else {
                continue;
            };
            if models.iter().any(|m| m.0.name.name == decl.name.name) {
                continue;
            }
            let info = typed.layouts.iter().find(|l| l.name == decl.name.name);
            let chosen = info
                .and_then(|l| l.adt)
                .and_then(|a| typed.adts.get(a))
                .map(|a| a.name.as_str());
            let choice = chosen.map_or(AdtChoice::Undecided, AdtChoice::Chosen);
            let model = LayoutModel::of(decl, program, choice);
            let carried = info
                .map(|l| carried_derived(decl, &model, l, &typed.adts, &mut next_id))
                .unwrap_or_default();
            if carried.is_empty() {
                models.push((decl.clone(), model));
            } else {
                let mut d = decl.clone();
                d.params.extend(carried);
                let model = LayoutModel::of(&d, program, choice);
                models.push((d, model));
            }
        }
        Models { models }
    }

    /// The models of `program`'s layouts with their types found by the layout model alone
    /// (tests of the layout checks).
    pub fn inferred(program: &Program) -> Models {
        let mut models: Vec<(LayoutDecl, LayoutModel)> = Vec::new();
        for item in &program.items {
            if let crate::syntax::ast::Item::Layout(decl) = item {
                if !models.iter().any(|m| m.0.name.name == decl.name.name) {
                    models.push((decl.clone(), LayoutModel::from_ast(decl, program)));
                }
            }
        }
        Models { models }
    }

    /// The model of layout `name`.
    pub fn get(&self, name: &str) -> Option<&LayoutModel> {
        self.models
            .iter()
            .find(|m| m.0.name.name == name)
            .map(|m| &m.1)
    }

    /// The declaration of layout `name` the model was built from.
    pub fn decl(&self, name: &str) -> Option<&LayoutDecl> {
        self.models
            .iter()
            .find(|m| m.0.name.name == name)
            .map(|m| &m.0)
    }
}

/// Components to declare for `decl`: one per `parent.x` read by its expressions where `x` is a
/// derived field or let that no component carries, typed by the checker (`info`).
fn carried_derived(
    decl: &LayoutDecl,
    model: &LayoutModel,
    info: &crate::sema::LayoutInfo,
    adts: &crate::sema::AdtTable,
    next_id: &mut u32,
) -> Vec<crate::syntax::ast::LayoutParam> {
    use crate::syntax::ast::{ExprKind, LayoutParam, NodeId};
    let mut exprs: Vec<&Expr> = Vec::new();
    for m in &model.members {
        if let MemberModel::Derived { value, .. } | MemberModel::Let { value, .. } = &m.kind {
            exprs.push(value);
        }
    }
    exprs.extend(model.splits.iter().map(|s| &s.discriminant));
    let mut out: Vec<LayoutParam> = Vec::new();
    for e in exprs {
        for id in crate::layout::resolve::names_in(e) {
            let Some(x) = id.name.strip_prefix("parent.") else {
                continue;
            };
            let carried = |c: &Option<Ident>| c.as_ref().is_some_and(|c| c.name == x);
            if model.components.iter().any(|c| carried(&c.carried))
                || out.iter().any(|p| {
                    matches!(&p.default, Some(Expr { kind: ExprKind::Parent(c), .. }) if c.name == x)
                })
            {
                continue;
            }
            let derived = model.members.iter().any(|m| {
                matches!(&m.kind, MemberModel::Derived { name, .. } | MemberModel::Let { name, .. } if name.name == x)
            });
            let ty = info
                .members
                .iter()
                .find(|m| m.name == x)
                .and_then(|m| type_expr(&m.ty, adts, id.span));
            let (true, Some(ty)) = (derived, ty) else {
                continue;
            };
            let taken = |n: &str| {
                decl.params.iter().any(|p| p.name.name == n)
                    || out.iter().any(|p| p.name.name == n)
                    || info.members.iter().any(|m| m.name == n)
            };
            let mut name = format!("parent_{x}");
            while taken(&name) {
                name.push('_');
            }
            *next_id += 1;
            out.push(LayoutParam {
                name: Ident {
                    name,
                    span: id.span,
                },
                ty,
                default: Some(Expr {
                    id: NodeId(*next_id),
                    kind: ExprKind::Parent(Ident {
                        name: x.to_string(),
                        span: id.span,
                    }),
                    span: id.span,
                }),
                span: id.span,
            });
        }
    }
    out
}

/// The written form of a checked type, where it has one (scalars, vectors, declared types and
/// fixed arrays of them).
fn type_expr(t: &crate::sema::Ty, adts: &crate::sema::AdtTable, span: Span) -> Option<TypeExpr> {
    use crate::sema::Ty;
    use crate::syntax::ast::{ArrayLen, TypeExprKind};
    let named = |n: &str| {
        TypeExprKind::Named(Ident {
            name: n.to_string(),
            span,
        })
    };
    let kind = match t {
        Ty::Prim(p) => named(p.name()),
        Ty::Ptr => named("ptr"),
        Ty::Vector(p, lanes) => TypeExprKind::Vector {
            elem: Ident {
                name: p.name().to_string(),
                span,
            },
            lanes: *lanes,
        },
        Ty::Adt(a) => named(&adts.get(*a)?.name),
        Ty::Array(e, n) => TypeExprKind::Array {
            elem: Box::new(type_expr(e, adts, span)?),
            len: ArrayLen::Const(*n, span),
        },
        _ => return None,
    };
    Some(TypeExpr { kind, span })
}
