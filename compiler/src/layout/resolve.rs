//! Field resolution: from a variant's logical field to its unique physical path (paper §7.1,
//! Algorithm 1, with the scope management the paper leaves out; the design is written up in
//! `docs/well-formedness.md`).
//!
//! Input: a [`LayoutModel`], a variant name and a field name. Output: a [`FieldPath`]: either a
//! stored field (the chain of group indexings from the base, the array, the byte offset and the
//! stored type) or a derived field (its expression and what each name in it denotes), or an
//! error saying the field is missing or has two declarations.
//!
//! The search has two stages. First, the *routes* of a variant: every way the variant can be
//! realized, each a set of scopes (the top level, every direct group and its nested groups, the
//! split arms that name the variant, the indirect groups those arms reach with `from`) together
//! with the arm chosen at each split (its guards). A variant realized by a single arm per split
//! has one route. Second, on each route the field's declarations are looked up by name: exactly
//! one stored or derived field is a path, none is absence, two or more is ambiguity. Routes and
//! resolutions are cached per variant and per (variant, field) in a [`Resolver`].

use crate::layout::model::{
    ArmBody, GroupId, GroupKind, LayoutModel, MemberId, MemberModel, ScopeId, ScopeKind, SplitId,
    Storage,
};
use crate::syntax::ast::{Expr, ExprKind, Ident, Stmt, StmtKind, TypeExpr};
use rustc_hash::FxHashMap;

/// How one group level is indexed on a path.
#[derive(Clone, Debug, PartialEq)]
pub enum Index {
    /// `by e`: element `e` of a contiguous array.
    Value(Expr),
    /// `by p` with `p: ptr`: the element at address `p`.
    Pointer(Expr),
    /// `from g[key]`: element `key` of an indirect group.
    Key(Expr),
    /// A nested group of `count`: tile `index / count` of the outer element, slot `index % count`.
    Tile {
        /// Tile size.
        count: u64,
    },
    /// A direct group written without `by` (an error was reported).
    Missing,
}

/// One group level of a path.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    /// The group.
    pub group: GroupId,
    /// How it is indexed.
    pub index: Index,
}

/// A split arm taken on a route: `(split, arm index)`.
pub type Guard = (SplitId, usize);

/// What a name inside a derived expression denotes.
#[derive(Clone, Debug, PartialEq)]
pub enum Dep {
    /// A member on the same route (stored, derived or let).
    Member(MemberId),
    /// A component of the reference.
    Component(usize),
    /// `parent.x`.
    Parent(Ident),
    /// Nothing on the route.
    Unknown(Ident),
    /// Several members on the route.
    Ambiguous(Ident),
}

/// The physical path of a field.
#[derive(Clone, Debug, PartialEq)]
pub enum FieldPath {
    /// A load: follow `steps` from the base, then read `size` bytes of type `ty` at `storage`.
    Stored {
        /// The stored field.
        member: MemberId,
        /// Group levels from the base to the element (empty for a global).
        steps: Vec<Step>,
        /// Array and byte offset (or the globals block, or a global array).
        storage: Storage,
        /// Stored type.
        ty: TypeExpr,
        /// Stored size in bytes.
        size: u64,
    },
    /// A computation: evaluate `value`, whose names denote `deps` (same order as they occur).
    Derived {
        /// The derived field.
        member: MemberId,
        /// Group levels to the element the expression's names live in.
        steps: Vec<Step>,
        /// The definition.
        value: Expr,
        /// What each name of `value` denotes.
        deps: Vec<(Ident, Dep)>,
    },
    /// The variant is realized by several split arms that place the field differently: one
    /// path per set of guards.
    Alternatives(Vec<(Vec<Guard>, FieldPath)>),
}

impl FieldPath {
    /// The declaring member, when there is one path.
    pub fn member(&self) -> Option<MemberId> {
        match self {
            FieldPath::Stored { member, .. } | FieldPath::Derived { member, .. } => Some(*member),
            FieldPath::Alternatives(_) => None,
        }
    }
}

/// Why a field has no unique path.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ResolveError {
    /// The layout's ADT has no such variant.
    UnknownVariant(String),
    /// No split arm realizes the variant.
    Unrealized(String),
    /// No stored or derived field of that name on some route of the variant.
    Missing {
        /// Variant.
        variant: String,
        /// Field.
        field: String,
        /// The arms of the route that lacks it.
        guards: Vec<Guard>,
    },
    /// Two or more declarations on one route.
    Ambiguous {
        /// Variant.
        variant: String,
        /// Field.
        field: String,
        /// The declarations.
        members: Vec<MemberId>,
    },
}

/// Why a route could not be completed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RouteError {
    /// A split on the route has no arm for the variant.
    NoArm(SplitId),
    /// `from` re-enters an indirect group already on the route.
    IndirectCycle {
        /// The split.
        split: SplitId,
        /// The arm.
        arm: usize,
    },
    /// More than [`MAX_ROUTES`] ways to realize one variant.
    TooMany,
}

/// Bound on the routes of one variant (each split with k arms for a variant multiplies them).
pub const MAX_ROUTES: usize = 256;

/// One way to realize a variant.
#[derive(Clone, Debug, Default)]
pub struct Route {
    /// Arms taken.
    pub guards: Vec<Guard>,
    /// Scopes visited, with the group levels that reach their elements.
    pub scopes: Vec<(ScopeId, Vec<Step>)>,
    names: FxHashMap<String, Vec<MemberId>>,
}

impl Route {
    /// Stored fields, derived fields and lets named `name` on this route.
    pub fn lookup(&self, name: &str) -> &[MemberId] {
        self.names.get(name).map(Vec::as_slice).unwrap_or(&[])
    }

    /// The steps reaching the elements of `scope`, if the route visits it.
    pub fn steps_of(&self, scope: ScopeId) -> Option<&[Step]> {
        self.scopes
            .iter()
            .find(|(s, _)| *s == scope)
            .map(|(_, st)| st.as_slice())
    }

    /// Every member declared in a scope on this route.
    pub fn members<'a>(&'a self, model: &'a LayoutModel) -> impl Iterator<Item = MemberId> + 'a {
        self.scopes
            .iter()
            .flat_map(move |(s, _)| model.scopes[*s].members.iter().copied())
    }

    /// Every name with two or more declarations on this route.
    pub fn duplicates(&self) -> impl Iterator<Item = (&String, &Vec<MemberId>)> {
        self.names.iter().filter(|(_, v)| v.len() > 1)
    }
}

#[derive(Clone)]
enum Pending {
    Scope(ScopeId, Vec<Step>),
    Split(SplitId, Vec<Step>),
}

/// Computes routes and resolutions, with caches.
pub struct Resolver<'m> {
    model: &'m LayoutModel,
    routes: FxHashMap<String, (Vec<Route>, Vec<RouteError>)>,
    cache: FxHashMap<(String, String), Result<FieldPath, ResolveError>>,
}

impl<'m> Resolver<'m> {
    /// A resolver for `model`.
    pub fn new(model: &'m LayoutModel) -> Resolver<'m> {
        Resolver {
            model,
            routes: FxHashMap::default(),
            cache: FxHashMap::default(),
        }
    }

    /// The model.
    pub fn model(&self) -> &'m LayoutModel {
        self.model
    }

    /// The routes of `variant` and the problems met while enumerating them.
    pub fn routes(&mut self, variant: &str) -> &(Vec<Route>, Vec<RouteError>) {
        if !self.routes.contains_key(variant) {
            let r = compute_routes(self.model, variant);
            self.routes.insert(variant.to_string(), r);
        }
        &self.routes[variant]
    }

    /// The unique path of `field` for `variant`.
    pub fn resolve(&mut self, variant: &str, field: &str) -> Result<FieldPath, ResolveError> {
        let key = (variant.to_string(), field.to_string());
        if let Some(r) = self.cache.get(&key) {
            return r.clone();
        }
        let r = self.resolve_uncached(variant, field);
        self.cache.insert(key, r.clone());
        r
    }

    fn resolve_uncached(&mut self, variant: &str, field: &str) -> Result<FieldPath, ResolveError> {
        let model = self.model;
        if let Some(adt) = &model.adt {
            if adt.variant(variant).is_none() {
                return Err(ResolveError::UnknownVariant(variant.to_string()));
            }
        }
        let (routes, _) = self.routes(variant);
        if routes.is_empty() {
            return Err(ResolveError::Unrealized(variant.to_string()));
        }
        let mut cases: Vec<(Vec<Guard>, FieldPath)> = Vec::new();
        for route in routes {
            let decls: Vec<MemberId> = route
                .lookup(field)
                .iter()
                .copied()
                .filter(|m| {
                    matches!(
                        model.members[*m].kind,
                        MemberModel::Stored(_) | MemberModel::Derived { .. }
                    )
                })
                .collect();
            match decls.as_slice() {
                [] => {
                    return Err(ResolveError::Missing {
                        variant: variant.to_string(),
                        field: field.to_string(),
                        guards: route.guards.clone(),
                    })
                }
                [m] => cases.push((route.guards.clone(), path_of(model, route, *m))),
                _ => {
                    return Err(ResolveError::Ambiguous {
                        variant: variant.to_string(),
                        field: field.to_string(),
                        members: decls,
                    })
                }
            }
        }
        let first = cases[0].1.clone();
        if cases.iter().all(|(_, p)| *p == first) {
            Ok(first)
        } else {
            Ok(FieldPath::Alternatives(cases))
        }
    }
}

/// The unique path of `field` for `variant` in `model` (uncached; use a [`Resolver`] to resolve
/// many fields).
pub fn resolve_field(
    model: &LayoutModel,
    variant: &str,
    field: &str,
) -> Result<FieldPath, ResolveError> {
    Resolver::new(model).resolve(variant, field)
}

fn path_of(model: &LayoutModel, route: &Route, m: MemberId) -> FieldPath {
    let steps = route
        .steps_of(model.members[m].scope)
        .map(<[Step]>::to_vec)
        .unwrap_or_default();
    match &model.members[m].kind {
        MemberModel::Stored(s) => FieldPath::Stored {
            member: m,
            steps,
            storage: s.storage,
            ty: s.ty.clone(),
            size: s.size,
        },
        MemberModel::Derived { value, .. } => {
            let deps = names_in(value).into_iter().map(|id| {
                let d = dep_of(model, route, &id);
                (id, d)
            });
            FieldPath::Derived {
                member: m,
                steps,
                value: value.clone(),
                deps: deps.collect(),
            }
        }
        _ => FieldPath::Derived {
            member: m,
            steps,
            value: unit_expr(),
            deps: Vec::new(),
        },
    }
}

fn unit_expr() -> Expr {
    Expr {
        id: crate::syntax::ast::NodeId(0),
        kind: ExprKind::Tuple(Vec::new()),
        span: Default::default(),
    }
}

/// What `name` denotes on `route`: a member, else a reference component.
pub fn dep_of(model: &LayoutModel, route: &Route, name: &Ident) -> Dep {
    if name.name.starts_with("parent.") {
        return Dep::Parent(name.clone());
    }
    match route.lookup(&name.name) {
        [m] => Dep::Member(*m),
        [] => match model.component(&name.name) {
            Some(c) => Dep::Component(c),
            None => Dep::Unknown(name.clone()),
        },
        _ => Dep::Ambiguous(name.clone()),
    }
}

/// The variable names an expression reads, in order (`parent.x` as a name `parent.x`).
pub fn names_in(e: &Expr) -> Vec<Ident> {
    let mut out = Vec::new();
    walk_names(e, &mut out, 0);
    out
}

fn walk_names(e: &Expr, out: &mut Vec<Ident>, depth: u32) {
    if depth > 256 {
        return;
    }
    let d = depth + 1;
    match &e.kind {
        ExprKind::Name(id) => out.push(id.clone()),
        ExprKind::Parent(id) => out.push(Ident {
            name: format!("parent.{}", id.name),
            span: id.span,
        }),
        ExprKind::Int(_)
        | ExprKind::Float(_)
        | ExprKind::Bool(_)
        | ExprKind::This
        | ExprKind::Build(_) => {}
        ExprKind::Call { args, .. } | ExprKind::Tuple(args) | ExprKind::Array(args) => {
            args.iter().for_each(|a| walk_names(a, out, d))
        }
        ExprKind::Field { base, .. } => walk_names(base, out, d),
        ExprKind::Index { base, index } => {
            walk_names(base, out, d);
            walk_names(index, out, d);
        }
        ExprKind::Slice { base, lo, hi } => {
            walk_names(base, out, d);
            walk_names(lo, out, d);
            walk_names(hi, out, d);
        }
        ExprKind::Unary { operand, .. } => walk_names(operand, out, d),
        ExprKind::Binary { lhs, rhs, .. } => {
            walk_names(lhs, out, d);
            walk_names(rhs, out, d);
        }
        ExprKind::Cast { expr, .. } | ExprKind::BitCast { expr, .. } => walk_names(expr, out, d),
        ExprKind::If {
            branches,
            otherwise,
        } => {
            for (cond, body) in branches {
                walk_names(cond, out, d);
                stmt_exprs(body, &mut |x| walk_names(x, out, d));
            }
            stmt_exprs(otherwise, &mut |x| walk_names(x, out, d));
        }
    }
}

/// Calls `f` on every expression directly inside `s` (not recursing into sub-expressions).
pub fn stmt_exprs<'a>(s: &'a Stmt, f: &mut dyn FnMut(&'a Expr)) {
    match &s.kind {
        StmtKind::Expr(e) => f(e),
        StmtKind::Assign { target, value } => {
            f(target);
            f(value);
        }
        StmtKind::Block(b) => b.iter().for_each(|s| stmt_exprs(s, f)),
        StmtKind::Return(Some(e)) => f(e),
        StmtKind::Return(None) => {}
        StmtKind::Match { scrutinee, arms } => {
            f(scrutinee);
            arms.iter().for_each(|a| stmt_exprs(&a.body, f));
        }
        StmtKind::Let { value, .. } => f(value),
        StmtKind::If {
            branches,
            otherwise,
        } => {
            for (c, b) in branches {
                f(c);
                stmt_exprs(b, f);
            }
            if let Some(o) = otherwise {
                stmt_exprs(o, f);
            }
        }
        StmtKind::Foreach { iter, body, .. } => {
            f(iter);
            stmt_exprs(body, f);
        }
        StmtKind::Build { value: Some(e), .. } => f(e),
        StmtKind::Build { value: None, .. } => {}
    }
}

fn group_step(model: &LayoutModel, g: GroupId) -> Step {
    let grp = &model.groups[g];
    let index = match grp.kind {
        GroupKind::Nested => Index::Tile {
            count: grp.count.unwrap_or(1),
        },
        GroupKind::Pointer => grp.by.clone().map(Index::Pointer).unwrap_or(Index::Missing),
        GroupKind::Direct | GroupKind::Indirect => {
            grp.by.clone().map(Index::Value).unwrap_or(Index::Missing)
        }
    };
    Step { group: g, index }
}

/// Enumerates the routes of `variant` (see the module docs).
pub fn compute_routes(model: &LayoutModel, variant: &str) -> (Vec<Route>, Vec<RouteError>) {
    let mut out = Vec::new();
    let mut errors = Vec::new();
    let start = vec![Pending::Scope(0, Vec::new())];
    expand(
        model,
        variant,
        Route::default(),
        start,
        Vec::new(),
        &mut out,
        &mut errors,
    );
    for r in &mut out {
        let mut names: FxHashMap<String, Vec<MemberId>> = FxHashMap::default();
        for (s, _) in &r.scopes {
            for &m in &model.scopes[*s].members {
                if let Some(id) = model.members[m].kind.value_name() {
                    names.entry(id.name.clone()).or_default().push(m);
                }
            }
        }
        r.names = names;
    }
    errors.dedup();
    (out, errors)
}

fn expand(
    model: &LayoutModel,
    variant: &str,
    mut route: Route,
    mut pending: Vec<Pending>,
    entered: Vec<GroupId>,
    out: &mut Vec<Route>,
    errors: &mut Vec<RouteError>,
) {
    while let Some(p) = pending.pop() {
        match p {
            Pending::Scope(s, steps) => {
                for &m in model.scopes[s].members.iter().rev() {
                    match &model.members[m].kind {
                        MemberModel::Group(g) if model.groups[*g].kind != GroupKind::Indirect => {
                            let mut st = steps.clone();
                            st.push(group_step(model, *g));
                            pending.push(Pending::Scope(model.groups[*g].scope, st));
                        }
                        MemberModel::Split(sp) => pending.push(Pending::Split(*sp, steps.clone())),
                        _ => {}
                    }
                }
                route.scopes.push((s, steps));
            }
            Pending::Split(sp, steps) => {
                let arms: Vec<usize> = model.splits[sp]
                    .arms
                    .iter()
                    .enumerate()
                    .filter(|(_, a)| a.variant.name == variant)
                    .map(|(i, _)| i)
                    .collect();
                if arms.is_empty() {
                    if !errors.contains(&RouteError::NoArm(sp)) {
                        errors.push(RouteError::NoArm(sp));
                    }
                    continue;
                }
                for ai in arms {
                    let mut r = route.clone();
                    let mut p = pending.clone();
                    let mut e = entered.clone();
                    r.guards.push((sp, ai));
                    match &model.splits[sp].arms[ai].body {
                        ArmBody::Members(scope) => p.push(Pending::Scope(*scope, steps.clone())),
                        ArmBody::From {
                            group: Some(g),
                            key,
                            ..
                        } => {
                            if e.contains(g) {
                                errors.push(RouteError::IndirectCycle { split: sp, arm: ai });
                                continue;
                            }
                            e.push(*g);
                            let step = Step {
                                group: *g,
                                index: Index::Key(key.clone()),
                            };
                            p.push(Pending::Scope(model.groups[*g].scope, vec![step]));
                        }
                        ArmBody::From { group: None, .. } => {}
                    }
                    expand(model, variant, r, p, e, out, errors);
                    if out.len() >= MAX_ROUTES {
                        if !errors.contains(&RouteError::TooMany) {
                            errors.push(RouteError::TooMany);
                        }
                        return;
                    }
                }
                return;
            }
        }
    }
    if out.len() < MAX_ROUTES {
        out.push(route);
    }
}

/// The derived fields and lets of `route` in an order where each comes after everything it
/// reads (Kahn's algorithm, ties broken by declaration order); `Err` holds the members left on
/// or behind a cycle.
pub fn evaluation_order(
    model: &LayoutModel,
    route: &Route,
) -> Result<Vec<MemberId>, Vec<MemberId>> {
    let nodes: Vec<MemberId> = route
        .members(model)
        .filter(|m| {
            matches!(
                model.members[*m].kind,
                MemberModel::Derived { .. } | MemberModel::Let { .. }
            )
        })
        .collect();
    let mut indegree: FxHashMap<MemberId, usize> = nodes.iter().map(|n| (*n, 0)).collect();
    let mut readers: FxHashMap<MemberId, Vec<MemberId>> = FxHashMap::default();
    for &n in &nodes {
        let value = match &model.members[n].kind {
            MemberModel::Derived { value, .. } | MemberModel::Let { value, .. } => value,
            _ => continue,
        };
        let mut seen = Vec::new();
        for id in names_in(value) {
            if let Dep::Member(t) = dep_of(model, route, &id) {
                if indegree.contains_key(&t) && !seen.contains(&t) {
                    seen.push(t);
                    readers.entry(t).or_default().push(n);
                    *indegree.get_mut(&n).expect("node") += 1;
                }
            }
        }
    }
    let mut ready: Vec<MemberId> = nodes.iter().copied().filter(|n| indegree[n] == 0).collect();
    ready.sort_unstable_by(|a, b| b.cmp(a));
    let mut order = Vec::new();
    while let Some(n) = ready.pop() {
        order.push(n);
        for r in readers.get(&n).cloned().unwrap_or_default() {
            let d = indegree.get_mut(&r).expect("node");
            *d -= 1;
            if *d == 0 {
                ready.push(r);
                ready.sort_unstable_by(|a, b| b.cmp(a));
            }
        }
    }
    if order.len() == nodes.len() {
        Ok(order)
    } else {
        Err(nodes.into_iter().filter(|n| !order.contains(n)).collect())
    }
}

/// The scope kind's split, for an arm scope.
pub fn arm_of_scope(model: &LayoutModel, scope: ScopeId) -> Option<(SplitId, usize)> {
    match model.scopes[scope].kind {
        ScopeKind::Arm { split, arm } => Some((split, arm)),
        _ => None,
    }
}
