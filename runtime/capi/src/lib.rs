//! The Scion runtime as a C library (`libscion_runtime.a`, header `include/scion_runtime.h`;
//! docs/c-abi.md). Input: C callers; output: scenes, logical trees, their `ScionTreeView`,
//! the rays of `scion trace`, the reference closest hits and the hits checksum; the points and
//! the reference closest points of closest-point queries; a scene's rotated copy and the
//! reference pairs of a collision.
//!
//! Every fallible function runs inside [`ffi::guard`] and [`ffi::report`]: errors become a status code and a
//! NUL-terminated message in the caller's buffer, and a panic is caught
//! (`SCION_RT_ERR_INTERNAL`) instead of unwinding into C. Handles are `Box`es handed out as
//! raw pointers; each has its free function, and freeing NULL does nothing.

#![allow(unsafe_code)]

mod ffi;
mod kinds;
mod queries;
mod scene;

pub use ffi::{
    Status, SCION_RT_ERR_ARGUMENT, SCION_RT_ERR_EMPTY, SCION_RT_ERR_INTERNAL, SCION_RT_ERR_SCENE,
    SCION_RT_OK,
};
pub use kinds::{
    scion_reference_closest_points, scion_reference_collide, scion_scene_rotated,
    scion_uniform_points, ScionClosestPoint,
};
pub use queries::{
    scion_hit_from_best, scion_hits_checksum, scion_primary_rays, scion_reference_closest_hits,
    ScionHit, ScionRay,
};
pub use scene::{
    scion_scene_free, scion_scene_load, scion_scene_triangle_count, scion_tree_build,
    scion_tree_free, scion_tree_view, ScionLogicalSchema, ScionScene, ScionTree, ScionTreeView,
    SCION_PRIM_SEGMENT, SCION_PRIM_TRIANGLE, SCION_PRIM_TRIANGLE4,
};

#[cfg(test)]
mod tests;
