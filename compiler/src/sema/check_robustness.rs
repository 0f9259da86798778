//! Robustness of the layout and build checks: no input makes them panic. Inputs are the library
//! and catalog fixtures, mutated at the AST level (every member and statement removed or
//! duplicated, attributes and patterns set to extreme values) and at the text level (every
//! line deleted, and the project's fuzz mutator), where the parser's error recovery hands the
//! checks partial programs.

use crate::layout::check_build::check_builds;
use crate::layout::check_layout::check_layouts;
use crate::layout::fixtures::*;
use crate::layout::plan::BufferPlan;
use crate::layout::resolve::Resolver;
use crate::layout::LayoutModel;
use crate::syntax::ast::*;

fn run_everything(p: &Program) {
    let models = crate::layout::model::Models::inferred(p);
    let _ = check_layouts(p, &models);
    let _ = check_builds(p, &models);
    let (typed, _) = crate::sema::check_program(p);
    let typed_models = crate::layout::model::Models::of(p, &typed);
    let _ = check_layouts(p, &typed_models);
    let _ = check_builds(p, &typed_models);
    for item in &p.items {
        if let Item::Layout(l) = item {
            let m = LayoutModel::from_ast(l, p);
            let _ = BufferPlan::of(&m);
            let mut r = Resolver::new(&m);
            for v in m.adt.iter().flat_map(|a| a.variants.iter()) {
                for f in &v.fields {
                    let _ = r.resolve(&v.name.name, &f.name.name);
                }
            }
        }
    }
}

fn all_fixtures() -> Vec<String> {
    vec![
        PBRT.to_string(),
        PTR.to_string(),
        PBRT_SOAOS.to_string(),
        PBRT_Q16.to_string(),
        SG_EQ.to_string(),
        format!("{BVH8_TYPE}\n{BVH8_Q8}"),
        "type T = One(a: f32, b: u16);\nlayout Tiled(I: u32) { N: u32; group outer[size=N] by I { group inner[4] { a: f32; --- b: u16; }; }; };".to_string(),
    ]
}

#[derive(Clone, Copy)]
enum Op {
    Remove,
    Duplicate,
    Extreme,
}

/// Applies `op` to the `k`-th member (pre-order) of `members`; returns how many were counted.
fn edit_members(members: &mut Vec<Member>, k: &mut usize, op: Op) -> bool {
    let mut i = 0;
    while i < members.len() {
        if *k == 0 {
            match op {
                Op::Remove => {
                    members.remove(i);
                }
                Op::Duplicate => {
                    let m = members[i].clone();
                    members.insert(i, m);
                }
                Op::Extreme => extreme(&mut members[i]),
            }
            return true;
        }
        *k -= 1;
        let done = match &mut members[i].kind {
            MemberKind::Group(g) => edit_members(&mut g.members, k, op),
            MemberKind::Split { arms, .. } => {
                let mut done = false;
                for a in arms.iter_mut() {
                    if let SplitArmBody::Members { members, .. } = &mut a.body {
                        if edit_members(members, k, op) {
                            done = true;
                            break;
                        }
                    }
                }
                done
            }
            _ => false,
        };
        if done {
            return true;
        }
        i += 1;
    }
    false
}

fn extreme(m: &mut Member) {
    let span = m.span;
    match &mut m.kind {
        MemberKind::Padding { bytes } => *bytes = u64::MAX,
        MemberKind::Group(g) => {
            g.attrs.push(GroupAttr {
                kind: GroupAttrKind::Align(1 << 63),
                span,
            });
            g.attrs.push(GroupAttr {
                kind: GroupAttrKind::Count(u64::MAX),
                span,
            });
            g.by = None;
        }
        MemberKind::Split { discriminant, arms } => {
            discriminant.kind = ExprKind::This;
            for (i, a) in arms.iter_mut().enumerate() {
                a.pattern.kind = match i % 3 {
                    0 => SplitPatternKind::Lt(i128::MIN),
                    1 => SplitPatternKind::Gt(i128::MAX),
                    _ => SplitPatternKind::Ne(i128::MIN),
                };
            }
        }
        MemberKind::Field { ty, .. } => {
            let elem = Box::new(ty.clone());
            ty.kind = TypeExprKind::Array {
                elem,
                len: ArrayLen::Const(u64::MAX, span),
            };
        }
        MemberKind::Derived { value, .. } | MemberKind::Let { value, .. } => {
            let id = value.id;
            let inner = value.clone();
            *value = Expr {
                id,
                kind: ExprKind::Slice {
                    base: Box::new(inner),
                    lo: Box::new(Expr {
                        id,
                        kind: ExprKind::Int(u128::MAX),
                        span,
                    }),
                    hi: Box::new(Expr {
                        id,
                        kind: ExprKind::Int(0),
                        span,
                    }),
                },
                span,
            };
        }
        MemberKind::Separator => {}
    }
}

fn edit_stmts(stmts: &mut Vec<Stmt>, k: &mut usize, op: Op) -> bool {
    let mut i = 0;
    while i < stmts.len() {
        if *k == 0 {
            match op {
                Op::Remove => {
                    stmts.remove(i);
                }
                Op::Duplicate | Op::Extreme => {
                    let s = stmts[i].clone();
                    stmts.insert(i, s);
                }
            }
            return true;
        }
        *k -= 1;
        i += 1;
    }
    false
}

#[test]
fn ast_mutations_never_panic() {
    let mut runs = 0;
    for src in all_fixtures() {
        let base = program(&[&src]);
        for op in [Op::Remove, Op::Duplicate, Op::Extreme] {
            for k in 0.. {
                let mut p = base.clone();
                let mut edited = false;
                let mut kk = k;
                for item in p.items.iter_mut() {
                    let done = match item {
                        Item::Layout(l) => edit_members(&mut l.members, &mut kk, op),
                        Item::Build(b) => {
                            let mut d = false;
                            for v in b.variants.iter_mut() {
                                if edit_stmts(&mut v.body, &mut kk, op) {
                                    d = true;
                                    break;
                                }
                            }
                            d
                        }
                        _ => false,
                    };
                    if done {
                        edited = true;
                        break;
                    }
                }
                if !edited {
                    break;
                }
                run_everything(&p);
                runs += 1;
            }
        }
    }
    assert!(runs > 100, "only {runs} mutants");
}

#[test]
fn text_mutations_never_panic() {
    // The parser recovers from errors, so every mutant yields a (possibly partial) program that
    // the checks must take without panicking, whether or not it parsed cleanly.
    let fixtures = all_fixtures();
    let mut checked = 0;
    for src in &fixtures {
        let lines: Vec<&str> = src.lines().collect();
        for skip in 0..lines.len() {
            let text: String = lines
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != skip)
                .map(|(_, l)| format!("{l}\n"))
                .collect();
            let (p, _, _) = parse_with_errors(&[&text]);
            run_everything(&p);
            checked += 1;
        }
    }
    let mut m = crate::fuzz::Mutator::new(fixtures, 7);
    for _ in 0..800 {
        let text = m.next_input();
        let (p, _, _) = parse_with_errors(&[&text]);
        run_everything(&p);
        checked += 1;
    }
    assert!(checked > 800);
}
