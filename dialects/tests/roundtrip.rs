//! Property tests of the text form: random well-formed `tree` modules (arithmetic on every
//! scalar type with special float values, `if` with yields and early returns, `match` with
//! variant and wildcard arms, `foreach`, calls, tuples, vectors, fields, references) verify,
//! print, parse back and print identically; the generic passes keep them valid; and mangled
//! text never makes the parser, verifier or printer panic. The generator is in `common/`.

use proptest::prelude::*;
use scion_ir::diag::FileId;
use scion_ir::{parse_module, print_module, verify, PassCx, PassManager, PassRegistry};

use crate::common;
use common::random_module;

proptest! {
    #![proptest_config(ProptestConfig { cases: std::env::var("PROPTEST_CASES").ok().and_then(|c| c.parse().ok()).unwrap_or(300), ..ProptestConfig::default() })]

    #[test]
    fn print_parse_print_is_identity(seed in any::<u64>()) {
        let m = random_module(seed);
        if let Err(e) = verify(&m) {
            panic!("generator made invalid IR: {e}");
        }
        let text = print_module(&m);
        let back = match parse_module(&text, FileId(0)) {
            Ok(b) => b,
            Err(d) => panic!("{:?}\n{text}", d),
        };
        if let Err(e) = verify(&back) {
            panic!("parsed module fails verification: {e}");
        }
        prop_assert_eq!(print_module(&back), text);
    }

    #[test]
    fn generic_passes_keep_modules_valid(seed in any::<u64>()) {
        let mut m = random_module(seed);
        let reg = PassRegistry::with_builtin();
        let mut pm = PassManager::parse(&reg, "const-fold,dce,const-fold").unwrap();
        let mut sink = String::new();
        if let Err(e) = pm.run(&mut m, &mut PassCx::new(), &mut sink) {
            panic!("{e:?}");
        }
        let text = print_module(&m);
        let back = parse_module(&text, FileId(0)).unwrap();
        prop_assert_eq!(print_module(&back), text);
    }

    #[test]
    fn mangled_text_never_panics(seed in any::<u64>(), cut in any::<u16>(), len in 0usize..40, junk in "[(){}%^@!<>,:=\"a-z0-9. \\n-]{0,8}") {
        let text = print_module(&random_module(seed));
        let mut bytes: Vec<u8> = text.into_bytes();
        let at = (cut as usize) % (bytes.len() + 1);
        let end = (at + len).min(bytes.len());
        bytes.splice(at..end, junk.bytes());
        let mangled = String::from_utf8_lossy(&bytes).into_owned();
        if let Ok(m) = parse_module(&mangled, FileId(0)) {
            let _ = verify(&m).map_err(|e| e.to_string());
            let _ = print_module(&m);
        }
    }

    /// Damaged arenas (operands, results, regions and block lists pointing anywhere, in range
    /// or not) are reported by the verifier, never a panic of the verifier or the printer.
    #[test]
    fn damaged_modules_never_panic_the_verifier(seed in any::<u64>(), edits in proptest::collection::vec((any::<u8>(), any::<u32>(), any::<u32>()), 1..6)) {
        let mut m = random_module(seed);
        let nops = m.ops.len() as u32;
        for (what, a, b) in edits {
            let op = scion_ir::OpId::from_raw(la_arena::RawIdx::from(a % nops.max(1)));
            let wild = b % (m.values.len() as u32 + 3);
            match what % 5 {
                0 if !m.ops[op].operands.is_empty() => {
                    let i = b as usize % m.ops[op].operands.len();
                    m.ops[op].operands[i] = scion_ir::ValueId::from_raw(la_arena::RawIdx::from(wild));
                }
                1 if !m.ops[op].results.is_empty() => {
                    m.ops[op].results[0] = scion_ir::ValueId::from_raw(la_arena::RawIdx::from(wild));
                }
                2 => m.ops[op].regions.push(scion_ir::RegionId::from_raw(la_arena::RawIdx::from(b % (m.regions.len() as u32 + 2)))),
                3 => {
                    let blk = scion_ir::BlockId::from_raw(la_arena::RawIdx::from(b % m.blocks.len() as u32));
                    m.blocks[blk].ops.push(op);
                }
                _ => {
                    let blk = scion_ir::BlockId::from_raw(la_arena::RawIdx::from(b % m.blocks.len() as u32));
                    m.blocks[blk].ops.clear();
                }
            }
        }
        let _ = verify(&m).map_err(|e| e.to_string());
        let _ = print_module(&m);
    }
}

#[test]
fn generator_covers_the_interesting_ops() {
    let mut seen = std::collections::BTreeSet::new();
    for seed in 0..200u64 {
        let text = print_module(&random_module(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15)));
        for op in [
            "tree.if",
            "tree.match",
            "tree.foreach",
            "tree.call",
            "tree.return\"(",
            "nan(",
            "-0.0",
            "tree.yield",
        ] {
            if text.contains(op) {
                seen.insert(op);
            }
        }
    }
    assert_eq!(seen.len(), 8, "{seen:?}");
    if std::env::var("SHOW_SAMPLE").is_ok() {
        println!("{}", print_module(&random_module(12345)));
    }
}
