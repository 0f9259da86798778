//! The two places that size types agree: the layout language's physical types
//! (`scion_compiler::layout::types`, sizing written types before any IR exists) and the IR's
//! plain-data layout (`scion_ir::data_layout`, what `mem-to-lo`, the interpreter and the C ABI
//! use). A record stored in a layout and the same record loaded by generated code must have one
//! size and alignment.

use crate::common;

use scion_compiler::layout::types::TypeEnv;
use scion_compiler::syntax::ast::{Ident, TypeExpr, TypeExprKind};
use scion_ir::diag::Span;

const TYPES: &str = r#"
type Mixed(a: u8, b: f64, c: u16, v: f32x3, t: (u8, u32), arr: u16[3], h: f16)
type Nested(m: Mixed, flag: bool, q: u8x4, tail: u8)
type Planes(lo: f32[8], hi: f32[8], link: u64[8])
func use_them(m: Mixed, n: Nested, p: Planes, a: AABB, t: Triangle) -> u32 = 0
"#;

#[test]
fn record_sizes_and_alignments_agree() {
    let prelude = std::fs::read_to_string(common::library_dir().join("prelude.scion")).unwrap();
    let text = format!("{prelude}\n{TYPES}");
    let (program, diags, sources) = common::parse_str("types.scion", &text);
    assert!(diags.is_empty(), "{}", diags.render(&sources));
    let env = TypeEnv::new(&program);
    let mut m = common::tree_module_of(&[("types.scion", TYPES)], true).unwrap();
    let mut checked = 0;
    for name in ["Mixed", "Nested", "Planes", "AABB", "Triangle", "Ray"] {
        let written = TypeExpr {
            kind: TypeExprKind::Named(Ident {
                name: name.to_string(),
                span: Span::default(),
            }),
            span: Span::default(),
        };
        let shape = env
            .shape(&written)
            .unwrap_or_else(|e| panic!("{name}: {}", e.message()));
        assert!(m.adt(name).is_some(), "{name} not in the module");
        let ty = m.types.adt(name);
        let (size, align) = scion_ir::data_layout::size_align(&m, ty).unwrap();
        assert_eq!((shape.size, shape.align), (size, align), "{name}");
        checked += 1;
    }
    assert_eq!(checked, 6);
}
