//! Every library file parses with zero diagnostics, and printing is a fixed point:
//! parse(print(parse(src))) is the same tree (up to spans and ids) and prints identically.

use crate::common;

use common::{library_files, parse_str, strip_positions};
use scion_compiler::syntax::print::print_program;

#[test]
fn every_library_file_parses_cleanly() {
    let files = library_files();
    assert!(files.len() >= 4, "library files not found: {files:?}");
    for (path, text) in &files {
        let (program, diags, sources) = parse_str(path, text);
        assert!(diags.is_empty(), "{path}:\n{}", diags.render(&sources));
        assert!(!program.items.is_empty(), "{path}: no items");
    }
}

#[test]
fn printing_library_files_round_trips() {
    for (path, text) in library_files() {
        let (first, _, _) = parse_str(&path, &text);
        let printed = print_program(&first);
        let (second, diags, sources) = parse_str("printed.scion", &printed);
        assert!(
            diags.is_empty(),
            "{path} printed:\n{printed}\n{}",
            diags.render(&sources)
        );
        assert_eq!(
            strip_positions(&format!("{:?}", first.items)),
            strip_positions(&format!("{:?}", second.items)),
            "{path}: the printed program parses to a different tree:\n{printed}"
        );
        assert_eq!(
            print_program(&second),
            printed,
            "{path}: printing is not a fixed point"
        );
    }
}

#[test]
fn whole_library_as_one_program_has_distinct_node_ids() {
    use scion_compiler::syntax::parse_program;
    use scion_ir::diag::SourceMap;
    let mut sources = SourceMap::new();
    let ids: Vec<_> = library_files()
        .into_iter()
        .map(|(path, text)| sources.add(path, text))
        .collect();
    let (program, diags) = parse_program(&sources, &ids);
    assert!(diags.is_empty(), "{}", diags.render(&sources));
    let debug = format!("{:?}", program.items);
    let mut seen = std::collections::BTreeSet::new();
    for chunk in debug.split("NodeId(").skip(1) {
        let n: u32 = chunk[..chunk.find(')').unwrap()].parse().unwrap();
        assert!(seen.insert(n), "NodeId({n}) used twice");
        assert!(
            n < program.node_count,
            "NodeId({n}) >= node_count {}",
            program.node_count
        );
    }
    assert_eq!(seen.len() as u32, program.node_count, "ids are not dense");
}

#[test]
fn identifier_spans_cover_their_names() {
    for (path, text) in library_files() {
        let (program, _, _) = parse_str(&path, &text);
        let debug = format!("{:?}", program.items);
        let mut checked = 0;
        for chunk in debug.split("Ident { name: \"").skip(1) {
            let name = &chunk[..chunk.find('"').unwrap()];
            let start: usize = field(chunk, "start: ");
            let end: usize = field(chunk, "end: ");
            let written = &text[start..end];
            // A vector word `f32x3` is one token: its element type's Ident spans the word.
            assert!(
                written == name
                    || written.starts_with(name) && written[name.len()..].starts_with('x'),
                "{path}: Ident `{name}` spans `{written}`"
            );
            checked += 1;
        }
        assert!(checked > 10, "{path}: only {checked} identifiers");
    }
}

fn field(chunk: &str, key: &str) -> usize {
    let at = chunk.find(key).unwrap() + key.len();
    let digits: String = chunk[at..]
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    digits.parse().unwrap()
}

/// Every expression's span, read back and parsed alone, gives the same expression.
#[test]
fn expression_spans_cover_their_expressions() {
    use scion_compiler::syntax::ast::*;
    use scion_compiler::syntax::print::print_expr;

    fn sub_exprs<'a>(e: &'a Expr, out: &mut Vec<&'a Expr>) {
        out.push(e);
        match &e.kind {
            ExprKind::Call { args: xs, .. } | ExprKind::Tuple(xs) | ExprKind::Array(xs) => {
                xs.iter().for_each(|x| sub_exprs(x, out))
            }
            ExprKind::Field { base: x, .. }
            | ExprKind::Unary { operand: x, .. }
            | ExprKind::Cast { expr: x, .. }
            | ExprKind::BitCast { expr: x, .. } => sub_exprs(x, out),
            ExprKind::Index { base, index } => {
                sub_exprs(base, out);
                sub_exprs(index, out);
            }
            ExprKind::Slice { base, lo, hi } => {
                sub_exprs(base, out);
                sub_exprs(lo, out);
                sub_exprs(hi, out);
            }
            ExprKind::Binary { lhs, rhs, .. } => {
                sub_exprs(lhs, out);
                sub_exprs(rhs, out);
            }
            _ => {}
        }
    }
    fn stmt_exprs<'a>(s: &'a Stmt, out: &mut Vec<&'a Expr>) {
        match &s.kind {
            StmtKind::Expr(e) | StmtKind::Return(Some(e)) | StmtKind::Let { value: e, .. } => {
                sub_exprs(e, out)
            }
            StmtKind::Build { value: Some(e), .. } => sub_exprs(e, out),
            StmtKind::Assign { target, value } => {
                sub_exprs(target, out);
                sub_exprs(value, out);
            }
            StmtKind::Block(stmts) => stmts.iter().for_each(|s| stmt_exprs(s, out)),
            StmtKind::Match { scrutinee, arms } => {
                sub_exprs(scrutinee, out);
                arms.iter().for_each(|a| stmt_exprs(&a.body, out));
            }
            StmtKind::If {
                branches,
                otherwise,
            } => {
                for (c, b) in branches {
                    sub_exprs(c, out);
                    stmt_exprs(b, out);
                }
                otherwise.iter().for_each(|o| stmt_exprs(o, out));
            }
            StmtKind::Foreach { iter, body, .. } => {
                sub_exprs(iter, out);
                stmt_exprs(body, out);
            }
            StmtKind::Return(None) | StmtKind::Build { value: None, .. } => {}
        }
    }
    fn member_exprs<'a>(m: &'a Member, out: &mut Vec<&'a Expr>) {
        match &m.kind {
            MemberKind::Derived { value: e, .. } | MemberKind::Let { value: e, .. } => {
                sub_exprs(e, out)
            }
            MemberKind::Group(g) => {
                for a in &g.attrs {
                    if let GroupAttrKind::Size(e) = &a.kind {
                        sub_exprs(e, out);
                    }
                }
                g.by.iter().for_each(|e| sub_exprs(e, out));
                g.members.iter().for_each(|m| member_exprs(m, out));
            }
            MemberKind::Split { discriminant, arms } => {
                sub_exprs(discriminant, out);
                for arm in arms {
                    match &arm.body {
                        SplitArmBody::Members { members, .. } => {
                            members.iter().for_each(|m| member_exprs(m, out))
                        }
                        SplitArmBody::From { key, .. } => sub_exprs(key, out),
                    }
                }
            }
            MemberKind::Field { .. } | MemberKind::Padding { .. } | MemberKind::Separator => {}
        }
    }

    for (path, text) in library_files() {
        let (program, _, _) = parse_str(&path, &text);
        let mut exprs = Vec::new();
        for item in &program.items {
            match item {
                Item::Func(f) => stmt_exprs(&f.body, &mut exprs),
                Item::Layout(l) => l.members.iter().for_each(|m| member_exprs(m, &mut exprs)),
                Item::Build(b) => {
                    b.root
                        .iter()
                        .flat_map(|r| &r.body)
                        .for_each(|s| stmt_exprs(s, &mut exprs));
                    b.variants
                        .iter()
                        .flat_map(|v| &v.body)
                        .for_each(|s| stmt_exprs(s, &mut exprs));
                }
                Item::Type(t) => t
                    .fields
                    .iter()
                    .filter_map(|f| f.default.as_ref())
                    .for_each(|e| sub_exprs(e, &mut exprs)),
            }
        }
        assert!(!exprs.is_empty(), "{path}: no expressions");
        for e in exprs {
            let snippet = &text[e.span.start as usize..e.span.end as usize];
            let (alone, diags, _) = parse_str("snippet.scion", &format!("func f() = ({snippet});"));
            assert!(
                diags.is_empty(),
                "{path}: span text `{snippet}` does not parse"
            );
            let Item::Func(f) = &alone.items[0] else {
                unreachable!()
            };
            let StmtKind::Expr(again) = &f.body.kind else {
                unreachable!()
            };
            assert_eq!(
                print_expr(again),
                print_expr(e),
                "{path}: span text `{snippet}`"
            );
        }
    }
}
