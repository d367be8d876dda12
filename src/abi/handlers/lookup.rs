//! GetProcAddress: programs fetch most entry points this way (GLEW, VTK, glretrace), so every
//! name glray exports is answered with glray's own function. A name of the GL, GLX, EGL or OSMesa
//! APIs that glray does not export (an extension newer than its registry) gets whatever the real
//! implementation answers, as without glray. Any other name gets NULL: glvnd would hand out a
//! dispatch stub even for "notAFunction" (the GLX spec allows that), but a NULL tells a program
//! the truth.

use std::ffi::{c_void, CStr};

use crate::abi::exports::own_function;
use crate::abi::real;

/// How to answer a lookup of `name`.
enum Answer {
    Own(*mut c_void),
    AskReal,
    Unknown,
}

unsafe fn answer(name: *const c_void) -> Answer {
    if name.is_null() {
        return Answer::Unknown;
    }
    // SAFETY: a non-null name is NUL-terminated (the GetProcAddress contract).
    let name = unsafe { CStr::from_ptr(name.cast()) }.to_bytes();
    if let Some(p) = own_function(name) {
        Answer::Own(p as *mut c_void)
    } else if [&b"gl"[..], b"egl", b"OSMesa"].iter().any(|api| name.starts_with(api)) {
        Answer::AskReal
    } else {
        Answer::Unknown
    }
}

/// Answers a lookup: glray's function, the real one, or NULL.
unsafe fn resolve(name: *mut c_void, real: impl FnOnce(*mut c_void) -> *mut c_void) -> *mut c_void {
    match answer(name) {
        Answer::Own(p) => p,
        Answer::AskReal => real(name),
        Answer::Unknown => std::ptr::null_mut(),
    }
}

pub unsafe fn glXGetProcAddress(procName: *mut c_void) -> *mut c_void {
    resolve(procName, |n| real::glXGetProcAddress(n))
}

pub unsafe fn glXGetProcAddressARB(procName: *mut c_void) -> *mut c_void {
    resolve(procName, |n| real::glXGetProcAddressARB(n))
}

pub unsafe fn eglGetProcAddress(procname: *mut c_void) -> *mut c_void {
    resolve(procname, |n| real::eglGetProcAddress(n))
}

pub unsafe fn OSMesaGetProcAddress(funcName: *mut c_void) -> *mut c_void {
    resolve(funcName, |n| real::OSMesaGetProcAddress(n))
}
