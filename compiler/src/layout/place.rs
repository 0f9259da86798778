//! Byte placement: builds a [`LayoutModel`] from a `layout` declaration (docs/design/layout-catalog.md §2.3).
//!
//! Input: a [`LayoutDecl`] and its [`Program`]; output: the model with every member's scope,
//! array and byte offset, each group's arrays (size, alignment, stride), each split's overlay,
//! the globals block and the global arrays, plus the diagnostics (E0301-E0309, E0322) met on
//! the way. Members are placed in textual order at their natural alignment; a split's arms all
//! start at the split's offset and the split is as large as its largest arm; a nested group is
//! a tile of `count` elements of each of its arrays, one block after the other.

use crate::layout::adt::{adt_of_decl, find_adt, unknown_variants};
use crate::layout::model::*;
use crate::layout::types::{record_shape, round_up, Shape, ShapeError, TypeEnv};
use crate::syntax::ast::{
    ArrayLen, Expr, ExprKind, GroupAttrKind, GroupDecl, Ident, Item, LayoutDecl, Member,
    MemberKind, Program, SplitArmBody, TypeExpr, TypeExprKind,
};
use scion_ir::diag::{Diagnostic, Diagnostics, Span};

/// Builds the model of `decl` (see [`LayoutModel::of`]); `adt` is the type it realizes when
/// the type checker chose it, `None` to find it here ([`find_adt`]).
pub(crate) fn build(decl: &LayoutDecl, program: &Program, adt: Option<AdtChoice>) -> LayoutModel {
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
    b.m.adt = match adt {
        None => find_adt(decl, program, &mut b.m.diagnostics),
        Some(AdtChoice::Chosen(name)) => {
            let t = program.items.iter().find_map(|i| match i {
                Item::Type(t) if t.name.name == name => Some(t),
                _ => None,
            });
            if let Some(t) = t {
                unknown_variants(decl, program, t, &mut b.m.diagnostics);
            }
            t.and_then(adt_of_decl)
        }
        // The type checker could not tell: the search says why (E0311), and the model
        // realizes no type rather than one the checker did not choose.
        Some(AdtChoice::Undecided) => {
            find_adt(decl, program, &mut b.m.diagnostics);
            None
        }
    };
    if let Some(adt) = &b.m.adt {
        b.env.reference = Some((adt.name.clone(), b.m.reference));
    }
    b.top(&decl.members);
    b.link_from_arms();
    crate::layout::parents::carry_parents(&mut b.m, &b.env);
    b.m
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
        let mut end = 0u64;
        for p in &decl.params {
            let shape = match self.env.shape(&p.ty) {
                Ok(s) => Some(s),
                // An unknown name is the type checker's E0202.
                Err(ShapeError::Unknown(_)) => None,
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
            let sh = shape.unwrap_or(Shape { size: 0, align: 1 });
            let offset = round_up(end, sh.align);
            end = offset.saturating_add(sh.size);
            shapes.push(sh);
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
                offset,
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
            // An unknown name is the type checker's E0202.
            Err(ShapeError::Unknown(_)) => None,
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
