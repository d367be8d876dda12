//! Finding the real GL, GLX, EGL and OSMesa libraries, never glray itself.
//!
//! glray may be preloaded (its symbols come first in the global scope) or dropped in (a directory
//! on LD_LIBRARY_PATH whose libGL.so.1, libEGL.so.1 and libOSMesa.so.8 are glray). Either way a
//! plain `dlopen("libEGL.so.1")` may hand back glray, so every library found is checked: a probe
//! symbol is looked up through the new handle and `dladdr` tells which file defines it. If that
//! file is glray's, the candidate is skipped with a clear reason and the system directories are
//! tried next. Libraries are opened with the dlopen that comes after glray (RTLD_NEXT), so that
//! glray's own dlopen redirection never applies to itself.

use std::ffi::{c_void, CStr, CString};
use std::os::unix::fs::MetadataExt;
use std::path::Path;

use libloading::os::unix::Library;

/// Which real library.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RealKind {
    OpenGL,
    Glx,
    Egl,
    OSMesa,
}

impl RealKind {
    pub const ALL: [RealKind; 4] = [RealKind::OpenGL, RealKind::Glx, RealKind::Egl, RealKind::OSMesa];

    /// The setting that overrides its path.
    pub fn setting(self) -> &'static str {
        match self {
            RealKind::OpenGL => "real_opengl",
            RealKind::Glx => "real_glx",
            RealKind::Egl => "real_egl",
            RealKind::OSMesa => "real_osmesa",
        }
    }

    pub fn soname(self) -> &'static str {
        match self {
            RealKind::OpenGL => "libOpenGL.so.0",
            RealKind::Glx => "libGLX.so.0",
            RealKind::Egl => "libEGL.so.1",
            RealKind::OSMesa => "libOSMesa.so.8",
        }
    }

    /// A symbol every real library of this kind defines.
    fn probe(self) -> &'static CStr {
        match self {
            RealKind::OpenGL => c"glGetString",
            RealKind::Glx => c"glXQueryVersion",
            RealKind::Egl => c"eglGetDisplay",
            RealKind::OSMesa => c"OSMesaCreateContext",
        }
    }
}

/// A file's identity, to tell "this is glray" whatever name or symlink reached it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FileId {
    dev: u64,
    ino: u64,
}

impl FileId {
    pub fn of(path: &Path) -> Option<FileId> {
        let m = std::fs::metadata(path).ok()?;
        Some(FileId { dev: m.dev(), ino: m.ino() })
    }
}

/// The file that defines the code or data at `addr`, from the dynamic loader.
// dladdr only compares `addr` with the loader's tables; it never reads through it.
#[allow(clippy::not_unsafe_ptr_arg_deref)]
pub fn defining_file(addr: *const c_void) -> Option<String> {
    // SAFETY: dladdr only reads the loader's tables; a zeroed Dl_info is a valid out-parameter.
    unsafe {
        let mut info: libc::Dl_info = std::mem::zeroed();
        if libc::dladdr(addr, &mut info) == 0 || info.dli_fname.is_null() {
            return None;
        }
        Some(CStr::from_ptr(info.dli_fname).to_string_lossy().into_owned())
    }
}

type DlopenFn = unsafe extern "C" fn(*const libc::c_char, libc::c_int) -> *mut c_void;

/// The dlopen that comes after the calling object in symbol order: libc's, or another
/// interposer's, but never glray's own redirection.
pub fn next_dlopen() -> Option<DlopenFn> {
    // SAFETY: dlsym with RTLD_NEXT and a literal name; the result is dlopen's address or null.
    let p = unsafe { libc::dlsym(libc::RTLD_NEXT, c"dlopen".as_ptr()) };
    // SAFETY: a non-null result is the address of a function with dlopen's signature.
    (!p.is_null()).then(|| unsafe { std::mem::transmute::<*mut c_void, DlopenFn>(p) })
}

fn dlerror() -> String {
    // SAFETY: dlerror returns null or a NUL-terminated thread-local string.
    unsafe {
        let e = libc::dlerror();
        if e.is_null() {
            "unknown dlopen error".into()
        } else {
            CStr::from_ptr(e).to_string_lossy().into_owned()
        }
    }
}

/// An opened real library. It is never closed: function pointers from it live as long as the
/// process.
pub struct RealLib {
    pub kind: RealKind,
    /// The file that defines the library's symbols (after symlinks and search paths).
    pub path: String,
    lib: Library,
}

impl RealLib {
    /// The address of `name` in this library (or its dependencies), or null.
    pub fn sym(&self, name: &CStr) -> *mut c_void {
        // SAFETY: we only read the symbol's address; nothing is called here.
        unsafe { self.lib.get::<*mut c_void>(name.to_bytes_with_nul()) }.map(|s| *s).unwrap_or(std::ptr::null_mut())
    }
}

/// Standard library directories, searched when the library path leads to glray itself.
fn system_dirs() -> Vec<String> {
    let triple = format!("{}-linux-gnu", std::env::consts::ARCH);
    vec![
        format!("/usr/lib/{triple}"),
        format!("/lib/{triple}"),
        "/usr/lib64".into(),
        "/lib64".into(),
        "/usr/lib".into(),
        "/lib".into(),
        "/usr/local/lib".into(),
    ]
}

/// Opens the real library of `kind`: the user's path if given, else its soname through the
/// library search path, else the system directories. `glray` is glray's own file, which must
/// never be taken for the real library.
pub fn open(kind: RealKind, user_path: Option<&str>, glray: Option<FileId>) -> Result<RealLib, String> {
    let dlopen = next_dlopen().ok_or("no dlopen after glray in symbol order")?;
    let candidates: Vec<String> = match user_path {
        Some(p) => vec![p.to_string()],
        None => std::iter::once(kind.soname().to_string())
            .chain(system_dirs().into_iter().map(|d| format!("{d}/{}", kind.soname())))
            .collect(),
    };
    let mut reasons = Vec::new();
    for cand in &candidates {
        if cand.contains('/') && !Path::new(cand).exists() {
            if user_path.is_some() {
                reasons.push(format!("{cand}: no such file"));
            }
            continue;
        }
        let Ok(c) = CString::new(cand.as_str()) else {
            reasons.push(format!("{cand:?}: contains a NUL byte"));
            continue;
        };
        // SAFETY: dlopen with a valid C string; RTLD_LOCAL keeps the real library's symbols out
        // of the global scope (where they would shadow nothing, but could confuse other lookups).
        let handle = unsafe { dlopen(c.as_ptr(), libc::RTLD_LAZY | libc::RTLD_LOCAL) };
        if handle.is_null() {
            reasons.push(format!("{cand}: {}", dlerror()));
            continue;
        }
        // SAFETY: `handle` came from dlopen and is owned by the Library from here on.
        let lib = unsafe { Library::from_raw(handle) };
        let real = RealLib { kind, path: cand.clone(), lib };
        let probe = real.sym(kind.probe());
        if probe.is_null() {
            reasons.push(format!("{cand}: has no {:?}, not a {} library", kind.probe(), kind.soname()));
            std::mem::forget(real);
            continue;
        }
        let file = defining_file(probe).unwrap_or_else(|| cand.clone());
        if glray.is_some() && FileId::of(Path::new(&file)) == glray {
            reasons.push(format!("{cand}: resolves to glray itself ({file})"));
            // Not closed: closing a handle to ourselves would only drop a reference anyway.
            std::mem::forget(real);
            continue;
        }
        return Ok(RealLib { path: file, ..real });
    }
    Err(format!(
        "cannot find the real {} (setting `{}`, GLRAY_{}): {}",
        kind.soname(),
        kind.setting(),
        kind.setting().to_ascii_uppercase(),
        reasons.join("; ")
    ))
}

/// OSMesa's context functions (osmesa.h), typed: what `glray replay` and `glray info` drive.
pub struct OSMesaApi {
    pub create_ext: unsafe extern "C" fn(u32, i32, i32, i32, *mut c_void) -> *mut c_void,
    pub make_current: unsafe extern "C" fn(*mut c_void, *mut c_void, u32, i32, i32) -> u8,
    pub destroy: unsafe extern "C" fn(*mut c_void),
    pub get_proc: unsafe extern "C" fn(*const libc::c_char) -> *mut c_void,
}

impl OSMesaApi {
    /// Looks the functions up in an opened libOSMesa.
    pub fn load(lib: &RealLib) -> Result<OSMesaApi, String> {
        let sym = |n: &CStr| {
            let p = lib.sym(n);
            if p.is_null() {
                Err(format!("{} has no {}", lib.path, n.to_string_lossy()))
            } else {
                Ok(p)
            }
        };
        // SAFETY: these names are osmesa.h's functions, with these signatures.
        unsafe {
            Ok(OSMesaApi {
                create_ext: std::mem::transmute::<
                    *mut c_void,
                    unsafe extern "C" fn(u32, i32, i32, i32, *mut c_void) -> *mut c_void,
                >(sym(c"OSMesaCreateContextExt")?),
                make_current: std::mem::transmute::<
                    *mut c_void,
                    unsafe extern "C" fn(*mut c_void, *mut c_void, u32, i32, i32) -> u8,
                >(sym(c"OSMesaMakeCurrent")?),
                destroy: std::mem::transmute::<*mut c_void, unsafe extern "C" fn(*mut c_void)>(sym(
                    c"OSMesaDestroyContext",
                )?),
                get_proc: std::mem::transmute::<*mut c_void, unsafe extern "C" fn(*const libc::c_char) -> *mut c_void>(
                    sym(c"OSMesaGetProcAddress")?,
                ),
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bad_user_path_is_named() {
        let e = open(RealKind::Egl, Some("/nonexistent/libEGL.so.1"), None).err().unwrap();
        assert!(e.contains("/nonexistent/libEGL.so.1") && e.contains("real_egl"), "{e}");
    }

    #[test]
    fn a_library_of_the_wrong_kind_is_refused() {
        let e = open(RealKind::OSMesa, Some("libm.so.6"), None).err().unwrap();
        assert!(e.contains("not a libOSMesa.so.8 library"), "{e}");
    }
    // That glray itself is refused is tested end to end in tests/interposer.rs, with
    // GLRAY_REAL_EGL pointing at libglray.so.
}
