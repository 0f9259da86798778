//! The logical tree as generated constructors read it, for any tree type: a [`Schema`] says
//! where each logical field of a node sits (the compiler derives it from the `type`
//! declaration the layout realizes, `scionc --emit=header` prints it as C), and
//! [`LogicalBytes::fill`] writes a built tree into nodes of that shape.
//!
//! Node form (C ABI, one record per logical node, `node_size` bytes each, 8-aligned storage):
//! a `u32` kind at offset 0 (the variant's index in the `type` declaration), then the shared
//! fields, then the variants' own fields overlaid at the same offset, each at its natural
//! alignment (`scion_ir::data_layout`'s rules). Every field has a [`Role`]: what the runtime
//! writes into it. Fields of a variant other than the node's are zero.
//!
//! Shapes: an interior variant with `arity` child slots (single recursive fields and arrays of
//! children, in declaration order), a leaf variant with a primitive count and the first
//! primitive. Arity 2 maps the binary [`LogicalTree`] node for node (same indices); any other
//! arity collapses it first ([`super::wide`]'s collapse: interior nodes in pre-order, then the
//! leaves), and an empty child slot refers to an empty leaf of its own (no primitives, box
//! [`crate::geom::Aabb::EMPTY`]) so that the layout's `Leaf` build decides how an empty slot is stored and
//! the node count bounds what a layout places.
//! Primitives are the tree's triangles, 40 bytes each.

pub use super::fill::LogicalBytes;

/// What the runtime writes into a logical field.
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Role {
    /// The node's own box: an `AABB` (`low: f32x3, high: f32x3`, 24 bytes).
    Bounds = 1,
    /// The boxes of child slots `slot .. slot + count`, `count` `AABB`s ([`crate::geom::Aabb::EMPTY`] for
    /// an empty slot).
    ChildBounds = 2,
    /// Child slots `slot .. slot + count` as `u32` node indices (`count` 1 for a field of the
    /// tree type itself, `n` for an array of `n` children).
    Children = 3,
    /// A leaf's number of primitives: an unsigned integer of `width` bytes (1, 2, 4 or 8).
    PrimCount = 4,
    /// A leaf's first primitive in the primitive array (`u32`).
    PrimOffset = 5,
    /// The node's own DOP-14 ([`super::dop14::Dop14`], 56 bytes: `lo1`, `hi1` `f32x3`, `lo2`,
    /// `hi2` `f32x4`).
    Dop14Bounds = 6,
    /// Oriented boxes of child slots `slot .. slot + count` ([`super::oriented`]), 60 bytes
    /// each: the columns `vx`, `vy`, `vz` (`f32x3`) of the node's integer matrix `M` and the
    /// box (`AABB`) of the child's triangles mapped by `M` (an empty slot: zero columns and
    /// [`crate::geom::Aabb::EMPTY`]). Its variant is the oriented interior variant: a node of the tree
    /// takes it where [`super::oriented::fit`] orients it.
    ChildObbs = 7,
}

impl Role {
    /// The role of a C-ABI role number.
    pub fn from_u32(r: u32) -> Option<Role> {
        Some(match r {
            1 => Role::Bounds,
            2 => Role::ChildBounds,
            3 => Role::Children,
            4 => Role::PrimCount,
            5 => Role::PrimOffset,
            6 => Role::Dop14Bounds,
            7 => Role::ChildObbs,
            _ => return None,
        })
    }

    /// The role's name in the C header (`SCION_ROLE_...`).
    pub fn c_name(self) -> &'static str {
        match self {
            Role::Bounds => "SCION_ROLE_BOUNDS",
            Role::ChildBounds => "SCION_ROLE_CHILD_BOUNDS",
            Role::Children => "SCION_ROLE_CHILDREN",
            Role::PrimCount => "SCION_ROLE_PRIM_COUNT",
            Role::PrimOffset => "SCION_ROLE_PRIM_OFFSET",
            Role::Dop14Bounds => "SCION_ROLE_DOP14_BOUNDS",
            Role::ChildObbs => "SCION_ROLE_CHILD_OBBS",
        }
    }
}

/// "Every variant": the `variant` of a shared field.
pub const SHARED: u32 = u32::MAX;

/// One logical field of a node (C ABI `ScionLogicalField`, 24 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SchemaField {
    /// [`Role`] as a number.
    pub role: u32,
    /// The variant (its kind) whose field it is, or [`SHARED`].
    pub variant: u32,
    /// Byte offset in the node.
    pub offset: u32,
    /// First child slot ([`Role::Children`], [`Role::ChildBounds`]); 0 otherwise.
    pub slot: u32,
    /// Number of slots ([`Role::Children`], [`Role::ChildBounds`]); 1 otherwise.
    pub count: u32,
    /// Byte width of the integer ([`Role::PrimCount`]); 0 otherwise.
    pub width: u32,
}

impl SchemaField {
    /// A field of `role` (`variant` [`SHARED`] for a shared field).
    pub fn new(role: Role, variant: u32, offset: u32, slot: u32, count: u32, width: u32) -> Self {
        SchemaField {
            role: role as u32,
            variant,
            offset,
            slot,
            count,
            width,
        }
    }
}

/// Where the logical fields of a tree type sit in its logical nodes.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Schema {
    /// The tree type's name (for messages).
    pub adt: String,
    /// Bytes per node (a multiple of `node_align`).
    pub node_size: u32,
    /// Alignment of a node.
    pub node_align: u32,
    /// Kind of the interior variant (of the axis-aligned one when the type also has an
    /// oriented one: the variant with [`Role::ChildObbs`] fields).
    pub interior: u32,
    /// Kind of the leaf variant.
    pub leaf: u32,
    /// Child slots of an interior node.
    pub arity: u32,
    /// The fields the runtime writes.
    pub fields: Vec<SchemaField>,
    /// The prelude type of the primitives the leaves hold (`Triangle`, `Segment`:
    /// [`crate::primitive::Primitive::TYPE_NAME`]); a tree of other primitives is refused.
    pub primitive: String,
}

/// The binary tree's shape in schema form: the prelude's
/// `type BVH(bounds: AABB) = Interior(left: BVH, right: BVH) | Leaf(nprims: u16, data: Triangle[nprims])`,
/// 36-byte nodes (`kind` @0, `bounds` @4, `left` @28, `right` @32 | `nprims` @28, `data` @32).
/// The compiler derives the same from the declaration (its test `prelude_bvh_is_binary_bvh`
/// keeps the two equal); this copy serves the runtime's own tests and tools that hold no
/// compiled layout.
pub fn binary_bvh() -> Schema {
    let f = |role, variant, offset, slot, width| {
        SchemaField::new(role, variant, offset, slot, 1, width)
    };
    Schema {
        adt: "BVH".to_string(),
        primitive: "Triangle".to_string(),
        node_size: 36,
        node_align: 4,
        interior: 0,
        leaf: 1,
        arity: 2,
        fields: vec![
            f(Role::Bounds, SHARED, 4, 0, 0),
            f(Role::Children, 0, 28, 0, 0),
            f(Role::Children, 0, 32, 1, 0),
            f(Role::PrimOffset, 1, 32, 0, 0),
            f(Role::PrimCount, 1, 28, 0, 2),
        ],
    }
}

impl Schema {
    /// Checks that the fields fit the node, do not overlap within a variant, and give every
    /// slot `0 .. arity` exactly one child reference.
    pub fn validate(&self) -> Result<(), String> {
        let name = &self.adt;
        if self.node_align == 0 || !self.node_align.is_power_of_two() {
            return Err(format!(
                "`{name}`: node alignment {} is not a power of two",
                self.node_align
            ));
        }
        if self.node_size < 4 || self.node_size % self.node_align != 0 {
            return Err(format!(
                "`{name}`: node size {} is not a multiple of its alignment {} holding the kind",
                self.node_size, self.node_align
            ));
        }
        if self.arity == 0 || self.interior == self.leaf {
            return Err(format!("`{name}`: no interior variant with children"));
        }
        // Per interior variant (the interior kind, and any other variant with children),
        // how many references each slot has.
        let mut slots: Vec<(u32, Vec<u32>)> = vec![(self.interior, vec![0; self.arity as usize])];
        let mut used: Vec<(u32, u32, u32)> = vec![(SHARED, 0, 4)];
        for (k, f) in self.fields.iter().enumerate() {
            let role = Role::from_u32(f.role)
                .ok_or_else(|| format!("`{name}`: field {k} has unknown role {}", f.role))?;
            let size = field_size(role, f)
                .ok_or_else(|| format!("`{name}`: field {k} ({role:?}) has width {}", f.width))?;
            let end = u64::from(f.offset) + u64::from(size);
            if end > u64::from(self.node_size) {
                return Err(format!("`{name}`: field {k} ({role:?}) ends past the node"));
            }
            match role {
                Role::Children | Role::ChildBounds | Role::ChildObbs
                    if f.variant == SHARED || f.variant == self.leaf =>
                {
                    return Err(format!(
                        "`{name}`: field {k} ({role:?}) is not an interior variant's"
                    ));
                }
                Role::ChildObbs if f.variant == self.interior => {
                    return Err(format!(
                        "`{name}`: field {k} ({role:?}) is in the axis-aligned interior variant"
                    ));
                }
                Role::PrimCount | Role::PrimOffset if f.variant != self.leaf => {
                    return Err(format!("`{name}`: field {k} ({role:?}) is not the leaf's"));
                }
                _ => {}
            }
            if role == Role::Children {
                let at = match slots.iter().position(|(v, _)| *v == f.variant) {
                    Some(i) => i,
                    None => {
                        slots.push((f.variant, vec![0; self.arity as usize]));
                        slots.len() - 1
                    }
                };
                for s in f.slot..f.slot.saturating_add(f.count) {
                    match slots[at].1.get_mut(s as usize) {
                        Some(n) => *n += 1,
                        None => {
                            return Err(format!(
                                "`{name}`: child slot {s} past arity {}",
                                self.arity
                            ))
                        }
                    }
                }
            }
            if matches!(role, Role::ChildBounds | Role::ChildObbs)
                && f.slot.saturating_add(f.count) > self.arity
            {
                return Err(format!(
                    "`{name}`: child box slots past arity {}",
                    self.arity
                ));
            }
            for &(v, o, s) in &used {
                let same = v == SHARED || f.variant == SHARED || v == f.variant;
                if same && f.offset < o + s && o < f.offset + size {
                    return Err(format!("`{name}`: field {k} ({role:?}) overlaps another"));
                }
            }
            used.push((f.variant, f.offset, size));
        }
        for (v, counts) in &slots {
            if let Some(s) = counts.iter().position(|&n| n != 1) {
                return Err(format!(
                    "`{name}`: child slot {s} of variant {v} has {} references",
                    counts[s]
                ));
            }
        }
        if let Some(v) = self.oriented() {
            if !slots.iter().any(|(k, _)| *k == v) {
                return Err(format!(
                    "`{name}`: the oriented variant {v} has no children"
                ));
            }
        }
        Ok(())
    }
}

impl Schema {
    /// The kind of the oriented interior variant (the one with [`Role::ChildObbs`] fields), if
    /// the type has one.
    pub fn oriented(&self) -> Option<u32> {
        self.fields
            .iter()
            .find(|f| f.role == Role::ChildObbs as u32)
            .map(|f| f.variant)
    }

    /// One line of text (`BVH 36 4 0 1 2 1,4294967295,4,0,1,0;...`): the tree type's name
    /// (`NAME:PRIMITIVE` when its primitives are not `Triangle`s),
    /// node size and alignment, interior and leaf kinds, arity, then each field's six numbers.
    pub fn to_text(&self) -> String {
        let fields: Vec<String> = self
            .fields
            .iter()
            .map(|f| {
                format!(
                    "{},{},{},{},{},{}",
                    f.role, f.variant, f.offset, f.slot, f.count, f.width
                )
            })
            .collect();
        // The primitive type follows the name after a colon unless it is `Triangle`.
        let name = if self.primitive == "Triangle" {
            self.adt.clone()
        } else {
            format!("{}:{}", self.adt, self.primitive)
        };
        format!(
            "{} {} {} {} {} {} {}",
            name,
            self.node_size,
            self.node_align,
            self.interior,
            self.leaf,
            self.arity,
            fields.join(";")
        )
    }

    /// The schema [`Schema::to_text`] wrote, validated.
    pub fn from_text(text: &str) -> Result<Schema, String> {
        let bad = || format!("`{text}` is not a logical-tree schema");
        let parts: Vec<&str> = text.split_whitespace().collect();
        if !(6..=7).contains(&parts.len()) {
            return Err(bad());
        }
        let n = |s: &str| s.parse::<u32>().map_err(|_| bad());
        let mut fields = Vec::new();
        for f in parts
            .get(6)
            .map_or("", |s| s)
            .split(';')
            .filter(|f| !f.is_empty())
        {
            let v: Vec<u32> = f.split(',').map(n).collect::<Result<_, _>>()?;
            let [role, variant, offset, slot, count, width] = v[..] else {
                return Err(bad());
            };
            fields.push(SchemaField {
                role,
                variant,
                offset,
                slot,
                count,
                width,
            });
        }
        let (adt, primitive) = parts[0].split_once(':').unwrap_or((parts[0], "Triangle"));
        let s = Schema {
            adt: adt.to_string(),
            primitive: primitive.to_string(),
            node_size: n(parts[1])?,
            node_align: n(parts[2])?,
            interior: n(parts[3])?,
            leaf: n(parts[4])?,
            arity: n(parts[5])?,
            fields,
        };
        s.validate()?;
        Ok(s)
    }
}

fn field_size(role: Role, f: &SchemaField) -> Option<u32> {
    Some(match role {
        Role::Bounds => 24,
        Role::ChildBounds => 24 * f.count,
        Role::Children => 4 * f.count,
        Role::PrimCount if matches!(f.width, 1 | 2 | 4 | 8) => f.width,
        Role::PrimCount => return None,
        Role::PrimOffset => 4,
        Role::Dop14Bounds => 56,
        Role::ChildObbs => 60 * f.count,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::logical::{LogicalTree, NO_NODE};
    use crate::bvh::{build_sah_binned, SahOptions};
    use crate::geom::Aabb;
    use crate::geom::{Triangle, Vec3};

    fn tree(n: usize) -> LogicalTree {
        let tris: Vec<Triangle> = (0..n)
            .map(|i| {
                let x = (i % 17) as f32 * 1.5;
                let y = (i / 17) as f32 * 0.75;
                Triangle::new(
                    Vec3::new(x, y, 0.0),
                    Vec3::new(x + 1.0, y, 0.25),
                    Vec3::new(x, y + 1.0, 0.5),
                    i as u32,
                )
            })
            .collect();
        build_sah_binned(&tris, &SahOptions::default())
    }

    fn u32_at(b: &[u8], at: usize) -> u32 {
        u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
    }

    #[test]
    fn a_dop14_field_gets_each_nodes_dop() {
        let t = tree(200);
        let mut s = binary_bvh();
        // The DopBVH of library/algorithms/closest_hit_dop14.scion: the DOP at 4, 56 bytes,
        // then the variants at 60.
        s.node_size = 68;
        s.fields = vec![
            SchemaField::new(Role::Dop14Bounds, SHARED, 4, 0, 1, 0),
            SchemaField::new(Role::Children, 0, 60, 0, 1, 0),
            SchemaField::new(Role::Children, 0, 64, 1, 1, 0),
            SchemaField::new(Role::PrimOffset, 1, 64, 0, 1, 0),
            SchemaField::new(Role::PrimCount, 1, 60, 0, 1, 2),
        ];
        let lb = LogicalBytes::fill(&t, &s).unwrap();
        let dops = crate::bvh::dop14::node_dops(&t);
        for (i, d) in dops.iter().enumerate() {
            let b = &lb.nodes()[i * 68..(i + 1) * 68];
            let got: Vec<f32> = (0..14)
                .map(|k| f32::from_bits(u32_at(b, 4 + 4 * k)))
                .collect();
            assert_eq!(got, d.to_array());
            assert_eq!(&got[..6], &t.nodes[i].bounds);
        }
    }

    #[test]
    fn binary_schema_is_the_tree_node_for_node() {
        let t = tree(300);
        let s = binary_bvh();
        let lb = LogicalBytes::fill(&t, &s).unwrap();
        assert_eq!((lb.node_count, lb.root), (t.nodes.len(), t.root));
        for (i, n) in t.nodes.iter().enumerate() {
            let b = &lb.nodes()[i * 36..(i + 1) * 36];
            assert_eq!(u32_at(b, 0), n.kind);
            let bounds: Vec<f32> = (0..6)
                .map(|k| f32::from_bits(u32_at(b, 4 + 4 * k)))
                .collect();
            assert_eq!(bounds, n.bounds);
            if n.is_leaf() {
                assert_eq!(u32::from(u16::from_le_bytes([b[28], b[29]])), n.prim_count);
                assert_eq!(u32_at(b, 32), n.prim_offset);
            } else {
                assert_eq!([u32_at(b, 28), u32_at(b, 32)], n.child);
            }
        }
    }

    /// An eight-wide schema (`Interior(child_bounds: AABB[8], children: BVH8[8]) | Leaf(..)`):
    /// every primitive is reached once, child boxes are the children's, every node (empty
    /// leaves included) is reached exactly once.
    #[test]
    fn wide_schema_covers_every_primitive_once() {
        let t = tree(500);
        let s = Schema {
            adt: "BVH8".into(),
            primitive: "Triangle".into(),
            node_size: 228,
            node_align: 4,
            interior: 0,
            leaf: 1,
            arity: 8,
            fields: vec![
                SchemaField::new(Role::ChildBounds, 0, 4, 0, 8, 0),
                SchemaField::new(Role::Children, 0, 196, 0, 8, 0),
                SchemaField::new(Role::PrimCount, 1, 4, 0, 1, 2),
                SchemaField::new(Role::PrimOffset, 1, 8, 0, 1, 0),
            ],
        };
        let lb = LogicalBytes::fill(&t, &s).unwrap();
        let node = |i: u32| &lb.nodes()[i as usize * 228..(i as usize + 1) * 228];
        let mut covered = vec![0u32; t.primitives.len()];
        let mut stack = vec![(lb.root, None::<[f32; 6]>)];
        let mut empties = 0;
        let mut seen = vec![0u32; lb.node_count];
        while let Some((i, parent_box)) = stack.pop() {
            seen[i as usize] += 1;
            let b = node(i);
            if u32_at(b, 0) == 1 {
                let count = u16::from_le_bytes([b[4], b[5]]) as usize;
                let off = u32_at(b, 8) as usize;
                let mut bx = Aabb::EMPTY;
                for p in &t.primitives[off..off + count] {
                    covered[p.id as usize] += 1;
                    bx = bx.union(p.bounds());
                }
                if count == 0 {
                    empties += 1;
                }
                if let Some(pb) = parent_box {
                    assert_eq!(
                        pb,
                        bx.to_array(),
                        "a leaf's slot box is its primitives' box"
                    );
                }
                continue;
            }
            for k in 0..8 {
                let c = u32_at(b, 196 + 4 * k);
                let bx: Vec<f32> = (0..6)
                    .map(|j| f32::from_bits(u32_at(b, 4 + 24 * k + 4 * j)))
                    .collect();
                stack.push((c, Some(bx.try_into().unwrap())));
            }
        }
        assert!(covered.iter().all(|&c| c == 1));
        assert!(empties > 0, "500 triangles leave some slot empty");
        assert_eq!(
            u32_at(node(lb.node_count as u32 - 1), 0),
            1,
            "the empty leaf is last"
        );
    }

    #[test]
    fn bad_schemas_are_refused() {
        let mut s = binary_bvh();
        s.fields[2].slot = 0;
        assert!(s
            .validate()
            .unwrap_err()
            .contains("slot 0 of variant 0 has 2"));
        // Oriented child boxes belong to a second interior variant with children of its own.
        let mut s = binary_bvh();
        s.fields
            .push(SchemaField::new(Role::ChildObbs, 0, 36, 0, 2, 0));
        s.node_size = 156;
        assert!(s.validate().unwrap_err().contains("axis-aligned interior"));
        s.fields.last_mut().unwrap().variant = 2;
        assert!(s
            .validate()
            .unwrap_err()
            .contains("oriented variant 2 has no children"));
        s.fields
            .push(SchemaField::new(Role::Children, 2, 28, 0, 2, 0));
        assert_eq!(s.validate(), Ok(()));
        assert_eq!(s.oriented(), Some(2));
        let mut s = binary_bvh();
        s.fields[4].width = 3;
        assert!(s.validate().unwrap_err().contains("width 3"));
        let mut s = binary_bvh();
        s.fields[0].offset = 0;
        assert!(s.validate().unwrap_err().contains("overlaps"));
        let t = tree(10);
        assert!(LogicalBytes::fill(
            &t,
            &Schema {
                node_size: 3,
                ..binary_bvh()
            }
        )
        .is_err());
    }

    #[test]
    fn text_round_trips() {
        let s = binary_bvh();
        assert_eq!(Schema::from_text(&s.to_text()).unwrap(), s);
        let strands = Schema {
            primitive: "Segment".into(),
            ..binary_bvh()
        };
        assert!(strands.to_text().starts_with("BVH:Segment 36 "));
        assert_eq!(Schema::from_text(&strands.to_text()).unwrap(), strands);
        assert!(Schema::from_text("BVH 36 4").is_err());
        assert!(Schema::from_text("BVH 36 4 0 1 2 9,9").is_err());
    }

    #[test]
    fn empty_and_single_leaf_trees() {
        let e = LogicalTree::<crate::geom::Triangle>::empty();
        let lb = LogicalBytes::fill(&e, &binary_bvh()).unwrap();
        assert_eq!((lb.node_count, lb.root), (0, NO_NODE));
        let t = tree(1);
        assert_eq!(t.nodes.len(), 1);
        let mut s = binary_bvh();
        s.arity = 2;
        let lb = LogicalBytes::fill(&t, &s).unwrap();
        assert_eq!((lb.node_count, lb.root), (1, t.root));
    }
}
