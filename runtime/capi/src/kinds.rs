//! The query kinds beyond closest hit: closest point (`scion_uniform_points`,
//! `scion_reference_closest_points`) and collision (`scion_scene_rotated`,
//! `scion_reference_collide`): the queries `scion run` makes and the references it checks
//! against, for C hosts of the generated entries.

use crate::ffi::{bad_arg, guard, report, Status, SCION_RT_ERR_EMPTY};
use crate::scene::ScionScene;
use rt::batch::{BatchDriver, BLOCK};
use rt::geom::Vec3;
use rt::query::points::uniform_points;
use rt::reference::closest_point::closest_point_brute;
use rt::reference::collide::{collide_sweep, rotated};
use rt::scene::Scene;
use std::ffi::c_char;
use std::sync::Mutex;

/// A closest point (`ScionClosestPoint`, 20 bytes): the result record of `closest_point_query`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ScionClosestPoint {
    /// Distance to the nearest point.
    pub distance: f32,
    /// Its triangle's id, `u32::MAX` when none.
    pub prim: u32,
    /// The point.
    pub point: [f32; 3],
}

const _: () = assert!(std::mem::size_of::<ScionClosestPoint>() == 20);

/// `scion_uniform_points`: `n` points uniform in the scene's box (`scion run --algorithm
/// closest-point --n N --seed S`), 3 floats each.
///
/// # Safety
/// `scene` is NULL or a live handle; `points` is NULL or has room for `3 * n` floats; `err` as
/// `ffi::write_error`.
#[no_mangle]
pub unsafe extern "C" fn scion_uniform_points(
    scene: *const ScionScene,
    n: u64,
    seed: u64,
    points: *mut f32,
    err: *mut c_char,
    err_len: usize,
) -> Status {
    let r = guard(|| {
        // SAFETY: NULL or a live handle.
        let Some(s) = (unsafe { scene.as_ref() }) else {
            return Err(bad_arg("scion_uniform_points: `scene` must not be NULL"));
        };
        if points.is_null() && n > 0 {
            return Err(bad_arg("scion_uniform_points: `points` must not be NULL"));
        }
        if s.scene.is_empty() {
            return Err((
                SCION_RT_ERR_EMPTY,
                "the scene has no triangles, so there is no box to place points in".into(),
            ));
        }
        let n = usize::try_from(n).map_err(|_| bad_arg("scion_uniform_points: n is too large"))?;
        let b = s.scene.bounds();
        let made = uniform_points(b.low, b.high, n, seed);
        if n > 0 {
            // SAFETY: `points` has room for `3 * n` floats.
            let out = unsafe { std::slice::from_raw_parts_mut(points, 3 * n) };
            for (o, p) in out.chunks_exact_mut(3).zip(made) {
                o.copy_from_slice(&p.to_array());
            }
        }
        Ok(())
    });
    // SAFETY: `err` is NULL or has `err_len` writable bytes (the caller's contract).
    unsafe { report(err, err_len, r) }
}

/// `scion_reference_closest_points`: float32 brute force over the scene's triangles.
///
/// # Safety
/// `scene` is NULL or a live handle; `points` (3 floats each) and `out` are NULL or hold `n`
/// elements; `err` as `ffi::write_error`.
#[no_mangle]
pub unsafe extern "C" fn scion_reference_closest_points(
    scene: *const ScionScene,
    points: *const f32,
    n: u64,
    threads: u32,
    out: *mut ScionClosestPoint,
    err: *mut c_char,
    err_len: usize,
) -> Status {
    let r = guard(|| {
        let name = "scion_reference_closest_points";
        // SAFETY: NULL or a live handle.
        let Some(s) = (unsafe { scene.as_ref() }) else {
            return Err(bad_arg(format!("{name}: `scene` must not be NULL")));
        };
        if n == 0 {
            return Ok(());
        }
        if points.is_null() || out.is_null() {
            return Err(bad_arg(format!(
                "{name}: `points` and `out` must not be NULL"
            )));
        }
        let n = usize::try_from(n).map_err(|_| bad_arg(format!("{name}: n is too large")))?;
        // SAFETY: `points` holds `n` points of 3 floats.
        let input = unsafe { std::slice::from_raw_parts(points, 3 * n) };
        let input: Vec<Vec3> = input
            .chunks_exact(3)
            .map(|p| Vec3::new(p[0], p[1], p[2]))
            .collect();
        let driver = BatchDriver::new(threads as usize)
            .map_err(|e| bad_arg(format!("{name}: {threads} threads: {e}")))?;
        // SAFETY: `out` has room for `n` records.
        let out = unsafe { std::slice::from_raw_parts_mut(out, n) };
        let chunks: Vec<Mutex<&mut [ScionClosestPoint]>> =
            out.chunks_mut(BLOCK).map(Mutex::new).collect();
        let tris = &s.scene.triangles;
        driver.run(n, |begin, end| {
            let mut o = chunks[begin / BLOCK]
                .lock()
                .unwrap_or_else(|p| p.into_inner());
            for (j, i) in (begin..end).enumerate() {
                let c = closest_point_brute(tris, input[i], f32::INFINITY);
                o[j] = ScionClosestPoint {
                    distance: c.distance,
                    prim: c.prim,
                    point: c.point.to_array(),
                };
            }
        });
        Ok(())
    });
    // SAFETY: `err` is NULL or has `err_len` writable bytes (the caller's contract).
    unsafe { report(err, err_len, r) }
}

/// `scion_scene_rotated`: a new scene, `scene` turned by `(x, y, z)` degrees about the centre
/// of its box (`scion run --algorithm collide --rotate X,Y,Z`).
///
/// # Safety
/// `scene` is NULL or a live handle; `out` is NULL or writable; `err` as `ffi::write_error`.
#[no_mangle]
pub unsafe extern "C" fn scion_scene_rotated(
    scene: *const ScionScene,
    x: f64,
    y: f64,
    z: f64,
    out: *mut *mut ScionScene,
    err: *mut c_char,
    err_len: usize,
) -> Status {
    let r = guard(|| {
        // SAFETY: NULL or a live handle.
        let Some(s) = (unsafe { scene.as_ref() }) else {
            return Err(bad_arg("scion_scene_rotated: `scene` must not be NULL"));
        };
        if out.is_null() {
            return Err(bad_arg("scion_scene_rotated: `out` must not be NULL"));
        }
        if ![x, y, z].iter().all(|a| a.is_finite()) {
            return Err(bad_arg(format!(
                "scion_scene_rotated: ({x}, {y}, {z}) are not finite angles"
            )));
        }
        let turned = rotated(&s.scene.triangles, [x, y, z]);
        let scene = Scene::new(format!("{} rotated", s.scene.name), turned);
        // SAFETY: `out` is writable.
        unsafe { *out = Box::into_raw(Box::new(ScionScene { scene })) };
        Ok(())
    });
    // SAFETY: `err` is NULL or has `err_len` writable bytes (the caller's contract).
    unsafe { report(err, err_len, r) }
}

/// `scion_reference_collide`: the colliding pairs of two scenes, sorted, as a sink.
///
/// # Safety
/// `a`, `b` are NULL or live handles; `pairs` is NULL or has room for `capacity` pairs of two
/// `uint32_t`; `count` is NULL or writable; `err` as `ffi::write_error`.
#[no_mangle]
pub unsafe extern "C" fn scion_reference_collide(
    a: *const ScionScene,
    b: *const ScionScene,
    pairs: *mut [u32; 2],
    capacity: u64,
    count: *mut u64,
    err: *mut c_char,
    err_len: usize,
) -> Status {
    let r = guard(|| {
        // SAFETY: NULL or live handles.
        let (Some(a), Some(b)) = (unsafe { a.as_ref() }, unsafe { b.as_ref() }) else {
            return Err(bad_arg(
                "scion_reference_collide: `a` and `b` must not be NULL",
            ));
        };
        if count.is_null() || (pairs.is_null() && capacity > 0) {
            return Err(bad_arg(
                "scion_reference_collide: `count` (and `pairs` with a capacity) must not be NULL",
            ));
        }
        let found = collide_sweep(&a.scene.triangles, &b.scene.triangles);
        // SAFETY: `count` is writable.
        unsafe { *count = found.len() as u64 };
        let room = usize::try_from(capacity)
            .unwrap_or(usize::MAX)
            .min(found.len());
        if room > 0 {
            // SAFETY: `pairs` has room for `capacity >= room` pairs.
            let out = unsafe { std::slice::from_raw_parts_mut(pairs, room) };
            for (o, &(x, y)) in out.iter_mut().zip(&found) {
                *o = [x, y];
            }
        }
        Ok(())
    });
    // SAFETY: `err` is NULL or has `err_len` writable bytes (the caller's contract).
    unsafe { report(err, err_len, r) }
}
