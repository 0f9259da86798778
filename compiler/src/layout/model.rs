//! The physical layout model: a `layout` declaration with every byte placed (paper §4.2,
//! layout-catalog §2.3).
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

use crate::layout::types::{record_shape, round_up, Shape, TypeEnv};
use crate::syntax::ast::{
    ArrayLen, Expr, ExprKind, GroupAttrKind, GroupDecl, Ident, Item, LayoutDecl, Member,
    MemberKind, Program, SplitArmBody, SplitPattern, TypeExpr, TypeExprKind,
};
use scion_ir::diag::{Diagnostic, Diagnostics, Span};

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

impl LayoutModel {
    /// Builds the model of `decl`; `program` supplies the `type` declarations and the build of
    /// the same name (used to find the ADT of a layout without splits).
    pub fn from_ast(decl: &LayoutDecl, program: &Program) -> LayoutModel {
        let env = TypeEnv::new(program);
        let mut b = Builder {
            m: LayoutModel {
                name: decl.name.clone(),
                span: decl.span,
                components: Vec::new(),
                reference: Shape { size: 0, align: 1 },
                members: Vec::new(),
                scopes: vec![Scope {
                    kind: ScopeKind::Top,
                    parent: None,
                    members: Vec::new(),
                }],
                groups: Vec::new(),
                splits: Vec::new(),
                globals: Shape { size: 0, align: 1 },
                global_arrays: Vec::new(),
                adt: None,
                diagnostics: Diagnostics::new(),
            },
            env,
        };
        b.components(decl);
        b.m.adt = find_adt(decl, program, &b.env, &mut b.m.diagnostics);
        if let Some(adt) = &b.m.adt {
            b.env.reference = Some((adt.name.clone(), b.m.reference));
        }
        b.top(&decl.members);
        b.link_from_arms();
        b.m
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

/// Placement cursor inside one element (or the globals block).
#[derive(Clone, Copy, Debug)]
struct Cursor {
    off: u64,
    align: u64,
    part: usize,
}

/// Where members being placed go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Place {
    Top,
    TopArm,
    Elem(GroupId),
}

struct Builder<'p> {
    m: LayoutModel,
    env: TypeEnv<'p>,
}

fn err(code: &str, msg: impl Into<String>, span: Span, label: &str) -> Diagnostic {
    Diagnostic::error(code, msg).with_primary(span, label)
}

impl Builder<'_> {
    fn components(&mut self, decl: &LayoutDecl) {
        let mut shapes = Vec::new();
        for p in &decl.params {
            let shape = match self.env.shape(&p.ty) {
                Ok(s) => Some(s),
                Err(e) => {
                    self.m.diagnostics.push(err(
                        "E0301",
                        e.message(),
                        p.ty.span,
                        "in this reference component",
                    ));
                    None
                }
            };
            shapes.push(shape.unwrap_or(Shape { size: 0, align: 1 }));
            let carried = match &p.default {
                Some(Expr {
                    kind: ExprKind::Parent(x),
                    ..
                }) => Some(x.clone()),
                _ => None,
            };
            self.m.components.push(Component {
                name: p.name.clone(),
                ty: p.ty.clone(),
                shape,
                default: p.default.clone(),
                carried,
            });
        }
        self.m.reference = if shapes.len() == 1 {
            shapes[0]
        } else {
            record_shape(&shapes)
        };
    }

    fn add_member(
        &mut self,
        kind: MemberModel,
        span: Span,
        scope: ScopeId,
        part: usize,
    ) -> MemberId {
        self.m.members.push(MemberInfo {
            kind,
            span,
            scope,
            part,
        });
        let id = self.m.members.len() - 1;
        self.m.scopes[scope].members.push(id);
        id
    }

    fn new_scope(&mut self, kind: ScopeKind, parent: ScopeId) -> ScopeId {
        self.m.scopes.push(Scope {
            kind,
            parent: Some(parent),
            members: Vec::new(),
        });
        self.m.scopes.len() - 1
    }

    fn shape_or_report(&mut self, ty: &TypeExpr) -> Option<Shape> {
        match self.env.shape(ty) {
            Ok(s) => Some(s),
            Err(e) => {
                self.m.diagnostics.push(err(
                    "E0301",
                    e.message(),
                    ty.span,
                    "this type has no fixed size",
                ));
                None
            }
        }
    }

    fn top(&mut self, members: &[Member]) {
        let mut cur = Cursor {
            off: 0,
            align: 1,
            part: 0,
        };
        for mem in members {
            match &mem.kind {
                MemberKind::Field { name, ty } => {
                    if let TypeExprKind::Array {
                        elem,
                        len: ArrayLen::Name(len),
                    } = &ty.kind
                    {
                        let Some(shape) = self.shape_or_report(elem) else {
                            self.stored_nowhere(name, ty, mem.span, 0);
                            continue;
                        };
                        let id = self.add_member(
                            MemberModel::Stored(Stored {
                                name: name.clone(),
                                ty: ty.clone(),
                                size: 0,
                                align: shape.align,
                                storage: Storage::GlobalArray(self.m.global_arrays.len()),
                            }),
                            mem.span,
                            0,
                            0,
                        );
                        self.m.global_arrays.push(GlobalArray {
                            member: id,
                            name: name.clone(),
                            len: len.clone(),
                            elem: (**elem).clone(),
                            shape,
                        });
                    } else {
                        self.place_field(name, ty, mem.span, 0, Place::Top, &mut cur);
                    }
                }
                MemberKind::Group(g) => self.group(g, mem.span, 0, Place::Top, &mut cur),
                _ => self.place_other(mem, 0, Place::Top, &mut cur),
            }
        }
        self.m.globals = Shape {
            size: round_up(cur.off, cur.align),
            align: cur.align,
        };
    }

    fn stored_nowhere(&mut self, name: &Ident, ty: &TypeExpr, span: Span, scope: ScopeId) {
        self.add_member(
            MemberModel::Stored(Stored {
                name: name.clone(),
                ty: ty.clone(),
                size: 0,
                align: 1,
                storage: Storage::None,
            }),
            span,
            scope,
            0,
        );
    }

    fn place_field(
        &mut self,
        name: &Ident,
        ty: &TypeExpr,
        span: Span,
        scope: ScopeId,
        place: Place,
        cur: &mut Cursor,
    ) {
        if place == Place::TopArm {
            self.m.diagnostics.push(
                err("E0322", format!("stored field `{}` has no storage", name.name), span, "declared in a split outside any group")
                    .with_note("a split at the top level may only derive fields or use `from`; put stored fields in a group"),
            );
            self.stored_nowhere(name, ty, span, scope);
            return;
        }
        let Some(shape) = self.shape_or_report(ty) else {
            self.stored_nowhere(name, ty, span, scope);
            return;
        };
        let offset = round_up(cur.off, shape.align);
        cur.off = offset.saturating_add(shape.size);
        cur.align = cur.align.max(shape.align);
        let storage = match place {
            Place::Elem(group) => Storage::Element {
                group,
                array: cur.part,
                offset,
            },
            _ => Storage::Globals { offset },
        };
        self.add_member(
            MemberModel::Stored(Stored {
                name: name.clone(),
                ty: ty.clone(),
                size: shape.size,
                align: shape.align,
                storage,
            }),
            span,
            scope,
            cur.part,
        );
    }

    /// Padding, derived fields, lets, separators and splits, in any place.
    fn place_other(&mut self, mem: &Member, scope: ScopeId, place: Place, cur: &mut Cursor) {
        match &mem.kind {
            MemberKind::Padding { bytes } => {
                if *bytes == 0 {
                    self.m.diagnostics.push(err(
                        "E0303",
                        "padding of zero bytes",
                        mem.span,
                        "remove this or give a positive byte count",
                    ));
                }
                let offset = cur.off;
                cur.off = cur.off.saturating_add(*bytes);
                self.add_member(
                    MemberModel::Padding {
                        bytes: *bytes,
                        offset,
                    },
                    mem.span,
                    scope,
                    cur.part,
                );
            }
            MemberKind::Derived { name, value } => {
                self.add_member(
                    MemberModel::Derived {
                        name: name.clone(),
                        value: value.clone(),
                    },
                    mem.span,
                    scope,
                    cur.part,
                );
            }
            MemberKind::Let { name, ty, value } => {
                self.add_member(
                    MemberModel::Let {
                        name: name.clone(),
                        ty: ty.clone(),
                        value: value.clone(),
                    },
                    mem.span,
                    scope,
                    cur.part,
                );
            }
            MemberKind::Separator => {
                self.m.diagnostics.push(
                    err("E0304", "`---` outside a group", mem.span, "not directly inside a group body")
                        .with_note("`---` ends one array of a group and starts the next; it must be a direct member of a group"),
                );
            }
            MemberKind::Split { discriminant, arms } => {
                self.split(discriminant, arms, mem.span, scope, place, cur)
            }
            MemberKind::Field { name, ty } => {
                self.place_field(name, ty, mem.span, scope, place, cur)
            }
            MemberKind::Group(g) => self.group(g, mem.span, scope, place, cur),
        }
    }

    fn split(
        &mut self,
        discriminant: &Expr,
        arms: &[crate::syntax::ast::SplitArm],
        span: Span,
        scope: ScopeId,
        place: Place,
        cur: &mut Cursor,
    ) {
        let align = arms
            .iter()
            .map(|a| match &a.body {
                SplitArmBody::Members { members, .. } => self.list_align(members, 0),
                SplitArmBody::From { .. } => 1,
            })
            .max()
            .unwrap_or(1);
        let start = round_up(cur.off, align);
        let sid = self.m.splits.len();
        self.m.splits.push(Split {
            member: 0,
            scope,
            discriminant: discriminant.clone(),
            arms: Vec::new(),
            offset: start,
            size: 0,
            span,
        });
        let member = self.add_member(MemberModel::Split(sid), span, scope, cur.part);
        self.m.splits[sid].member = member;
        let arm_place = if place == Place::Top {
            Place::TopArm
        } else {
            place
        };
        let mut end = start;
        for (i, arm) in arms.iter().enumerate() {
            let (variant, body) = match &arm.body {
                SplitArmBody::Members { variant, members } => {
                    let s = self.new_scope(ScopeKind::Arm { split: sid, arm: i }, scope);
                    let mut c = Cursor {
                        off: start,
                        align: 1,
                        part: cur.part,
                    };
                    for mem in members {
                        self.place_other(mem, s, arm_place, &mut c);
                    }
                    end = end.max(c.off);
                    (variant.clone(), ArmBody::Members(s))
                }
                SplitArmBody::From {
                    variant,
                    group,
                    key,
                } => (
                    variant.clone(),
                    ArmBody::From {
                        group_name: group.clone(),
                        group: None,
                        key: key.clone(),
                    },
                ),
            };
            self.m.splits[sid].arms.push(Arm {
                pattern: arm.pattern.clone(),
                variant,
                body,
                span: arm.span,
            });
        }
        self.m.splits[sid].size = end - start;
        cur.off = end;
        cur.align = cur.align.max(align);
    }

    /// Natural alignment of a member list, without placing it.
    fn list_align(&self, members: &[Member], depth: u32) -> u64 {
        if depth > 64 {
            return 1;
        }
        members
            .iter()
            .map(|m| match &m.kind {
                MemberKind::Field { ty, .. } => self.env.shape(ty).map(|s| s.align).unwrap_or(1),
                MemberKind::Split { arms, .. } => arms
                    .iter()
                    .map(|a| match &a.body {
                        SplitArmBody::Members { members, .. } => {
                            self.list_align(members, depth + 1)
                        }
                        SplitArmBody::From { .. } => 1,
                    })
                    .max()
                    .unwrap_or(1),
                MemberKind::Group(g) => {
                    let attr = g.attrs.iter().find_map(|a| match a.kind {
                        GroupAttrKind::Align(n) if n.is_power_of_two() => Some(n),
                        _ => None,
                    });
                    self.list_align(&g.members, depth + 1)
                        .max(attr.unwrap_or(1))
                }
                _ => 1,
            })
            .max()
            .unwrap_or(1)
    }

    fn group(&mut self, g: &GroupDecl, span: Span, scope: ScopeId, place: Place, cur: &mut Cursor) {
        let mut size = None;
        let mut align_attr = None;
        let mut count = None;
        for a in &g.attrs {
            match &a.kind {
                GroupAttrKind::Size(e) => size = Some(e.clone()),
                GroupAttrKind::Align(n) => {
                    if n.is_power_of_two() {
                        align_attr = Some(*n);
                    } else {
                        self.m.diagnostics.push(err(
                            "E0305",
                            format!("alignment {n} is not a power of two"),
                            a.span,
                            "`align` must be 1, 2, 4, 8, ...",
                        ));
                    }
                }
                GroupAttrKind::Count(n) => count = Some((*n, a.span)),
            }
        }
        let name = &g.name.name;
        let kind = match place {
            Place::Top if g.indirect => {
                if let Some(by) = &g.by {
                    self.m.diagnostics.push(
                        err(
                            "E0307",
                            format!("indirect group `{name}` has a `by` index"),
                            by.span,
                            "remove this",
                        )
                        .with_note(
                            "an indirect group is reached only through `Variant from g[key]`",
                        ),
                    );
                }
                if let Some((_, s)) = count {
                    self.m.diagnostics.push(err(
                        "E0308",
                        "a tile count belongs on a nested group",
                        s,
                        "not allowed here",
                    ));
                }
                GroupKind::Indirect
            }
            Place::Top => {
                if g.by.is_none() {
                    self.m.diagnostics.push(
                        err(
                            "E0307",
                            format!("direct group `{name}` has no `by` index"),
                            g.name.span,
                            "add `by I`",
                        )
                        .with_note(
                            "a direct group is indexed by the reference (or an expression over it)",
                        ),
                    );
                }
                if size.is_none() {
                    self.m.diagnostics.push(
                        err(
                            "E0306",
                            format!("direct group `{name}` has no `size` attribute"),
                            g.name.span,
                            "add `[size=N]`",
                        )
                        .with_note(
                            "the constructor allocates `size` elements; name a global such as `N`",
                        ),
                    );
                }
                if let Some((_, s)) = count {
                    self.m.diagnostics.push(err(
                        "E0308",
                        "a tile count belongs on a nested group",
                        s,
                        "not allowed on a top-level group",
                    ));
                }
                if self.is_pointer_index(g.by.as_ref()) {
                    GroupKind::Pointer
                } else {
                    GroupKind::Direct
                }
            }
            Place::TopArm => {
                self.m.diagnostics.push(err(
                    "E0322",
                    format!("group `{name}` inside a top-level split"),
                    g.name.span,
                    "groups must be declared at the top level or inside a group",
                ));
                return;
            }
            Place::Elem(_) => {
                if g.indirect {
                    self.m.diagnostics.push(err(
                        "E0322",
                        format!("indirect group `{name}` inside a group"),
                        g.name.span,
                        "indirect groups must be declared at the top level",
                    ));
                }
                if let Some(by) = &g.by {
                    self.m.diagnostics.push(err(
                        "E0307",
                        format!("nested group `{name}` has a `by` index"),
                        by.span,
                        "a nested group is indexed by its position in the tile",
                    ));
                }
                match count {
                    None => self.m.diagnostics.push(err(
                        "E0308",
                        format!("nested group `{name}` has no tile count"),
                        g.name.span,
                        "add a count, e.g. `[4]`",
                    )),
                    Some((0, s)) => self.m.diagnostics.push(err(
                        "E0308",
                        "a tile count must be at least 1",
                        s,
                        "zero elements",
                    )),
                    Some(_) => {}
                }
                GroupKind::Nested
            }
        };
        let gid = self.m.groups.len();
        let member = self.add_member(MemberModel::Group(gid), span, scope, cur.part);
        let body_scope = self.new_scope(ScopeKind::Group(gid), scope);
        self.m.groups.push(Group {
            name: g.name.clone(),
            kind,
            scope: body_scope,
            member,
            by: g.by.clone(),
            size,
            align_attr,
            count: count.map(|c| c.0.max(1)),
            parent: None,
            arrays: Vec::new(),
            span: g.span,
        });
        let mut c = Cursor {
            off: 0,
            align: 1,
            part: 0,
        };
        let mut parts = Vec::new();
        for mem in &g.members {
            match &mem.kind {
                MemberKind::Separator => {
                    parts.push((c.off, c.align));
                    c = Cursor {
                        off: 0,
                        align: 1,
                        part: c.part + 1,
                    };
                    self.add_member(MemberModel::Separator, mem.span, body_scope, c.part);
                }
                MemberKind::Field { name, ty } => {
                    self.place_field(name, ty, mem.span, body_scope, Place::Elem(gid), &mut c)
                }
                MemberKind::Group(inner) => {
                    self.group(inner, mem.span, body_scope, Place::Elem(gid), &mut c)
                }
                _ => self.place_other(mem, body_scope, Place::Elem(gid), &mut c),
            }
        }
        parts.push((c.off, c.align));
        let attr = align_attr.unwrap_or(1);
        let mut tile_off = 0u64;
        let mut tile_align = 1u64;
        let n = self.m.groups[gid].count.unwrap_or(1);
        for (size, natural) in parts {
            let align = natural.max(attr);
            let stride = round_up(size, align);
            let offset = if kind == GroupKind::Nested {
                round_up(tile_off, align)
            } else {
                0
            };
            tile_off = offset.saturating_add(stride.saturating_mul(n));
            tile_align = tile_align.max(align);
            self.m.groups[gid].arrays.push(ArrayShape {
                size,
                align,
                stride,
                offset,
            });
        }
        if let Place::Elem(outer) = place {
            let offset = round_up(cur.off, tile_align);
            cur.off = offset.saturating_add(tile_off);
            cur.align = cur.align.max(tile_align);
            self.m.groups[gid].parent = Some((outer, cur.part, offset));
        }
    }

    fn is_pointer_index(&self, by: Option<&Expr>) -> bool {
        let Some(Expr {
            kind: ExprKind::Name(x),
            ..
        }) = by
        else {
            return false;
        };
        self.m.components.iter().any(|c| {
            c.name.name == x.name && matches!(&c.ty.kind, TypeExprKind::Named(t) if t.name == "ptr")
        })
    }

    fn link_from_arms(&mut self) {
        for sid in 0..self.m.splits.len() {
            for ai in 0..self.m.splits[sid].arms.len() {
                let ArmBody::From { group_name, .. } = &self.m.splits[sid].arms[ai].body else {
                    continue;
                };
                let gname = group_name.clone();
                let found = self.m.group_named(&gname.name);
                let linked = match found {
                    Some(g) if self.m.groups[g].kind == GroupKind::Indirect => Some(g),
                    Some(g) => {
                        self.m.diagnostics.push(
                            err(
                                "E0309",
                                format!(
                                    "`from` needs an indirect group, but `{}` is direct",
                                    gname.name
                                ),
                                gname.span,
                                "not an indirect group",
                            )
                            .with_secondary(
                                self.m.groups[g].name.span,
                                "declared here without `indirect`",
                            ),
                        );
                        None
                    }
                    None => {
                        self.m.diagnostics.push(err(
                            "E0309",
                            format!("no group named `{}`", gname.name),
                            gname.span,
                            "`from` must name an indirect group of this layout",
                        ));
                        None
                    }
                };
                if let ArmBody::From { group, .. } = &mut self.m.splits[sid].arms[ai].body {
                    *group = linked;
                }
            }
        }
    }
}

/// Finds the sum type whose variants the layout's split arms name (E0311 when there is none or
/// more than one).
fn find_adt(
    decl: &LayoutDecl,
    program: &Program,
    env: &TypeEnv<'_>,
    diags: &mut Diagnostics,
) -> Option<Adt> {
    let mut named: Vec<Ident> = Vec::new();
    collect_arm_variants(&decl.members, &mut named, 0);
    if named.is_empty() {
        for item in &program.items {
            if let Item::Build(b) = item {
                if b.name.name == decl.name.name {
                    named.extend(b.variants.iter().map(|v| v.name.clone()));
                }
            }
        }
    }
    let mut sums: Vec<_> = program
        .items
        .iter()
        .filter_map(|i| match i {
            Item::Type(t) if t.variants.is_some() => Some(t),
            _ => None,
        })
        .collect();
    sums.dedup_by(|a, b| a.name.name == b.name.name);
    let has = |t: &crate::syntax::ast::TypeDecl, v: &str| {
        t.variants
            .as_ref()
            .is_some_and(|vs| vs.iter().any(|x| x.name.name == v))
    };
    let chosen = if named.is_empty() {
        let single: Vec<_> = sums
            .iter()
            .filter(|t| t.variants.as_ref().is_some_and(|v| v.len() == 1))
            .collect();
        if single.len() == 1 {
            Some(*single[0])
        } else {
            diags.push(
                err(
                    "E0311",
                    format!(
                        "cannot tell which type layout `{}` realizes",
                        decl.name.name
                    ),
                    decl.name.span,
                    "no split names a variant",
                )
                .with_note("name the variants in `split` arms, or write a build for this layout"),
            );
            None
        }
    } else {
        let mut unknown = false;
        for v in &named {
            if !sums.iter().any(|t| has(t, &v.name)) {
                unknown = true;
                diags.push(err(
                    "E0311",
                    format!("`{}` is not a variant of any type", v.name),
                    v.span,
                    "unknown variant",
                ));
            }
        }
        let mut all: Vec<_> = sums
            .iter()
            .filter(|t| named.iter().all(|v| has(t, &v.name)))
            .collect();
        if all.len() > 1 {
            // Several types have these variant names (BVH and BVH8 both have Interior and
            // Leaf): keep those whose logical fields the layout declares best.
            let mut declared: Vec<&str> = Vec::new();
            collect_member_names(&decl.members, &mut declared, 0);
            let score = |t: &crate::syntax::ast::TypeDecl| {
                let mut fields: Vec<&str> = t.fields.iter().map(|f| f.name.name.as_str()).collect();
                for v in t.variants.iter().flatten() {
                    fields.extend(v.fields.iter().map(|f| f.name.name.as_str()));
                }
                let found = fields.iter().filter(|f| declared.contains(f)).count();
                (found * 1000) / fields.len().max(1)
            };
            let best = all.iter().map(|t| score(t)).max().unwrap_or(0);
            all.retain(|t| score(t) == best);
        }
        match all.len() {
            1 => Some(*all[0]),
            0 if unknown => None,
            0 => {
                let owners: Vec<String> = named
                    .iter()
                    .map(|v| {
                        let t = sums
                            .iter()
                            .find(|t| has(t, &v.name))
                            .map(|t| t.name.name.as_str())
                            .unwrap_or("?");
                        format!("`{}` of `{t}`", v.name)
                    })
                    .collect();
                diags.push(
                    err(
                        "E0311",
                        "split arms name variants of different types",
                        decl.name.span,
                        "a layout realizes exactly one type",
                    )
                    .with_note(format!("the arms name {}", owners.join(", "))),
                );
                None
            }
            _ => {
                let names: Vec<String> = all.iter().map(|t| format!("`{}`", t.name.name)).collect();
                diags.push(
                    err(
                        "E0311",
                        format!("layout `{}` could realize several types", decl.name.name),
                        decl.name.span,
                        "ambiguous",
                    )
                    .with_note(format!("candidates: {}", names.join(", "))),
                );
                None
            }
        }
    };
    let t = chosen?;
    let shared = &t.fields;
    let variants = t
        .variants
        .as_ref()?
        .iter()
        .map(|v| AdtVariant {
            name: v.name.clone(),
            fields: shared
                .iter()
                .chain(v.fields.iter())
                .map(|f| LogicalField {
                    name: f.name.clone(),
                    ty: f.ty.clone(),
                    recursive: mentions_type(&f.ty, &t.name.name),
                    array: matches!(f.ty.kind, TypeExprKind::Array { .. }),
                })
                .collect(),
        })
        .collect();
    let _ = env;
    Some(Adt {
        name: t.name.name.clone(),
        variants,
    })
}

fn mentions_type(ty: &TypeExpr, name: &str) -> bool {
    match &ty.kind {
        TypeExprKind::Named(id) => id.name == name,
        TypeExprKind::Array { elem, .. } | TypeExprKind::Set(elem) | TypeExprKind::Option(elem) => {
            mentions_type(elem, name)
        }
        TypeExprKind::Tuple(ts) => ts.iter().any(|t| mentions_type(t, name)),
        TypeExprKind::Vector { .. } => false,
    }
}

fn collect_member_names<'a>(members: &'a [Member], out: &mut Vec<&'a str>, depth: u32) {
    if depth > 64 {
        return;
    }
    for m in members {
        match &m.kind {
            MemberKind::Field { name, .. } | MemberKind::Derived { name, .. } => {
                out.push(&name.name)
            }
            MemberKind::Group(g) => collect_member_names(&g.members, out, depth + 1),
            MemberKind::Split { arms, .. } => {
                for a in arms {
                    if let SplitArmBody::Members { members, .. } = &a.body {
                        collect_member_names(members, out, depth + 1);
                    }
                }
            }
            _ => {}
        }
    }
}

fn collect_arm_variants(members: &[Member], out: &mut Vec<Ident>, depth: u32) {
    if depth > 64 {
        return;
    }
    for m in members {
        match &m.kind {
            MemberKind::Group(g) => collect_arm_variants(&g.members, out, depth + 1),
            MemberKind::Split { arms, .. } => {
                for a in arms {
                    match &a.body {
                        SplitArmBody::Members { variant, members } => {
                            if !out.iter().any(|v| v.name == variant.name) {
                                out.push(variant.clone());
                            }
                            collect_arm_variants(members, out, depth + 1);
                        }
                        SplitArmBody::From { variant, .. } => {
                            if !out.iter().any(|v| v.name == variant.name) {
                                out.push(variant.clone());
                            }
                        }
                    }
                }
            }
            _ => {}
        }
    }
}
