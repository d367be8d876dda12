//! GetProcAddress: programs fetch most entry points this way (GLEW, VTK, glretrace), so every
//! name glray exports is answered with glray's own function, and any other name with whatever
//! the real implementation answers (glvnd hands out dispatch stubs even for names it does not
//! know, exactly as it would without glray).

use std::ffi::{c_void, CStr};

use crate::exports::own_function;
use crate::real;

/// glray's function for `name`, or None if glray does not export it.
unsafe fn own(name: *const c_void) -> Option<*mut c_void> {
    // SAFETY: the caller passes a NUL-terminated name (checked for null by the callers).
    let name = unsafe { CStr::from_ptr(name.cast()) };
    own_function(name.to_bytes()).map(|p| p as *mut c_void)
}

pub unsafe fn glXGetProcAddress(procName: *mut c_void) -> *mut c_void {
    if procName.is_null() {
        return std::ptr::null_mut();
    }
    own(procName).unwrap_or_else(|| real::glXGetProcAddress(procName))
}

pub unsafe fn glXGetProcAddressARB(procName: *mut c_void) -> *mut c_void {
    if procName.is_null() {
        return std::ptr::null_mut();
    }
    own(procName).unwrap_or_else(|| real::glXGetProcAddressARB(procName))
}

pub unsafe fn eglGetProcAddress(procname: *mut c_void) -> *mut c_void {
    if procname.is_null() {
        return std::ptr::null_mut();
    }
    own(procname).unwrap_or_else(|| real::eglGetProcAddress(procname))
}

pub unsafe fn OSMesaGetProcAddress(funcName: *mut c_void) -> *mut c_void {
    if funcName.is_null() {
        return std::ptr::null_mut();
    }
    own(funcName).unwrap_or_else(|| real::OSMesaGetProcAddress(funcName))
}
