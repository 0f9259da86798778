//! `scion-ir`: the intermediate representation shared by every level of the Scion compiler.
//!
//! This crate depends on nothing else of Scion's and on neither LLVM nor Cranelift. It holds
//! source positions and diagnostics ([`diag`]), the IR core, its dialects, its text form, its
//! verifier, the pass manager and a reference interpreter of the `tree` level ([`interp`]).
//!
//! # The shape of the IR
//!
//! The IR has MLIR's shape with Cranelift's storage. One generic container serves every level:
//!
//! - A [`Module`] holds functions, the table of algebraic data types (records, and sums whose
//!   variants share a prefix of fields: `BVH(bounds) = Interior(left, right) | Leaf(...)`), the
//!   interned types, and one arena each of regions, blocks, operations and values.
//! - A [`module::Func`] has a name, parameter and result types, and a body region whose entry
//!   block's arguments are the parameters.
//! - A [`module::Region`] is a list of blocks. `tree` (and later `mem`) regions are
//!   *structured*: one block, left only through its terminator (`tree.yield` back to the op
//!   that owns the region, or `tree.return` out of the function). `lo` regions will be CFGs:
//!   several blocks with arguments, linked by successors.
//! - A [`module::Block`] has arguments (values) and a list of operations; the last one is a
//!   terminator.
//! - An [`op::Operation`] has a kind ([`op::OpKind`], a closed enum per dialect: today
//!   [`tree::Op`]), operands, results, attributes ([`attr::Attrs`]), regions and successors.
//! - A value (`ValueId`) is an op's result or a block's argument, defined exactly once, with an
//!   interned type ([`types::Type`]: `i1`, `i8`..`u64`, floats, vectors, tuples, arrays and
//!   slices, sets, options, ADTs, references, `ptr`).
//!
//! Entities are referenced by typed ids ([`entity`]). Spans sit in a side table
//! ([`Module::spans`]), never in the ops, so op equality never sees positions. There are no
//! use-lists: replace-all-uses writes an alias map that the pass manager resolves after each
//! pass ([`rewrite`]). Analyses such as use counts are computed on demand ([`walk`]).
//!
//! # Levels
//!
//! `tree` is the layout-agnostic level produced from the typed AST: match on variants, field
//! reads, constructors, calls, structured control flow, loads and stores through `mut`
//! references. Destructor and constructor specialization lower it to `mem` (loads at resolved
//! byte offsets of a layout), and `mem` is lowered to `lo` (an SSA CFG the backends translate
//! one-to-one). Each level's ops are one enum in `dialects/src/<level>/`.
//!
//! # Invariants
//!
//! [`verify::verify`] checks them all; the pass manager runs it between passes:
//! every id exists; every region, block and op is listed once and its parent link is right;
//! every value is defined once and dominates its uses (in structured regions: defined earlier
//! in the same block or in an enclosing block); every block ends with a terminator and has
//! none elsewhere; each op's operands, results, attributes and regions follow its kind's rules.
//!
//! # Reading the text form
//!
//! ```text
//! tree.type @Pair(a: f32, b: f32)
//!
//! func @sum(%0: !tree.adt<"Pair">) -> (f32) {
//!   %1 = "tree.field"(%0) {index = 0, name = "a"} : (!tree.adt<"Pair">) -> f32
//!   %2 = "tree.field"(%0) {index = 1, name = "b"} : (!tree.adt<"Pair">) -> f32
//!   %3 = "tree.add"(%1, %2) : (f32, f32) -> f32
//!   "tree.return"(%3) : (f32) -> ()
//! }
//! ```
//!
//! Each op reads: results, `=`, the quoted op name, operands in parentheses, successors in
//! brackets, regions in parentheses (`({ ^bb1(%x: T): ... }, { ... })`), attributes in braces,
//! then `:` and the operand and result types. Values and blocks are numbered per function in
//! print order. Floats print exactly (`-0.0`, `inf`, `nan`, `nan(0x...)`). See [`mod@print`] and
//! [`parse`]; `docs/ir.md` lists every op.
//!
//! # Building IR
//!
//! ```
//! use scion_ir::module::{AdtDef, Field};
//! use scion_ir::tree::{CmpPred, Op};
//! use scion_ir::{print_module, verify, Builder, Module};
//!
//! let mut m = Module::new();
//! let f32t = m.types.f32();
//! let pair = m
//!     .declare_adt(AdtDef {
//!         name: "Pair".into(),
//!         shared: vec![Field { name: "a".into(), ty: f32t }, Field { name: "b".into(), ty: f32t }],
//!         variants: vec![],
//!     })
//!     .unwrap();
//! // func @larger(p: Pair) -> f32 = if p.a < p.b { p.b } else { p.a }
//! let (_f, entry) = m.add_func("larger", &[pair], &[f32t]);
//! let p = m.blocks[entry].args[0];
//! let mut b = Builder::at_end(&mut m, entry);
//! let a = b.field(p, "a").unwrap();
//! let bv = b.field(p, "b").unwrap();
//! let lt = b.cmp(CmpPred::Lt, a, bv);
//! let if_op = b.if_(lt, &[f32t], |b| { b.yield_(&[bv]); }, |b| { b.yield_(&[a]); });
//! let r = b.result(if_op, 0);
//! b.ret(&[r]);
//! verify(&m).unwrap();
//! let text = print_module(&m);
//! assert!(text.contains(r#""tree.if"(%3) ({"#));
//! let back = scion_ir::parse_module(&text, scion_ir::diag::FileId(0)).unwrap();
//! assert_eq!(print_module(&back), text);
//! # let _ = Op::Add;
//! ```

#![warn(missing_docs)]

/// docs/howto-add-a-backend.md, compiled and run as a doctest so the how-to follows the traits.
#[cfg(doctest)]
#[doc = include_str!("../../docs/howto-add-a-backend.md")]
pub struct HowtoAddABackend;

pub mod attr;
pub mod backend;
pub mod builder;
pub mod data_layout;
pub mod diag;
pub mod entity;
pub mod interp;
pub mod lo;
pub mod mem;
pub mod module;
pub mod op;
pub mod parse;
pub mod pass;
pub mod print;
pub mod rewrite;
pub mod transforms;
pub mod tree;
pub mod types;
pub mod verify;
pub mod walk;

pub use builder::{Builder, InsertPoint, OpSpec};
pub use entity::{BlockId, FuncId, OpId, RegionId, TypeId, ValueId};
pub use module::Module;
pub use op::{OpKind, Operation};
pub use parse::parse_module;
pub use pass::{Pass, PassCx, PassError, PassInfo, PassManager, PassRegistry, PipelineOptions};
pub use print::{print_func, print_module, print_op};
pub use types::Type;
pub use verify::{verify, VerifyErrors};
