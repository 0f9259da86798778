//! Structural well-formedness of layouts (paper §6.1; codes E03xx).
//!
//! Input: a [`Program`]; output: [`Diagnostics`] for every `layout` in it. All problems of a
//! layout are collected before stopping. The checks: member types have sizes and group
//! attributes are valid (from [`LayoutModel::from_ast`]); member names are unique in each scope;
//! `parent.x` names a field; the layout realizes exactly one ADT; every variant is realized by
//! a split arm, and every split on its route has an arm for it; every logical field of every
//! variant has exactly one physical path and a stored field keeps the logical type; names in
//! derived fields, lets, discriminants and keys resolve on every route; derived-field and let
//! dependencies are acyclic; split arms cover their discriminant's domain, with a warning for
//! arms that can never match. The unique-path search is [`crate::layout::resolve`].

use crate::layout::domain::{coverage, Uncovered};
use crate::layout::model::{ArmBody, LayoutModel, MemberId, MemberModel, Models, ScopeId};
use crate::layout::resolve::{
    dep_of, names_in, Dep, FieldPath, ResolveError, Resolver, Route, RouteError,
};
use crate::layout::types::integer_domain;
use crate::syntax::ast::{Expr, ExprKind, Item, Program, SplitPatternKind, TypeExpr, TypeExprKind};
use rustc_hash::{FxHashMap, FxHashSet};
use scion_ir::diag::{Diagnostic, Diagnostics, Span};

/// Checks every layout of `program` (their models are `models`').
pub fn check_layouts(program: &Program, models: &Models) -> Diagnostics {
    let mut out = Diagnostics::new();
    let mut seen: FxHashMap<&str, Span> = FxHashMap::default();
    for item in &program.items {
        let Item::Layout(l) = item else { continue };
        if let Some(first) = seen.get(l.name.name.as_str()) {
            out.push(
                Diagnostic::error(
                    "E0302",
                    format!("layout `{}` is declared twice", l.name.name),
                )
                .with_primary(l.name.span, "second declaration")
                .with_secondary(*first, "first declared here"),
            );
            continue;
        }
        seen.insert(&l.name.name, l.name.span);
        if let Some(model) = models.get(&l.name.name) {
            out.extend(check_layout(model));
        }
    }
    out
}

/// Checks one layout.
pub fn check_layout(model: &LayoutModel) -> Diagnostics {
    let mut c = Checker {
        m: model,
        d: model.diagnostics.clone(),
        reported: FxHashSet::default(),
    };
    c.duplicates();
    c.parents();
    c.group_exprs();
    c.splits();
    c.bit_slices();
    c.variants();
    c.d
}

struct Checker<'m> {
    m: &'m LayoutModel,
    d: Diagnostics,
    /// Keys of diagnostics already reported (several routes find the same problem).
    reported: FxHashSet<String>,
}

impl Checker<'_> {
    fn once(&mut self, key: String) -> bool {
        self.reported.insert(key)
    }

    fn member_name(&self, m: MemberId) -> (String, Span) {
        let info = &self.m.members[m];
        match &info.kind {
            MemberModel::Group(g) => {
                let n = &self.m.groups[*g].name;
                (n.name.clone(), n.span)
            }
            k => k
                .value_name()
                .map(|n| (n.name.clone(), n.span))
                .unwrap_or_default(),
        }
    }

    /// E0302: a name declared twice in one scope (or a global named like a component).
    fn duplicates(&mut self) {
        for (si, scope) in self.m.scopes.iter().enumerate() {
            let mut first: FxHashMap<String, Span> = FxHashMap::default();
            if si == 0 {
                for c in &self.m.components {
                    first.entry(c.name.name.clone()).or_insert(c.name.span);
                }
            }
            for &m in &scope.members {
                let (name, span) = self.member_name(m);
                if name.is_empty() {
                    continue;
                }
                if let Some(prev) = first.get(&name) {
                    self.d.push(
                        Diagnostic::error(
                            "E0302",
                            format!("`{name}` is declared twice in the same scope"),
                        )
                        .with_primary(span, "second declaration")
                        .with_secondary(*prev, "first declared here"),
                    );
                } else {
                    first.insert(name, span);
                }
            }
        }
    }

    /// E0310: `parent.x` must name a member or a component.
    fn parents(&mut self) {
        let mut exprs: Vec<&Expr> = self
            .m
            .components
            .iter()
            .filter_map(|c| c.default.as_ref())
            .collect();
        for info in &self.m.members {
            if let MemberModel::Derived { value, .. } | MemberModel::Let { value, .. } = &info.kind
            {
                exprs.push(value);
            }
        }
        let known: FxHashSet<&str> = self
            .m
            .members
            .iter()
            .filter_map(|i| i.kind.value_name().map(|n| n.name.as_str()))
            .chain(self.m.components.iter().map(|c| c.name.name.as_str()))
            .collect();
        for e in exprs {
            for id in names_in(e) {
                if let Some(x) = id.name.strip_prefix("parent.") {
                    if !known.contains(x) {
                        self.d.push(
                            Diagnostic::error("E0310", format!("`parent.{x}` names no field of layout `{}`", self.m.name.name))
                                .with_primary(id.span, "unknown field")
                                .with_note("`parent.x` reads the parent's value of a field or reference component `x`"),
                        );
                    }
                }
            }
        }
    }

    /// E0319: `size` reads globals and `by` reads reference components.
    fn group_exprs(&mut self) {
        let globals: FxHashSet<&str> = self.m.scopes[0]
            .members
            .iter()
            .filter_map(|m| {
                self.m.members[*m]
                    .kind
                    .value_name()
                    .map(|n| n.name.as_str())
            })
            .collect();
        for g in &self.m.groups {
            if let Some(size) = &g.size {
                for id in names_in(size) {
                    if !globals.contains(id.name.as_str()) {
                        self.d.push(
                            Diagnostic::error(
                                "E0319",
                                format!(
                                    "`{}` in the size of group `{}` is not a global",
                                    id.name, g.name.name
                                ),
                            )
                            .with_primary(id.span, "not a top-level field")
                            .with_note("a group's `size` is an expression over globals"),
                        );
                    }
                }
            }
            if let Some(by) = &g.by {
                for id in names_in(by) {
                    if self.m.component(&id.name).is_none() && !globals.contains(id.name.as_str()) {
                        self.d.push(
                            Diagnostic::error("E0319", format!("`{}` in the index of group `{}` is not a reference component", id.name, g.name.name))
                                .with_primary(id.span, "unknown here")
                                .with_note("a direct group is indexed by an expression over the reference's components"),
                        );
                    }
                }
            }
        }
    }

    /// The declared type of `name` seen from `scope`: members of enclosing scopes, then
    /// components.
    fn type_of_name(&self, mut scope: ScopeId, name: &str) -> Option<&TypeExpr> {
        loop {
            for &m in &self.m.scopes[scope].members {
                match &self.m.members[m].kind {
                    MemberModel::Stored(s) if s.name.name == name => return Some(&s.ty),
                    MemberModel::Let {
                        name: n,
                        ty: Some(t),
                        ..
                    } if n.name == name => return Some(t),
                    _ => {}
                }
            }
            match self.m.scopes[scope].parent {
                Some(p) => scope = p,
                None => break,
            }
        }
        self.m
            .components
            .iter()
            .find(|c| c.name.name == name)
            .map(|c| &c.ty)
    }

    /// The discriminant's domain: `Ok(Some)` for integers, `Ok(None)` when unknown,
    /// `Err(type)` when it is known not to be an integer.
    fn domain(&self, scope: ScopeId, e: &Expr) -> Result<Option<(i128, i128)>, String> {
        let of_type = |t: &TypeExpr| match &t.kind {
            TypeExprKind::Named(n) => integer_domain(&n.name)
                .map(Some)
                .ok_or_else(|| n.name.clone()),
            _ => Err("a non-scalar type".to_string()),
        };
        match &e.kind {
            ExprKind::Name(n) => match self.type_of_name(scope, &n.name) {
                Some(t) => of_type(t),
                None => Ok(None),
            },
            ExprKind::Cast { ty, .. } => of_type(ty),
            ExprKind::Slice { lo, hi, .. } => match (&lo.kind, &hi.kind) {
                (ExprKind::Int(a), ExprKind::Int(b)) if b > a && b - a <= 64 => {
                    Ok(Some((0, (1i128 << (b - a)) - 1)))
                }
                _ => Ok(None),
            },
            _ => Ok(None),
        }
    }

    /// E0325: a literal bit slice `x[a:b]` of an integer stays within `x`'s bits, with a < b.
    fn bit_slices(&mut self) {
        let mut found: Vec<(ScopeId, &Expr)> = Vec::new();
        for info in &self.m.members {
            match &info.kind {
                MemberModel::Derived { value, .. } | MemberModel::Let { value, .. } => {
                    found.push((info.scope, value))
                }
                MemberModel::Split(sp) => {
                    let split = &self.m.splits[*sp];
                    found.push((split.scope, &split.discriminant));
                    for a in &split.arms {
                        if let ArmBody::From { key, .. } = &a.body {
                            found.push((split.scope, key));
                        }
                    }
                }
                _ => {}
            }
        }
        let mut slices = Vec::new();
        for (scope, e) in found {
            collect_slices(e, scope, &mut slices, 0);
        }
        for (scope, e) in slices {
            let ExprKind::Slice { base, lo, hi } = &e.kind else {
                continue;
            };
            let (ExprKind::Name(x), ExprKind::Int(a), ExprKind::Int(b)) =
                (&base.kind, &lo.kind, &hi.kind)
            else {
                continue;
            };
            let Some(TypeExprKind::Named(t)) = self.type_of_name(scope, &x.name).map(|t| &t.kind)
            else {
                continue;
            };
            let Some(shape) = crate::layout::types::primitive(&t.name) else {
                continue;
            };
            if integer_domain(&t.name).is_none() {
                continue;
            }
            let bits = u128::from(shape.size * 8);
            if a >= b || *b > bits {
                self.d.push(
                    Diagnostic::error("E0325", format!("bit range [{a}:{b}] of `{}` does not fit its {bits} bits", x.name))
                        .with_primary(e.span, "out of range")
                        .with_note("bit ranges are half-open, low bit 0: `x[a:b]` needs a < b <= the width of x"),
                );
            }
        }
    }

    /// E0316, W0317, E0320: coverage of every split.
    fn splits(&mut self) {
        for sp in &self.m.splits {
            let patterns: Vec<SplitPatternKind> =
                sp.arms.iter().map(|a| a.pattern.kind.clone()).collect();
            let has_wild = patterns.contains(&SplitPatternKind::Wildcard);
            let typed = self.domain(sp.scope, &sp.discriminant);
            let not_integer = typed.is_err();
            let domain = match typed {
                Ok(d) => d,
                Err(ty) => {
                    self.d.push(
                        Diagnostic::error(
                            "E0320",
                            format!("split discriminant has type `{ty}`, not an integer type"),
                        )
                        .with_primary(sp.discriminant.span, "not an integer")
                        .with_note(
                            "split on an integer field, a bit slice `x[a:b]` or a cast `e as u32`",
                        ),
                    );
                    None
                }
            };
            let cov = coverage(&patterns, domain);
            match cov.uncovered {
                Uncovered::No => {}
                Uncovered::Value(v) => {
                    let (lo, hi) = domain.unwrap_or((0, 0));
                    self.d.push(
                        Diagnostic::error("E0316", "split arms do not cover every value of the discriminant")
                            .with_primary(sp.discriminant.span, format!("value {v} matches no arm"))
                            .with_note(format!("the discriminant ranges over {lo}..={hi}; add an arm for {v} or a `_` arm")),
                    );
                }
                // A discriminant that is no integer was reported above.
                Uncovered::Unknown => {
                    if !has_wild && !not_integer {
                        self.d.push(
                            Diagnostic::error("E0320", "cannot tell the range of this split's discriminant")
                                .with_primary(sp.discriminant.span, "type unknown here")
                                .with_note("split on a field with a declared integer type, a bit slice, or a cast; or add a `_` arm"),
                        );
                    }
                }
            }
            for i in cov.unreachable {
                let arm = &sp.arms[i];
                self.d.push(
                    Diagnostic::warning("W0317", "unreachable split arm")
                        .with_primary(arm.pattern.span, "no value reaches this arm")
                        .with_note("earlier arms already match every value this pattern accepts"),
                );
            }
        }
    }

    /// Variant-level checks: realization, unique paths, names, cycles.
    fn variants(&mut self) {
        let Some(adt) = &self.m.adt else { return };
        let m = self.m;
        if m.splits.is_empty() && adt.variants.len() > 1 {
            self.d.push(
                Diagnostic::error(
                    "E0314",
                    format!(
                        "layout `{}` has no split, but `{}` has {} variants",
                        m.name.name,
                        adt.name,
                        adt.variants.len()
                    ),
                )
                .with_primary(m.name.span, "nothing tells the variants apart")
                .with_note("add a `split` whose arms name each variant"),
            );
            return;
        }
        let mut resolver = Resolver::new(m);
        for v in &adt.variants {
            let vname = v.name.name.as_str();
            let (routes, errors) = resolver.routes(vname).clone();
            let named_anywhere = m
                .splits
                .iter()
                .any(|s| s.arms.iter().any(|a| a.variant.name == vname));
            for e in &errors {
                match e {
                    RouteError::NoArm(sp) if !named_anywhere => {
                        if self.once(format!("unrealized {vname}")) {
                            self.d.push(
                                Diagnostic::error(
                                    "E0314",
                                    format!("variant `{vname}` is not realized by any split arm"),
                                )
                                .with_primary(
                                    m.splits[*sp].span,
                                    format!("no arm of this split names `{vname}`"),
                                )
                                .with_secondary(v.name.span, "variant declared here"),
                            );
                        }
                    }
                    RouteError::NoArm(sp) => {
                        self.d.push(
                            Diagnostic::error("E0315", format!("split has no arm for variant `{vname}`"))
                                .with_primary(m.splits[*sp].span, format!("`{vname}` reaches this split"))
                                .with_note("every split on a variant's route must have an arm for it; otherwise no value of the discriminant can mean that variant"),
                        );
                    }
                    RouteError::IndirectCycle { split, arm } => {
                        self.d.push(
                            Diagnostic::error(
                                "E0323",
                                "`from` re-enters an indirect group already on the route",
                            )
                            .with_primary(m.splits[*split].arms[*arm].span, "cyclic `from`"),
                        );
                    }
                    RouteError::TooMany => {
                        self.d.push(
                            Diagnostic::error(
                                "E0324",
                                format!(
                                    "variant `{vname}` can be realized in more than {} ways",
                                    crate::layout::resolve::MAX_ROUTES
                                ),
                            )
                            .with_primary(m.name.span, "too many split arms for one variant"),
                        );
                    }
                }
            }
            if routes.is_empty() {
                continue;
            }
            for f in &v.fields {
                match resolver.resolve(vname, &f.name.name) {
                    Ok(path) => self.preserves_type(f, &path),
                    Err(ResolveError::Missing { guards, .. }) => {
                        let at = guards
                            .last()
                            .map(|(s, a)| m.splits[*s].arms[*a].variant.span)
                            .unwrap_or(m.name.span);
                        self.d.push(
                            Diagnostic::error("E0312", format!("field `{}` of variant `{vname}` has no physical path in layout `{}`", f.name.name, m.name.name))
                                .with_primary(at, format!("`{vname}` is realized here without `{}`", f.name.name))
                                .with_secondary(f.name.span, "logical field declared here")
                                .with_note(format!("declare a stored field `{}: T` or derive it with `{} = e`", f.name.name, f.name.name)),
                        );
                    }
                    Err(ResolveError::Ambiguous { members, .. }) => {
                        self.ambiguous(&f.name.name, vname, &members)
                    }
                    Err(ResolveError::UnknownVariant(_)) | Err(ResolveError::Unrealized(_)) => {}
                }
            }
            for r in &routes {
                self.route_names(vname, r);
                self.cycles(r);
            }
        }
    }

    fn ambiguous(&mut self, name: &str, vname: &str, members: &[MemberId]) {
        let mut key: Vec<MemberId> = members.to_vec();
        key.sort_unstable();
        if !self.once(format!("ambiguous {key:?}")) {
            return;
        }
        let spans: Vec<Span> = members.iter().map(|m| self.m.members[*m].span).collect();
        let mut d = Diagnostic::error(
            "E0313",
            format!(
                "`{name}` has {} declarations on the route of variant `{vname}`",
                members.len()
            ),
        )
        .with_primary(spans[0], "declared here");
        for s in &spans[1..] {
            d = d.with_secondary(*s, "and here");
        }
        self.d
            .push(d.with_note("a field must have exactly one physical path; rename or remove one"));
    }

    /// E0327: a stored field realizing a logical field keeps its type.
    fn preserves_type(&mut self, f: &crate::layout::model::LogicalField, path: &FieldPath) {
        let FieldPath::Stored { member, ty, .. } = path else {
            return;
        };
        if f.recursive {
            let Some(s) = self.m.stored(*member) else {
                return;
            };
            let refs = match &f.ty.kind {
                TypeExprKind::Array {
                    len: crate::syntax::ast::ArrayLen::Const(n, _),
                    ..
                } => *n,
                _ => 1,
            };
            if s.size != 0
                && s.size != self.m.reference.size * refs
                && self.once(format!("reftype {member}"))
            {
                self.d.push(
                    Diagnostic::error("E0327", format!("child field `{}` is stored in {} bytes, but a reference takes {}", f.name.name, s.size, self.m.reference.size * refs))
                        .with_primary(s.ty.span, "size differs from the reference's")
                        .with_note("store children as the layout's reference type (e.g. `ptr` or the index type)"),
                );
            }
            return;
        }
        if !crate::layout::types::same_type(&f.ty, ty) && self.once(format!("type {member}")) {
            self.d.push(
                Diagnostic::error("E0327", format!("stored field `{}` does not have the logical field's type", f.name.name))
                    .with_primary(ty.span, "physical type")
                    .with_secondary(f.ty.span, "logical type")
                    .with_note("store the logical type, or store an encoding under another name and derive the field with an explicit conversion"),
            );
        }
    }

    /// E0313 for any name declared twice on a route; E0319 for unknown names.
    fn route_names(&mut self, vname: &str, r: &Route) {
        let dups: Vec<(String, Vec<MemberId>)> = r
            .duplicates()
            .map(|(n, v)| (n.clone(), v.clone()))
            .collect();
        for (n, ms) in dups {
            self.ambiguous(&n, vname, &ms);
        }
        let mut exprs: Vec<&Expr> = Vec::new();
        for mid in r.members(self.m) {
            match &self.m.members[mid].kind {
                MemberModel::Derived { value, .. } | MemberModel::Let { value, .. } => {
                    exprs.push(value)
                }
                MemberModel::Split(sp) => exprs.push(&self.m.splits[*sp].discriminant),
                _ => {}
            }
        }
        for (sp, arm) in &r.guards {
            if let ArmBody::From { key, .. } = &self.m.splits[*sp].arms[*arm].body {
                exprs.push(key);
            }
        }
        for e in exprs {
            for id in names_in(e) {
                if let Dep::Unknown(n) = dep_of(self.m, r, &id) {
                    if self.once(format!("unknown {}:{}", n.span.start, n.name)) {
                        self.d.push(
                            Diagnostic::error("E0319", format!("`{}` is not a field, let or reference component on the route of variant `{vname}`", n.name))
                                .with_primary(n.span, "unknown name")
                                .with_note("a derived field reads the reference, globals, fields of its group and of the arms realizing the same variant"),
                        );
                    }
                }
            }
        }
    }

    /// E0318: a cycle among derived fields and lets on a route.
    fn cycles(&mut self, r: &Route) {
        let nodes: Vec<MemberId> = r
            .members(self.m)
            .filter(|m| {
                matches!(
                    self.m.members[*m].kind,
                    MemberModel::Derived { .. } | MemberModel::Let { .. }
                )
            })
            .collect();
        let mut edges: FxHashMap<MemberId, Vec<MemberId>> = FxHashMap::default();
        for &n in &nodes {
            let value = match &self.m.members[n].kind {
                MemberModel::Derived { value, .. } | MemberModel::Let { value, .. } => value,
                _ => continue,
            };
            let succ = names_in(value)
                .iter()
                .filter_map(|id| match dep_of(self.m, r, id) {
                    Dep::Member(t) if nodes.contains(&t) => Some(t),
                    _ => None,
                })
                .collect();
            edges.insert(n, succ);
        }
        // Iterative DFS with colours; a grey successor closes a cycle.
        let mut colour: FxHashMap<MemberId, u8> = FxHashMap::default();
        for &start in &nodes {
            if colour.contains_key(&start) {
                continue;
            }
            let mut stack: Vec<(MemberId, usize)> = vec![(start, 0)];
            colour.insert(start, 1);
            while let Some(&mut (n, ref mut i)) = stack.last_mut() {
                let succ = edges.get(&n).map(Vec::as_slice).unwrap_or(&[]);
                if *i < succ.len() {
                    let t = succ[*i];
                    *i += 1;
                    match colour.get(&t).copied() {
                        None => {
                            colour.insert(t, 1);
                            stack.push((t, 0));
                        }
                        Some(1) => {
                            let from = stack.iter().position(|(x, _)| *x == t).unwrap_or(0);
                            let cycle: Vec<MemberId> =
                                stack[from..].iter().map(|(x, _)| *x).collect();
                            self.report_cycle(&cycle);
                        }
                        _ => {}
                    }
                } else {
                    colour.insert(n, 2);
                    stack.pop();
                }
            }
        }
    }

    fn report_cycle(&mut self, cycle: &[MemberId]) {
        let mut key = cycle.to_vec();
        key.sort_unstable();
        if !self.once(format!("cycle {key:?}")) {
            return;
        }
        let names: Vec<String> = cycle.iter().map(|m| self.member_name(*m).0).collect();
        let mut shown = names.join(" -> ");
        shown.push_str(" -> ");
        shown.push_str(&names[0]);
        let mut d = Diagnostic::error(
            "E0318",
            format!("derived fields depend on themselves: {shown}"),
        )
        .with_primary(
            self.m.members[cycle[0]].span,
            "this definition is part of a cycle",
        );
        for m in &cycle[1..] {
            d = d.with_secondary(self.m.members[*m].span, "depends on this");
        }
        self.d
            .push(d.with_note("derived fields and lets must be computable in some order"));
    }
}

fn collect_slices<'e>(e: &'e Expr, scope: ScopeId, out: &mut Vec<(ScopeId, &'e Expr)>, depth: u32) {
    if depth > 256 {
        return;
    }
    let d = depth + 1;
    match &e.kind {
        ExprKind::Slice { base, lo, hi } => {
            out.push((scope, e));
            for x in [base, lo, hi] {
                collect_slices(x, scope, out, d);
            }
        }
        ExprKind::Call { args, .. } | ExprKind::Tuple(args) | ExprKind::Array(args) => {
            args.iter().for_each(|a| collect_slices(a, scope, out, d))
        }
        ExprKind::Field { base, .. } => collect_slices(base, scope, out, d),
        ExprKind::Index { base, index } => {
            collect_slices(base, scope, out, d);
            collect_slices(index, scope, out, d);
        }
        ExprKind::Unary { operand, .. } => collect_slices(operand, scope, out, d),
        ExprKind::Binary { lhs, rhs, .. } => {
            collect_slices(lhs, scope, out, d);
            collect_slices(rhs, scope, out, d);
        }
        ExprKind::Cast { expr, .. } | ExprKind::BitCast { expr, .. } => {
            collect_slices(expr, scope, out, d)
        }
        _ => {}
    }
}
