//! Programs that dlopen a GL library themselves end up in glray (as VirtualGL's dlfaker does).
//!
//! Preloaded with SONAME libGL.so.1, glray already answers `dlopen("libGL.so.1")`; but
//! `dlopen("libGL.so")`, `"libGLX.so.0"`, `"libOpenGL.so.0"`, `"libEGL.so.1"` or
//! `"libOSMesa.so.8"` would reach the real libraries and bypass it. This dlopen redirects exactly
//! those library names (any directory, any version suffix, nothing else: VirtualGL once hijacked
//! VisIt's libGLabelPlot.so with a looser match) to glray's own file, and drops RTLD_DEEPBIND,
//! which would bind the caller past glray. dlsym on the handle then finds glray's exports first
//! and glvnd's (glray's dependencies) for anything else. `GLRAY_INTERCEPT_DLOPEN=0` turns it off.
//! glray's own loads of the real libraries use the next dlopen directly and never come here.

use std::ffi::{c_char, c_int, c_void, CStr};
use std::sync::OnceLock;

use glray_core::reallib::next_dlopen;

type DlopenFn = unsafe extern "C" fn(*const c_char, c_int) -> *mut c_void;

/// Whether `path` names one of the GL libraries glray stands in for.
pub fn is_gl_library(path: &[u8]) -> bool {
    let base = path.rsplit(|&c| c == b'/').next().unwrap_or(path);
    ["libGL", "libGLX", "libOpenGL", "libEGL", "libOSMesa"].iter().any(|stem| {
        base.strip_prefix(stem.as_bytes()).and_then(|rest| rest.strip_prefix(b".so")).is_some_and(|version| {
            // Nothing, or ".N", ".N.M", ...
            version.is_empty()
                || (version[0] == b'.'
                    && version[1..].split(|&c| c == b'.').all(|n| !n.is_empty() && n.iter().all(u8::is_ascii_digit)))
        })
    })
}

fn next() -> Option<DlopenFn> {
    static NEXT: OnceLock<Option<DlopenFn>> = OnceLock::new();
    *NEXT.get_or_init(next_dlopen)
}

#[no_mangle]
pub unsafe extern "C" fn dlopen(filename: *const c_char, flags: c_int) -> *mut c_void {
    let Some(next) = next() else { return std::ptr::null_mut() };
    let redirect = std::panic::catch_unwind(|| {
        if filename.is_null() {
            return None;
        }
        // SAFETY: a non-null dlopen argument is a NUL-terminated path.
        let name = unsafe { CStr::from_ptr(filename) };
        if !is_gl_library(name.to_bytes()) {
            return None;
        }
        let rt = crate::abi::runtime::get();
        if !rt.config.intercept_dlopen() {
            return None;
        }
        let own = rt.own_path.as_ref()?;
        glray_core::debug!("dlopen({:?}) -> glray ({:?})", name, own);
        Some(own.as_ptr())
    });
    match redirect {
        Ok(Some(own)) => next(own, flags & !libc::RTLD_DEEPBIND),
        _ => next(filename, flags),
    }
}

#[cfg(test)]
mod tests {
    use super::is_gl_library;

    #[test]
    fn matches_only_gl_library_names() {
        for yes in [
            "libGL.so.1",
            "/usr/lib/x86_64-linux-gnu/libGL.so.1",
            "libGL.so",
            "libGL.so.1.7.0",
            "libGLX.so.0",
            "libOpenGL.so.0",
            "libEGL.so.1",
            "libOSMesa.so.8",
            "libOSMesa.so.8.0.0",
        ] {
            assert!(is_gl_library(yes.as_bytes()), "{yes}");
        }
        for no in [
            "libGLX_mesa.so.0",
            "libGLdispatch.so.0",
            "libGLU.so.1",
            "libGLabelPlot.so",
            "libGLEW.so.2.2",
            "libEGL_mesa.so.0",
            "libGL.so.1x",
            "libGL.so.",
            "libgl.so.1",
            "mylibGL.so.1",
            "",
        ] {
            assert!(!is_gl_library(no.as_bytes()), "{no}");
        }
    }
}
