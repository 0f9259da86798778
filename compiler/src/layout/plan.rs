//! The buffer plan of a layout (paper §7.2): every contiguous buffer the constructor allocates,
//! once, before it packs the tree.
//!
//! Input: a [`LayoutModel`]. Output: a [`BufferPlan`]: the globals block, each global array and
//! each array of each top-level group (a group cut by `---` gives one buffer per part; nested
//! groups live inside their outer group's elements), each with its element size, stride and
//! alignment, and its element count in terms of the logical tree: the number of nodes, the
//! number of nodes of some variants (indirect groups reached by `from`), the total length of a
//! logical array field (the primitives behind `data = primitives[p_o : p_o + nprims]`), or the
//! value of a global.

use crate::layout::model::{GroupId, GroupKind, LayoutModel, MemberId, MemberModel};
use crate::layout::resolve::{FieldPath, Resolver};
use crate::syntax::ast::{Expr, ExprKind};

/// The buffers of one layout.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BufferPlan {
    /// The layout's name.
    pub layout: String,
    /// Its buffers: the globals block first, then global arrays, then group arrays.
    pub buffers: Vec<Buffer>,
}

/// One contiguous allocation.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Buffer {
    /// A readable name: `globals`, the array's name, or the group's name with `#k` for part k
    /// of a group cut by `---`.
    pub name: String,
    /// What it holds.
    pub kind: BufferKind,
    /// Bytes of data in one element.
    pub elem_size: u64,
    /// Distance between consecutive elements.
    pub stride: u64,
    /// Alignment of the base and of every element.
    pub align: u64,
    /// How many elements.
    pub count: Count,
}

/// What a buffer holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum BufferKind {
    /// The fixed-size globals.
    Globals,
    /// A global array (a stored field of the top level sized by a global).
    GlobalArray {
        /// The stored field.
        member: MemberId,
    },
    /// Array `array` of group `group`.
    GroupArray {
        /// The group.
        group: GroupId,
        /// Which part (0 unless cut by `---`).
        array: usize,
    },
}

/// The symbolic element count of a buffer.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Count {
    /// Exactly one element.
    One,
    /// One element per `per_element` nodes of the tree (rounded up; `per_element` is the tile
    /// count when the group's element is a tile of a nested group). `size_global` is the global
    /// the constructor sets to that count (`N`), if the group's `size` names one.
    Nodes {
        /// Nodes per element.
        per_element: u64,
        /// The global holding the count.
        size_global: Option<String>,
    },
    /// One element per node of these variants (an indirect group reached by `from`).
    VariantNodes {
        /// The variants whose arms reach the group.
        variants: Vec<String>,
    },
    /// The total length of logical array `field` over the nodes of `variants` (filled by
    /// `append`); the constructor stores it in global `len_global`.
    LogicalLength {
        /// The logical field.
        field: String,
        /// Variants that have it.
        variants: Vec<String>,
        /// The global holding the length.
        len_global: String,
    },
    /// The value of a global, which the build must know before allocation.
    Global(String),
}

impl BufferPlan {
    /// The plan of `model`.
    pub fn of(model: &LayoutModel) -> BufferPlan {
        let mut buffers = Vec::new();
        if model.globals.size > 0 {
            buffers.push(Buffer {
                name: "globals".into(),
                kind: BufferKind::Globals,
                elem_size: model.globals.size,
                stride: model.globals.size,
                align: model.globals.align,
                count: Count::One,
            });
        }
        let mut resolver = Resolver::new(model);
        for ga in &model.global_arrays {
            let count = logical_length(model, &mut resolver, &ga.name.name, &ga.len.name)
                .unwrap_or_else(|| Count::Global(ga.len.name.clone()));
            let stride = crate::layout::types::round_up(ga.shape.size, ga.shape.align);
            buffers.push(Buffer {
                name: ga.name.name.clone(),
                kind: BufferKind::GlobalArray { member: ga.member },
                elem_size: ga.shape.size,
                stride,
                align: ga.shape.align,
                count,
            });
        }
        for (gid, g) in model.groups.iter().enumerate() {
            let count = match g.kind {
                GroupKind::Nested => continue,
                GroupKind::Direct | GroupKind::Pointer => {
                    let per_element = model.scopes[g.scope]
                        .members
                        .iter()
                        .filter_map(|m| match model.members[*m].kind {
                            MemberModel::Group(inner) => model.groups[inner].count,
                            _ => None,
                        })
                        .max()
                        .unwrap_or(1);
                    let size_global = match &g.size {
                        Some(Expr {
                            kind: ExprKind::Name(n),
                            ..
                        }) => Some(n.name.clone()),
                        _ => None,
                    };
                    Count::Nodes {
                        per_element,
                        size_global,
                    }
                }
                GroupKind::Indirect => {
                    let mut variants: Vec<String> = Vec::new();
                    for s in &model.splits {
                        for a in &s.arms {
                            if let crate::layout::model::ArmBody::From { group: Some(t), .. } =
                                a.body
                            {
                                if t == gid && !variants.contains(&a.variant.name) {
                                    variants.push(a.variant.name.clone());
                                }
                            }
                        }
                    }
                    Count::VariantNodes { variants }
                }
            };
            let several = g.arrays.len() > 1;
            for (k, a) in g.arrays.iter().enumerate() {
                let name = if several {
                    format!("{}#{k}", g.name.name)
                } else {
                    g.name.name.clone()
                };
                buffers.push(Buffer {
                    name,
                    kind: BufferKind::GroupArray {
                        group: gid,
                        array: k,
                    },
                    elem_size: a.size,
                    stride: a.stride,
                    align: a.align,
                    count: count.clone(),
                });
            }
        }
        BufferPlan {
            layout: model.name.name.clone(),
            buffers,
        }
    }

    /// The buffer called `name`.
    pub fn buffer(&self, name: &str) -> Option<&Buffer> {
        self.buffers.iter().find(|b| b.name == name)
    }
}

/// The logical array field whose derived definition slices or indexes global array `array`.
fn logical_length(
    model: &LayoutModel,
    resolver: &mut Resolver<'_>,
    array: &str,
    len: &str,
) -> Option<Count> {
    let adt = model.adt.as_ref()?;
    let mut found: Option<(String, Vec<String>)> = None;
    for v in &adt.variants {
        for f in v.fields.iter().filter(|f| f.array && !f.recursive) {
            let Ok(path) = resolver.resolve(&v.name.name, &f.name.name) else {
                continue;
            };
            let cases: Vec<&FieldPath> = match &path {
                FieldPath::Alternatives(cs) => cs.iter().map(|(_, p)| p).collect(),
                p => vec![p],
            };
            let slices_it = |p: &FieldPath| match p {
                FieldPath::Derived { value, .. } => match &value.kind {
                    ExprKind::Slice { base, .. } | ExprKind::Index { base, .. } => {
                        matches!(&base.kind, ExprKind::Name(n) if n.name == array)
                    }
                    _ => false,
                },
                _ => false,
            };
            if cases.iter().all(|p| slices_it(p)) {
                let entry = found.get_or_insert_with(|| (f.name.name.clone(), Vec::new()));
                if entry.0 == f.name.name && !entry.1.contains(&v.name.name) {
                    entry.1.push(v.name.name.clone());
                }
            }
        }
    }
    found.map(|(field, variants)| Count::LogicalLength {
        field,
        variants,
        len_global: len.to_string(),
    })
}
