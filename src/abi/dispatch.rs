//! Which real function a call goes to.
//!
//! One table of function pointers per real implementation: glvnd (libOpenGL, libGLX, libEGL,
//! for GLX and EGL contexts alike) and OSMesa. A GL command follows the calling thread's current
//! context: `MakeCurrent` handlers set a thread-local backend. Slots are filled lazily, on the
//! first call of each command: the hot path is one thread-local read and one atomic load, with no
//! lock and no allocation (DESIGN.md rule 4).

use std::cell::Cell;
use std::ffi::{c_void, CStr};
use std::ptr::null_mut;
use std::sync::atomic::{AtomicPtr, AtomicU8, Ordering};

use glray_core::reallib::RealKind;

use crate::abi::commands::{Lib, COMMANDS, COUNT};
use crate::abi::runtime;

/// A slot value meaning "looked up, and there is no real function".
const MISSING: *mut c_void = std::ptr::dangling_mut::<c_void>();

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    Glvnd,
    OSMesa,
}

struct Table([AtomicPtr<c_void>; COUNT]);

static GLVND: Table = Table([const { AtomicPtr::new(null_mut()) }; COUNT]);
static OSMESA: Table = Table([const { AtomicPtr::new(null_mut()) }; COUNT]);

thread_local! {
    static BACKEND: Cell<Backend> = const { Cell::new(Backend::Glvnd) };
}

/// Which kinds of context the process has ever bound: a bit per backend. While only one kind has
/// been seen (nearly every program), GL calls go to it without reading the thread-local (a
/// `__tls_get_addr` call in a shared library, about half of glray's cost per call).
static SEEN: AtomicU8 = AtomicU8::new(0);
const SEEN_GLVND: u8 = 1;
const SEEN_OSMESA: u8 = 2;

/// Makes this thread's GL calls go to `backend` (called after a successful MakeCurrent).
/// The backend of this thread's current context.
pub fn backend() -> Backend {
    BACKEND.with(|b| b.get())
}

pub fn set_backend(backend: Backend) {
    BACKEND.with(|b| b.set(backend));
    let bit = match backend {
        Backend::Glvnd => SEEN_GLVND,
        Backend::OSMesa => SEEN_OSMESA,
    };
    if SEEN.load(Ordering::Relaxed) & bit == 0 {
        SEEN.fetch_or(bit, Ordering::SeqCst);
    }
}

/// The real function of GL command `i` for this thread's current context.
#[inline(always)]
pub fn gl(i: usize) -> *mut c_void {
    match SEEN.load(Ordering::Relaxed) {
        SEEN_OSMESA => osmesa(i),
        // Both kinds bound in this process: follow the thread's own context.
        s if s == SEEN_GLVND | SEEN_OSMESA => match BACKEND.with(|b| b.get()) {
            Backend::Glvnd => glvnd(i),
            Backend::OSMesa => osmesa(i),
        },
        // Only glvnd, or no context bound yet (GL calls then reach glvnd's no-op dispatch, as
        // they would without glray).
        _ => glvnd(i),
    }
}

/// The real function of GL command `i` if it is already known and the process has bound only
/// one kind of context; null otherwise (then `gl` finds it). No call, no thread-local: this is
/// what every export's fast path inlines.
#[inline(always)]
pub fn gl_cached(i: usize) -> *mut c_void {
    match SEEN.load(Ordering::Relaxed) {
        SEEN_OSMESA => cached(&OSMESA, i),
        s if s == SEEN_GLVND | SEEN_OSMESA => null_mut(),
        _ => cached(&GLVND, i),
    }
}

/// The real function of command `i` in glvnd if already known, else null.
#[inline(always)]
pub fn glvnd_cached(i: usize) -> *mut c_void {
    cached(&GLVND, i)
}

/// The real function of command `i` in OSMesa if already known, else null.
#[inline(always)]
pub fn osmesa_cached(i: usize) -> *mut c_void {
    cached(&OSMESA, i)
}

#[inline(always)]
fn cached(table: &Table, i: usize) -> *mut c_void {
    let p = table.0[i].load(Ordering::Acquire);
    if p as usize > MISSING as usize {
        p
    } else {
        null_mut()
    }
}

/// The real function of command `i` in glvnd (GL, GLX, EGL).
#[inline(always)]
pub fn glvnd(i: usize) -> *mut c_void {
    slot(&GLVND, i, Backend::Glvnd)
}

/// The real function of command `i` in OSMesa.
#[inline(always)]
pub fn osmesa(i: usize) -> *mut c_void {
    slot(&OSMESA, i, Backend::OSMesa)
}

#[inline(always)]
fn slot(table: &Table, i: usize, backend: Backend) -> *mut c_void {
    let p = table.0[i].load(Ordering::Acquire);
    if p as usize > MISSING as usize {
        p
    } else if p.is_null() {
        resolve(table, i, backend)
    } else {
        null_mut()
    }
}

#[cold]
#[inline(never)]
fn resolve(table: &Table, i: usize, backend: Backend) -> *mut c_void {
    let found = std::panic::catch_unwind(|| find(i, backend)).unwrap_or(null_mut());
    let value = if found.is_null() { MISSING } else { found };
    // Several threads may race here; they find the same pointer, and only the first one logs.
    if table.0[i].compare_exchange(null_mut(), value, Ordering::AcqRel, Ordering::Acquire).is_ok() {
        let name = COMMANDS[i].name.to_string_lossy();
        if found.is_null() {
            glray_core::warn!("{name} has no real implementation ({backend:?}); calls to it do nothing");
        } else if glray_core::log::enabled(glray_core::log::Level::Debug) {
            let file = glray_core::reallib::defining_file(found).unwrap_or_default();
            glray_core::debug!("{name} -> {backend:?} {file}");
        }
    }
    found
}

type GetProcFn = unsafe extern "C" fn(*const u8) -> *mut c_void;

/// Calls a real GetProcAddress-like function `getter` of `kind` for `name`.
fn get_proc(kind: RealKind, getter: &CStr, name: &CStr) -> *mut c_void {
    let Some(lib) = runtime::real(kind) else { return null_mut() };
    let f = lib.sym(getter);
    if f.is_null() {
        return null_mut();
    }
    // SAFETY: `getter` is a GetProcAddress function of that library: (const char*) -> pointer.
    unsafe { std::mem::transmute::<*mut c_void, GetProcFn>(f)(name.as_ptr().cast()) }
}

fn sym(kind: RealKind, name: &CStr) -> *mut c_void {
    runtime::real(kind).map_or(null_mut(), |l| l.sym(name))
}

/// Finds the real function of command `i`: by name in the real library, then through that
/// library's GetProcAddress (extensions are often only reachable that way).
fn find(i: usize, backend: Backend) -> *mut c_void {
    let info = &COMMANDS[i];
    let name = info.name;
    let or = |p: *mut c_void, then: &dyn Fn() -> *mut c_void| if p.is_null() { then() } else { p };
    let p = match (info.lib, backend) {
        (Lib::Gl, Backend::Glvnd) => or(sym(RealKind::OpenGL, name), &|| {
            or(sym(RealKind::Glx, name), &|| get_proc(RealKind::Glx, c"glXGetProcAddressARB", name))
        }),
        (Lib::Gl, Backend::OSMesa) | (Lib::OSMesa, _) => {
            or(sym(RealKind::OSMesa, name), &|| get_proc(RealKind::OSMesa, c"OSMesaGetProcAddress", name))
        }
        (Lib::Glx, _) => or(sym(RealKind::Glx, name), &|| get_proc(RealKind::Glx, c"glXGetProcAddressARB", name)),
        (Lib::Egl, _) => or(sym(RealKind::Egl, name), &|| get_proc(RealKind::Egl, c"eglGetProcAddress", name)),
    };
    if !p.is_null() && is_own(p) {
        glray_core::error!(
            "looking up the real {} found glray's own function: the real GL library setting \
             points at glray, or glray is installed as the system GL; treating it as missing",
            name.to_string_lossy()
        );
        return null_mut();
    }
    p
}

/// Whether `p` lies in glray's own library.
fn is_own(p: *mut c_void) -> bool {
    let own = runtime::get().own_base;
    let mut info: libc::Dl_info = unsafe { std::mem::zeroed() };
    // SAFETY: dladdr only reads the loader's tables.
    unsafe { libc::dladdr(p, &mut info) != 0 && std::ptr::eq(info.dli_fbase, own) }
}
