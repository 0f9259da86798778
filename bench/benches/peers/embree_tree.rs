//! `--tree embree`: Embree's own SAH builder (`rtcBuildBVH`, Embree 3's BVH builder API) as the
//! builder of the tree Scion's rows, the reference and the hand-written kernel traverse, so that
//! Scion's traversal can be timed on a tree of Embree's making (tree quality and traversal cost
//! measured apart, as `--tree tinybvh|obvhs` do for those peers). A binary tree (branching
//! factor 2, as Scion's layouts collapse binary trees themselves), leaves of at most
//! `max_leaf` triangles, Embree's medium build quality, its SAH counting leaves in blocks of
//! `block` primitives (4 for the trees whose leaves are cut into `Triangle4` blocks, as
//! Embree's own `Triangle4` BVH counts them; 1 otherwise), unit traversal and intersection
//! costs. The nodes live in Embree's BVH allocator until the tree is read out.

// FFI to a C library (Embree 3): the workspace denies `unsafe_code`.
#![allow(unsafe_code)]

use scion_bench::foreign_tree::{logical_tree as read_tree, Shape};
use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::Triangle;
use std::ffi::{c_char, c_void};
use std::mem::{align_of, size_of};

type Handle = *mut c_void;

/// `struct RTCBuildPrimitive` (rtcore_builder.h): 32 bytes, 32-byte aligned.
#[repr(C, align(32))]
#[derive(Clone, Copy)]
struct BuildPrimitive {
    lower: [f32; 3],
    geom_id: u32,
    upper: [f32; 3],
    prim_id: u32,
}

/// `struct RTCBuildArguments` (rtcore_builder.h of Embree 3.13).
#[repr(C)]
struct BuildArguments {
    byte_size: usize,
    build_quality: u32,
    build_flags: u32,
    max_branching_factor: u32,
    max_depth: u32,
    sah_block_size: u32,
    min_leaf_size: u32,
    max_leaf_size: u32,
    traversal_cost: f32,
    intersection_cost: f32,
    bvh: Handle,
    primitives: *mut BuildPrimitive,
    primitive_count: usize,
    primitive_array_capacity: usize,
    create_node: extern "C" fn(Handle, u32, *mut c_void) -> *mut c_void,
    set_node_children: extern "C" fn(*mut c_void, *mut *mut c_void, u32, *mut c_void),
    set_node_bounds: extern "C" fn(*mut c_void, *const *const c_void, u32, *mut c_void),
    create_leaf: extern "C" fn(Handle, *const BuildPrimitive, usize, *mut c_void) -> *mut c_void,
    split_primitive: Option<extern "C" fn()>,
    build_progress: Option<extern "C" fn()>,
    user_ptr: *mut c_void,
}

const _: () = assert!(size_of::<BuildPrimitive>() == 32 && align_of::<BuildPrimitive>() == 32);
const _: () = assert!(size_of::<BuildArguments>() == 136);

const RTC_BUILD_QUALITY_MEDIUM: u32 = 1;

#[link(name = "embree3")]
extern "C" {
    fn rtcNewDevice(config: *const c_char) -> Handle;
    fn rtcReleaseDevice(device: Handle);
    fn rtcGetDeviceError(device: Handle) -> u32;
    fn rtcNewBVH(device: Handle) -> Handle;
    fn rtcBuildBVH(args: *const BuildArguments) -> *mut c_void;
    fn rtcThreadLocalAlloc(allocator: Handle, bytes: usize, align: usize) -> *mut c_void;
    fn rtcReleaseBVH(bvh: Handle);
}

/// A node in Embree's allocator: an interior node's two children, or a leaf's triangles
/// (`count` indices stored right after the node).
#[repr(C)]
struct Node {
    count: u32,
    leaf: u32,
    children: [*const Node; 2],
}

extern "C" fn create_node(alloc: Handle, n: u32, _: *mut c_void) -> *mut c_void {
    // SAFETY: Embree's allocator returns `bytes` aligned to `align` or null.
    let p = unsafe { rtcThreadLocalAlloc(alloc, size_of::<Node>(), 16) } as *mut Node;
    if !p.is_null() {
        // SAFETY: `p` is a fresh allocation of one `Node`.
        unsafe {
            p.write(Node {
                count: n,
                leaf: 0,
                children: [std::ptr::null(); 2],
            })
        };
    }
    p as *mut c_void
}

extern "C" fn set_children(node: *mut c_void, ch: *mut *mut c_void, n: u32, _: *mut c_void) {
    let node = node as *mut Node;
    for k in 0..(n as usize).min(2) {
        // SAFETY: `node` is one of `create_node`'s and `ch` holds `n` child pointers.
        unsafe { (*node).children[k] = *ch.add(k) as *const Node };
    }
}

extern "C" fn set_bounds(_: *mut c_void, _: *const *const c_void, _: u32, _: *mut c_void) {}

extern "C" fn create_leaf(
    alloc: Handle,
    prims: *const BuildPrimitive,
    n: usize,
    _: *mut c_void,
) -> *mut c_void {
    let bytes = size_of::<Node>() + 4 * n;
    // SAFETY: as in `create_node`; the leaf's indices follow the node in the same allocation.
    unsafe {
        let p = rtcThreadLocalAlloc(alloc, bytes, 16) as *mut Node;
        if p.is_null() {
            return p as *mut c_void;
        }
        p.write(Node {
            count: n as u32,
            leaf: 1,
            children: [std::ptr::null(); 2],
        });
        let ids = (p as *mut u8).add(size_of::<Node>()) as *mut u32;
        for k in 0..n {
            *ids.add(k) = (*prims.add(k)).prim_id;
        }
        p as *mut c_void
    }
}

/// The binary tree Embree's SAH builder makes over `tris`, leaves of at most `max_leaf`
/// triangles, the SAH counting leaves in blocks of `block`.
pub fn logical_tree(tris: &[Triangle], max_leaf: usize, block: u32) -> Result<LogicalTree, String> {
    let n = tris.len();
    let mut prims: Vec<BuildPrimitive> = tris
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let lo = t.p0.min(t.p1).min(t.p2).to_array();
            let hi = t.p0.max(t.p1).max(t.p2).to_array();
            BuildPrimitive {
                lower: lo,
                geom_id: 0,
                upper: hi,
                prim_id: i as u32,
            }
        })
        .collect();
    // SAFETY: a null configuration asks for the default device; every handle is released
    // below; the nodes are read while the BVH (their allocator) is alive.
    unsafe {
        let device = rtcNewDevice(std::ptr::null());
        if device.is_null() {
            return Err("embree: rtcNewDevice failed".into());
        }
        let bvh = rtcNewBVH(device);
        let args = BuildArguments {
            byte_size: size_of::<BuildArguments>(),
            build_quality: RTC_BUILD_QUALITY_MEDIUM,
            build_flags: 0,
            max_branching_factor: 2,
            max_depth: 1024,
            sah_block_size: block,
            min_leaf_size: 1,
            max_leaf_size: max_leaf as u32,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
            bvh,
            primitives: prims.as_mut_ptr(),
            primitive_count: n,
            primitive_array_capacity: prims.capacity(),
            create_node,
            set_node_children: set_children,
            set_node_bounds: set_bounds,
            create_leaf,
            split_primitive: None,
            build_progress: None,
            user_ptr: std::ptr::null_mut(),
        };
        let root = rtcBuildBVH(&args) as *const Node;
        let err = rtcGetDeviceError(device);
        let out = if root.is_null() || err != 0 {
            Err(format!("embree: rtcBuildBVH failed (RTCError {err})"))
        } else {
            // Number the nodes in the order the reader asks for them.
            let mut all: Vec<*const Node> = Vec::new();
            let mut stack = vec![root];
            while let Some(p) = stack.pop() {
                all.push(p);
                if (*p).leaf == 0 {
                    stack.extend((*p).children.iter().rev().copied());
                }
            }
            let index: std::collections::HashMap<*const Node, u32> = all
                .iter()
                .enumerate()
                .map(|(i, &p)| (p, i as u32))
                .collect();
            read_tree(tris, 0, |i| {
                let p = all[i as usize];
                if (*p).leaf != 0 {
                    let ids = (p as *const u8).add(size_of::<Node>()) as *const u32;
                    Shape::Leaf(std::slice::from_raw_parts(ids, (*p).count as usize))
                } else {
                    Shape::Interior(index[&(*p).children[0]], index[&(*p).children[1]])
                }
            })
        };
        rtcReleaseBVH(bvh);
        rtcReleaseDevice(device);
        out
    }
}
