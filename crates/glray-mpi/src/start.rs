//! MPI started and ended: for the host (its MPI_Init, MPI_Init_thread and MPI_Finalize, which
//! libglray interposes and hands here) or by glray itself in a program that runs under mpirun
//! without using MPI. Always through the PMPI_ names: the MPI_ ones are libglray's own.

use std::ffi::{c_char, c_int, CString};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use mpi::ffi;

use crate::comm::{self, Comm};

pub static LAST_ERROR: std::sync::LazyLock<Mutex<CString>> =
    std::sync::LazyLock::new(|| Mutex::new(CString::default()));

/// Who started MPI: glray, in a program that does not use it, finalizes it at the end.
static STARTED_BY_GLRAY: Mutex<bool> = Mutex::new(false);

fn code(what: &str, rc: c_int) -> Result<(), String> {
    if rc == 0 {
        Ok(())
    } else {
        Err(format!("{what} failed with MPI error {rc}"))
    }
}

fn initialized() -> bool {
    let mut flag: c_int = 0;
    // SAFETY: MPI_Initialized may be called at any time.
    unsafe { ffi::MPI_Initialized(&mut flag) };
    flag != 0
}

fn finalized() -> bool {
    let mut flag: c_int = 0;
    // SAFETY: MPI_Finalized may be called at any time.
    unsafe { ffi::MPI_Finalized(&mut flag) };
    flag != 0
}

/// The host's start of MPI, asking for `required` or more: MPI_THREAD_MULTIPLE, so that
/// glray's messages may move on a thread of glray's while the host uses MPI on its own.
///
/// # Safety
/// As MPI_Init_thread.
pub unsafe fn init(
    argc: *mut c_int,
    argv: *mut *mut *mut c_char,
    required: c_int,
    provided: *mut c_int,
) -> Result<c_int, String> {
    let mut got: c_int = 0;
    let rc = if initialized() {
        // glray started it (the host calls MPI_Init after its first frame): the host's call
        // succeeds, as if it had started it.
        // SAFETY: MPI is started.
        unsafe { ffi::MPI_Query_thread(&mut got) };
        0
    } else {
        // SAFETY: as the caller's MPI_Init_thread.
        unsafe {
            let multiple = ffi::RSMPI_THREAD_MULTIPLE;
            ffi::PMPI_Init_thread(argc, argv, multiple.max(required), &mut got)
        }
    };
    if !provided.is_null() {
        // SAFETY: the caller's pointer.
        unsafe { *provided = got };
    }
    Ok(rc)
}

/// MPI started by glray, in a program under mpirun that does not use MPI itself.
fn init_for_glray() -> Result<(), String> {
    let mut got: c_int = 0;
    // SAFETY: MPI is not started; no arguments are passed (allowed since MPI-2).
    let rc = unsafe {
        ffi::PMPI_Init_thread(std::ptr::null_mut(), std::ptr::null_mut(), ffi::RSMPI_THREAD_MULTIPLE, &mut got)
    };
    code("MPI_Init_thread", rc)?;
    *STARTED_BY_GLRAY.lock().map_err(|e| e.to_string())? = true;
    Ok(())
}

/// glray's communicator: a duplicate of MPI_COMM_WORLD made without blocking (MPI_Comm_idup),
/// so that a rank where glray is missing (which never joins) costs a wait of `timeout`, not a
/// hang.
pub fn join(timeout: Duration) -> Result<(), String> {
    if comm::joined() {
        return Ok(());
    }
    if finalized() {
        return Err("MPI was finalized already".into());
    }
    if !initialized() {
        init_for_glray()?;
    }
    // SAFETY: MPI is started; the request is polled until done or abandoned.
    unsafe {
        let mut dup: ffi::MPI_Comm = ffi::RSMPI_COMM_NULL;
        let mut request: ffi::MPI_Request = ffi::RSMPI_REQUEST_NULL;
        code("MPI_Comm_idup", ffi::MPI_Comm_idup(ffi::RSMPI_COMM_WORLD, &mut dup, &mut request))?;
        let start = Instant::now();
        loop {
            let mut done: c_int = 0;
            code("MPI_Test", ffi::MPI_Test(&mut request, &mut done, ffi::RSMPI_STATUS_IGNORE))?;
            if done != 0 {
                break;
            }
            if start.elapsed() > timeout {
                // The duplicate is left pending: it cannot be cancelled.
                return Err(format!(
                    "not every rank joined glray's communicator within {:.0} s: every rank must run under \
                     glray (LD_PRELOAD and GLRAY_* forwarded to each, as `glray run --np` does)",
                    timeout.as_secs_f64()
                ));
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        // Errors on glray's communicator come back as codes: glray stops, the job goes on.
        ffi::MPI_Comm_set_errhandler(dup, ffi::RSMPI_ERRORS_RETURN);
        comm::set(Comm::new(dup));
    }
    Ok(())
}

pub fn threading() -> Result<c_int, String> {
    if !initialized() || finalized() {
        return Ok(-1);
    }
    let mut got: c_int = 0;
    // SAFETY: MPI is started.
    unsafe { ffi::MPI_Query_thread(&mut got) };
    Ok(got)
}

/// glray's MPI work ends (its communicator is freed), then MPI: when the host asks, or when
/// glray started it.
pub fn finalize(for_host: bool) -> Result<c_int, String> {
    comm::end();
    let ours = *STARTED_BY_GLRAY.lock().map_err(|e| e.to_string())?;
    if !initialized() || finalized() || !(for_host || ours) {
        return Ok(0);
    }
    // SAFETY: MPI is started and not finalized; glray's requests are gone.
    Ok(unsafe { ffi::PMPI_Finalize() })
}

pub fn abort(code: c_int) -> Result<c_int, String> {
    // SAFETY: MPI_Abort may be called once MPI is started.
    Ok(unsafe { ffi::MPI_Abort(ffi::RSMPI_COMM_WORLD, code) })
}
