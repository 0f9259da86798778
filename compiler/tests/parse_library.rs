//! Every library file parses with zero diagnostics, and printing is a fixed point:
//! parse(print(parse(src))) is the same tree (up to spans and ids) and prints identically.

mod common;

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
