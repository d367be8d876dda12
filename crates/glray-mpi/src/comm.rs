//! glray's communicator and the messages under way on it: sends started with MPI_Isend and
//! kept (with their bytes) until MPI_Test says they are done; receives by a matched probe
//! (rsmpi), so a message is taken whole or not at all. One tag: the communicator is glray's
//! alone.

use std::ffi::c_int;
use std::mem::ManuallyDrop;
use std::sync::Mutex;

use mpi::ffi;
use mpi::point_to_point::{MatchedReceiveVec, Source};
use mpi::raw::AsRaw;
use mpi::topology::{Communicator, SimpleCommunicator};
use mpi::traits::FromRaw;

const TAG: c_int = 7;

/// glray's duplicate of MPI_COMM_WORLD, and its sends under way.
pub struct Comm {
    /// Not dropped by rsmpi (that would free it behind `end`).
    comm: ManuallyDrop<SimpleCommunicator>,
    outbox: Vec<(Vec<u8>, ffi::MPI_Request)>,
}

// SAFETY: the communicator and requests are MPI handles, used by one thread at a time under
// `STATE`'s lock; MPI is started with MPI_THREAD_MULTIPLE, or libglray makes these calls only
// on the host's thread inside its GL calls.
unsafe impl Send for Comm {}

static STATE: Mutex<Option<Comm>> = Mutex::new(None);

impl Comm {
    /// # Safety
    /// `raw` is a live communicator, given over to this.
    pub unsafe fn new(raw: ffi::MPI_Comm) -> Comm {
        Comm { comm: ManuallyDrop::new(unsafe { SimpleCommunicator::from_raw(raw) }), outbox: Vec::new() }
    }

    pub fn rank(&self) -> c_int {
        self.comm.rank()
    }

    pub fn size(&self) -> c_int {
        self.comm.size()
    }

    pub fn send(&mut self, to: c_int, data: Vec<u8>) -> Result<(), String> {
        if !(0..self.size()).contains(&to) {
            return Err(format!("no rank {to} (of {})", self.size()));
        }
        let count =
            c_int::try_from(data.len()).map_err(|_| format!("a message of {} bytes (2 GiB at most)", data.len()))?;
        let mut request: ffi::MPI_Request = unsafe { ffi::RSMPI_REQUEST_NULL };
        // SAFETY: the bytes live in `outbox` until the request completes (a Vec's heap buffer
        // does not move when the Vec does).
        let rc = unsafe {
            ffi::MPI_Isend(data.as_ptr().cast(), count, ffi::RSMPI_UINT8_T, to, TAG, self.comm.as_raw(), &mut request)
        };
        if rc != 0 {
            return Err(format!("MPI_Isend to rank {to} failed with MPI error {rc}"));
        }
        self.outbox.push((data, request));
        Ok(())
    }

    pub fn flushed(&mut self) -> Result<bool, String> {
        let mut failed = None;
        self.outbox.retain_mut(|(_, request)| {
            let mut done: c_int = 0;
            // SAFETY: a request of ours, not yet completed.
            let rc = unsafe { ffi::MPI_Test(request, &mut done, ffi::RSMPI_STATUS_IGNORE) };
            if rc != 0 {
                failed = Some(rc);
            }
            done == 0 && rc == 0
        });
        match failed {
            Some(rc) => Err(format!("a send failed with MPI error {rc}")),
            None => Ok(self.outbox.is_empty()),
        }
    }

    /// Bytes of the sends still under way (after moving them on): how far behind the
    /// network is.
    pub fn unsent(&mut self) -> Result<u64, String> {
        self.flushed()?;
        Ok(self.outbox.iter().map(|(data, _)| data.len() as u64).sum())
    }

    pub fn poll(&mut self) -> Result<Option<(c_int, Vec<u8>)>, String> {
        // Sends move on as messages are looked for.
        self.flushed()?;
        match self.comm.any_process().immediate_matched_probe_with_tag(TAG) {
            Some(probed) => {
                let source = probed.1.source_rank();
                let (data, _) = probed.matched_receive_vec::<u8>();
                Ok(Some((source, data)))
            }
            None => Ok(None),
        }
    }
}

pub fn joined() -> bool {
    STATE.lock().map(|s| s.is_some()).unwrap_or(false)
}

pub fn set(comm: Comm) {
    if let Ok(mut s) = STATE.lock() {
        *s = Some(comm);
    }
}

pub fn with<T>(f: impl FnOnce(&mut Comm) -> Result<T, String>) -> Result<T, String> {
    let mut state = STATE.lock().map_err(|_| "glray's MPI edge is poisoned".to_string())?;
    match state.as_mut() {
        Some(c) => f(c),
        None => Err("glray has not joined MPI (glray_mpi_join)".into()),
    }
}

/// Cancels the sends under way and frees the communicator.
pub fn end() {
    let Ok(mut state) = STATE.lock() else { return };
    if let Some(mut c) = state.take() {
        for (_, mut request) in c.outbox.drain(..) {
            // SAFETY: our requests; a cancelled send is freed, never waited on.
            unsafe {
                ffi::MPI_Cancel(&mut request);
                ffi::MPI_Request_free(&mut request);
            }
        }
        let mut raw = c.comm.as_raw();
        // SAFETY: glray's own communicator, no request on it left.
        unsafe { ffi::MPI_Comm_free(&mut raw) };
    }
}
