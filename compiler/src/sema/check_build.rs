//! Build/layout consistency (paper §5, §6; codes E04xx).
//!
//! Input: a [`Program`]; output: [`Diagnostics`] for every `build` in it. A build must name a
//! layout (one build per layout); its variant entries name each variant of the layout's ADT
//! exactly once, with parameters that are logical fields of that variant. Each variant body is
//! walked as a small abstract interpretation over paths: for every stored field and every child
//! it counts writes as an interval `[min, max]` along all paths (branches join, loops may
//! repeat), so that it can tell "never written", "written on some paths only", "written twice"
//! and "read before written". Every stored field the variant reaches on each of its routes
//! (the fields of its groups and arms, not the globals) must be written exactly once, every
//! recursive child built exactly once, and every path must end in `return`. `build root`
//! writes the globals that are neither array sizes (set by the constructor) nor arrays (filled
//! by `append`), each exactly once. `append(x, n)` appends a logical array field; `this[a:b]`
//! stays within the reference's bits; a body reads no field that only other variants have.

use crate::layout::check_build_root::{check_root, GlobalFacts};
use crate::layout::model::{LayoutModel, LogicalField, MemberId, MemberModel, Models};
use crate::layout::resolve::{FieldPath, Resolver};
use crate::syntax::ast::{
    BuildDecl, BuildVariant, Expr, ExprKind, Ident, Item, Program, Stmt, StmtKind,
};
use rustc_hash::{FxHashMap, FxHashSet};
use scion_ir::diag::{Diagnostic, Diagnostics, Span};

/// Checks every build of `program`.
pub fn check_builds(program: &Program, models: &Models) -> Diagnostics {
    let mut out = Diagnostics::new();
    let mut seen: FxHashMap<&str, Span> = FxHashMap::default();
    for item in &program.items {
        let Item::Build(b) = item else { continue };
        if let Some(first) = seen.get(b.name.name.as_str()) {
            out.push(
                Diagnostic::error("E0414", format!("layout `{}` has two builds", b.name.name))
                    .with_primary(b.name.span, "second build")
                    .with_secondary(*first, "first build here"),
            );
            continue;
        }
        seen.insert(&b.name.name, b.name.span);
        out.extend(check_build(b, program, models));
    }
    out
}

/// Checks one build against its layout.
pub fn check_build(build: &BuildDecl, program: &Program, models: &Models) -> Diagnostics {
    let mut d = Diagnostics::new();
    let layout = program.items.iter().find_map(|i| match i {
        Item::Layout(l) if l.name.name == build.name.name => Some(l),
        _ => None,
    });
    let Some(layout) = layout else {
        let names: Vec<String> = program
            .items
            .iter()
            .filter_map(|i| match i {
                Item::Layout(l) => Some(format!("`{}`", l.name.name)),
                _ => None,
            })
            .collect();
        let mut diag = Diagnostic::error("E0401", format!("no layout named `{}`", build.name.name))
            .with_primary(
                build.name.span,
                "a build populates the layout of the same name",
            );
        if !names.is_empty() {
            diag = diag.with_note(format!("layouts: {}", names.join(", ")));
        }
        d.push(diag);
        return d;
    };
    let Some(model) = models.get(&layout.name.name) else {
        return d;
    };
    let Some(adt) = model.adt.clone() else {
        return d;
    };
    let mut resolver = Resolver::new(model);
    let facts = GlobalFacts::of(model);
    if let Some(root) = &build.root {
        check_root(model, &facts, &root.body, root.span, &mut d);
    } else {
        check_root(model, &facts, &[], build.span, &mut d);
    }
    let mut built: FxHashMap<&str, Span> = FxHashMap::default();
    for bv in &build.variants {
        let Some(var) = adt.variant(&bv.name.name) else {
            d.push(
                Diagnostic::error(
                    "E0403",
                    format!("`{}` is not a variant of `{}`", bv.name.name, adt.name),
                )
                .with_primary(bv.name.span, "unknown variant")
                .with_note(format!(
                    "the variants of `{}` are {}",
                    adt.name,
                    adt.variants
                        .iter()
                        .map(|v| format!("`{}`", v.name.name))
                        .collect::<Vec<_>>()
                        .join(", ")
                )),
            );
            continue;
        };
        if let Some(first) = built.get(bv.name.name.as_str()) {
            d.push(
                Diagnostic::error(
                    "E0404",
                    format!("variant `{}` is built twice", bv.name.name),
                )
                .with_primary(bv.name.span, "second build of this variant")
                .with_secondary(*first, "first here"),
            );
            continue;
        }
        built.insert(&bv.name.name, bv.name.span);
        for p in &bv.params {
            if !var.fields.iter().any(|f| f.name.name == p.name.name) {
                d.push(
                    Diagnostic::error(
                        "E0415",
                        format!(
                            "`{}` is not a field of variant `{}`",
                            p.name.name, var.name.name
                        ),
                    )
                    .with_primary(p.name.span, "not a logical field")
                    .with_secondary(var.name.span, "variant declared here"),
                );
            }
        }
        let mut vc = VariantCheck::new(model, &mut resolver, &facts, &var.fields, &bv.name.name);
        vc.run(bv);
        d.extend(vc.d);
    }
    for v in &adt.variants {
        if !built.contains_key(v.name.name.as_str()) {
            d.push(
                Diagnostic::error("E0405", format!("variant `{}` has no build", v.name.name))
                    .with_primary(
                        build.name.span,
                        format!("add `build {}(...) {{ ... }}`", v.name.name),
                    )
                    .with_secondary(v.name.span, "variant declared here"),
            );
        }
    }
    d
}

/// Write counts along all paths: `[min, max]`, `max` saturating at 2 ("many").
type Counts = FxHashMap<Key, (u8, u8)>;

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum Key {
    Field(MemberId),
    Child(String),
}

fn join(a: Option<Counts>, b: Option<Counts>) -> Option<Counts> {
    match (a, b) {
        (None, x) | (x, None) => x,
        (Some(a), Some(b)) => {
            let mut out = Counts::default();
            for k in a.keys().chain(b.keys()) {
                let (x0, x1) = a.get(k).copied().unwrap_or((0, 0));
                let (y0, y1) = b.get(k).copied().unwrap_or((0, 0));
                out.insert(k.clone(), (x0.min(y0), x1.max(y1)));
            }
            Some(out)
        }
    }
}

struct VariantCheck<'a, 'm> {
    m: &'m LayoutModel,
    resolver: &'a mut Resolver<'m>,
    facts: &'a GlobalFacts,
    fields: &'a [LogicalField],
    variant: String,
    /// Stored fields (not globals) on some route, by name.
    reachable: FxHashMap<String, Vec<MemberId>>,
    /// Every name declared on some route of the variant (stored, derived, let).
    on_route: FxHashSet<String>,
    /// Stored fields on every route: each must be written exactly once.
    required: Vec<MemberId>,
    locals: FxHashSet<String>,
    first_write: FxHashMap<Key, Span>,
    returns: Option<Counts>,
    d: Diagnostics,
}

impl<'a, 'm> VariantCheck<'a, 'm> {
    fn new(
        m: &'m LayoutModel,
        resolver: &'a mut Resolver<'m>,
        facts: &'a GlobalFacts,
        fields: &'a [LogicalField],
        variant: &str,
    ) -> VariantCheck<'a, 'm> {
        let (routes, _) = resolver.routes(variant).clone();
        let mut reachable: FxHashMap<String, Vec<MemberId>> = FxHashMap::default();
        let mut per_route: Vec<FxHashSet<MemberId>> = Vec::new();
        let mut on_route = FxHashSet::default();
        for r in &routes {
            let mut set = FxHashSet::default();
            for mid in r.members(m) {
                if let Some(n) = m.members[mid].kind.value_name() {
                    on_route.insert(n.name.clone());
                }
                if m.members[mid].scope == 0 {
                    continue;
                }
                if let MemberModel::Stored(s) = &m.members[mid].kind {
                    set.insert(mid);
                    let e = reachable.entry(s.name.name.clone()).or_default();
                    if !e.contains(&mid) {
                        e.push(mid);
                    }
                }
            }
            per_route.push(set);
        }
        let mut required: Vec<MemberId> = match per_route.split_first() {
            Some((first, rest)) => first
                .iter()
                .copied()
                .filter(|x| rest.iter().all(|s| s.contains(x)))
                .collect(),
            None => Vec::new(),
        };
        required.sort_unstable();
        VariantCheck {
            m,
            resolver,
            facts,
            fields,
            variant: variant.to_string(),
            reachable,
            on_route,
            required,
            locals: FxHashSet::default(),
            first_write: FxHashMap::default(),
            returns: None,
            d: Diagnostics::new(),
        }
    }

    fn logical(&self, name: &str) -> Option<&'a LogicalField> {
        self.fields.iter().find(|f| f.name.name == name)
    }

    fn run(&mut self, bv: &BuildVariant) {
        for p in &bv.params {
            self.locals.insert(p.name.name.clone());
        }
        let end = self.block(&bv.body, Some(Counts::default()));
        if end.is_some() {
            self.d.push(
                Diagnostic::error("E0411", format!("the build of `{}` may end without `return`", self.variant))
                    .with_primary(bv.span, "some path reaches the end of this body")
                    .with_note("end every path with `return e`, the reference of the node built (usually `this`)"),
            );
        }
        let fin = join(self.returns.take(), end).unwrap_or_default();
        for mid in self.required.clone() {
            let (min, max) = fin.get(&Key::Field(mid)).copied().unwrap_or((0, 0));
            if min == 0 {
                let name = self.m.members[mid]
                    .kind
                    .value_name()
                    .map(|n| n.name.clone())
                    .unwrap_or_default();
                let how = if max == 0 {
                    "is not written"
                } else {
                    "is not written on every path"
                };
                self.d.push(
                    Diagnostic::error(
                        "E0407",
                        format!(
                            "stored field `{name}` {how} by the build of `{}`",
                            self.variant
                        ),
                    )
                    .with_primary(
                        bv.name.span,
                        format!("add `build {name}` or `build {name} = e`"),
                    )
                    .with_secondary(
                        self.m.members[mid].span,
                        format!("`{}` reaches this field", self.variant),
                    ),
                );
            }
        }
        for f in self.fields.iter().filter(|f| f.recursive) {
            let (min, max) = fin
                .get(&Key::Child(f.name.name.clone()))
                .copied()
                .unwrap_or((0, 0));
            if min == 0 {
                let how = if max == 0 {
                    "is never built"
                } else {
                    "is not built on every path"
                };
                self.d.push(
                    Diagnostic::error(
                        "E0410",
                        format!("child `{}` of `{}` {how}", f.name.name, self.variant),
                    )
                    .with_primary(bv.name.span, format!("add `build {}`", f.name.name))
                    .with_note("every subtree must be materialized exactly once"),
                );
            }
        }
    }

    fn block(&mut self, stmts: &[Stmt], mut st: Option<Counts>) -> Option<Counts> {
        for s in stmts {
            st = self.stmt(s, st);
        }
        st
    }

    fn stmt(&mut self, s: &Stmt, st: Option<Counts>) -> Option<Counts> {
        let mut st = st?;
        match &s.kind {
            StmtKind::Expr(e) => self.expr(e, &mut st),
            StmtKind::Let { name, value, .. } => {
                self.expr(value, &mut st);
                self.locals.insert(name.name.clone());
            }
            StmtKind::Assign { target, value } => {
                self.expr(value, &mut st);
                self.assign_target(target, &mut st);
            }
            StmtKind::Block(b) => return self.block(b, Some(st)),
            StmtKind::Return(e) => {
                if let Some(e) = e {
                    self.expr(e, &mut st);
                }
                self.returns = join(self.returns.take(), Some(st));
                return None;
            }
            StmtKind::If {
                branches,
                otherwise,
            } => {
                let mut out = None;
                let mut cur = st;
                for (c, b) in branches {
                    self.expr(c, &mut cur);
                    out = join(out, self.stmt(b, Some(cur.clone())));
                }
                let rest = match otherwise {
                    Some(o) => self.stmt(o, Some(cur)),
                    None => Some(cur),
                };
                return join(out, rest);
            }
            StmtKind::Match { scrutinee, arms } => {
                self.expr(scrutinee, &mut st);
                if arms.is_empty() {
                    return Some(st);
                }
                let mut out = None;
                for a in arms {
                    out = join(out, self.stmt(&a.body, Some(st.clone())));
                }
                return out;
            }
            StmtKind::Foreach {
                var,
                index,
                iter,
                body,
            } => {
                self.expr(iter, &mut st);
                self.locals.insert(var.name.clone());
                if let Some(k) = index {
                    self.locals.insert(k.name.clone());
                }
                let after = self.stmt(body, Some(st.clone()));
                let mut repeated = after.clone().unwrap_or_default();
                for (k, v) in repeated.iter_mut() {
                    if v.1 > st.get(k).map(|x| x.1).unwrap_or(0) {
                        v.1 = 2;
                    }
                }
                return join(Some(st), after.map(|_| repeated));
            }
            StmtKind::Build { field, value } => self.build_stmt(field, value.as_ref(), &mut st),
        }
        Some(st)
    }

    fn write(&mut self, key: Key, span: Span, what: &str, st: &mut Counts) {
        let e = st.entry(key.clone()).or_insert((0, 0));
        if e.1 >= 1 {
            let code = if matches!(key, Key::Child(_)) {
                "E0410"
            } else {
                "E0408"
            };
            let mut d = Diagnostic::error(
                code,
                format!(
                    "{what} is written more than once by the build of `{}`",
                    self.variant
                ),
            )
            .with_primary(
                span,
                if e.0 >= 1 {
                    "written again here"
                } else {
                    "may be written again here"
                },
            );
            if let Some(first) = self.first_write.get(&key) {
                d = d.with_secondary(*first, "first written here");
            }
            self.d.push(d);
        } else {
            self.first_write.insert(key, span);
        }
        e.0 = (e.0 + 1).min(2);
        e.1 = (e.1 + 1).min(2);
    }

    /// The stored member a build of `name` for a recursive field also writes.
    fn child_storage(&mut self, name: &Ident) -> Result<Option<MemberId>, ()> {
        match self.resolver.resolve(&self.variant, &name.name) {
            Ok(FieldPath::Stored { member, .. }) => Ok(Some(member)),
            Ok(_) => Ok(None),
            Err(_) => Err(()),
        }
    }

    fn build_child(&mut self, name: &Ident, span: Span, st: &mut Counts) {
        match self.child_storage(name) {
            Ok(Some(mid)) => self.write(
                Key::Field(mid),
                span,
                &format!("stored field `{}`", name.name),
                st,
            ),
            Ok(None) => {}
            Err(()) => {
                self.d.push(
                    Diagnostic::error(
                        "E0406",
                        format!(
                            "child `{}` has no field in layout `{}`",
                            name.name, self.m.name.name
                        ),
                    )
                    .with_primary(
                        name.span,
                        "no stored or derived field of this name for this variant",
                    ),
                );
            }
        }
        self.write(
            Key::Child(name.name.clone()),
            span,
            &format!("child `{}`", name.name),
            st,
        );
    }

    fn build_stmt(&mut self, field: &Ident, value: Option<&Expr>, st: &mut Counts) {
        if let Some(v) = value {
            self.expr(v, st);
        }
        let name = &field.name;
        if let Some(lf) = self.logical(name) {
            if lf.recursive {
                if value.is_some() {
                    self.d.push(
                        Diagnostic::error(
                            "E0410",
                            format!("child `{name}` is built with `build {name}`, not assigned"),
                        )
                        .with_primary(field.span, "a recursive field cannot take a value"),
                    );
                    return;
                }
                self.build_child(field, field.span, st);
                return;
            }
        }
        let Some(members) = self.reachable.get(name).cloned() else {
            let derived = matches!(
                self.resolver.resolve(&self.variant, name),
                Ok(FieldPath::Derived { .. })
            );
            let (msg, label) =
                if self.facts.scalars.contains_key(name) || self.facts.arrays.contains(name) {
                    (
                        format!("global `{name}` cannot be written by a variant build"),
                        "write globals in `build root`",
                    )
                } else if derived {
                    (
                        format!(
                            "`{name}` is derived in layout `{}`, not stored",
                            self.m.name.name
                        ),
                        "build the stored fields its definition reads instead",
                    )
                } else {
                    (
                        format!(
                            "layout `{}` has no stored field `{name}` for variant `{}`",
                            self.m.name.name, self.variant
                        ),
                        "not a stored field this variant reaches",
                    )
                };
            self.d
                .push(Diagnostic::error("E0406", msg).with_primary(field.span, label));
            return;
        };
        if value.is_none() && self.logical(name).is_none() {
            self.d.push(
                Diagnostic::error(
                    "E0417",
                    format!(
                        "`build {name}` copies logical field `{name}`, but `{}` has none",
                        self.variant
                    ),
                )
                .with_primary(field.span, format!("write `build {name} = e`")),
            );
        }
        for mid in members {
            self.write(
                Key::Field(mid),
                field.span,
                &format!("stored field `{name}`"),
                st,
            );
        }
    }

    fn assign_target(&mut self, target: &Expr, st: &mut Counts) {
        if let ExprKind::Slice { base, lo, hi } = &target.kind {
            if matches!(base.kind, ExprKind::This) {
                let width = self.m.reference.size.saturating_mul(8);
                match (&lo.kind, &hi.kind) {
                    (ExprKind::Int(a), ExprKind::Int(b)) if a < b && *b <= u128::from(width) => {}
                    (ExprKind::Int(a), ExprKind::Int(b)) => self.d.push(
                        Diagnostic::error(
                            "E0413",
                            format!("bit range [{a}:{b}] does not fit the {width}-bit reference"),
                        )
                        .with_primary(target.span, "out of range")
                        .with_note(
                            "bit ranges are half-open, low bit 0: `this[a:b]` needs a < b <= width",
                        ),
                    ),
                    _ => self.d.push(
                        Diagnostic::error(
                            "E0413",
                            "bit range bounds of `this[a:b]` must be integer literals",
                        )
                        .with_primary(target.span, "not constant"),
                    ),
                }
                return;
            }
        }
        self.expr(target, st);
    }

    fn expr(&mut self, e: &Expr, st: &mut Counts) {
        match &e.kind {
            ExprKind::Name(n) => {
                if self.locals.contains(&n.name) {
                    return;
                }
                if !self.on_route.contains(&n.name) {
                    let elsewhere = self.m.members.iter().any(|i| {
                        i.scope != 0 && i.kind.value_name().is_some_and(|x| x.name == n.name)
                    });
                    if elsewhere {
                        self.d.push(
                            Diagnostic::error(
                                "E0418",
                                format!("`{}` is a field of another variant in layout `{}`", n.name, self.m.name.name),
                            )
                            .with_primary(n.span, format!("`{}` does not have it", self.variant)),
                        );
                    }
                    return;
                }
                if let Some(ms) = self.reachable.get(&n.name) {
                    let written = ms.iter().any(|m| st.get(&Key::Field(*m)).is_some_and(|c| c.0 >= 1));
                    if !written {
                        self.d.push(
                            Diagnostic::error("E0409", format!("stored field `{}` is read before it is written", n.name))
                                .with_primary(n.span, "not written on every path to here"),
                        );
                    }
                }
            }
            ExprKind::Build(x) => match self.logical(&x.name) {
                Some(lf) if lf.recursive => self.build_child(x, e.span, st),
                _ => self.d.push(
                    Diagnostic::error("E0410", format!("`build {}` in an expression builds a child, but `{}` is not a recursive field of `{}`", x.name, x.name, self.variant))
                        .with_primary(x.span, "not a child"),
                ),
            },
            ExprKind::Call { callee, args } => {
                if callee.name == "append" {
                    self.append(e, args);
                }
                for a in args {
                    self.expr(a, st);
                }
            }
            ExprKind::Int(_) | ExprKind::Float(_) | ExprKind::Bool(_) | ExprKind::This | ExprKind::Parent(_) => {}
            ExprKind::Field { base, .. } => self.expr(base, st),
            ExprKind::Index { base, index } => {
                self.expr(base, st);
                self.expr(index, st);
            }
            ExprKind::Slice { base, lo, hi } => {
                self.expr(base, st);
                self.expr(lo, st);
                self.expr(hi, st);
            }
            ExprKind::Tuple(xs) | ExprKind::Array(xs) => xs.iter().for_each(|x| self.expr(x, st)),
            ExprKind::Unary { operand, .. } => self.expr(operand, st),
            ExprKind::Binary { lhs, rhs, .. } => {
                self.expr(lhs, st);
                self.expr(rhs, st);
            }
            ExprKind::Cast { expr, .. } | ExprKind::BitCast { expr, .. } => self.expr(expr, st),
            ExprKind::If {
                branches,
                otherwise,
            } => {
                // As an `if` statement: the conditions in order, the branches joined.
                let mut out = None;
                let mut cur = st.clone();
                for (c, b) in branches {
                    self.expr(c, &mut cur);
                    out = join(out, self.stmt(b, Some(cur.clone())));
                }
                out = join(out, self.stmt(otherwise, Some(cur)));
                if let Some(o) = out {
                    *st = o;
                }
            }
        }
    }

    fn append(&mut self, call: &Expr, args: &[Expr]) {
        let ok = match args {
            [Expr {
                kind: ExprKind::Name(x),
                ..
            }, _] => self
                .logical(&x.name)
                .is_some_and(|f| f.array && !f.recursive),
            _ => false,
        };
        if !ok {
            self.d.push(
                Diagnostic::error("E0412", format!("`append(x, n)` needs a logical array field of `{}` as `x`", self.variant))
                    .with_primary(call.span, "not `append(field, count)` of an array field")
                    .with_note("`append` copies the elements of a logical array (e.g. `data`) to the global or indirect array the layout maps it to"),
            );
        }
    }
}
