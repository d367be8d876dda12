//! MakeCurrent: after a successful bind, the thread's GL calls go to the implementation that owns
//! the context (glvnd for GLX and EGL, Mesa's OSMesa for OSMesa). A failed bind changes nothing,
//! as in GL. Before any bind, capture follows the attribute calls the thread made in the context
//! it leaves (`record::given::flush`).

use std::ffi::{c_ulong, c_void};

use crate::abi::dispatch::{set_backend, Backend};
use crate::abi::real;

/// Binds with `bind` (the real MakeCurrent), after capture followed what the thread made in the
/// context it leaves.
fn bind<T: PartialEq + Default>(bind: impl FnOnce() -> T, backend: Backend) -> T {
    crate::calls::given::flush();
    let ok = bind();
    if ok != T::default() {
        set_backend(backend);
        crate::abi::profile::made_current();
    }
    ok
}

pub unsafe fn glXMakeCurrent(dpy: *mut c_void, drawable: c_ulong, ctx: *mut c_void) -> i32 {
    bind(|| real::glXMakeCurrent(dpy, drawable, ctx), Backend::Glvnd)
}

pub unsafe fn glXMakeContextCurrent(dpy: *mut c_void, draw: c_ulong, read: c_ulong, ctx: *mut c_void) -> i32 {
    bind(|| real::glXMakeContextCurrent(dpy, draw, read, ctx), Backend::Glvnd)
}

pub unsafe fn glXMakeCurrentReadSGI(dpy: *mut c_void, draw: c_ulong, read: c_ulong, ctx: *mut c_void) -> i32 {
    bind(|| real::glXMakeCurrentReadSGI(dpy, draw, read, ctx), Backend::Glvnd)
}

pub unsafe fn eglMakeCurrent(dpy: *mut c_void, draw: *mut c_void, read: *mut c_void, ctx: *mut c_void) -> u32 {
    bind(|| real::eglMakeCurrent(dpy, draw, read, ctx), Backend::Glvnd)
}

pub unsafe fn eglReleaseThread() -> u32 {
    bind(|| real::eglReleaseThread(), Backend::Glvnd)
}

pub unsafe fn OSMesaMakeCurrent(ctx: *mut c_void, buffer: *mut c_void, type_: u32, width: i32, height: i32) -> u8 {
    bind(|| real::OSMesaMakeCurrent(ctx, buffer, type_, width, height), Backend::OSMesa)
}
