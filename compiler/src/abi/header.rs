//! The C header of `scionc --emit=header --layout L --entry A` (docs/design/backends.md §2).
//!
//! Input: the [`EntrySig`] and the root reference type. Output: a
//! self-contained C99/C++ header: the runtime contract's structs (shared with the runtime's
//! `scion_runtime.h` under the guard `SCION_ABI_TYPES_DEFINED`) with size assertions, the
//! buffer count and alignment, one comment per buffer, the query and result records with size
//! and offset assertions, the status codes and the prototypes of the exported functions.

use super::record::{c_type, Record};
use super::EntrySig;
use scion_ir::types::Type;
use std::fmt::Write;

/// The runtime contract's structs (docs/design/specialization.md §3.1), guarded so that
/// several generated headers and `scion_runtime.h` can be included together.
pub const CONTRACT_TYPES: &str = "\
#ifndef SCION_ABI_TYPES_DEFINED
#define SCION_ABI_TYPES_DEFINED
/* A triangle (40 bytes), the same in the logical tree and in packed layouts. */
typedef struct ScionTriangle {
    float p0[3];
    float p1[3];
    float p2[3];
    uint32_t id;
} ScionTriangle;
/* A strand segment (36 bytes): the axis from p0 to p1, radius r0 at p0 and r1 at p1. */
typedef struct ScionSegment {
    float p0[3];
    float r0;
    float p1[3];
    float r1;
    uint32_t id;
} ScionSegment;
/* Four triangles stored lane by lane (160 bytes): each coordinate of each corner an array over
 * the lanes; a block of fewer than four repeats its last triangle. */
typedef struct ScionTriangle4 {
    float x0[4], y0[4], z0[4];
    float x1[4], y1[4], z1[4];
    float x2[4], y2[4], z2[4];
    uint32_t id[4];
} ScionTriangle4;
/* The logical tree as generated code reads it (32 bytes): node_count nodes of the layout's
 * tree type (its ScionLogical_<Type> struct in the layout's header), 8-byte aligned. */
typedef struct ScionTreeView {
    const void *nodes;
    uint32_t node_count;
    uint32_t root; /* UINT32_MAX for the empty tree */
    const void *prims; /* prim_count records of the layout's primitive: ScionTriangle,
                          ScionSegment for a layout over strands, or ScionTriangle4 for one
                          over blocks of four triangles (its schema's primitive) */
    uint32_t prim_count;
} ScionTreeView;
/* What the runtime writes into a field of a logical node (docs/c-abi.md). */
#define SCION_ROLE_BOUNDS 1       /* the node's box: float[6] */
#define SCION_ROLE_CHILD_BOUNDS 2 /* the boxes of child slots slot..slot+count: float[count][6] */
#define SCION_ROLE_CHILDREN 3     /* child slots slot..slot+count: uint32_t node indices */
#define SCION_ROLE_PRIM_COUNT 4   /* a leaf's primitive count: an unsigned int of width bytes */
#define SCION_ROLE_PRIM_OFFSET 5  /* a leaf's first primitive: uint32_t */
#define SCION_ROLE_DOP14_BOUNDS 6 /* the node's DOP-14: float[14], axis mins, maxes, diagonal mins, maxes */
#define SCION_ROLE_CHILD_OBBS 7   /* oriented boxes of child slots: float[count][15], columns vx, vy, vz of M, then the box of M*x */
#define SCION_SHARED 0xFFFFFFFFu  /* `variant` of a field every variant has */
typedef struct ScionLogicalField {
    uint32_t role, variant, offset, slot, count, width;
} ScionLogicalField;
/* What a tree type's leaves hold (ScionLogicalSchema.primitive; ScionTreeView.prims). */
#define SCION_PRIM_TRIANGLE 0  /* ScionTriangle */
#define SCION_PRIM_SEGMENT 1   /* ScionSegment (strands) */
#define SCION_PRIM_TRIANGLE4 2 /* ScionTriangle4 (the tree's leaves cut into blocks of four) */
/* The shape of a tree type's logical nodes (its scion_logical_<Type> constant). */
typedef struct ScionLogicalSchema {
    uint32_t node_size, node_align, interior, leaf, arity, field_count;
    const ScionLogicalField *fields;
    uint32_t primitive; /* SCION_PRIM_* */
} ScionLogicalSchema;
SCION_STATIC_ASSERT(sizeof(ScionTriangle) == 40, \"ScionTriangle is 40 bytes\");
SCION_STATIC_ASSERT(sizeof(ScionSegment) == 36, \"ScionSegment is 36 bytes\");
SCION_STATIC_ASSERT(sizeof(ScionTriangle4) == 160, \"ScionTriangle4 is 160 bytes\");
SCION_STATIC_ASSERT(sizeof(ScionTreeView) == 32, \"ScionTreeView is 32 bytes\");
SCION_STATIC_ASSERT(offsetof(ScionTreeView, root) == 12, \"ScionTreeView.root at 12\");
SCION_STATIC_ASSERT(offsetof(ScionTreeView, prims) == 16, \"ScionTreeView.prims at 16\");
SCION_STATIC_ASSERT(sizeof(ScionLogicalField) == 24, \"ScionLogicalField is 24 bytes\");
SCION_STATIC_ASSERT(sizeof(ScionLogicalSchema) == 40, \"ScionLogicalSchema is 40 bytes\");
SCION_STATIC_ASSERT(offsetof(ScionLogicalSchema, primitive) == 32, \"ScionLogicalSchema.primitive at 32\");
#endif
";

/// The `SCION_STATIC_ASSERT` macro for C11/C++11 and older compilers.
const STATIC_ASSERT: &str = "\
#ifndef SCION_STATIC_ASSERT
#if defined(__cplusplus)
#define SCION_STATIC_ASSERT(c, msg) static_assert(c, msg)
#elif defined(__STDC_VERSION__) && __STDC_VERSION__ >= 201112L
#define SCION_STATIC_ASSERT(c, msg) _Static_assert(c, msg)
#else
#define SCION_STATIC_ASSERT_CAT2(a, b) a##b
#define SCION_STATIC_ASSERT_CAT(a, b) SCION_STATIC_ASSERT_CAT2(a, b)
#define SCION_STATIC_ASSERT(c, msg) \\
    typedef char SCION_STATIC_ASSERT_CAT(scion_static_assert_, __LINE__)[(c) ? 1 : -1]
#endif
#endif
";

fn record(out: &mut String, name: &str, what: &str, r: &Record) {
    let _ = writeln!(out, "/* {what} ({} bytes, align {}). */", r.size, r.align);
    let _ = writeln!(out, "typedef struct {name} {{");
    let mut at = 0;
    let mut pad = 0;
    for f in &r.fields {
        if f.offset > at {
            let _ = writeln!(out, "    uint8_t _pad{pad}[{}];", f.offset - at);
            pad += 1;
        }
        let _ = writeln!(
            out,
            "    {} {}; /* offset {} */",
            c_type(&f.ty),
            f.name,
            f.offset
        );
        at = f.offset + scalar_size(&f.ty);
    }
    if r.fields.is_empty() {
        // C has no empty structs; the entries never read this byte.
        let _ = writeln!(out, "    uint8_t _unused;");
    } else if r.size > at {
        let _ = writeln!(out, "    uint8_t _pad{pad}[{}];", r.size - at);
    }
    let _ = writeln!(out, "}} {name};");
    if !r.fields.is_empty() {
        let _ = writeln!(
            out,
            "SCION_STATIC_ASSERT(sizeof({name}) == {}, \"{name} is {} bytes\");",
            r.size, r.size
        );
        for f in &r.fields {
            let _ = writeln!(
                out,
                "SCION_STATIC_ASSERT(offsetof({name}, {}) == {}, \"{name}.{} at {}\");",
                f.name, f.offset, f.name, f.offset
            );
        }
    }
}

/// The size of a record field (a scalar leaf; pointers and references are 8 bytes).
fn scalar_size(ty: &Type) -> u64 {
    scion_ir::data_layout::scalar_type_size(ty).unwrap_or(8)
}

/// The header text. `root` is the layout's reference type (an integer or `ptr`).
pub fn render(sig: &EntrySig, root: &Type) -> String {
    let (a, l) = (&sig.algorithm, &sig.layout);
    let guard = format!("SCION_{a}_{l}_H");
    let root_c = c_type(root);
    let upper = l.to_string();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "/* Generated by scionc: the C ABI of `{a}` specialized to layout `{l}`.\n \
         * See docs/c-abi.md. Do not edit. */"
    );
    let _ = writeln!(s, "#ifndef {guard}\n#define {guard}\n");
    s.push_str("#include <stddef.h>\n#include <stdint.h>\n\n");
    s.push_str(STATIC_ASSERT);
    s.push_str("\n#ifdef __cplusplus\nextern \"C\" {\n#endif\n\n");
    s.push_str(CONTRACT_TYPES);
    s.push('\n');
    s.push_str(&sig.logical_c);
    s.push('\n');
    s.push_str(
        "/* Status codes: 0 success; batch entries return 1 when a traversal stack overflowed. */\n\
         #ifndef SCION_OK\n#define SCION_OK 0\n#define SCION_STACK_OVERFLOW 1\n#endif\n",
    );
    let _ = writeln!(
        s,
        "/* scion_{l}_build returns 1 when a packed field got a value that does not fit its bits\n \
         * (the low bits are stored and packing goes on). */\n\
         #define SCION_{upper}_BUILD_FIELD_OVERFLOW 1\n"
    );
    let _ = writeln!(
        s,
        "/* The buffers of layout `{l}`, in the order of the table `B`. */"
    );
    let _ = writeln!(
        s,
        "#define SCION_{upper}_BUFFER_COUNT {}",
        sig.buffers.len()
    );
    let _ = writeln!(
        s,
        "#define SCION_{upper}_BUFFER_ALIGN {}",
        sig.buffer_align()
    );
    for (i, b) in sig.buffers.iter().enumerate() {
        let _ = writeln!(
            s,
            "/* buffer {i}: {} (element {} bytes, stride {}, align {}) */",
            b.name, b.elem_size, b.stride, b.align
        );
    }
    s.push('\n');
    let query = format!("scion_{a}_query");
    let result = format!("scion_{a}_result");
    // The records depend on the algorithm only: the headers of several layouts share them.
    let _ = writeln!(
        s,
        "#ifndef SCION_{a}_RECORDS_DEFINED\n#define SCION_{a}_RECORDS_DEFINED"
    );
    record(&mut s, &query, &format!("One query of `{a}`"), &sig.query);
    s.push('\n');
    record(
        &mut s,
        &result,
        &format!("One result of `{a}` (read and written)"),
        &sig.result,
    );
    s.push_str("#endif\n\n");
    let _ = writeln!(
        s,
        "/* The reference to a packed node of `{l}`. */\ntypedef {root_c} scion_{l}_ref;\n"
    );
    let _ = writeln!(
        s,
        "/* Writes the byte size of every buffer to sizes[0..SCION_{upper}_BUFFER_COUNT). */\n\
         void {}(const ScionTreeView *tree, uint64_t *sizes);",
        sig.layout_fn("sizes")
    );
    let _ = writeln!(
        s,
        "/* Packs the tree into the buffers B[i] (each sizes[i] bytes, aligned to\n \
         * SCION_{upper}_BUFFER_ALIGN); returns SCION_OK or a build status. */\n\
         int32_t {}(const ScionTreeView *tree, void *const *B);",
        sig.layout_fn("build")
    );
    let _ = writeln!(
        s,
        "/* The root reference of the tree packed by {} (0 for an empty tree, which has no\n \
         * packed node: do not run queries on it, they all miss). */\n\
         scion_{l}_ref {}(const ScionTreeView *tree, void *const *B);",
        sig.layout_fn("build"),
        sig.layout_fn("root")
    );
    // An algorithm over several trees takes each other tree's table and root after the first's.
    let more: String = (1..sig.trees())
        .map(|k| format!(",\n    void *const *B{k}, scion_{l}_ref root{k}"))
        .collect();
    let trees_note = if sig.trees() > 1 {
        format!(
            "\n * The {} trees of `{a}`, in the order of its parameters: (B, root), then (B1, root1)...",
            sig.trees()
        )
    } else {
        String::new()
    };
    let _ = writeln!(
        s,
        "/* Runs queries[begin..end) with results[begin..end) (in/out); stops at the first\n \
         * nonzero status and returns it, else SCION_OK. Thread-safe on disjoint ranges.{trees_note} */\n\
         int32_t {}(void *const *B, const {query} *queries, {result} *results,\n    \
         uint64_t begin, uint64_t end, scion_{l}_ref root{more});",
        sig.batch_fn()
    );
    let (batch, sizes, build, root) = (
        sig.batch_fn(),
        sig.layout_fn("sizes"),
        sig.layout_fn("build"),
        sig.layout_fn("root"),
    );
    let kmore: String = (1..sig.trees())
        .map(|k| format!(", B{k}, root{k}"))
        .collect();
    let _ = writeln!(
        s,
        "/* The kernels of `scionc --target nvptx64` live in the PTX, not in this object\n \
         * (docs/design/backends.md section 1; the batch kernel with 256 threads per block,\n \
         * the others one thread):\n \
         * {batch}_kernel(B, queries, results, uint64_t n, scion_{l}_ref root, int32_t *status{kmore});\n \
         * {sizes}_kernel(tree, sizes); {build}_kernel(tree, B, int32_t *status);\n \
         * {root}_kernel(tree, B, scion_{l}_ref *root). */"
    );
    s.push_str("\n#ifdef __cplusplus\n} /* extern \"C\" */\n#endif\n\n");
    let _ = writeln!(s, "#endif /* {guard} */");
    s
}
