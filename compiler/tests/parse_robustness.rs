//! The parser never panics and always terminates: random token soups, random mutations of the
//! library files (tokens and bytes deleted, inserted, swapped) and pathological nesting.
//! Errors are fine; a panic, a hang or a stack overflow is a bug.

use crate::common;

use common::{library_files, parse_str};
use proptest::prelude::*;
use scion_compiler::fuzz::DICTIONARY;
use scion_compiler::syntax::print::print_program;

/// Lexer edge cases added to the front-end fuzzer's dictionary ([`DICTIONARY`]: every keyword,
/// operator and construct): malformed literals and vector words, stray characters.
const LEXER_EDGES: &[&str] = &[
    "u8x0",
    "42",
    "1_000",
    "2.5e+8",
    "0x",
    "1e",
    "99999999999999999999999999999999999999999",
    "//c\n",
    "@",
];

/// Fragments that exercise every token kind and every construct's keyword.
fn fragments() -> Vec<&'static str> {
    DICTIONARY.iter().chain(LEXER_EDGES).copied().collect()
}

/// Parses `src`, and when it parses cleanly, checks that its printed form does too.
fn check(src: &str) {
    let (program, diags, _) = parse_str("fuzz.scion", src);
    for d in &diags.list {
        assert!(
            d.code.as_deref().is_some_and(|c| c.starts_with("E01")),
            "{d}"
        );
        assert!(d.primary_span().is_some(), "{d} has no primary span");
    }
    if diags.is_empty() {
        let printed = print_program(&program);
        let (_, again, sources) = parse_str("printed.scion", &printed);
        assert!(
            again.is_empty(),
            "{src}\nprinted as\n{printed}\n{}",
            again.render(&sources)
        );
    }
}

fn soup() -> impl Strategy<Value = String> {
    prop::collection::vec(prop::sample::select(fragments()), 0..60)
        .prop_map(|parts| parts.join(" "))
}

/// A library file with random edits: (file index, [(kind, position, fragment or byte)]).
fn mutation() -> impl Strategy<Value = (usize, Vec<(u8, usize, usize)>)> {
    (
        0usize..16,
        prop::collection::vec((0u8..5, 0usize..100_000, 0usize..1000), 1..6),
    )
}

fn mutate(text: &str, edits: &[(u8, usize, usize)]) -> String {
    let mut bytes = text.as_bytes().to_vec();
    for &(kind, at, what) in edits {
        if bytes.is_empty() {
            break;
        }
        let at = at % bytes.len();
        match kind {
            // Delete a run of bytes.
            0 => {
                let end = (at + what % 12 + 1).min(bytes.len());
                bytes.drain(at..end);
            }
            // Insert a fragment (a token).
            1 => {
                let fragments = fragments();
                let frag = fragments[what % fragments.len()];
                bytes.splice(at..at, frag.bytes().chain(std::iter::once(b' ')));
            }
            // Swap two bytes.
            2 => {
                let other = what % bytes.len();
                bytes.swap(at, other);
            }
            // Overwrite one byte with a printable ASCII byte.
            3 => bytes[at] = b' ' + (what % 95) as u8,
            // Duplicate a run (repeats a token or a whole line).
            _ => {
                let end = (at + what % 40 + 1).min(bytes.len());
                let run: Vec<u8> = bytes[at..end].to_vec();
                bytes.splice(at..at, run);
            }
        }
    }
    String::from_utf8_lossy(&bytes).into_owned()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn token_soup_never_panics(src in soup()) {
        check(&src);
    }

    #[test]
    fn mutated_library_files_never_panic((file, edits) in mutation()) {
        let files = library_files();
        let (_, text) = &files[file % files.len()];
        check(&mutate(text, &edits));
    }
}

#[test]
fn deep_nesting_is_an_error_not_a_stack_overflow() {
    let cases = [
        format!(
            "func f() = {}1{};",
            "(".repeat(100_000),
            ")".repeat(100_000)
        ),
        format!("func f() = {}1;", "-".repeat(5_000).replace("--", "- -")),
        format!("func f() = {}1{};", "f(".repeat(10_000), ")".repeat(10_000)),
        format!("func f() = {}{};", "{".repeat(10_000), "}".repeat(10_000)),
        format!(
            "func f(x: {}u8{}) = 0;",
            "(".repeat(10_000),
            ")".repeat(10_000)
        ),
        format!(
            "func f() = {}x{};",
            "if c { ".repeat(5_000),
            " }".repeat(5_000)
        ),
        format!("layout L() {{ {} }};", "group g { ".repeat(5_000)),
        format!("func f() = {}1;", "!".repeat(50_000)),
    ];
    for src in &cases {
        let (_, diags, _) = parse_str("deep.scion", src);
        assert!(
            diags
                .list
                .iter()
                .any(|d| d.code.as_deref() == Some("E0106")),
            "no E0106 for input starting {:?}: {:?}",
            &src[..40],
            diags.list.iter().map(|d| d.to_string()).collect::<Vec<_>>()
        );
        assert!(
            diags.len() <= 3,
            "too many errors after bailing: {}",
            diags.len()
        );
    }
}

#[test]
fn long_chains_are_bounded_and_long_lists_are_fine() {
    // A chain builds a left-deep tree: its length counts towards the nesting limit, so no
    // later recursive pass (or the tree's drop) can overflow the stack.
    for chain in ["1 + ", "x.", "y["] {
        let src = if chain == "y[" {
            format!("func f() = y{};", "[0]".repeat(50_000))
        } else {
            format!("func f() = {}x;", chain.repeat(50_000))
        };
        let (_, diags, _) = parse_str("chain.scion", &src);
        assert!(
            diags
                .list
                .iter()
                .any(|d| d.code.as_deref() == Some("E0106")),
            "{chain}"
        );
    }
    let block = format!("func f() = {{ {} }}", "x = 1; ".repeat(50_000));
    let (program, diags, _) = parse_str("flat.scion", &block);
    assert!(diags.is_empty());
    assert_eq!(program.node_count, 150_001);
}

#[test]
fn nesting_within_the_limit_parses() {
    let parens = format!("func f() = {}1{};", "(".repeat(200), ")".repeat(200));
    let blocks = format!("func f() = {}x{};", "{ ".repeat(120), " }".repeat(120));
    let sum = format!("func f() = {}1;", "1 + ".repeat(200));
    for src in [parens, blocks, sum] {
        let (_, diags, sources) = parse_str("ok.scion", &src);
        assert!(diags.is_empty(), "{}", diags.render(&sources));
    }
}
