//! A headless EGL context: Mesa's surfaceless platform, a pbuffer, desktop GL (compatibility).
//! Which library provides the gl* functions is the program's choice (egl_scene links libGL, as
//! xscreensaver does).
#![allow(dead_code)]

use glray_gl::{
    EGL_DEPTH_SIZE, EGL_HEIGHT, EGL_NONE, EGL_OPENGL_API, EGL_OPENGL_BIT, EGL_PBUFFER_BIT,
    EGL_PLATFORM_SURFACELESS_MESA, EGL_RED_SIZE, EGL_RENDERABLE_TYPE, EGL_SURFACE_TYPE, EGL_WIDTH,
};
use std::ffi::c_void;

#[link(name = "EGL")]
extern "C" {
    fn eglGetPlatformDisplay(platform: u32, native: *mut c_void, attribs: *const isize) -> *mut c_void;
    fn eglInitialize(dpy: *mut c_void, major: *mut i32, minor: *mut i32) -> u32;
    fn eglBindAPI(api: u32) -> u32;
    fn eglChooseConfig(dpy: *mut c_void, attribs: *const i32, configs: *mut *mut c_void, n: i32, num: *mut i32) -> u32;
    fn eglCreateContext(dpy: *mut c_void, cfg: *mut c_void, share: *mut c_void, attribs: *const i32) -> *mut c_void;
    fn eglCreatePbufferSurface(dpy: *mut c_void, cfg: *mut c_void, attribs: *const i32) -> *mut c_void;
    pub fn eglMakeCurrent(dpy: *mut c_void, draw: *mut c_void, read: *mut c_void, ctx: *mut c_void) -> u32;
    pub fn eglGetProcAddress(name: *const u8) -> *const c_void;
    pub fn eglSwapBuffers(dpy: *mut c_void, surface: *mut c_void) -> u32;
    fn eglDestroySurface(dpy: *mut c_void, surface: *mut c_void) -> u32;
    fn eglDestroyContext(dpy: *mut c_void, ctx: *mut c_void) -> u32;
    fn eglTerminate(dpy: *mut c_void) -> u32;
    pub fn eglGetError() -> i32;
}

pub struct Egl {
    pub dpy: *mut c_void,
    pub surface: *mut c_void,
    ctx: *mut c_void,
    pub version: (i32, i32),
    /// eglTerminate the display when dropped. The display is one per process: a program whose
    /// threads each have a context must not terminate it while the others still use it.
    pub terminate_on_drop: bool,
}

impl Egl {
    /// Creates the context and makes it current on this thread.
    pub unsafe fn new(width: i32, height: i32) -> Result<Egl, String> {
        let fail = |what: &str| format!("{what} failed (eglGetError {:#x})", eglGetError());
        let dpy = eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA as u32, std::ptr::null_mut(), std::ptr::null());
        let (mut major, mut minor) = (0, 0);
        if dpy.is_null() || eglInitialize(dpy, &mut major, &mut minor) == 0 {
            return Err(fail("eglInitialize"));
        }
        eglBindAPI(EGL_OPENGL_API as u32);
        let attribs = [
            EGL_SURFACE_TYPE,
            EGL_PBUFFER_BIT,
            EGL_RENDERABLE_TYPE,
            EGL_OPENGL_BIT,
            EGL_RED_SIZE,
            8,
            EGL_DEPTH_SIZE,
            16,
            EGL_NONE,
        ];
        let mut cfg = std::ptr::null_mut();
        let mut n = 0;
        if eglChooseConfig(dpy, attribs.as_ptr(), &mut cfg, 1, &mut n) == 0 || n < 1 {
            return Err(fail("eglChooseConfig"));
        }
        let ctx = eglCreateContext(dpy, cfg, std::ptr::null_mut(), [EGL_NONE].as_ptr());
        let surface = eglCreatePbufferSurface(dpy, cfg, [EGL_WIDTH, width, EGL_HEIGHT, height, EGL_NONE].as_ptr());
        if ctx.is_null() || surface.is_null() || eglMakeCurrent(dpy, surface, surface, ctx) == 0 {
            return Err(fail("context or surface"));
        }
        Ok(Egl { dpy, surface, ctx, version: (major, minor), terminate_on_drop: true })
    }

    pub unsafe fn swap(&self) {
        eglSwapBuffers(self.dpy, self.surface);
    }
}

impl Drop for Egl {
    fn drop(&mut self) {
        unsafe {
            let none = std::ptr::null_mut();
            eglMakeCurrent(self.dpy, none, none, none);
            eglDestroySurface(self.dpy, self.surface);
            eglDestroyContext(self.dpy, self.ctx);
            if self.terminate_on_drop {
                eglTerminate(self.dpy);
            }
        }
    }
}
