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
