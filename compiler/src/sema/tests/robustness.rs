//! No input makes semantic analysis panic: mutated library sources are parsed and checked,
//! whatever the parser recovered.

use crate::fuzz::Mutator;
use crate::sema::check_program;
use crate::syntax::parse_program;
use scion_ir::diag::SourceMap;

const SEEDS: [&str; 4] = [
    super::PRELUDE,
    include_str!("../../../../library/algorithms/closest_hit.scion"),
    include_str!("../../../../library/layouts/pbrt.scion"),
    include_str!("../../../../library/layouts/ptr.scion"),
];

#[test]
fn mutated_inputs_never_panic() {
    let iterations: usize = std::env::var("SCION_SEMA_FUZZ")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(400);
    let mut m = Mutator::new(SEEDS.iter().map(|s| s.to_string()).collect(), 7);
    for i in 0..iterations {
        let input = m.next_input();
        let mut sm = SourceMap::new();
        let prelude = sm.add("prelude.scion", super::PRELUDE);
        let f = sm.add("fuzz.scion", input.clone());
        let (program, _) = parse_program(&sm, &[prelude, f]);
        let result = std::panic::catch_unwind(|| check_program(&program));
        assert!(
            result.is_ok(),
            "sema panicked on iteration {i}; input:\n{input}"
        );
    }
}

#[test]
fn deep_nesting_does_not_overflow() {
    for (open, close) in [
        ("(", ")"),
        ("- ", ""),
        ("abs(", ")"),
        ("min(1.0, ", ")"),
        ("{ ", " }"),
    ] {
        let depth = crate::syntax::parser::MAX_DEPTH / 2;
        let body = format!("{}1.0{}", open.repeat(depth), close.repeat(depth));
        let src = format!(
            "func f() = {body}\nfunc g(x: u32) = x + x + x {}",
            "+ x ".repeat(depth)
        );
        let mut sm = SourceMap::new();
        let f = sm.add("deep.scion", src);
        let (program, pdiags) = parse_program(&sm, &[f]);
        assert!(!pdiags.has_errors(), "{}", pdiags.render(&sm));
        let (_, diags) = check_program(&program);
        assert!(!diags.has_errors(), "{}", diags.render(&sm));
    }
}

/// Replaces one word (a name, a type, a number) of `text` by another, so that the result
/// usually still parses and reaches the checker with a plausible mistake.
fn swap_word(text: &str, rng: &mut crate::fuzz::Rng, words: &[&str]) -> String {
    let spans: Vec<(usize, usize)> = {
        let b = text.as_bytes();
        let mut out = Vec::new();
        let mut i = 0;
        while i < b.len() {
            if b[i].is_ascii_alphanumeric() || b[i] == b'_' {
                let s = i;
                while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_' || b[i] == b'.')
                {
                    i += 1;
                }
                out.push((s, i));
            } else if b[i] == b'/' && b.get(i + 1) == Some(&b'/') {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            } else {
                i += 1;
            }
        }
        out
    };
    if spans.is_empty() {
        return text.to_string();
    }
    let (s, e) = spans[rng.below(spans.len())];
    format!(
        "{}{}{}",
        &text[..s],
        words[rng.below(words.len())],
        &text[e..]
    )
}

/// Word swaps in the library: no panic, and whenever neither sema nor the structural checks
/// report an error, every expression has a complete type (what `irgen` relies on).
#[test]
fn word_swaps_never_panic_and_clean_programs_are_fully_typed() {
    let iterations: usize = std::env::var("SCION_SEMA_FUZZ")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(300);
    let words = [
        "u8",
        "u16",
        "u32",
        "u64",
        "i32",
        "f32",
        "f64",
        "bool",
        "f32x3",
        "u16x3",
        "ptr",
        "AABB",
        "Ray",
        "Triangle",
        "BVH",
        "Leaf",
        "Interior",
        "bounds",
        "left",
        "right",
        "nprims",
        "data",
        "I",
        "N",
        "P",
        "p_o",
        "c_o",
        "this",
        "x",
        "0",
        "1",
        "2.0",
        "65536",
        "min",
        "dot",
        "intersects",
        "distmin",
        "best",
        "ray",
        "t",
        "inf",
        "true",
    ];
    let mut rng = crate::fuzz::Rng::new(11);
    let (mut parsed, mut clean) = (0, 0);
    for i in 0..iterations {
        let which = rng.below(SEEDS.len());
        let mut text = SEEDS[which].to_string();
        for _ in 0..1 + rng.below(2) {
            text = swap_word(&text, &mut rng, &words);
        }
        let mut sm = SourceMap::new();
        let prelude = sm.add("prelude.scion", super::PRELUDE);
        let files = if which == 0 {
            vec![sm.add("fuzz.scion", text.clone())]
        } else {
            vec![prelude, sm.add("fuzz.scion", text.clone())]
        };
        let (program, pdiags) = parse_program(&sm, &files);
        if pdiags.has_errors() {
            continue;
        }
        parsed += 1;
        let result = std::panic::catch_unwind(|| {
            let (typed, diags) = check_program(&program);
            let models = crate::layout::model::Models::inferred(&program);
            let layout = crate::layout::check_layout::check_layouts(&program, &models);
            let build = crate::layout::check_build::check_builds(&program, &models);
            (
                typed,
                diags.has_errors() || layout.has_errors() || build.has_errors(),
            )
        });
        let Ok((typed, failed)) = result else {
            panic!("panicked on iteration {i}; input:\n{text}");
        };
        if !failed {
            clean += 1;
            let bad = typed
                .expr_types
                .values()
                .any(|t| t.has_vars() || t.has_error());
            assert!(
                !bad,
                "no error reported but a type is incomplete on iteration {i}:\n{text}"
            );
        }
    }
    eprintln!("{iterations} swaps: {parsed} parsed, {clean} without errors");
    assert!(
        parsed > iterations / 4,
        "the swaps rarely parse: {parsed} of {iterations}"
    );
}
