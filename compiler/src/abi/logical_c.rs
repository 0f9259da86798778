//! The logical tree in C (`--emit=header`): the node struct of the layout's tree type and its
//! `ScionLogicalSchema`, both from [`LogicalAbi`], so that a C program fills nodes that
//! `scion_L_build` reads, or asks the runtime for them (`scion_tree_view(tree, &schema, ..)`).

use crate::layout::logical::{LogicalAbi, LogicalField, Slot};
use scion_ir::types::Type;
use scion_ir::Module;
use scion_runtime::bvh::schema::{Role, SHARED};
use std::fmt::Write;

/// The C name of the node struct of tree type `adt`.
pub fn node_struct(adt: &str) -> String {
    format!("ScionLogical_{adt}")
}

/// The C name of the schema constant of tree type `adt`.
pub fn schema_const(adt: &str) -> String {
    format!("scion_logical_{adt}")
}

/// One field's C declaration and its size.
fn decl(m: &Module, name: &str, ty: scion_ir::TypeId, slot: &Slot) -> (String, u64) {
    match slot {
        Slot::Children { count: 1, .. } => (format!("uint32_t {name}; /* child: node index */"), 4),
        Slot::Children { count, .. } => (
            format!("uint32_t {name}[{count}]; /* children: node indices */"),
            4 * count,
        ),
        Slot::Prims { .. } => (
            format!("uint32_t {name}; /* first primitive in prims */"),
            4,
        ),
        Slot::Value { .. } => match m.types.get(ty) {
            // Oriented boxes (60 bytes each) or boxes.
            Type::Array { elem, len: Some(n) } => match scion_ir::data_layout::size_align(m, *elem)
            {
                Some((60, _)) => (
                    format!(
                        "float {name}[{n}][15]; /* oriented boxes: columns vx, vy, vz of M, \
                         then low x, y, z, high x, y, z of the box of M*x */"
                    ),
                    60 * n,
                ),
                _ => (
                    format!("float {name}[{n}][6]; /* boxes: low x, y, z, high x, y, z */"),
                    24 * n,
                ),
            },
            Type::Int(_) => {
                let (size, _) = scion_ir::data_layout::size_align(m, ty).unwrap_or((4, 4));
                (
                    format!("{} {name};", super::record::c_type(m.types.get(ty))),
                    size,
                )
            }
            // Bounds: an AABB, or a DOP-14 (layout::logical decides which the runtime fills).
            _ => match scion_ir::data_layout::size_align(m, ty) {
                Some((56, _)) => (
                    format!(
                        "float {name}[14]; /* DOP-14: min x, y, z, max x, y, z, min of x+y+z, \
                         x+y-z, x-y+z, x-y-z, max of the same */"
                    ),
                    56,
                ),
                _ => (
                    format!("float {name}[6]; /* box: low x, y, z, high x, y, z */"),
                    24,
                ),
            },
        },
    }
}

/// Writes `fields` (starting at byte `at`) with explicit padding, each line indented by
/// `indent`; records `(prefix + name, offset)` for the offset assertions; returns the end.
fn emit_fields(
    s: &mut String,
    m: &Module,
    fields: &[LogicalField],
    mut at: u64,
    indent: &str,
    prefix: &str,
    asserts: &mut Vec<(String, u64)>,
) -> u64 {
    for (pad, f) in fields.iter().enumerate() {
        let o = f.slot.offset();
        if o > at {
            let _ = writeln!(s, "{indent}uint8_t _pad{pad}[{}];", o - at);
        }
        let (d, size) = decl(m, &f.name, f.ty, &f.slot);
        let _ = writeln!(s, "{indent}{d}");
        asserts.push((format!("{prefix}{}", f.name), o));
        at = o + size;
    }
    at
}

/// The node struct and the schema constant of `abi`, guarded by the tree type's name so that
/// the headers of several layouts of one tree type can be included together.
pub fn render(abi: &LogicalAbi, m: &Module) -> String {
    let adt = &abi.adt;
    let st = node_struct(adt);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "#ifndef SCION_LOGICAL_{adt}_DEFINED\n#define SCION_LOGICAL_{adt}_DEFINED"
    );
    let kinds: Vec<String> = abi
        .variants
        .iter()
        .enumerate()
        .map(|(k, v)| format!("{k} {}", v.0))
        .collect();
    let _ = writeln!(
        s,
        "/* A node of the logical tree of `{adt}` ({} bytes, align {}), as scion_*_build reads\n \
         * it; fields of another variant than `kind`'s are unused. */",
        abi.node_size, abi.node_align
    );
    let _ = writeln!(s, "typedef struct {st} {{");
    let _ = writeln!(s, "    uint32_t kind; /* {} */", kinds.join(", "));
    let mut asserts = vec![(String::from("kind"), 0u64)];
    let shared = &abi.variants[0].1[..abi.shared];
    let at = emit_fields(&mut s, m, shared, 4, "    ", "", &mut asserts);
    let own: Vec<_> = abi
        .variants
        .iter()
        .filter(|v| v.1.len() > abi.shared)
        .collect();
    if !own.is_empty() {
        let base = abi.variant_base;
        if base > at {
            let _ = writeln!(s, "    uint8_t _pad_u[{}];", base - at);
        }
        let _ = writeln!(s, "    union {{");
        for (vname, fields) in &own {
            let _ = writeln!(s, "        struct {{");
            let fields = &fields[abi.shared..];
            let prefix = format!("u.{vname}.");
            emit_fields(
                &mut s,
                m,
                fields,
                base,
                "            ",
                &prefix,
                &mut asserts,
            );
            let _ = writeln!(s, "        }} {vname};");
        }
        let _ = writeln!(s, "    }} u;");
    }
    let _ = writeln!(s, "}} {st};");
    let _ = writeln!(
        s,
        "SCION_STATIC_ASSERT(sizeof({st}) == {}, \"{st} is {} bytes\");",
        abi.node_size, abi.node_size
    );
    for (f, o) in asserts {
        let _ = writeln!(
            s,
            "SCION_STATIC_ASSERT(offsetof({st}, {f}) == {o}, \"{st}.{f} at {o}\");"
        );
    }
    let sc = schema_const(adt);
    let _ = writeln!(
        s,
        "/* What the runtime writes where (scion_tree_view(tree, &{sc}, &view, ..)). */"
    );
    let _ = writeln!(s, "static const ScionLogicalField {sc}_fields[] = {{");
    for f in &abi.schema.fields {
        let role = Role::from_u32(f.role).map_or("0", |r| r.c_name());
        let variant = if f.variant == SHARED {
            "SCION_SHARED".to_string()
        } else {
            f.variant.to_string()
        };
        let _ = writeln!(
            s,
            "    {{{role}, {variant}, {}, {}, {}, {}}},",
            f.offset, f.slot, f.count, f.width
        );
    }
    let _ = writeln!(s, "}};");
    let sch = &abi.schema;
    let _ = writeln!(
        s,
        "static const ScionLogicalSchema {sc} = {{{}, {}, {}, {}, {}, {}, {sc}_fields, {}}};",
        sch.node_size,
        sch.node_align,
        sch.interior,
        sch.leaf,
        sch.arity,
        sch.fields.len(),
        primitive_c_name(&sch.primitive)
    );
    let _ = writeln!(s, "#endif");
    s
}

/// The `SCION_PRIM_*` constant of the runtime's primitive type `name` (the schema's
/// `primitive`, one of `scion_runtime::primitive::PRIMITIVE_TYPES`; a name without one, which
/// the test below rules out, gives a value `scion_tree_view` rejects with an error).
fn primitive_c_name(name: &str) -> &'static str {
    match name {
        "Triangle" => "SCION_PRIM_TRIANGLE",
        "Segment" => "SCION_PRIM_SEGMENT",
        "Triangle4" => "SCION_PRIM_TRIANGLE4",
        _ => "0xFFFFFFFFu",
    }
}

#[cfg(test)]
mod primitive_tests {
    #[test]
    fn every_runtime_primitive_has_a_c_constant() {
        for (name, _) in scion_runtime::primitive::PRIMITIVE_TYPES {
            assert!(
                super::primitive_c_name(name).starts_with("SCION_PRIM_"),
                "{name}"
            );
        }
    }
}
