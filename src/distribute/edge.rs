//! libglray_mpi.so, glray's MPI edge, loaded with dlopen only in an MPI rank (libglray itself
//! links no MPI): its functions as a table (`Edge`), and the message transport over them
//! (`MpiTransport`) that the protocol (glray-distribute) runs on.

use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::path::PathBuf;
use std::sync::OnceLock;

use glray_distribute::Transport;

/// The version of the edge's functions this libglray was built with (glray-mpi's `ABI`).
const ABI: u32 = 2;

type Init = unsafe extern "C" fn(*mut c_int, *mut *mut *mut c_char, c_int, *mut c_int) -> c_int;

/// The edge's functions.
pub struct Edge {
    pub init: Init,
    join: extern "C" fn(u64) -> c_int,
    pub threading: extern "C" fn() -> c_int,
    rank: extern "C" fn() -> c_int,
    size: extern "C" fn() -> c_int,
    send: unsafe extern "C" fn(c_int, *const u8, usize) -> c_int,
    flushed: extern "C" fn() -> c_int,
    unsent: extern "C" fn() -> c_int,
    poll: unsafe extern "C" fn(*mut c_int, *mut *mut u8, *mut usize) -> c_int,
    free: unsafe extern "C" fn(*mut u8, usize),
    pub finalize: extern "C" fn(c_int) -> c_int,
    error: extern "C" fn() -> *const c_char,
}

/// Where the edge is: the setting `mpi_library`, else beside libglray.so (its real file: a
/// drop-in directory holds only links to libglray.so).
fn path() -> PathBuf {
    let rt = crate::abi::runtime::get();
    if let Some(p) = rt.config.real_path("mpi_library") {
        return PathBuf::from(p);
    }
    let own = rt.own_path.as_ref().map(|p| PathBuf::from(&*p.to_string_lossy())).unwrap_or_default();
    let own = std::fs::canonicalize(&own).unwrap_or(own);
    own.parent().map(|d| d.join("libglray_mpi.so")).unwrap_or_else(|| PathBuf::from("libglray_mpi.so"))
}

/// The edge, loaded on first use; Err (the same text every time) when it cannot be.
pub fn get() -> Result<&'static Edge, &'static str> {
    static EDGE: OnceLock<Result<Edge, String>> = OnceLock::new();
    EDGE.get_or_init(load).as_ref().map_err(|e| e.as_str())
}

fn load() -> Result<Edge, String> {
    let path = path();
    let c = CString::new(path.to_string_lossy().as_bytes()).map_err(|e| e.to_string())?;
    // SAFETY: dlopen of a library of glray's own. RTLD_GLOBAL: Open MPI loads its components
    // with dlopen and they bind to libmpi's symbols in the global scope (loaded locally, a
    // program that does not use MPI itself was reported by mpirun as "exiting improperly").
    let handle = unsafe { libc::dlopen(c.as_ptr(), libc::RTLD_NOW | libc::RTLD_GLOBAL) };
    if handle.is_null() {
        // SAFETY: dlerror's text is valid until the next dl call.
        let why = unsafe { CStr::from_ptr(libc::dlerror()) }.to_string_lossy().into_owned();
        return Err(format!(
            "cannot load glray's MPI edge {} ({why}); set mpi_library (GLRAY_MPI_LIBRARY) or build it with \
             `cargo build --release --workspace`",
            path.display()
        ));
    }
    let sym = |name: &CStr| -> Result<*mut c_void, String> {
        // SAFETY: a symbol of the library just opened.
        let p = unsafe { libc::dlsym(handle, name.as_ptr()) };
        if p.is_null() {
            Err(format!("{} has no {} (another version of glray?)", path.display(), name.to_string_lossy()))
        } else {
            Ok(p)
        }
    };
    // SAFETY: each symbol is glray-mpi's function of this signature (checked by its ABI number
    // first).
    unsafe {
        let abi: extern "C" fn() -> u32 = std::mem::transmute(sym(c"glray_mpi_abi")?);
        if abi() != ABI {
            return Err(format!("{} is edge version {}, this libglray needs {ABI}", path.display(), abi()));
        }
        Ok(Edge {
            init: std::mem::transmute::<*mut c_void, Init>(sym(c"glray_mpi_init")?),
            join: std::mem::transmute::<*mut c_void, extern "C" fn(u64) -> c_int>(sym(c"glray_mpi_join")?),
            threading: std::mem::transmute::<*mut c_void, extern "C" fn() -> c_int>(sym(c"glray_mpi_threading")?),
            rank: std::mem::transmute::<*mut c_void, extern "C" fn() -> c_int>(sym(c"glray_mpi_rank")?),
            size: std::mem::transmute::<*mut c_void, extern "C" fn() -> c_int>(sym(c"glray_mpi_size")?),
            send: std::mem::transmute::<*mut c_void, unsafe extern "C" fn(c_int, *const u8, usize) -> c_int>(sym(
                c"glray_mpi_send",
            )?),
            flushed: std::mem::transmute::<*mut c_void, extern "C" fn() -> c_int>(sym(c"glray_mpi_flushed")?),
            unsent: std::mem::transmute::<*mut c_void, extern "C" fn() -> c_int>(sym(c"glray_mpi_unsent")?),
            poll: std::mem::transmute::<*mut c_void, unsafe extern "C" fn(*mut c_int, *mut *mut u8, *mut usize) -> c_int>(
                sym(c"glray_mpi_poll")?,
            ),
            free: std::mem::transmute::<*mut c_void, unsafe extern "C" fn(*mut u8, usize)>(sym(c"glray_mpi_free")?),
            finalize: std::mem::transmute::<*mut c_void, extern "C" fn(c_int) -> c_int>(sym(c"glray_mpi_finalize")?),
            error: std::mem::transmute::<*mut c_void, extern "C" fn() -> *const c_char>(sym(c"glray_mpi_error")?),
        })
    }
}

impl Edge {
    /// The edge's last error.
    pub fn error(&self) -> String {
        let p = (self.error)();
        if p.is_null() {
            return "unknown error".into();
        }
        // SAFETY: a NUL-terminated string the edge keeps until its next call.
        unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
    }

    fn check(&self, rc: c_int) -> Result<c_int, String> {
        if rc < 0 {
            Err(self.error())
        } else {
            Ok(rc)
        }
    }

    /// Joins glray's communicator (starting MPI if nobody has), waiting at most `timeout`.
    pub fn join(&'static self, timeout: std::time::Duration) -> Result<MpiTransport, String> {
        self.check((self.join)(timeout.as_millis() as u64))?;
        let rank = self.check((self.rank)())? as usize;
        let size = self.check((self.size)())? as usize;
        Ok(MpiTransport { edge: self, rank, size })
    }
}

/// Byte messages over glray's communicator.
pub struct MpiTransport {
    edge: &'static Edge,
    rank: usize,
    size: usize,
}

impl Transport for MpiTransport {
    fn rank(&self) -> usize {
        self.rank
    }

    fn size(&self) -> usize {
        self.size
    }

    fn send(&mut self, to: usize, bytes: Vec<u8>) -> Result<(), String> {
        // SAFETY: the edge copies the bytes before it returns.
        let rc = unsafe { (self.edge.send)(to as c_int, bytes.as_ptr(), bytes.len()) };
        self.edge.check(rc).map(|_| ())
    }

    fn poll(&mut self) -> Result<Option<(usize, Vec<u8>)>, String> {
        let (mut from, mut bytes, mut len) = (0 as c_int, std::ptr::null_mut::<u8>(), 0usize);
        // SAFETY: out-pointers to locals.
        let rc = unsafe { (self.edge.poll)(&mut from, &mut bytes, &mut len) };
        if self.edge.check(rc)? == 0 {
            return Ok(None);
        }
        // SAFETY: the edge's buffer of `len` bytes, copied and given back once.
        let data = unsafe {
            let data = std::slice::from_raw_parts(bytes, len).to_vec();
            (self.edge.free)(bytes, len);
            data
        };
        Ok(Some((from as usize, data)))
    }

    fn flushed(&mut self) -> Result<bool, String> {
        self.edge.check((self.edge.flushed)()).map(|f| f != 0)
    }

    fn unsent(&mut self) -> Result<u64, String> {
        self.edge.check((self.edge.unsent)()).map(|b| b as u64)
    }
}
