//! The peer library Embree 3 (Debian's `libembree-dev`, 3.13.5, linked as `libembree3`) as a
//! contender: one triangle mesh over the workload's triangles in their order, committed once
//! with the default build quality (the build time is the setup), traced one ray at a time with
//! `rtcIntersect1` (Embree's own BVH, its traversal for this CPU and its triangle test) through
//! the benchmark's batch driver. Input: the workload's triangles; output: hits in the runtime's
//! convention (original primitive id, `t`), so they compare with Scion's (another triangle
//! test, so some `t` differ in the last bits). Its bytes are what the device holds after the
//! commit (by its memory monitor): vertex and index buffers, BVH and allocator blocks. The
//! flush-to-zero and denormals-are-zero modes Embree's manual recommends for speed are not
//! set: they would change the arithmetic of the other contenders on the same threads.
//! `SCION_EMBREE_CONFIG` in the environment is passed to `rtcNewDevice` as its configuration
//! string (e.g. `isa=avx2`, to measure Embree without its AVX-512 kernels on a CPU that has
//! them; `verbose=1` prints the ISA Embree picked).
//!
//! Embree has no Rust bindings we depend on: this module declares the few functions and
//! `#[repr(C)]` structs it needs by hand, from `/usr/include/embree3/*.h` of 3.13.5 (where
//! `RTC_MAX_INSTANCE_LEVEL_COUNT` is 1 and `RTC_MIN_WIDTH` is 0), and checks their sizes and
//! offsets at compile time against those a C compiler gives for that header (`offsetof`,
//! `sizeof`, `_Alignof`, printed by a C program once).

// FFI to a C library (Embree 3): the workspace denies `unsafe_code`; this module needs it
// to call Embree and to fill the buffers Embree allocates.
#![allow(unsafe_code)]

use scion_bench::Contender;
use scion_runtime::batch::BatchDriver;
use scion_runtime::geom::{Hit, Ray, Triangle};
use scion_runtime::primitive::Segment;
use std::ffi::{c_char, c_void};
use std::mem::{align_of, offset_of, size_of};
use std::sync::atomic::{AtomicIsize, Ordering};
use std::time::Instant;

/// `RTCDevice`, `RTCScene`, `RTCGeometry`: opaque handles.
type Handle = *mut c_void;

const RTC_GEOMETRY_TYPE_TRIANGLE: u32 = 0;
const RTC_GEOMETRY_TYPE_FLAT_LINEAR_CURVE: u32 = 17;
const RTC_BUFFER_TYPE_INDEX: u32 = 0;
const RTC_BUFFER_TYPE_VERTEX: u32 = 1;
const RTC_FORMAT_UINT: u32 = 0x5001;
const RTC_FORMAT_UINT3: u32 = 0x5003;
const RTC_FORMAT_FLOAT3: u32 = 0x9003;
const RTC_FORMAT_FLOAT4: u32 = 0x9004;
const RTC_INVALID_GEOMETRY_ID: u32 = u32::MAX;
const RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT: u32 = 0;
const RTC_ERROR_NONE: u32 = 0;

/// `struct RTCRay` (rtcore_ray.h): 48 bytes, 16-byte aligned.
#[repr(C, align(16))]
struct RTCRay {
    org: [f32; 3],
    tnear: f32,
    dir: [f32; 3],
    time: f32,
    tfar: f32,
    mask: u32,
    id: u32,
    flags: u32,
}

/// `struct RTCHit` (rtcore_ray.h): 32 bytes, 16-byte aligned.
#[repr(C, align(16))]
struct RTCHit {
    ng: [f32; 3],
    u: f32,
    v: f32,
    prim_id: u32,
    geom_id: u32,
    inst_id: [u32; 1],
}

/// `struct RTCRayHit` (rtcore_ray.h): 80 bytes, 16-byte aligned.
#[repr(C)]
struct RTCRayHit {
    ray: RTCRay,
    hit: RTCHit,
}

/// `struct RTCIntersectContext` (rtcore_common.h): flags, filter function, `instID[1]`.
#[repr(C)]
struct RTCIntersectContext {
    flags: u32,
    filter: Option<unsafe extern "C" fn(*const c_void)>,
    inst_id: [u32; 1],
}

// The layout of the C header (gcc on x86-64), field by field.
const _: () = {
    assert!(size_of::<RTCRay>() == 48 && align_of::<RTCRay>() == 16);
    assert!(offset_of!(RTCRay, tnear) == 12 && offset_of!(RTCRay, dir) == 16);
    assert!(offset_of!(RTCRay, time) == 28 && offset_of!(RTCRay, tfar) == 32);
    assert!(offset_of!(RTCRay, mask) == 36 && offset_of!(RTCRay, id) == 40);
    assert!(offset_of!(RTCRay, flags) == 44);
    assert!(size_of::<RTCHit>() == 32 && align_of::<RTCHit>() == 16);
    assert!(offset_of!(RTCHit, u) == 12 && offset_of!(RTCHit, v) == 16);
    assert!(offset_of!(RTCHit, prim_id) == 20 && offset_of!(RTCHit, geom_id) == 24);
    assert!(offset_of!(RTCHit, inst_id) == 28);
    assert!(size_of::<RTCRayHit>() == 80 && align_of::<RTCRayHit>() == 16);
    assert!(offset_of!(RTCRayHit, ray) == 0 && offset_of!(RTCRayHit, hit) == 48);
    assert!(size_of::<RTCIntersectContext>() == 24 && align_of::<RTCIntersectContext>() == 8);
    assert!(offset_of!(RTCIntersectContext, filter) == 8);
    assert!(offset_of!(RTCIntersectContext, inst_id) == 16);
};

#[link(name = "embree3")]
extern "C" {
    fn rtcNewDevice(config: *const c_char) -> Handle;
    fn rtcGetDeviceError(device: Handle) -> u32;
    fn rtcReleaseDevice(device: Handle);
    fn rtcSetDeviceMemoryMonitorFunction(
        device: Handle,
        monitor: extern "C" fn(user: *mut c_void, bytes: isize, post: bool) -> bool,
        user: *mut c_void,
    );
    fn rtcNewScene(device: Handle) -> Handle;
    fn rtcCommitScene(scene: Handle);
    fn rtcReleaseScene(scene: Handle);
    fn rtcNewGeometry(device: Handle, kind: u32) -> Handle;
    fn rtcSetNewGeometryBuffer(
        geometry: Handle,
        kind: u32,
        slot: u32,
        format: u32,
        byte_stride: usize,
        item_count: usize,
    ) -> *mut c_void;
    fn rtcCommitGeometry(geometry: Handle);
    fn rtcAttachGeometry(scene: Handle, geometry: Handle) -> u32;
    fn rtcReleaseGeometry(geometry: Handle);
    fn rtcIntersect1(scene: Handle, context: *mut RTCIntersectContext, rayhit: *mut RTCRayHit);
}

/// `rtcInitIntersectContext` of rtcore_common.h (an inline function there): incoherent rays,
/// no filter function, no instance on the stack.
fn init_intersect_context() -> RTCIntersectContext {
    RTCIntersectContext {
        flags: RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT,
        filter: None,
        inst_id: [RTC_INVALID_GEOMETRY_ID],
    }
}

/// Embree's memory monitor callback: adds the bytes the device allocates (`bytes > 0`) or
/// frees (`bytes < 0`) to the counter `user` points to, and lets every allocation happen.
extern "C" fn count_bytes(user: *mut c_void, bytes: isize, _post: bool) -> bool {
    // SAFETY: `user` is the `AtomicIsize` of the `Scene` that owns the device; it outlives it.
    let counter = unsafe { &*(user as *const AtomicIsize) };
    counter.fetch_add(bytes, Ordering::Relaxed);
    true
}

/// A device and its committed scene of one triangle mesh; released on drop.
struct Scene {
    device: Handle,
    scene: Handle,
    /// Bytes the device holds (its memory monitor's running sum): after the commit, the
    /// geometry buffers, the BVH and Embree's allocator blocks. Dropped after the device.
    bytes: Box<AtomicIsize>,
}

// A committed Embree scene may be traced from any number of threads at once (Embree's API
// documentation: `rtcIntersect1` is thread-safe on a committed scene), and both handles are
// only released by `Drop`, which has the scene to itself.
unsafe impl Send for Scene {}
unsafe impl Sync for Scene {}

/// The configuration string of `SCION_EMBREE_CONFIG`, if set (module comment).
fn device_config() -> Result<Option<std::ffi::CString>, String> {
    match std::env::var("SCION_EMBREE_CONFIG") {
        Ok(c) => std::ffi::CString::new(c)
            .map(Some)
            .map_err(|_| "SCION_EMBREE_CONFIG: a NUL byte in the configuration".into()),
        Err(_) => Ok(None),
    }
}

impl Scene {
    /// Builds the scene over `tris`, in their order (primitive `i` is `tris[i]`).
    fn build(tris: &[Triangle]) -> Result<Scene, String> {
        let n = tris.len();
        let n32 = u32::try_from(n).map_err(|_| format!("embree: {n} triangles: too many"))?;
        Scene::with_geometry(RTC_GEOMETRY_TYPE_TRIANGLE, |s, geometry| {
            let (verts, index) = s.new_buffers::<[f32; 3], [u32; 3]>(
                geometry,
                (RTC_FORMAT_FLOAT3, 3 * n),
                (RTC_FORMAT_UINT3, n),
            )?;
            for (i, t) in (0..n32).zip(tris) {
                let k = 3 * i as usize;
                verts[k] = t.p0.to_array();
                verts[k + 1] = t.p1.to_array();
                verts[k + 2] = t.p2.to_array();
                index[i as usize] = [3 * i, 3 * i + 1, 3 * i + 2];
            }
            Ok(())
        })
    }

    /// Builds the scene over strand segments as Embree's flat linear curves (ribbons facing
    /// the ray, radius linear along the segment: the geometry of the prelude's ribbon test),
    /// one curve of two vertices per segment, in their order (primitive `i` is `segs[i]`).
    fn build_curves(segs: &[Segment]) -> Result<Scene, String> {
        let n = segs.len();
        let n32 = u32::try_from(2 * n).map_err(|_| format!("embree: {n} segments: too many"))?;
        Scene::with_geometry(RTC_GEOMETRY_TYPE_FLAT_LINEAR_CURVE, |s, geometry| {
            let (verts, index) = s.new_buffers::<[f32; 4], u32>(
                geometry,
                (RTC_FORMAT_FLOAT4, 2 * n),
                (RTC_FORMAT_UINT, n),
            )?;
            for (i, g) in (0..n32).step_by(2).zip(segs) {
                let k = i as usize;
                verts[k] = [g.p0.x, g.p0.y, g.p0.z, g.r0];
                verts[k + 1] = [g.p1.x, g.p1.y, g.p1.z, g.r1];
                index[k / 2] = i;
            }
            Ok(())
        })
    }

    /// The vertex and index buffers of `geometry` (a live geometry of this scene's device):
    /// `vertices` and `indices` are each a format and an item count; the items are `V` and `I`
    /// (their size the format's, 4-byte aligned), which the caller writes in full.
    #[allow(clippy::mut_from_ref)]
    fn new_buffers<V, I>(
        &self,
        geometry: Handle,
        vertices: (u32, usize),
        indices: (u32, usize),
    ) -> Result<(&mut [V], &mut [I]), String> {
        // SAFETY: `geometry` is a live geometry of this scene's device; the buffers Embree
        // returns hold the asked number of items of `size_of` bytes each, 4-byte aligned, owned
        // by the geometry (alive as long as the scene) and written by nobody else.
        unsafe {
            let vb = rtcSetNewGeometryBuffer(
                geometry,
                RTC_BUFFER_TYPE_VERTEX,
                0,
                vertices.0,
                size_of::<V>(),
                vertices.1,
            ) as *mut V;
            let ib = rtcSetNewGeometryBuffer(
                geometry,
                RTC_BUFFER_TYPE_INDEX,
                0,
                indices.0,
                size_of::<I>(),
                indices.1,
            ) as *mut I;
            self.check("rtcSetNewGeometryBuffer")?;
            Ok((
                std::slice::from_raw_parts_mut(vb, vertices.1),
                std::slice::from_raw_parts_mut(ib, indices.1),
            ))
        }
    }

    /// A device and a scene of one geometry of `kind`, its buffers filled by `fill`, committed.
    fn with_geometry(
        kind: u32,
        fill: impl FnOnce(&Scene, Handle) -> Result<(), String>,
    ) -> Result<Scene, String> {
        let config = device_config()?;
        // SAFETY: `config` is null (the default device) or a NUL-terminated string that lives
        // for the call.
        let device =
            unsafe { rtcNewDevice(config.as_ref().map_or(std::ptr::null(), |c| c.as_ptr())) };
        if device.is_null() {
            // SAFETY: with a null device Embree reports the error of the last device creation.
            let e = unsafe { rtcGetDeviceError(std::ptr::null_mut()) };
            return Err(format!("embree: rtcNewDevice failed (RTCError {e})"));
        }
        // From here on `Drop` releases whatever is non-null.
        let mut s = Scene {
            device,
            scene: std::ptr::null_mut(),
            bytes: Box::new(AtomicIsize::new(0)),
        };
        // SAFETY: `device` is a live device; the monitor's counter lives in `s` and so outlives
        // it; the buffers Embree returns hold `item_count` items of `byte_stride` bytes (plus
        // its own padding), 4-byte aligned, and are written in bounds below; the geometry is
        // released after the scene took its reference.
        unsafe {
            let counter: *const AtomicIsize = &*s.bytes;
            rtcSetDeviceMemoryMonitorFunction(device, count_bytes, counter as *mut c_void);
            s.scene = rtcNewScene(device);
            s.check("rtcNewScene")?;
            let geometry = rtcNewGeometry(device, kind);
            s.check("rtcNewGeometry")?;
            if let Err(e) = fill(&s, geometry) {
                rtcReleaseGeometry(geometry);
                return Err(e);
            }
            rtcCommitGeometry(geometry);
            rtcAttachGeometry(s.scene, geometry);
            rtcReleaseGeometry(geometry);
            s.check("rtcAttachGeometry")?;
            // Default build quality (RTC_BUILD_QUALITY_MEDIUM) and scene flags: the scene is
            // built by Embree's own thread pool (TBB), all cores.
            rtcCommitScene(s.scene);
            s.check("rtcCommitScene")?;
        }
        Ok(s)
    }

    /// The device's pending error, if any, as a message naming `what`.
    fn check(&self, what: &str) -> Result<(), String> {
        // SAFETY: `self.device` is a live device.
        match unsafe { rtcGetDeviceError(self.device) } {
            RTC_ERROR_NONE => Ok(()),
            e => Err(format!("embree: {what} failed (RTCError {e})")),
        }
    }

    /// The closest hit of `r`: Embree's primitive index, `t`; `None` on a miss.
    fn intersect(&self, r: &Ray) -> Option<(u32, f32)> {
        let mut ctx = init_intersect_context();
        let mut rh = RTCRayHit {
            ray: RTCRay {
                org: r.origin.to_array(),
                tnear: r.tmin,
                dir: r.dir.to_array(),
                time: 0.0,
                tfar: r.tmax,
                mask: u32::MAX,
                id: 0,
                flags: 0,
            },
            hit: RTCHit {
                ng: [0.0; 3],
                u: 0.0,
                v: 0.0,
                prim_id: RTC_INVALID_GEOMETRY_ID,
                geom_id: RTC_INVALID_GEOMETRY_ID,
                inst_id: [RTC_INVALID_GEOMETRY_ID],
            },
        };
        // SAFETY: the scene is committed and alive; `ctx` and `rh` are valid and aligned as
        // the header requires (checked above).
        unsafe { rtcIntersect1(self.scene, &mut ctx, &mut rh) };
        (rh.hit.geom_id != RTC_INVALID_GEOMETRY_ID).then_some((rh.hit.prim_id, rh.ray.tfar))
    }
}

impl Drop for Scene {
    fn drop(&mut self) {
        // SAFETY: both handles are live (or null, for a scene never made) and not used again.
        unsafe {
            if !self.scene.is_null() {
                rtcReleaseScene(self.scene);
            }
            rtcReleaseDevice(self.device);
        }
    }
}

/// The Embree contender over `tris` (the scene's build time is its setup).
#[allow(dead_code)] // (the strands bench includes this module for `embree_curves`)
pub fn embree<'a>(tris: &'a [Triangle], driver: &'a BatchDriver) -> Result<Contender<'a>, String> {
    let start = Instant::now();
    let scene = Scene::build(tris)?;
    let setup = start.elapsed();
    Ok(Contender {
        name: "embree".into(),
        bytes: usize::try_from(scene.bytes.load(Ordering::Relaxed)).ok(),
        setup,
        subset: None,
        trace: Box::new(move |rays: &[Ray]| {
            Ok(driver.map(rays, |r| match scene.intersect(r) {
                Some((prim, t)) => Hit {
                    t,
                    prim: tris[prim as usize].id,
                },
                None => Hit::MISS,
            }))
        }),
    })
}

/// The Embree contender over strand segments, as flat linear curves (the scene's build time is
/// its setup; hits name the segments' ids).
#[allow(dead_code)] // (the peers bench includes this module for `embree`)
pub fn embree_curves<'a>(
    segs: &'a [Segment],
    driver: &'a BatchDriver,
) -> Result<Contender<'a>, String> {
    let start = Instant::now();
    let scene = Scene::build_curves(segs)?;
    let setup = start.elapsed();
    Ok(Contender {
        name: "embree flat curves".into(),
        bytes: usize::try_from(scene.bytes.load(Ordering::Relaxed)).ok(),
        setup,
        subset: None,
        trace: Box::new(move |rays: &[Ray]| {
            Ok(driver.map(rays, |r| match scene.intersect(r) {
                Some((prim, t)) => Hit {
                    t,
                    prim: segs[prim as usize].id,
                },
                None => Hit::MISS,
            }))
        }),
    })
}
