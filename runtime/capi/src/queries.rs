//! Rays, the reference closest hit and the checksum: `scion_primary_rays`,
//! `scion_reference_closest_hits`, `scion_hit_from_best`, `scion_hits_checksum`.

use crate::ffi::{bad_arg, guard, report, Status, SCION_RT_ERR_EMPTY};
use crate::scene::{ScionScene, ScionTree};
use rt::batch::BatchDriver;
use rt::geom::{Hit, Ray, Vec3};
use rt::query::{hits_checksum, primary_rays_n, secondary_rays};
use rt::reference::closest_hits_tree;
use std::ffi::c_char;

/// A ray (`ScionRay`, 32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ScionRay {
    /// Origin.
    pub origin: [f32; 3],
    /// Direction.
    pub dir: [f32; 3],
    /// Hits have `t > tmin`.
    pub tmin: f32,
    /// Hits have `t < tmax`.
    pub tmax: f32,
}

/// A closest hit (`ScionHit`, 8 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ScionHit {
    /// Distance, `+inf` on a miss.
    pub t: f32,
    /// Primitive id, `u32::MAX` on a miss.
    pub prim: u32,
}

const _: () = assert!(std::mem::size_of::<ScionRay>() == 32);
const _: () = assert!(std::mem::size_of::<ScionHit>() == 8);

impl From<Ray> for ScionRay {
    fn from(r: Ray) -> ScionRay {
        ScionRay {
            origin: r.origin.to_array(),
            dir: r.dir.to_array(),
            tmin: r.tmin,
            tmax: r.tmax,
        }
    }
}

impl From<ScionRay> for Ray {
    fn from(r: ScionRay) -> Ray {
        Ray {
            origin: Vec3::from_array(r.origin),
            dir: Vec3::from_array(r.dir),
            tmin: r.tmin,
            tmax: r.tmax,
        }
    }
}

fn to_hit(h: ScionHit) -> Hit {
    Hit {
        t: h.t,
        prim: h.prim,
    }
}

/// `scion_primary_rays`.
///
/// # Safety
/// `scene` is NULL or a live handle; `rays` is NULL or has room for `n` rays; `err` as
/// `ffi::write_error`.
#[no_mangle]
pub unsafe extern "C" fn scion_primary_rays(
    scene: *const ScionScene,
    n: u64,
    seed: u64,
    rays: *mut ScionRay,
    err: *mut c_char,
    err_len: usize,
) -> Status {
    // SAFETY: the caller's contract, passed on.
    unsafe {
        make_rays("scion_primary_rays", scene, n, rays, (err, err_len), |b| {
            primary_rays_n(b, n, seed)
        })
    }
}

/// `scion_secondary_rays`.
///
/// # Safety
/// As [`scion_primary_rays`].
#[no_mangle]
pub unsafe extern "C" fn scion_secondary_rays(
    scene: *const ScionScene,
    n: u64,
    seed: u64,
    rays: *mut ScionRay,
    err: *mut c_char,
    err_len: usize,
) -> Status {
    // SAFETY: the caller's contract, passed on.
    unsafe {
        make_rays(
            "scion_secondary_rays",
            scene,
            n,
            rays,
            (err, err_len),
            |b| {
                (1..=1 << 32)
                    .contains(&n)
                    .then(|| secondary_rays(b, n as usize, seed))
            },
        )
    }
}

/// The body of the ray makers: checks the handles, makes `n` rays of the scene's box with
/// `make` (`None` when `n` is out of range) and writes them to `rays`.
///
/// # Safety
/// As [`scion_primary_rays`].
unsafe fn make_rays(
    name: &str,
    scene: *const ScionScene,
    n: u64,
    rays: *mut ScionRay,
    (err, err_len): (*mut c_char, usize),
    make: impl FnOnce(rt::geom::Aabb) -> Option<Vec<Ray>>,
) -> Status {
    let r = guard(|| {
        // SAFETY: NULL or a live handle.
        let Some(s) = (unsafe { scene.as_ref() }) else {
            return Err(bad_arg(format!("{name}: `scene` must not be NULL")));
        };
        if rays.is_null() {
            return Err(bad_arg(format!("{name}: `rays` must not be NULL")));
        }
        if s.scene.is_empty() {
            return Err((
                SCION_RT_ERR_EMPTY,
                "the scene has no triangles, so there is no box to aim rays at".into(),
            ));
        }
        let made = make(s.scene.bounds())
            .ok_or_else(|| bad_arg(format!("{name}: n = {n} is not in 1..=2^32")))?;
        // SAFETY: `rays` has room for `n` rays and `made` has exactly `n`.
        let out = unsafe { std::slice::from_raw_parts_mut(rays, made.len()) };
        for (o, r) in out.iter_mut().zip(made) {
            *o = r.into();
        }
        Ok(())
    });
    // SAFETY: `err` is NULL or has `err_len` writable bytes (the caller's contract).
    unsafe { report(err, err_len, r) }
}

/// `scion_reference_closest_hits`.
///
/// # Safety
/// `tree` is NULL or a live handle; `rays` and `hits` are NULL or hold `n` elements;
/// `err` as `ffi::write_error`.
#[no_mangle]
pub unsafe extern "C" fn scion_reference_closest_hits(
    tree: *const ScionTree,
    rays: *const ScionRay,
    n: u64,
    threads: u32,
    hits: *mut ScionHit,
    err: *mut c_char,
    err_len: usize,
) -> Status {
    let r = guard(|| {
        // SAFETY: NULL or a live handle.
        let Some(t) = (unsafe { tree.as_ref() }) else {
            return Err(bad_arg(
                "scion_reference_closest_hits: `tree` must not be NULL",
            ));
        };
        if n == 0 {
            return Ok(());
        }
        if rays.is_null() || hits.is_null() {
            return Err(bad_arg(
                "scion_reference_closest_hits: `rays` and `hits` must not be NULL",
            ));
        }
        let n = usize::try_from(n)
            .map_err(|_| bad_arg("scion_reference_closest_hits: n is too large"))?;
        // SAFETY: `rays` holds `n` rays.
        let input = unsafe { std::slice::from_raw_parts(rays, n) };
        let input: Vec<Ray> = input.iter().map(|&r| r.into()).collect();
        let driver = BatchDriver::new(threads as usize).map_err(|e| {
            bad_arg(format!(
                "scion_reference_closest_hits: {threads} threads: {e}"
            ))
        })?;
        let got = closest_hits_tree(&t.tree, &input, &driver);
        // SAFETY: `hits` has room for `n` hits.
        let out = unsafe { std::slice::from_raw_parts_mut(hits, n) };
        for (o, h) in out.iter_mut().zip(got) {
            *o = ScionHit {
                t: h.t,
                prim: h.prim,
            };
        }
        Ok(())
    });
    // SAFETY: `err` is NULL or has `err_len` writable bytes (the caller's contract).
    unsafe { report(err, err_len, r) }
}

/// `scion_hit_from_best`.
#[no_mangle]
pub extern "C" fn scion_hit_from_best(t: f32, prim: u32) -> ScionHit {
    let h = Hit::from_best(t, prim);
    ScionHit {
        t: h.t,
        prim: h.prim,
    }
}

/// `scion_hits_checksum`: `rt::query::hits_checksum` (0 hits when `hits` is NULL).
///
/// # Safety
/// `hits` is NULL or holds `n` hits.
#[no_mangle]
pub unsafe extern "C" fn scion_hits_checksum(hits: *const ScionHit, n: u64) -> u64 {
    if hits.is_null() || n == 0 {
        return hits_checksum(&[]);
    }
    // SAFETY: `hits` holds `n` hits (the caller's contract); a count the address space
    // cannot hold is treated as none.
    let Ok(n) = usize::try_from(n) else {
        return hits_checksum(&[]);
    };
    // SAFETY: see above.
    let s = unsafe { std::slice::from_raw_parts(hits, n) };
    let v: Vec<Hit> = s.iter().map(|&h| to_hit(h)).collect();
    hits_checksum(&v)
}
