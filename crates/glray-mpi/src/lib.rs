//! libglray_mpi.so: the only part of glray that links an MPI library. libglray loads it with
//! dlopen in a process that is an MPI rank (mpirun's environment, or a host calling
//! MPI_Init), so glxgears under glray never loads libmpi. What it offers is small and C-shaped
//! (`glray_mpi_*`, version `ABI`): start MPI (for the host, asking for MPI_THREAD_MULTIPLE, or
//! for glray itself), glray's own duplicate of MPI_COMM_WORLD (its messages never meet the
//! host's), byte messages that never block, and the end. The protocol above it lives in
//! libglray (glray-distribute).
//!
//! Every MPI call here is made by one thread at a time (libglray holds a lock around them),
//! and none waits without a limit: the duplicate is made with MPI_Comm_idup, polled against a
//! deadline, and errors on glray's communicator return codes instead of aborting the job.

mod comm;
mod start;

use std::ffi::{c_char, c_int};
use std::panic::catch_unwind;

/// The version of this edge's functions: libglray refuses another.
pub const ABI: u32 = 2;

/// What went wrong last, for `glray_mpi_error`.
fn set_error(e: String) {
    if let Ok(mut last) = start::LAST_ERROR.lock() {
        *last = std::ffi::CString::new(e.replace('\0', " ")).unwrap_or_default();
    }
}

/// Runs `f`, turning an error or a panic into -1 (the text for `glray_mpi_error`): nothing
/// unwinds into libglray.
fn guarded(f: impl FnOnce() -> Result<c_int, String>) -> c_int {
    match catch_unwind(std::panic::AssertUnwindSafe(f)) {
        Ok(Ok(v)) => v,
        Ok(Err(e)) => {
            set_error(e);
            -1
        }
        Err(_) => {
            set_error("internal error in glray's MPI edge".into());
            -1
        }
    }
}

#[no_mangle]
pub extern "C" fn glray_mpi_abi() -> u32 {
    ABI
}

/// The text of the last error (valid until the next call).
#[no_mangle]
pub extern "C" fn glray_mpi_error() -> *const c_char {
    match start::LAST_ERROR.lock() {
        Ok(last) => last.as_ptr(),
        Err(_) => c"glray's MPI edge is poisoned".as_ptr(),
    }
}

/// Starts MPI if it is not started, asking for `required` threading (the host's MPI_Init or
/// MPI_Init_thread, interposed by libglray; `argc`/`argv` may be null), and sets `*provided`.
/// Returns the MPI error code of the start (0: success), or -1 if glray's part failed (MPI is
/// then started all the same).
///
/// # Safety
/// `argc`, `argv` as MPI_Init_thread takes them; `provided` valid or null.
#[no_mangle]
pub unsafe extern "C" fn glray_mpi_init(
    argc: *mut c_int,
    argv: *mut *mut *mut c_char,
    required: c_int,
    provided: *mut c_int,
) -> c_int {
    guarded(|| unsafe { start::init(argc, argv, required, provided) })
}

/// Makes glray's communicator (MPI_Comm_idup of MPI_COMM_WORLD), waiting at most
/// `timeout_ms`; starts MPI first if nobody has. 0 on success.
#[no_mangle]
pub extern "C" fn glray_mpi_join(timeout_ms: u64) -> c_int {
    guarded(|| start::join(std::time::Duration::from_millis(timeout_ms)).map(|()| 0))
}

/// The threading MPI provides (MPI_THREAD_*), -1 before it is started.
#[no_mangle]
pub extern "C" fn glray_mpi_threading() -> c_int {
    guarded(start::threading)
}

#[no_mangle]
pub extern "C" fn glray_mpi_rank() -> c_int {
    guarded(|| comm::with(|c| Ok(c.rank())))
}

#[no_mangle]
pub extern "C" fn glray_mpi_size() -> c_int {
    guarded(|| comm::with(|c| Ok(c.size())))
}

/// Starts sending `len` bytes to rank `to` (copied: the caller's buffer is free at once).
///
/// # Safety
/// `bytes` points to `len` readable bytes.
#[no_mangle]
pub unsafe extern "C" fn glray_mpi_send(to: c_int, bytes: *const u8, len: usize) -> c_int {
    let data = if len == 0 { Vec::new() } else { unsafe { std::slice::from_raw_parts(bytes, len) }.to_vec() };
    guarded(|| comm::with(|c| c.send(to, data).map(|()| 0)))
}

/// 1 when every send has completed, 0 when some are under way.
#[no_mangle]
pub extern "C" fn glray_mpi_flushed() -> c_int {
    guarded(|| comm::with(|c| c.flushed().map(c_int::from)))
}

/// Bytes of the sends still under way, at most 2 GiB (-1: see `glray_mpi_error`).
#[no_mangle]
pub extern "C" fn glray_mpi_unsent() -> c_int {
    guarded(|| comm::with(|c| c.unsent().map(|b| b.min(c_int::MAX as u64) as c_int)))
}

/// 1 and a message (its sender, and bytes to give back with `glray_mpi_free`) when one has
/// arrived, 0 when none has.
///
/// # Safety
/// The pointers are valid for writes.
#[no_mangle]
pub unsafe extern "C" fn glray_mpi_poll(from: *mut c_int, bytes: *mut *mut u8, len: *mut usize) -> c_int {
    guarded(|| {
        comm::with(|c| match c.poll()? {
            Some((source, data)) => {
                let data = data.into_boxed_slice();
                unsafe {
                    *len = data.len();
                    *from = source;
                    *bytes = Box::into_raw(data).cast();
                }
                Ok(1)
            }
            None => Ok(0),
        })
    })
}

/// Gives back a message's bytes from `glray_mpi_poll`.
///
/// # Safety
/// `bytes` and `len` as `glray_mpi_poll` gave them, once.
#[no_mangle]
pub unsafe extern "C" fn glray_mpi_free(bytes: *mut u8, len: usize) {
    if !bytes.is_null() {
        drop(unsafe { Box::from_raw(std::ptr::slice_from_raw_parts_mut(bytes, len)) });
    }
}

/// Ends glray's MPI work (its communicator freed, sends under way cancelled) and then MPI
/// itself: for the host (its interposed MPI_Finalize: `for_host` 1) or, at exit, when glray
/// started MPI. Returns the MPI error code of MPI_Finalize (0 when it was not called).
#[no_mangle]
pub extern "C" fn glray_mpi_finalize(for_host: c_int) -> c_int {
    guarded(|| start::finalize(for_host != 0))
}

/// Ends the whole job (MPI_Abort on MPI_COMM_WORLD) with `code`.
#[no_mangle]
pub extern "C" fn glray_mpi_abort(code: c_int) -> c_int {
    guarded(|| start::abort(code))
}
