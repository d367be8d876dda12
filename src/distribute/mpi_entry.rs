//! MPI_Init, MPI_Init_thread and MPI_Finalize, interposed (libglray is preloaded before the
//! host's libmpi): MPI starts through glray's MPI edge, asking for MPI_THREAD_MULTIPLE, and
//! glray's MPI work stops before the host's MPI_Finalize. Where the edge cannot be loaded,
//! the calls go on to the MPI library unchanged (its PMPI_ names), with one warning.

use std::ffi::{c_char, c_int, c_void};
use std::sync::atomic::{AtomicBool, Ordering};

use super::edge;

/// The host called MPI_Init: this process is an MPI rank even without mpirun's environment.
pub static HOST_STARTED_MPI: AtomicBool = AtomicBool::new(false);

type InitThread = unsafe extern "C" fn(*mut c_int, *mut *mut *mut c_char, c_int, *mut c_int) -> c_int;
type Finalize = unsafe extern "C" fn() -> c_int;

/// The MPI library's own function `name` (found after libglray).
fn next(name: &std::ffi::CStr) -> *mut c_void {
    // SAFETY: dlsym with RTLD_NEXT from libglray's own code.
    unsafe { libc::dlsym(libc::RTLD_NEXT, name.as_ptr()) }
}

unsafe fn init(argc: *mut c_int, argv: *mut *mut *mut c_char, required: c_int, provided: *mut c_int) -> c_int {
    HOST_STARTED_MPI.store(true, Ordering::Relaxed);
    let started = std::panic::catch_unwind(|| edge::get().map_err(str::to_string));
    match started {
        Ok(Ok(edge)) => {
            // SAFETY: the host's arguments, as MPI_Init_thread takes them.
            let rc = unsafe { (edge.init)(argc, argv, required, provided) };
            if rc >= 0 {
                return rc;
            }
            glray_core::error!("glray's part of MPI_Init failed: {}", edge.error());
            return rc;
        }
        Ok(Err(e)) => glray_core::warn!("{e}; MPI starts without glray's image-parallel tracing"),
        Err(_) => glray_core::error!("internal error in MPI_Init; MPI starts without glray"),
    }
    let f = next(c"PMPI_Init_thread");
    if f.is_null() {
        glray_core::error!("MPI_Init: no MPI library is loaded");
        return 1;
    }
    // SAFETY: the MPI library's MPI_Init_thread.
    unsafe {
        let f: InitThread = std::mem::transmute::<*mut c_void, InitThread>(f);
        let mut got = 0;
        let rc = f(argc, argv, required, &mut got);
        if !provided.is_null() {
            *provided = got;
        }
        rc
    }
}

/// # Safety
/// As MPI_Init.
#[no_mangle]
pub unsafe extern "C" fn MPI_Init(argc: *mut c_int, argv: *mut *mut *mut c_char) -> c_int {
    // SAFETY: forwarded as MPI_Init_thread with MPI_THREAD_SINGLE (0), as MPI defines it.
    unsafe { init(argc, argv, 0, std::ptr::null_mut()) }
}

/// # Safety
/// As MPI_Init_thread.
#[no_mangle]
pub unsafe extern "C" fn MPI_Init_thread(
    argc: *mut c_int,
    argv: *mut *mut *mut c_char,
    required: c_int,
    provided: *mut c_int,
) -> c_int {
    // SAFETY: the caller's arguments.
    unsafe { init(argc, argv, required, provided) }
}

#[no_mangle]
pub extern "C" fn MPI_Finalize() -> c_int {
    let ended = std::panic::catch_unwind(|| {
        // glray's MPI work ends first: no frame of glray's talks to MPI from here on.
        super::end();
        edge::get().ok().map(|edge| (edge.finalize)(1))
    });
    if let Ok(Some(rc)) = ended {
        return rc;
    }
    let f = next(c"PMPI_Finalize");
    if f.is_null() {
        return 0;
    }
    // SAFETY: the MPI library's MPI_Finalize.
    unsafe { std::mem::transmute::<*mut c_void, Finalize>(f)() }
}
