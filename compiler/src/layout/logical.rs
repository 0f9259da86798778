//! The logical tree a layout's constructor reads, derived from the `type` declaration it
//! realizes: one description ([`LogicalAbi`]) from which the constructor's reader
//! (`constructor-specialize`), the C struct of `--emit=header` and the runtime's filler
//! (`scion_runtime::bvh::schema`, through [`LogicalAbi::schema`]) all follow.
//!
//! Input: the `tree` module's ADT (field types) and the layout model's ADT (array lengths by
//! name, `Triangle[nprims]`). Output: every variant's logical fields with their byte offsets
//! and what the runtime writes into them, or the reason the runtime cannot fill the type.
//!
//! Node form (the runtime's, `scion_runtime::bvh::schema`): `kind: u32` at 0 (the variant's
//! index), the shared fields, then each variant's fields from the same offset, at natural
//! alignment (`scion_ir::data_layout`). A child is a `u32` node index and an array of `n`
//! children `u32[n]`; a primitive array `Triangle[count]` is its first primitive (`u32`), its
//! length the integer field `count` names.

use crate::layout::model::Adt;
use crate::syntax::ast::{ArrayLen, TypeExprKind};
use scion_ir::data_layout::size_align;
use scion_ir::module::{AdtDef, Module};
use scion_ir::types::Type;
use scion_ir::TypeId;
use scion_runtime::bvh::schema::{Role, Schema, SchemaField, SHARED};
use scion_runtime::primitive::PRIMITIVE_TYPES;

/// How a logical field sits in a node.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Slot {
    /// Read as its own type at this offset (bounds, counts).
    Value {
        /// Byte offset in the node.
        offset: u64,
    },
    /// Child slots `first .. first + count`, `u32` indices from this offset (one child when
    /// the field is the tree type, `count` when it is an array of children).
    Children {
        /// Byte offset in the node.
        offset: u64,
        /// Number of children.
        count: u64,
    },
    /// A primitive array: its first primitive (`u32`) at `offset`, its length the logical
    /// field `count` of the same variant.
    Prims {
        /// Byte offset of the first-primitive index.
        offset: u64,
        /// Index (in the variant's logical fields) of the length field.
        count: usize,
    },
}

impl Slot {
    /// The byte offset in the node where the field starts.
    pub fn offset(&self) -> u64 {
        match self {
            Slot::Value { offset } | Slot::Children { offset, .. } | Slot::Prims { offset, .. } => {
                *offset
            }
        }
    }
}

/// The name a primitive array's length refers to (`nprims` in `Triangle[nprims]`), from the
/// declaration of `variant`'s field `field`.
fn length_name(model: &Adt, variant: &str, field: &str) -> Option<String> {
    let f = model
        .variant(variant)?
        .fields
        .iter()
        .find(|x| x.name.name == field)?;
    match &f.ty.kind {
        TypeExprKind::Array {
            len: ArrayLen::Name(n),
            ..
        } => Some(n.name.clone()),
        _ => None,
    }
}

/// One logical field of a variant.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LogicalField {
    /// Its name.
    pub name: String,
    /// Its logical type.
    pub ty: TypeId,
    /// Where it sits.
    pub slot: Slot,
}

/// The logical tree of one tree type.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LogicalAbi {
    /// The tree type's name.
    pub adt: String,
    /// Per variant (kind order): its name and logical fields, shared ones first.
    pub variants: Vec<(String, Vec<LogicalField>)>,
    /// Number of shared fields (the first of every variant's).
    pub shared: usize,
    /// Where the variants' own fields start.
    pub variant_base: u64,
    /// Kind of the (axis-aligned) interior variant.
    pub interior: usize,
    /// Kinds of every variant with children: `interior`, and an oriented one (child boxes
    /// of type `OBB[n]`) when the type has it.
    pub interiors: Vec<usize>,
    /// Kind of the leaf variant.
    pub leaf: usize,
    /// Bytes per node.
    pub node_size: u64,
    /// Alignment of a node.
    pub node_align: u64,
    /// The runtime's form of the same.
    pub schema: Schema,
}

/// The fields of record type `ty`, when it is a declared record.
fn record_fields(m: &Module, ty: TypeId) -> Option<&[scion_ir::module::Field]> {
    let Type::Adt(name) = m.types.get(ty) else {
        return None;
    };
    let def = m.adt(name)?;
    def.is_record().then_some(def.shared.as_slice())
}

/// Whether `t` is a vector of `lanes` `f32`s.
fn f32_vector(m: &Module, t: TypeId, lanes: u32) -> bool {
    matches!(m.types.get(t), Type::Vector { elem, lanes: n } if *n == lanes
        && matches!(m.types.get(*elem), Type::Float(f) if f.bits() == 32))
}

/// An axis-aligned box: two `f32x3` (low, high).
fn is_aabb(m: &Module, ty: TypeId) -> bool {
    record_fields(m, ty).is_some_and(|f| f.len() == 2 && f.iter().all(|x| f32_vector(m, x.ty, 3)))
}

/// A DOP-14 record: four vectors of `f32`, 3, 3, 4 and 4 lanes (axis minima and maxima, then
/// the minima and maxima along x+y+z, x+y−z, x−y+z, x−y−z; `scion_runtime::bvh::dop14`).
fn is_dop14(m: &Module, ty: TypeId) -> bool {
    record_fields(m, ty).is_some_and(|f| {
        f.len() == 4
            && f.iter()
                .zip([3, 3, 4, 4])
                .all(|(x, n)| f32_vector(m, x.ty, n))
    })
}

/// An oriented box record: three `f32x3` columns of a matrix `M`, then an `AABB` (the box of
/// `M·x`; `scion_runtime::bvh::oriented`).
fn is_obb(m: &Module, ty: TypeId) -> bool {
    record_fields(m, ty).is_some_and(|f| {
        f.len() == 4 && f[..3].iter().all(|x| f32_vector(m, x.ty, 3)) && is_aabb(m, f[3].ty)
    })
}

/// The runtime's name of primitive type `ty` (`Triangle`, `Segment`: a type of
/// `scion_runtime::primitive::PRIMITIVE_TYPES` with the runtime's record size), if it is one.
fn primitive_type(m: &Module, ty: TypeId) -> Option<&'static str> {
    let Type::Adt(n) = m.types.get(ty) else {
        return None;
    };
    PRIMITIVE_TYPES
        .iter()
        .find(|(name, size)| name == n && size_align(m, ty) == Some((*size, 4)))
        .map(|(name, _)| *name)
}

/// A type as the source writes it (`DOP14`, not `!tree.adt<"DOP14">`).
fn source_type(m: &Module, ty: TypeId) -> String {
    match m.types.get(ty) {
        Type::Adt(n) => n.clone(),
        Type::Array { elem, len: Some(n) } => format!("{}[{n}]", source_type(m, *elem)),
        Type::Array { elem, len: None } => format!("{}[]", source_type(m, *elem)),
        _ => m.types.display(ty).to_string(),
    }
}

fn align_up(x: u64, a: u64) -> u64 {
    x.div_ceil(a) * a
}

impl LogicalAbi {
    /// The logical tree of `adt` (the module's declaration of the model's ADT), or why the
    /// runtime cannot fill it.
    pub fn derive(m: &Module, model: &Adt) -> Result<LogicalAbi, String> {
        let name = &model.name;
        let def: &AdtDef = m
            .adt(name)
            .ok_or_else(|| format!("the tree type `{name}` is not declared"))?;
        let tree_ty = m.types.lookup(&Type::Adt(name.clone()));
        let is_tree = |t: TypeId| Some(t) == tree_ty;
        let children_of = |t: TypeId| -> Option<u64> {
            if is_tree(t) {
                return Some(1);
            }
            match m.types.get(t) {
                Type::Array { elem, len: Some(n) } if is_tree(*elem) => Some(*n),
                _ => None,
            }
        };
        let shape = |v: &scion_ir::module::Variant| {
            v.fields
                .iter()
                .filter_map(|f| children_of(f.ty))
                .sum::<u64>()
        };
        // One leaf variant; one axis-aligned interior variant and at most one oriented one
        // (child boxes `OBB[n]`), all of the same arity.
        let oriented_variant = |v: &scion_ir::module::Variant| {
            v.fields.iter().any(|f| {
                matches!(m.types.get(f.ty), Type::Array { elem, len: Some(_) } if is_obb(m, *elem))
            })
        };
        let leaves: Vec<usize> = (0..def.variants.len())
            .filter(|&k| shape(&def.variants[k]) == 0)
            .collect();
        let interiors: Vec<usize> = (0..def.variants.len())
            .filter(|&k| shape(&def.variants[k]) > 0)
            .collect();
        let aligned: Vec<usize> = interiors
            .iter()
            .copied()
            .filter(|&k| !oriented_variant(&def.variants[k]))
            .collect();
        let arity = interiors.first().map_or(0, |&k| shape(&def.variants[k]));
        let (interior, leaf) = match (&leaves[..], &aligned[..]) {
            ([l], [i])
                if interiors.len() <= 2
                    && interiors.iter().all(|&k| shape(&def.variants[k]) == arity) =>
            {
                (*i, *l)
            }
            _ => {
                return Err(format!(
                    "the runtime builds trees of one variant with primitives, one with children \
                     and at most one more with children and oriented child boxes (`OBB[n]`), of \
                     the same arity; `{name}` has {} variant(s) of another shape",
                    def.variants.len()
                ))
            }
        };
        let bad = |field: &str, what: String| Err(format!("`{name}`'s field `{field}`: {what}"));
        // Shared fields.
        let mut at = 4u64;
        let mut align = 4u64;
        let mut shared = Vec::new();
        let mut fields = Vec::new();
        for f in &def.shared {
            let (role, size) = if is_aabb(m, f.ty) {
                (Role::Bounds, 24)
            } else if is_dop14(m, f.ty) {
                (Role::Dop14Bounds, 56)
            } else {
                return bad(
                    &f.name,
                    format!(
                        "a shared field of type {} (the runtime's builders give each node an \
                         `AABB` box or a DOP-14 of four `f32` vectors of 3, 3, 4 and 4 lanes; \
                         other bounds need a builder that computes them)",
                        source_type(m, f.ty)
                    ),
                );
            };
            at = align_up(at, 4);
            shared.push(LogicalField {
                name: f.name.clone(),
                ty: f.ty,
                slot: Slot::Value { offset: at },
            });
            fields.push(SchemaField::new(role, SHARED, at as u32, 0, 1, 0));
            at += size;
        }
        // The variants' fields start together, at the largest alignment any of them needs
        // (so that C's union of the variants' structs puts them where they are here).
        let ualign = def
            .variants
            .iter()
            .flat_map(|v| v.fields.iter())
            .map(|f| match m.types.get(f.ty) {
                Type::Int(t) => u64::from(t.bits() / 8),
                _ => 4,
            })
            .max()
            .unwrap_or(1);
        let base = align_up(at, ualign);
        let mut end = at;
        let mut primitive = "Triangle";
        let mut variants = Vec::new();
        for (k, v) in def.variants.iter().enumerate() {
            let mut next_slot = 0u64;
            let mut at = base;
            let mut out = shared.clone();
            let mut pending: Vec<(usize, String)> = Vec::new();
            for f in &v.fields {
                let (size, falign, slot, role) = if let Some(n) = children_of(f.ty) {
                    let o = align_up(at, 4);
                    let s = Slot::Children {
                        offset: o,
                        count: n,
                    };
                    let r = SchemaField::new(
                        Role::Children,
                        k as u32,
                        o as u32,
                        next_slot as u32,
                        n as u32,
                        0,
                    );
                    next_slot += n;
                    (4 * n, 4, s, Some(r))
                } else {
                    match m.types.get(f.ty) {
                        Type::Array { elem, len: None } => {
                            let Some(p) = primitive_type(m, *elem) else {
                                let known: Vec<String> = PRIMITIVE_TYPES
                                    .iter()
                                    .map(|(n, _)| format!("`{n}`"))
                                    .collect();
                                let (last, rest) = known.split_last().expect("primitives");
                                return bad(
                                    &f.name,
                                    format!(
                                        "an array of {} (the runtime's primitives are {} or {last})",
                                        source_type(m, *elem),
                                        rest.join(", ")
                                    ),
                                );
                            };
                            primitive = p;
                            let Some(len) = length_name(model, &v.name, &f.name) else {
                                return bad(&f.name, "its length is not a field".into());
                            };
                            pending.push((out.len(), len));
                            let o = align_up(at, 4);
                            let r = SchemaField::new(Role::PrimOffset, k as u32, o as u32, 0, 1, 0);
                            (
                                4,
                                4,
                                Slot::Prims {
                                    offset: o,
                                    count: usize::MAX,
                                },
                                Some(r),
                            )
                        }
                        // Child boxes of the axis-aligned interior variant, oriented child
                        // boxes of another interior one: one per child slot.
                        Type::Array { elem, len: Some(n) }
                            if (k == interior && is_aabb(m, *elem))
                                || (k != interior
                                    && interiors.contains(&k)
                                    && is_obb(m, *elem)) =>
                        {
                            let (role, size, what) = if k == interior {
                                (Role::ChildBounds, 24, "child boxes")
                            } else {
                                (Role::ChildObbs, 60, "oriented child boxes")
                            };
                            if *n != arity {
                                return bad(&f.name, format!("{n} {what} for {arity} children"));
                            }
                            let o = align_up(at, 4);
                            let r = SchemaField::new(role, k as u32, o as u32, 0, *n as u32, 0);
                            (size * n, 4, Slot::Value { offset: o }, Some(r))
                        }
                        Type::Int(t) if !t.is_signed() && k == leaf => {
                            let w = u64::from(t.bits() / 8);
                            let o = align_up(at, w);
                            // Its role is known once the array it sizes is seen.
                            (w, w, Slot::Value { offset: o }, None)
                        }
                        _ => {
                            return bad(
                                &f.name,
                                format!(
                                    "a field of type {} in `{}` (the runtime writes node boxes, \
                                 child boxes, children, primitive counts and primitives)",
                                    source_type(m, f.ty),
                                    v.name
                                ),
                            )
                        }
                    }
                };
                at = slot.offset() + size;
                align = align.max(falign);
                out.push(LogicalField {
                    name: f.name.clone(),
                    ty: f.ty,
                    slot,
                });
                fields.extend(role);
            }
            // Tie each primitive array to its length field.
            for (idx, len) in pending {
                let Some(ci) = out.iter().position(|x| x.name == len) else {
                    return bad(
                        &out[idx].name,
                        format!("its length `{len}` is not a field of `{}`", v.name),
                    );
                };
                let (Slot::Value { offset }, Type::Int(t)) =
                    (&out[ci].slot, m.types.get(out[ci].ty))
                else {
                    return bad(
                        &len,
                        "the length of a primitive array is an unsigned integer field".into(),
                    );
                };
                fields.push(SchemaField::new(
                    Role::PrimCount,
                    k as u32,
                    *offset as u32,
                    0,
                    1,
                    t.bits() / 8,
                ));
                if let Slot::Prims { count, .. } = &mut out[idx].slot {
                    *count = ci;
                }
            }
            for f in &out[shared.len()..] {
                let written = match f.slot {
                    Slot::Value { offset } => fields
                        .iter()
                        .any(|s| u64::from(s.offset) == offset && s.variant == k as u32),
                    _ => true,
                };
                if !written {
                    return bad(&f.name, format!("the runtime has nothing to write into this field of `{}` (an integer field of a leaf is the length of its primitive array)", v.name));
                }
            }
            end = end.max(at);
            variants.push((v.name.clone(), out));
        }
        let leaf_prims = fields
            .iter()
            .any(|f| f.role == Role::PrimOffset as u32 && f.variant == leaf as u32);
        if !leaf_prims {
            return Err(format!(
                "`{name}`'s `{}` holds no primitive array",
                def.variants[leaf].name
            ));
        }
        let node_size = align_up(end, align);
        let schema = Schema {
            adt: name.clone(),
            node_size: node_size as u32,
            node_align: align as u32,
            interior: interior as u32,
            leaf: leaf as u32,
            arity: arity as u32,
            fields,
            primitive: primitive.to_string(),
        };
        schema.validate()?;
        Ok(LogicalAbi {
            adt: name.clone(),
            variants,
            shared: shared.len(),
            variant_base: base,
            interior,
            interiors,
            leaf,
            node_size,
            node_align: align,
            schema,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::fixtures::{program, BVH8_TYPE};
    use crate::layout::model::LayoutModel;
    use crate::syntax::ast::Item;

    /// The logical tree of the first layout of `sources` (after the prelude).
    fn derive(sources: &[&str]) -> Result<LogicalAbi, String> {
        let prog = program(sources);
        let decl = prog
            .items
            .iter()
            .find_map(|i| match i {
                Item::Layout(d) => Some(d),
                _ => None,
            })
            .expect("a layout");
        let model = LayoutModel::from_ast(decl, &prog);
        // Only the module's type declarations matter here; the layouts need not check.
        let (typed, _) = crate::sema::check_program(&prog);
        let m = crate::irgen::generate(&prog, &typed).expect("irgen");
        LogicalAbi::derive(&m, model.adt.as_ref().expect("an ADT"))
    }

    #[test]
    fn prelude_bvh_is_binary_bvh() {
        let abi = derive(&[crate::layout::fixtures::PBRT]).unwrap();
        assert_eq!(abi.schema, scion_runtime::bvh::schema::binary_bvh());
        assert_eq!((abi.node_size, abi.shared, abi.variant_base), (36, 1, 28));
    }

    #[test]
    fn eight_wide_children_and_child_boxes() {
        let layout = r#"
layout W8(R: u32) {
  P: u32; primitives: Triangle[P];
  indirect group nodes { child: u32[8]; children = child; };
  split R { 0 -> Interior from nodes[R]; _ -> Leaf { nprims = R as u16; data = primitives[0 : nprims]; }; };
};
"#;
        let abi = derive(&[BVH8_TYPE, layout]).unwrap();
        let s = &abi.schema;
        assert_eq!((s.arity, s.node_size, s.interior, s.leaf), (8, 228, 0, 1));
        let roles: Vec<(u32, u32, u32)> = s
            .fields
            .iter()
            .map(|f| (f.role, f.offset, f.count))
            .collect();
        assert_eq!(
            roles,
            [
                (Role::ChildBounds as u32, 4, 8),
                (Role::Children as u32, 196, 8),
                (Role::PrimOffset as u32, 8, 1),
                (Role::PrimCount as u32, 4, 1)
            ]
        );
    }

    #[test]
    fn dop14_bounds_are_a_role_of_their_own() {
        let abi = derive(&[crate::layout::fixtures::DOP_SPLIT]).unwrap();
        assert_eq!(
            abi.schema.fields[0],
            SchemaField::new(Role::Dop14Bounds, SHARED, 4, 0, 1, 0)
        );
        // The variants' fields start after the 56 bytes of the DOP.
        assert!(abi.variant_base >= 60, "{}", abi.variant_base);
    }

    #[test]
    fn an_oriented_interior_variant_has_its_own_slots() {
        let hair = concat!(
            include_str!("../../../library/algorithms/closest_hit_hair.scion"),
            include_str!("../../../library/layouts/hair_bvh.scion")
        );
        let abi = derive(&[hair]).unwrap();
        let s = &abi.schema;
        assert_eq!((s.arity, s.interior, s.leaf), (4, 0, 2));
        assert_eq!(abi.interiors, [0, 1]);
        assert_eq!(s.oriented(), Some(1));
        // Both interior variants number their children from slot 0.
        let children: Vec<(u32, u32, u32)> = s
            .fields
            .iter()
            .filter(|f| f.role == Role::Children as u32)
            .map(|f| (f.variant, f.slot, f.count))
            .collect();
        assert_eq!(children, [(0, 0, 4), (1, 0, 4)]);
        assert!(s
            .fields
            .contains(&SchemaField::new(Role::ChildObbs, 1, 4, 0, 4, 0)));
    }

    #[test]
    fn bounds_the_runtime_cannot_compute_are_named() {
        let sphere = include_str!("../../../lit-tests/Inputs/sphere_bvh.scion");
        let e = derive(&[sphere]).unwrap_err();
        assert!(
            e.contains("`SphereBVH`'s field `bounds`") && e.contains("Sphere"),
            "{e}"
        );
    }
}
