//! Typing of layouts (paper §4, Figure 6): the type of every member, which sum type a layout
//! realizes, and the rule that physical types preserve logical types.
//!
//! Input: a `layout` declaration (and the `build` of the same name, which names the variants).
//! Output: a [`LayoutInfo`] (reference type, members with types, split arms with variants) and
//! side-table entries for member expressions. Scopes: the reference components and globals
//! (top-level members) everywhere; every name of a group in the whole group (so a split's
//! discriminant may be declared after the split); the members of a split arm in that arm; a
//! `let` from its definition on. Split discriminants and `from` keys must be integers, group
//! sizes integers, `by` indices integers or `ptr`. A stored or derived field named like a logical
//! field of the variant must have the logical field's type, where a recursive field is realized
//! by the layout's reference type and a dependent array `T[x]` by a slice of `T`.

use super::errors::SemaError;
use super::infer::{Binding, Checker, Ctx};
use super::ops::{IntCheck, Obligation};
use super::resolve::LenScope;
use super::typed::{ArmInfo, LayoutInfo, MemberId, MemberInfo, MemberKindInfo, Resolution};
use super::types::{AdtId, Ty};
use super::unify::VarKind;
use crate::syntax::ast::{
    ExprKind, GroupAttrKind, Item, LayoutDecl, Member, MemberKind, Program, SplitArmBody,
    SplitPatternKind,
};
use rustc_hash::FxHashMap;
use scion_ir::diag::Span;

/// Per-layout state while its members are typed.
struct Walk {
    ids: FxHashMap<usize, MemberId>,
    arm: usize,
}

fn key(m: &Member) -> usize {
    m as *const Member as usize
}

fn member_name(m: &Member) -> Option<(&str, Span)> {
    match &m.kind {
        MemberKind::Field { name, .. }
        | MemberKind::Derived { name, .. }
        | MemberKind::Let { name, .. } => Some((&name.name, name.span)),
        MemberKind::Group(g) => Some((&g.name.name, g.name.span)),
        _ => None,
    }
}

impl Checker<'_> {
    /// Types layout item `item`.
    pub(super) fn check_layout(&mut self, item: usize, decl: &LayoutDecl) {
        let layout_idx = self.out.layouts.len();
        let param_names: Vec<String> = decl.params.iter().map(|p| p.name.name.clone()).collect();
        let params: Vec<(String, Ty)> = decl
            .params
            .iter()
            .map(|p| {
                (
                    p.name.name.clone(),
                    self.lower_type(&p.ty, &LenScope::Names(&param_names)),
                )
            })
            .collect();
        let ref_ty = match params.as_slice() {
            [(_, t)] => t.clone(),
            _ => Ty::Tuple(params.iter().map(|p| p.1.clone()).collect()),
        };
        // A child's reference as the layout's expression for it gives it: the components
        // that are not tree-carried (`c: T = parent.x` is filled by the compiler).
        let own: Vec<Ty> = decl
            .params
            .iter()
            .zip(&params)
            .enumerate()
            // The first is placed, never carried (a carried one is E0328).
            .filter(|(k, (p, _))| {
                *k == 0
                    || !matches!(
                        p.default.as_ref().map(|d| &d.kind),
                        Some(ExprKind::Parent(_))
                    )
            })
            .map(|(_, (_, t))| t.1.clone())
            .collect();
        let child_ty = match own.as_slice() {
            [t] => t.clone(),
            _ => Ty::Tuple(own),
        };
        let build_ref_ty = params
            .first()
            .map_or_else(|| ref_ty.clone(), |p| p.1.clone());
        self.out.layouts.push(LayoutInfo {
            item,
            name: decl.name.name.clone(),
            adt: None,
            params,
            ref_ty,
            child_ty,
            build_ref_ty,
            members: Vec::new(),
            arms: Vec::new(),
        });
        // Every member name, for array lengths `T[P]`.
        let mut all_names = param_names.clone();
        collect_names(&decl.members, &mut all_names);
        let mut walk = Walk {
            ids: FxHashMap::default(),
            arm: 0,
        };
        self.collect_members(layout_idx, &decl.members, None, None, &all_names, &mut walk);
        let cands = self.layout_adt_candidates(decl);
        if cands.len() == 1 {
            self.choose_adt(layout_idx, decl, cands[0], &walk.ids);
        }
        self.ctx = Ctx::Layout { layout: layout_idx };
        self.scopes.clear();
        self.push_scope();
        for (i, p) in decl.params.iter().enumerate() {
            self.define(&p.name.name, Binding::LayoutParam(i as u32));
        }
        for (i, p) in decl.params.iter().enumerate() {
            if let Some(d) = &p.default {
                let t = self.infer_expr(d);
                let want = self.out.layouts[layout_idx].params[i].1.clone();
                self.expect(&t, &want, d.span, "the reference component's type");
            }
        }
        walk.arm = 0;
        self.type_members(layout_idx, &decl.members, &walk.ids, &mut walk.arm);
        self.scopes.clear();
        self.ctx = Ctx::Const;
        if cands.len() > 1 {
            // Types of the members tell the candidates apart (`bounds = DOP14(...)`).
            self.run_pending(false);
            if let Some(adt) = self.pick_adt_by_types(layout_idx, &cands) {
                self.choose_adt(layout_idx, decl, adt, &walk.ids);
            }
        }
    }

    /// Records that layout `layout` realizes `adt`: split arms get their variants, and derived
    /// fields that realize logical fields get their physical types.
    fn choose_adt(
        &mut self,
        layout: usize,
        decl: &LayoutDecl,
        adt: AdtId,
        ids: &FxHashMap<usize, MemberId>,
    ) {
        self.out.layouts[layout].adt = Some(adt);
        self.resolve_arm_variants(layout, adt, &decl.members, ids, &mut 0);
        self.seed_derived_types(layout);
    }

    /// First pass: one [`MemberInfo`] per named member, in pre-order.
    fn collect_members(
        &mut self,
        layout: usize,
        members: &[Member],
        group: Option<MemberId>,
        variant: Option<u32>,
        names: &[String],
        walk: &mut Walk,
    ) {
        // Duplicate names in one scope are `check_layout`'s E0302; the later one wins here.
        for m in members {
            let (name, kind, ty) = match &m.kind {
                MemberKind::Field { name, ty } => (
                    name,
                    MemberKindInfo::Stored,
                    self.lower_type(ty, &LenScope::Layout(names)),
                ),
                MemberKind::Derived { name, .. } => {
                    (name, MemberKindInfo::Derived, self.fresh(VarKind::General))
                }
                MemberKind::Let { name, ty, .. } => {
                    let t = match ty {
                        Some(t) => self.lower_type(t, &LenScope::Layout(names)),
                        None => self.fresh(VarKind::General),
                    };
                    (name, MemberKindInfo::Let, t)
                }
                MemberKind::Group(g) => {
                    let kind = if g.indirect {
                        MemberKindInfo::IndirectGroup
                    } else {
                        MemberKindInfo::Group
                    };
                    (&g.name, kind, Ty::unit())
                }
                MemberKind::Split { arms, .. } => {
                    for arm in arms {
                        let from_group = None;
                        self.out.layouts[layout].arms.push(ArmInfo {
                            span: arm.span,
                            variant: None,
                            from_group,
                        });
                        if let SplitArmBody::Members { members, .. } = &arm.body {
                            // The arm's variant index is filled in once the ADT is known; members
                            // record it through `resolve_arm_variants`.
                            self.collect_members(layout, members, group, variant, names, walk);
                        }
                    }
                    continue;
                }
                MemberKind::Padding { .. } | MemberKind::Separator => continue,
            };
            let id = MemberId(self.out.layouts[layout].members.len() as u32);
            self.out.layouts[layout].members.push(MemberInfo {
                name: name.name.clone(),
                kind,
                ty,
                group,
                variant,
                span: name.span,
            });
            walk.ids.insert(key(m), id);
            if let MemberKind::Group(g) = &m.kind {
                self.collect_members(layout, &g.members, Some(id), variant, names, walk);
            }
        }
    }

    /// The sum types a layout may realize: those whose variants include most of the variants
    /// named by the layout's split arms and its build, narrowed by the build's parameter names
    /// and by the logical fields the members name.
    fn layout_adt_candidates(&mut self, decl: &LayoutDecl) -> Vec<AdtId> {
        let mut used: Vec<String> = Vec::new();
        arm_variant_names(&decl.members, &mut used);
        let build = self.program.items.iter().find_map(|i| match i {
            Item::Build(b) if b.name.name == decl.name.name => Some(b),
            _ => None,
        });
        if let Some(b) = build {
            used.extend(b.variants.iter().map(|v| v.name.name.clone()));
        }
        // The sum types naming the most of the variants used; then those whose fields the
        // build's parameters name; then those with the most logical fields named by members.
        let score =
            |d: &super::types::AdtDef| used.iter().filter(|u| d.variant_index(u).is_some()).count();
        let best = self
            .adts
            .adts
            .iter()
            .filter(|d| d.is_sum())
            .map(score)
            .max()
            .unwrap_or(0);
        let mut cands: Vec<AdtId> = (0..self.adts.adts.len() as u32)
            .map(AdtId)
            .filter(|a| {
                let d = &self.adts.adts[a.0 as usize];
                best > 0 && d.is_sum() && score(d) == best
            })
            .collect();
        if cands.len() > 1 {
            if let Some(b) = build {
                let matching: Vec<AdtId> = cands
                    .iter()
                    .copied()
                    .filter(|a| {
                        let d = &self.adts.adts[a.0 as usize];
                        b.variants.iter().all(|v| {
                            d.variant_index(&v.name.name).is_some_and(|vi| {
                                let fs = d.variant_fields(vi);
                                fs.len() == v.params.len()
                                    && fs
                                        .iter()
                                        .zip(v.params.iter())
                                        .all(|(f, p)| f.name == p.name.name)
                            })
                        })
                    })
                    .collect();
                if !matching.is_empty() {
                    cands = matching;
                }
            }
        }
        if cands.len() > 1 {
            let mut names = Vec::new();
            collect_names(&decl.members, &mut names);
            let realized = |a: &AdtId| {
                let d = &self.adts.adts[a.0 as usize];
                let mut fields: Vec<&str> = d.fields.iter().map(|f| f.name.as_str()).collect();
                for v in d.variants() {
                    fields.extend(v.fields.iter().map(|f| f.name.as_str()));
                }
                fields.sort_unstable();
                fields.dedup();
                fields
                    .iter()
                    .filter(|f| names.iter().any(|n| n == *f))
                    .count()
            };
            let top = cands.iter().map(realized).max().unwrap_or(0);
            cands.retain(|a| realized(a) == top);
        }
        // No candidate, or a tie that member types do not break, is `check_layout`'s E0311.
        cands
    }

    /// Among several candidate sum types, the one whose logical field types the layout's typed
    /// members agree with most (`None` when that does not decide either).
    fn pick_adt_by_types(&mut self, layout: usize, cands: &[AdtId]) -> Option<AdtId> {
        let ref_ty = self.out.layouts[layout].child_ty.clone();
        let members: Vec<(String, Ty)> = self.out.layouts[layout]
            .members
            .iter()
            .filter(|m| matches!(m.kind, MemberKindInfo::Stored | MemberKindInfo::Derived))
            .map(|m| (m.name.clone(), self.zonk(&m.ty)))
            .collect();
        let agree = |cx: &Self, a: AdtId| {
            let Some(d) = cx.adts.get(a) else { return 0 };
            let mut fields: Vec<&super::types::FieldDef> = d.fields.iter().collect();
            for v in d.variants() {
                fields.extend(v.fields.iter());
            }
            members
                .iter()
                .filter(|(n, t)| {
                    fields
                        .iter()
                        .any(|f| &f.name == n && cx.physical_of(&f.ty, a, &ref_ty) == *t)
                })
                .count()
        };
        let scores: Vec<usize> = cands.iter().map(|a| agree(self, *a)).collect();
        let best = scores.iter().copied().max().unwrap_or(0);
        let top: Vec<AdtId> = cands
            .iter()
            .zip(scores.iter())
            .filter(|(_, s)| **s == best)
            .map(|(a, _)| *a)
            .collect();
        match top.as_slice() {
            [one] => Some(*one),
            _ => None,
        }
    }

    /// Fills in the variant of every split arm and of the members inside arms.
    fn resolve_arm_variants(
        &mut self,
        layout: usize,
        adt: AdtId,
        members: &[Member],
        ids: &FxHashMap<usize, MemberId>,
        arm_ix: &mut usize,
    ) {
        for m in members {
            match &m.kind {
                MemberKind::Group(g) => {
                    self.resolve_arm_variants(layout, adt, &g.members, ids, arm_ix)
                }
                MemberKind::Split { arms, .. } => {
                    for arm in arms {
                        let (vname, inner) = match &arm.body {
                            SplitArmBody::Members { variant, members } => (variant, Some(members)),
                            SplitArmBody::From { variant, .. } => (variant, None),
                        };
                        // An arm naming no variant of the type is `check_layout`'s E0311.
                        let def = &self.adts.adts[adt.0 as usize];
                        let v = def.variant_index(&vname.name).map(|v| v as u32);
                        if let Some(a) = self.out.layouts[layout].arms.get_mut(*arm_ix) {
                            a.variant = v;
                        }
                        *arm_ix += 1;
                        if let Some(inner) = inner {
                            let mut own = Vec::new();
                            arm_members(inner, ids, &mut own);
                            for id in own {
                                if let Some(mi) =
                                    self.out.layouts[layout].members.get_mut(id.0 as usize)
                                {
                                    mi.variant = v;
                                }
                            }
                            self.resolve_arm_variants(layout, adt, inner, ids, arm_ix);
                        }
                    }
                }
                _ => {}
            }
        }
    }

    /// Defines the non-`let` names of one container.
    fn define_container(&mut self, members: &[Member], ids: &FxHashMap<usize, MemberId>) {
        for m in members {
            if matches!(m.kind, MemberKind::Let { .. }) {
                continue;
            }
            if let (Some((n, _)), Some(id)) = (member_name(m), ids.get(&key(m))) {
                self.define(n, Binding::Member(*id));
            }
        }
    }

    /// Second pass: types the expressions of the members.
    fn type_members(
        &mut self,
        layout: usize,
        members: &[Member],
        ids: &FxHashMap<usize, MemberId>,
        arm_ix: &mut usize,
    ) {
        self.push_scope();
        self.define_container(members, ids);
        for m in members {
            match &m.kind {
                MemberKind::Derived { value, .. } => {
                    let t = self.infer_expr(value);
                    if let Some(id) = ids.get(&key(m)) {
                        let want = self.out.layouts[layout].members[id.0 as usize].ty.clone();
                        if self.logical_expectation(layout, id.0 as usize).is_some() {
                            if self.unify(&t, &want).is_err() {
                                self.physical_error(layout, id.0 as usize, &t);
                            }
                        } else {
                            self.expect(&t, &want, value.span, "the derived field's other uses");
                        }
                    }
                }
                MemberKind::Let { value, name, .. } => {
                    let t = self.infer_expr(value);
                    if let Some(id) = ids.get(&key(m)) {
                        let want = self.out.layouts[layout].members[id.0 as usize].ty.clone();
                        self.expect(&t, &want, value.span, "the `let`'s declared type");
                        self.define(&name.name, Binding::Member(*id));
                    }
                }
                MemberKind::Group(g) => {
                    for a in &g.attrs {
                        if let GroupAttrKind::Size(e) = &a.kind {
                            let t = self.infer_expr(e);
                            self.solve_or_defer(Obligation::Int {
                                ty: t,
                                check: IntCheck::GroupSize,
                                span: e.span,
                            });
                        }
                    }
                    if let Some(by) = &g.by {
                        let t = self.infer_expr(by);
                        self.solve_or_defer(Obligation::Int {
                            ty: t,
                            check: IntCheck::GroupBy,
                            span: by.span,
                        });
                    }
                    self.type_members(layout, &g.members, ids, arm_ix);
                }
                MemberKind::Split { discriminant, arms } => {
                    let t = self.infer_expr(discriminant);
                    // `check_layout` (E0320) already rejects a discriminant whose type it can
                    // read off the syntax (a stored field, a component, a cast) and one of
                    // unknown type without a `_` arm; the rest is checked here, once.
                    let syntactic = match &discriminant.kind {
                        ExprKind::Cast { .. } => true,
                        ExprKind::Name(_) => {
                            matches!(
                                self.out.resolutions.get(&discriminant.id),
                                Some(Resolution::LayoutParam(_))
                            ) || matches!(
                                self.out.resolutions.get(&discriminant.id),
                                Some(Resolution::LayoutMember(m))
                                    if self.out.layouts[layout].members.get(m.0 as usize)
                                        .is_some_and(|mi| mi.kind == MemberKindInfo::Stored)
                            )
                        }
                        _ => false,
                    };
                    let wildcard = arms
                        .iter()
                        .any(|a| a.pattern.kind == SplitPatternKind::Wildcard);
                    if wildcard && !syntactic {
                        self.solve_or_defer(Obligation::Int {
                            ty: t,
                            check: IntCheck::Discriminant,
                            span: discriminant.span,
                        });
                    }
                    for arm in arms {
                        let this_arm = *arm_ix;
                        *arm_ix += 1;
                        match &arm.body {
                            SplitArmBody::Members { members, .. } => {
                                self.type_members(layout, members, ids, arm_ix)
                            }
                            SplitArmBody::From { group, key: k, .. } => {
                                let g = self.out.layouts[layout].members.iter().position(|mi| {
                                    mi.name == group.name
                                        && mi.kind == MemberKindInfo::IndirectGroup
                                });
                                // Not an indirect group: `check_layout`'s E0309.
                                if let (Some(g), Some(a)) =
                                    (g, self.out.layouts[layout].arms.get_mut(this_arm))
                                {
                                    a.from_group = Some(MemberId(g as u32));
                                }
                                let t = self.infer_expr(k);
                                self.solve_or_defer(Obligation::Int {
                                    ty: t,
                                    check: IntCheck::FromKey,
                                    span: k.span,
                                });
                            }
                        }
                    }
                }
                MemberKind::Field { .. } | MemberKind::Padding { .. } | MemberKind::Separator => {}
            }
        }
        self.pop_scope();
    }

    /// The physical type that realizes a logical type in a layout of `adt` with reference
    /// type `ref_ty`.
    pub(super) fn physical_of(&self, logical: &Ty, adt: AdtId, ref_ty: &Ty) -> Ty {
        match logical {
            Ty::Adt(a) if *a == adt => ref_ty.clone(),
            Ty::Array(e, n) => Ty::Array(Box::new(self.physical_of(e, adt, ref_ty)), *n),
            Ty::Slice(e) => Ty::Slice(Box::new(self.physical_of(e, adt, ref_ty))),
            Ty::Tuple(ts) => Ty::Tuple(
                ts.iter()
                    .map(|t| self.physical_of(t, adt, ref_ty))
                    .collect(),
            ),
            t => t.clone(),
        }
    }

    /// The logical field that member `m` of layout `layout` realizes by name, and the physical
    /// type it must therefore have.
    pub(super) fn logical_expectation(&self, layout: usize, m: usize) -> Option<(Ty, Ty)> {
        let l = self.out.layouts.get(layout)?;
        let adt = l.adt?;
        let def = self.adts.get(adt)?;
        let mi = l.members.get(m)?;
        if !matches!(mi.kind, MemberKindInfo::Stored | MemberKindInfo::Derived) {
            return None;
        }
        let variants: Vec<usize> = match mi.variant {
            Some(v) => vec![v as usize],
            None => (0..def.variants().len()).collect(),
        };
        let f = variants.iter().find_map(|v| {
            def.variant_fields(*v)
                .into_iter()
                .find(|f| f.name == mi.name)
                .cloned()
        })?;
        let expected = self.physical_of(&f.ty, adt, &l.child_ty);
        Some((f.ty, expected))
    }

    fn physical_error(&mut self, layout: usize, m: usize, found: &Ty) {
        let Some((logical, expected)) = self.logical_expectation(layout, m) else {
            return;
        };
        let show = |t: &Ty| t.display(&self.adts).to_string();
        let mi = &self.out.layouts[layout].members[m];
        let e = SemaError::PhysicalType {
            field: mi.name.clone(),
            logical: show(&logical),
            expected: show(&expected),
            found: self.show(found),
            span: mi.span,
        };
        self.error(e);
    }

    /// Gives derived fields that realize a logical field its physical type up front, so that
    /// literals and other uses are inferred from it.
    fn seed_derived_types(&mut self, layout: usize) {
        for m in 0..self.out.layouts[layout].members.len() {
            if self.out.layouts[layout].members[m].kind != MemberKindInfo::Derived {
                continue;
            }
            if let Some((_, expected)) = self.logical_expectation(layout, m) {
                let t = self.out.layouts[layout].members[m].ty.clone();
                if self.unify(&t, &expected).is_err() {
                    self.physical_error(layout, m, &t);
                }
            }
        }
    }

    /// Checks "physical types preserve logical types" on stored fields that hold children
    /// (derived fields are checked where their value is typed). A stored field that breaks a
    /// non-recursive logical type, or holds a child in the wrong number of bytes, is reported by
    /// `check_layout` (E0327); what remains is a child stored in a same-sized wrong type
    /// (`left: f32` for a `u32` reference).
    pub(super) fn check_physical_types(&mut self) {
        for li in 0..self.out.layouts.len() {
            let Some(adt) = self.out.layouts[li].adt else {
                continue;
            };
            for m in 0..self.out.layouts[li].members.len() {
                if self.out.layouts[li].members[m].kind != MemberKindInfo::Stored {
                    continue;
                }
                let Some((logical, expected)) = self.logical_expectation(li, m) else {
                    continue;
                };
                let found = self.zonk(&self.out.layouts[li].members[m].ty);
                let child = self.adts.mentions(&logical, adt);
                if child && same_size(&found, &expected) && found != expected {
                    self.physical_error(li, m, &found);
                }
            }
        }
    }
}

/// True when both types have a known size and it is the same.
fn same_size(a: &Ty, b: &Ty) -> bool {
    match (a, b) {
        (Ty::Array(x, n), Ty::Array(y, m)) => n == m && same_size(x, y),
        _ => a.bit_size().is_some() && a.bit_size() == b.bit_size(),
    }
}

fn collect_names(members: &[Member], out: &mut Vec<String>) {
    for m in members {
        if let Some((n, _)) = member_name(m) {
            out.push(n.to_string());
        }
        match &m.kind {
            MemberKind::Group(g) => collect_names(&g.members, out),
            MemberKind::Split { arms, .. } => {
                for a in arms {
                    if let SplitArmBody::Members { members, .. } = &a.body {
                        collect_names(members, out);
                    }
                }
            }
            _ => {}
        }
    }
}

/// The members of a split arm and of the groups inside it (not those of nested splits).
fn arm_members(members: &[Member], ids: &FxHashMap<usize, MemberId>, out: &mut Vec<MemberId>) {
    for m in members {
        if let Some(id) = ids.get(&key(m)) {
            out.push(*id);
        }
        if let MemberKind::Group(g) = &m.kind {
            arm_members(&g.members, ids, out);
        }
    }
}

fn arm_variant_names(members: &[Member], out: &mut Vec<String>) {
    for m in members {
        match &m.kind {
            MemberKind::Group(g) => arm_variant_names(&g.members, out),
            MemberKind::Split { arms, .. } => {
                for a in arms {
                    match &a.body {
                        SplitArmBody::Members { variant, members } => {
                            out.push(variant.name.clone());
                            arm_variant_names(members, out);
                        }
                        SplitArmBody::From { variant, .. } => out.push(variant.name.clone()),
                    }
                }
            }
            _ => {}
        }
    }
}

/// The layouts in `program` (helper for callers that only have the AST).
pub(super) fn layout_items(program: &Program) -> impl Iterator<Item = (usize, &LayoutDecl)> {
    program
        .items
        .iter()
        .enumerate()
        .filter_map(|(i, it)| match it {
            Item::Layout(l) => Some((i, l)),
            _ => None,
        })
}

/// The named members of a layout (stored fields, derived fields, lets, groups) in the order
/// that numbers them: `named_members(decl)[i]` is the member with [`MemberId`]`(i)`.
pub fn named_members(decl: &LayoutDecl) -> Vec<&Member> {
    fn walk<'a>(members: &'a [Member], out: &mut Vec<&'a Member>) {
        for m in members {
            match &m.kind {
                MemberKind::Split { arms, .. } => {
                    for a in arms {
                        if let SplitArmBody::Members { members, .. } = &a.body {
                            walk(members, out);
                        }
                    }
                }
                MemberKind::Group(g) => {
                    out.push(m);
                    walk(&g.members, out);
                }
                MemberKind::Padding { .. } | MemberKind::Separator => {}
                _ => out.push(m),
            }
        }
    }
    let mut out = Vec::new();
    walk(&decl.members, &mut out);
    out
}
