//! The peer C++ library tinybvh (1.6.8, through the cxx wrapper `tinybvh-rs` 0.1.0-beta.3, which
//! compiles it with `-march=native`) as contenders: its standard BVH of 32-byte nodes (`BVH`,
//! the library's binned SAH builder `Build`, traversed by `BVH::Intersect`, ordered, one ray at a
//! time) and its AVX2 8-wide `BVH8_CPU` (converted from such a BVH with leaves split to at most
//! 4 triangles, through `MBVH<8>`, traversed by `BVH8_CPU::Intersect`, which tests 4 triangles at
//! once, dividing by an approximate reciprocal refined by one Newton step). Input: the
//! workload's triangles in their order; output: hits in the runtime's convention (original
//! primitive id, `t`), so they compare with Scion's (other triangle tests: `t` differs in the
//! last bits on many rays).
//!
//! Two things about the wrapper shape how it is used here:
//!
//! * Its `Ray` is 64 bytes aligned to 16, but the C++ `tinybvh::Ray` of the tiny_bvh.h it
//!   bundles is 128 bytes aligned to 64 (its `Intersection` has an `auxData` pointer and 56 bytes
//!   of user data after `prim`, which the Rust one lacks). `Ray::new` returns a C++ `Ray` by value: cxx's shim placement-news it into the
//!   64-byte Rust slot, and the C++ constructor `memset`s and writes 128 bytes, zeroing the 64
//!   bytes of stack behind it. That smashed saved registers and return addresses: the SIGSEGV at
//!   a null address seen when `main` returned in release builds (debug frames have other
//!   layouts). So `Ray::new` is never called here: rays are written field by field in Rust, as
//!   the C++ constructor would (minus normalizing the direction), inside a 128-byte, 64-aligned
//!   [`FullRay`], so that `Intersect` gets the object size and alignment C++ assumes.
//! * Its BVH types are neither `Sync` nor `Send` (cxx's default for opaque C++ types), so they
//!   cannot be traced from the driver's threads without [`Shared`] (see its safety note).
//!
//! `BVH8_CPU`'s traversal is exposed by the wrapper only when the Rust code is compiled with the
//! `avx2` target feature (`#[cfg(target_feature = "avx2")]` on its `Intersector`), which the
//! workspace's default build does not enable: the `tinybvh bvh8_cpu` row exists only in a build
//! with `RUSTFLAGS="-C target-feature=+avx2,+fma"` (best with its own `CARGO_TARGET_DIR`: the
//! flag rebuilds the whole workspace, and also lets the Rust rows use AVX2 and FMA).

// The wrapper's BVHs are not `Sync` (cxx's default), so sharing one for reading across the
// driver's threads needs an `unsafe impl Sync`; nothing else here is unsafe.
#![allow(unsafe_code)]

use scion_bench::Contender;
use scion_runtime::batch::BatchDriver;
use scion_runtime::geom::{Hit, Ray, Triangle};
use std::mem::{align_of, size_of};
use std::time::Instant;
use tinybvh_rs::{bvh, Intersection, Intersector, Ray as TRay};

/// A wrapper `Ray` where tinybvh's C++ code may read and write a whole `tinybvh::Ray` (128
/// bytes, 64-byte aligned in the bundled tiny_bvh.h); see the module comment.
#[repr(C, align(64))]
struct FullRay {
    ray: TRay,
    _rest: [u8; 64],
}

const _: () = {
    assert!(size_of::<TRay>() == 64 && align_of::<TRay>() == 16);
    assert!(size_of::<FullRay>() == 128 && align_of::<FullRay>() == 64);
};

/// `RAY_MASK_INTERSECT_ALL` of tiny_bvh.h, the C++ constructor's default mask.
const MASK_ALL: u32 = 0xFFFF;

/// tiny_bvh.h's `tinybvh_safercp` (the ray's reciprocal direction as tinybvh computes it).
fn safe_rcp(x: f32) -> f32 {
    if !(-1e-12..=1e-12).contains(&x) {
        1.0 / x
    } else if x >= 0.0 {
        tinybvh_rs::INFINITE
    } else {
        -tinybvh_rs::INFINITE
    }
}

/// `r` as a tinybvh ray: what `Ray( origin, direction, t )` of tiny_bvh.h sets, except that the
/// direction is not normalized (so `t` is in the runtime's units), and no hit (`prim` =
/// `u32::MAX`) up to `tmax`. tinybvh has no `tmin`: hits need `t >= 0`, and every workload ray
/// starts at `tmin = 0` (checked per trace).
fn tray(r: &Ray) -> FullRay {
    let dir = r.dir.to_array();
    FullRay {
        ray: TRay {
            origin: r.origin.to_array(),
            padding_0: MASK_ALL,
            dir,
            padding_1: 0,
            r_d: dir.map(safe_rcp),
            padding_2: 0,
            hit: Intersection {
                t: r.tmax,
                u: 0.0,
                v: 0.0,
                prim: u32::MAX,
            },
        },
        _rest: [0; 64],
    }
}

/// A tinybvh tree shared by the driver's threads, read only.
struct Shared<'a, T>(&'a T);

// SAFETY: the trees are only traversed (`Intersector::intersect` takes `&self`): tinybvh's
// `BVH::Intersect` and `BVH8_CPU::Intersect` are `const` methods that read the tree and write
// only the ray they are given (tiny_bvh.h has no `mutable` member), so concurrent traversals
// of one built tree are data-race free; the wrapper's types lack `Sync` only because cxx
// marks no opaque C++ type `Sync`. The tree outlives the borrow.
unsafe impl<T: Intersector> Sync for Shared<'_, T> {}

impl<T: Intersector> Shared<'_, T> {
    /// The closest hit of `ray` (a method, so that closures capture the `Sync` wrapper, not
    /// its field).
    fn intersect(&self, ray: &mut FullRay) {
        self.0.intersect(&mut ray.ray);
    }
}

/// Traces `rays` through `tree` on the driver's threads.
fn trace<T: Intersector>(
    tree: &T,
    tris: &[Triangle],
    rays: &[Ray],
    driver: &BatchDriver,
) -> Result<Vec<Hit>, String> {
    if rays.iter().any(|r| r.tmin != 0.0) {
        return Err("tinybvh has no tmin: only rays with tmin = 0 can be traced".into());
    }
    let tree = Shared(tree);
    let tree = &tree;
    Ok(driver.map(rays, |r| {
        let mut q = tray(r);
        tree.intersect(&mut q);
        match q.ray.hit.prim {
            u32::MAX => Hit::MISS,
            p => Hit {
                t: q.ray.hit.t,
                prim: tris[p as usize].id,
            },
        }
    }))
}

/// The triangles as tinybvh's vertex list: three 16-byte vertices per triangle, in order (so
/// tinybvh's primitive `i` is `tris[i]`).
fn vertices(tris: &[Triangle]) -> Vec<[f32; 4]> {
    tris.iter()
        .flat_map(|t| [t.p0, t.p1, t.p2])
        .map(|p| [p.x, p.y, p.z, 0.0])
        .collect()
}

/// The `tinybvh bvh2` contender (its build time is the setup). The vertices and the built tree
/// are kept apart (`BVHData` is the tree without its borrow of the vertices) and bound together
/// for each trace, which costs a length check and a pointer.
pub fn bvh2<'a>(tris: &'a [Triangle], driver: &'a BatchDriver) -> Result<Contender<'a>, String> {
    let verts = vertices(tris);
    let start = Instant::now();
    let built = bvh::BVH::new(verts.as_slice().into()).map_err(|e| format!("tinybvh: {e}"))?;
    let setup = start.elapsed();
    let bytes =
        size_of_val(built.nodes()) + size_of_val(built.indices()) + size_of_val(verts.as_slice());
    let mut data = Some(built.data());
    Ok(Contender {
        name: "tinybvh bvh2".into(),
        bytes: Some(bytes),
        setup,
        subset: None,
        trace: Box::new(move |rays: &[Ray]| {
            let unbound = data.take().ok_or("tinybvh: tree lost by a failed trace")?;
            let tree = unbound
                .bvh(verts.as_slice().into())
                .map_err(|e| format!("tinybvh: {e}"))?;
            let hits = trace(&tree, tris, rays, driver);
            data = Some(tree.data());
            hits
        }),
    })
}

/// The `tinybvh bvh8_cpu` contender: a BVH as for [`bvh2`], leaves split to at most 4
/// triangles, converted to `MBVH<8>` and then to `BVH8_CPU` (which stores its own triangles, so
/// the BVH, the MBVH and the vertices are dropped once it is made); the whole chain is the
/// setup. `None`: this build cannot trace it (no `avx2` target feature, see the module comment).
#[cfg(target_feature = "avx2")]
pub fn bvh8_cpu<'a>(
    tris: &'a [Triangle],
    driver: &'a BatchDriver,
) -> Option<Result<Contender<'a>, String>> {
    use tinybvh_rs::{bvh8_cpu, mbvh};
    let build = || {
        let verts = vertices(tris);
        let start = Instant::now();
        let mut wide =
            bvh::BVH::new(verts.as_slice().into()).map_err(|e| format!("tinybvh: {e}"))?;
        wide.split_leaves(4);
        let m = mbvh::BVH::new(&wide);
        let tree = bvh8_cpu::BVH::new(&m).map_err(|e| format!("tinybvh: {e}"))?;
        let setup = start.elapsed();
        Ok(Contender {
            name: "tinybvh bvh8_cpu".into(),
            // The wrapper does not expose the size of BVH8_CPU's node and leaf blocks.
            bytes: None,
            setup,
            subset: None,
            trace: Box::new(move |rays: &[Ray]| trace(&tree, tris, rays, driver)),
        })
    };
    Some(build())
}

/// See the `avx2` version: this build has no `tinybvh bvh8_cpu`.
#[cfg(not(target_feature = "avx2"))]
pub fn bvh8_cpu<'a>(
    _tris: &'a [Triangle],
    _driver: &'a BatchDriver,
) -> Option<Result<Contender<'a>, String>> {
    None
}

/// The tree tinybvh's `BVH::Build` makes over `tris`, as a logical tree (for `--builders`).
/// tinybvh's node 1 is unused (its children come in pairs from node 2); a node with triangles
/// is a leaf over `indices[left_first..left_first + tri_count]`.
pub fn logical_tree(tris: &[Triangle]) -> Result<scion_runtime::bvh::LogicalTree, String> {
    use scion_bench::foreign_tree::{logical_tree, Shape};
    let verts = vertices(tris);
    let built = bvh::BVH::new(verts.as_slice().into()).map_err(|e| format!("tinybvh: {e}"))?;
    let (nodes, indices) = (built.nodes(), built.indices());
    logical_tree(tris, 0, |i| {
        let n = &nodes[i as usize];
        if n.is_leaf() {
            let first = n.left_first as usize;
            Shape::Leaf(&indices[first..first + n.tri_count as usize])
        } else {
            Shape::Interior(n.left_first, n.left_first + 1)
        }
    })
}
