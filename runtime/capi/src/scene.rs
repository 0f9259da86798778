//! Scenes and logical trees: `scion_scene_*`, `scion_tree_*`.

use crate::ffi::{bad_arg, guard, report, Status, SCION_RT_ERR_EMPTY, SCION_RT_ERR_SCENE};
use rt::bvh::schema::{LogicalBytes, Schema, SchemaField};
use rt::bvh::{build_sah_binned, LogicalTree, SahOptions};
use rt::geom::Triangle;
use rt::scene::{load_obj, Scene};
use rt::triangle4::{block_tree, Triangle4};
use std::ffi::{c_char, CStr};
use std::sync::{Mutex, OnceLock};

/// A loaded scene (opaque to C).
pub struct ScionScene {
    pub(crate) scene: Scene,
}

/// A logical tree over a scene's triangles (opaque to C), with its nodes in every schema a
/// view was asked for (kept as long as the tree, so views stay valid), and, once a schema over
/// blocks of four triangles asked for it, the same tree over blocks (`blocks`).
pub struct ScionTree {
    pub(crate) tree: LogicalTree,
    pub(crate) blocks: OnceLock<Result<LogicalTree<Triangle4>, String>>,
    pub(crate) filled: Mutex<Vec<(Schema, Box<LogicalBytes>)>>,
}

/// `ScionLogicalSchema.primitive`: the leaves hold `ScionTriangle`s.
pub const SCION_PRIM_TRIANGLE: u32 = 0;
/// The leaves hold `ScionSegment`s (strands; not what a scene from `scion_scene_load` holds).
pub const SCION_PRIM_SEGMENT: u32 = 1;
/// The leaves hold `ScionTriangle4`s, blocks of four triangles.
pub const SCION_PRIM_TRIANGLE4: u32 = 2;

/// A tree type's logical-node shape as C passes it (`ScionLogicalSchema`, 40 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct ScionLogicalSchema {
    /// Bytes per node.
    pub node_size: u32,
    /// Alignment of a node.
    pub node_align: u32,
    /// Kind of the interior variant.
    pub interior: u32,
    /// Kind of the leaf variant.
    pub leaf: u32,
    /// Child slots of an interior node.
    pub arity: u32,
    /// Number of `fields`.
    pub field_count: u32,
    /// The fields (`ScionLogicalField`, 24 bytes each).
    pub fields: *const SchemaField,
    /// What the leaves hold: `SCION_PRIM_TRIANGLE` (0), `SCION_PRIM_SEGMENT` (1) or
    /// `SCION_PRIM_TRIANGLE4` (2).
    pub primitive: u32,
}

/// The logical tree as generated code reads it (`ScionTreeView`, 32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct ScionTreeView {
    /// The nodes, in the schema of the layout's tree type.
    pub nodes: *const u8,
    /// How many.
    pub node_count: u32,
    /// The root's index, `u32::MAX` for the empty tree.
    pub root: u32,
    /// The leaves' primitives: 40-byte `ScionTriangle`s, or 160-byte `ScionTriangle4`s for a
    /// schema over blocks.
    pub prims: *const u8,
    /// How many.
    pub prim_count: u32,
}

const _: () = assert!(std::mem::size_of::<ScionTreeView>() == 32);
const _: () = assert!(std::mem::size_of::<ScionLogicalSchema>() == 40);
const _: () = assert!(std::mem::size_of::<SchemaField>() == 24);
const _: () = assert!(std::mem::size_of::<Triangle>() == 40);

/// `scion_scene_load`.
///
/// # Safety
/// `path` is NULL or a NUL-terminated string; `out` is NULL or writable; `err` as
/// `ffi::write_error`.
#[no_mangle]
pub unsafe extern "C" fn scion_scene_load(
    path: *const c_char,
    out: *mut *mut ScionScene,
    err: *mut c_char,
    err_len: usize,
) -> Status {
    let r = guard(|| {
        if path.is_null() || out.is_null() {
            return Err(bad_arg(
                "scion_scene_load: `path` and `out` must not be NULL",
            ));
        }
        // SAFETY: `path` is a NUL-terminated string (the caller's contract).
        let p = unsafe { CStr::from_ptr(path) }
            .to_str()
            .map_err(|_| bad_arg("scion_scene_load: the path is not UTF-8"))?;
        let scene =
            load_obj(p).map_err(|e| (SCION_RT_ERR_SCENE, format!("cannot load the scene: {e}")))?;
        let h = Box::into_raw(Box::new(ScionScene { scene }));
        // SAFETY: `out` is writable.
        unsafe { *out = h };
        Ok(())
    });
    // SAFETY: `err` is NULL or has `err_len` writable bytes (the caller's contract).
    unsafe { report(err, err_len, r) }
}

/// `scion_scene_triangle_count`.
///
/// # Safety
/// `scene` is NULL or a live handle.
#[no_mangle]
pub unsafe extern "C" fn scion_scene_triangle_count(scene: *const ScionScene) -> u64 {
    // SAFETY: NULL or a live handle from `scion_scene_load`.
    match unsafe { scene.as_ref() } {
        Some(s) => s.scene.len() as u64,
        None => 0,
    }
}

/// `scion_scene_free`.
///
/// # Safety
/// `scene` is NULL or a handle from `scion_scene_load` not freed before.
#[no_mangle]
pub unsafe extern "C" fn scion_scene_free(scene: *mut ScionScene) {
    if !scene.is_null() {
        // SAFETY: made by `Box::into_raw` in `scion_scene_load`, freed once.
        drop(unsafe { Box::from_raw(scene) });
    }
}

/// `scion_tree_build`.
///
/// # Safety
/// `scene` is NULL or a live handle; `out` is NULL or writable; `err` as
/// `ffi::write_error`.
#[no_mangle]
pub unsafe extern "C" fn scion_tree_build(
    scene: *const ScionScene,
    max_leaf: u32,
    out: *mut *mut ScionTree,
    err: *mut c_char,
    err_len: usize,
) -> Status {
    let r = guard(|| {
        // SAFETY: NULL or a live handle.
        let Some(s) = (unsafe { scene.as_ref() }) else {
            return Err(bad_arg("scion_tree_build: `scene` must not be NULL"));
        };
        if out.is_null() {
            return Err(bad_arg("scion_tree_build: `out` must not be NULL"));
        }
        if max_leaf > 15 {
            return Err(bad_arg(format!(
                "scion_tree_build: max_leaf {max_leaf} is above 15"
            )));
        }
        if s.scene.triangles.len() >= u32::MAX as usize {
            return Err((
                SCION_RT_ERR_EMPTY,
                "the scene has too many triangles".into(),
            ));
        }
        let mut opts = SahOptions::default();
        if max_leaf > 0 {
            opts.max_leaf = max_leaf as usize;
        }
        let tree = build_sah_binned(&s.scene.triangles, &opts);
        let h = Box::into_raw(Box::new(ScionTree {
            tree,
            blocks: OnceLock::new(),
            filled: Mutex::new(Vec::new()),
        }));
        // SAFETY: `out` is writable.
        unsafe { *out = h };
        Ok(())
    });
    // SAFETY: `err` is NULL or has `err_len` writable bytes (the caller's contract).
    unsafe { report(err, err_len, r) }
}

/// `scion_tree_view`.
///
/// # Safety
/// `tree` is NULL or a live handle; `schema` is NULL or points to a schema whose `fields`
/// holds `field_count` fields; `view` is NULL or writable; `err` as `ffi::write_error`.
#[no_mangle]
pub unsafe extern "C" fn scion_tree_view(
    tree: *const ScionTree,
    schema: *const ScionLogicalSchema,
    view: *mut ScionTreeView,
    err: *mut c_char,
    err_len: usize,
) -> Status {
    let r = guard(|| {
        // SAFETY: NULL or a live handle.
        let Some(t) = (unsafe { tree.as_ref() }) else {
            return Err(bad_arg("scion_tree_view: `tree` must not be NULL"));
        };
        // SAFETY: NULL or a valid schema (the caller's contract).
        let Some(c) = (unsafe { schema.as_ref() }) else {
            return Err(bad_arg("scion_tree_view: `schema` must not be NULL"));
        };
        if view.is_null() {
            return Err(bad_arg("scion_tree_view: `view` must not be NULL"));
        }
        if c.fields.is_null() && c.field_count > 0 {
            return Err(bad_arg("scion_tree_view: the schema's `fields` is NULL"));
        }
        let fields = if c.field_count == 0 {
            Vec::new()
        } else {
            // SAFETY: `fields` holds `field_count` fields (the caller's contract).
            unsafe { std::slice::from_raw_parts(c.fields, c.field_count as usize) }.to_vec()
        };
        // The C API's scenes are OBJ triangle meshes: the leaves hold its triangles, or the
        // same tree's leaves cut into blocks of four (`triangle4::block_tree`).
        let (primitive, blocks, prims, prim_count) = match c.primitive {
            SCION_PRIM_TRIANGLE => (
                "Triangle",
                None,
                t.tree.primitives.as_ptr().cast::<u8>(),
                t.tree.primitives.len(),
            ),
            SCION_PRIM_TRIANGLE4 => {
                let blocks = t
                    .blocks
                    .get_or_init(|| block_tree(&t.tree))
                    .as_ref()
                    .map_err(|e| bad_arg(format!("scion_tree_view: the tree over blocks: {e}")))?;
                (
                    "Triangle4",
                    Some(blocks),
                    blocks.primitives.as_ptr().cast::<u8>(),
                    blocks.primitives.len(),
                )
            }
            SCION_PRIM_SEGMENT => {
                return Err(bad_arg(
                    "scion_tree_view: the schema's leaves hold ScionSegment strands \
                     (SCION_PRIM_SEGMENT), and a tree of scion_tree_build holds a scene's \
                     triangles",
                ))
            }
            other => {
                return Err(bad_arg(format!(
                    "scion_tree_view: the schema's primitive is {other}, not SCION_PRIM_TRIANGLE \
                     (0), SCION_PRIM_SEGMENT (1) or SCION_PRIM_TRIANGLE4 (2)"
                )))
            }
        };
        let schema = Schema {
            adt: "ScionLogicalSchema".to_string(),
            primitive: primitive.to_string(),
            node_size: c.node_size,
            node_align: c.node_align,
            interior: c.interior,
            leaf: c.leaf,
            arity: c.arity,
            fields,
        };
        let mut filled = t
            .filled
            .lock()
            .map_err(|_| bad_arg("scion_tree_view: a view of this tree panicked"))?;
        let at = match filled.iter().position(|(s, _)| *s == schema) {
            Some(at) => at,
            None => {
                let lb = match blocks {
                    Some(blocks) => LogicalBytes::fill(blocks, &schema),
                    None => LogicalBytes::fill(&t.tree, &schema),
                }
                .map_err(|e| bad_arg(format!("scion_tree_view: {e}")))?;
                filled.push((schema, Box::new(lb)));
                filled.len() - 1
            }
        };
        let lb = &filled[at].1;
        let v = ScionTreeView {
            nodes: lb.nodes().as_ptr(),
            node_count: lb.node_count as u32,
            root: lb.root,
            prims,
            prim_count: prim_count as u32,
        };
        // SAFETY: `view` is writable.
        unsafe { *view = v };
        Ok(())
    });
    // SAFETY: `err` is NULL or has `err_len` writable bytes (the caller's contract).
    unsafe { report(err, err_len, r) }
}

/// `scion_tree_free`.
///
/// # Safety
/// `tree` is NULL or a handle from `scion_tree_build` not freed before.
#[no_mangle]
pub unsafe extern "C" fn scion_tree_free(tree: *mut ScionTree) {
    if !tree.is_null() {
        // SAFETY: made by `Box::into_raw` in `scion_tree_build`, freed once.
        drop(unsafe { Box::from_raw(tree) });
    }
}
