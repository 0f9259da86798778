//! Status codes, error messages into caller buffers, and the panic guard of every fallible
//! entry point.

use std::ffi::c_char;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// A status as C sees it.
pub type Status = i32;

/// Success.
pub const SCION_RT_OK: Status = 0;
/// A NULL pointer or a value out of range.
pub const SCION_RT_ERR_ARGUMENT: Status = 1;
/// The scene could not be read or parsed.
pub const SCION_RT_ERR_SCENE: Status = 2;
/// The scene has no triangles.
pub const SCION_RT_ERR_EMPTY: Status = 3;
/// A bug in the runtime, caught before it reached C.
pub const SCION_RT_ERR_INTERNAL: Status = 4;

/// An error: its status and its message.
pub type Failure = (Status, String);

/// An argument error.
pub fn bad_arg(msg: impl Into<String>) -> Failure {
    (SCION_RT_ERR_ARGUMENT, msg.into())
}

/// Writes `msg` to `err[0..err_len)` as a NUL-terminated string, cut at a character boundary
/// when it does not fit. Does nothing when `err` is NULL or `err_len` is 0.
///
/// # Safety
/// `err` is NULL or points to `err_len` writable bytes.
pub unsafe fn write_error(err: *mut c_char, err_len: usize, msg: &str) {
    if err.is_null() || err_len == 0 {
        return;
    }
    let mut n = msg.len().min(err_len - 1);
    while !msg.is_char_boundary(n) {
        n -= 1;
    }
    // SAFETY: the caller gives `err_len` writable bytes; `n + 1 <= err_len`.
    unsafe {
        std::ptr::copy_nonoverlapping(msg.as_ptr(), err.cast::<u8>(), n);
        *err.add(n) = 0;
    }
}

/// Runs `f`, turning a panic into `SCION_RT_ERR_INTERNAL` with the panic's message, so that
/// nothing unwinds into C.
pub fn guard(f: impl FnOnce() -> Result<(), Failure>) -> Result<(), Failure> {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|payload| {
        let what = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".to_string());
        Err((
            SCION_RT_ERR_INTERNAL,
            format!("internal error in the Scion runtime: {what}"),
        ))
    })
}

/// The status of `r`, with its message written to `err`.
///
/// # Safety
/// As [`write_error`] for `err`.
pub unsafe fn report(err: *mut c_char, err_len: usize, r: Result<(), Failure>) -> Status {
    match r {
        Ok(()) => SCION_RT_OK,
        Err((status, msg)) => {
            // SAFETY: forwarded from the caller.
            unsafe { write_error(err, err_len, &msg) };
            status
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_are_cut_to_the_buffer_and_terminated() {
        let mut buf = [0x55 as c_char; 6];
        // SAFETY: `buf` has 6 writable bytes.
        unsafe { write_error(buf.as_mut_ptr(), buf.len(), "héllo world") };
        let bytes: Vec<u8> = buf.iter().map(|&c| c as u8).collect();
        // "héllo" is 6 bytes; 5 fit and the cut falls inside no character: "héll".
        assert_eq!(&bytes[..5], "héll".as_bytes());
        assert_eq!(bytes[5], 0);
        // NULL and empty buffers are ignored.
        // SAFETY: NULL is allowed.
        unsafe { write_error(std::ptr::null_mut(), 10, "x") };
    }

    #[test]
    fn panics_become_internal_errors() {
        let mut buf = [0 as c_char; 128];
        let r = guard(|| panic!("boom"));
        // SAFETY: `buf` has 128 writable bytes.
        let s = unsafe { report(buf.as_mut_ptr(), buf.len(), r) };
        assert_eq!(s, SCION_RT_ERR_INTERNAL);
        // SAFETY: `write_error` terminated the message.
        let msg = unsafe { std::ffi::CStr::from_ptr(buf.as_ptr()) };
        assert!(msg.to_str().unwrap().contains("boom"));
    }
}
