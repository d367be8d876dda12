//! An OSMesa context drawing into a buffer the program owns (RGBA, bottom-up).
#![allow(dead_code)]

use glray_gl::{GL_UNSIGNED_BYTE, OSMESA_RGBA};
use std::ffi::c_void;

#[link(name = "OSMesa")]
extern "C" {
    fn OSMesaCreateContextExt(format: u32, depth: i32, stencil: i32, accum: i32, share: *mut c_void) -> *mut c_void;
    pub fn OSMesaMakeCurrent(ctx: *mut c_void, buffer: *mut c_void, ty: u32, w: i32, h: i32) -> u8;
    pub fn OSMesaGetProcAddress(name: *const u8) -> *const c_void;
    pub fn OSMesaGetCurrentContext() -> *mut c_void;
    fn OSMesaDestroyContext(ctx: *mut c_void);
}

pub struct OSMesa {
    pub ctx: *mut c_void,
    pub buffer: Vec<u8>,
}

impl OSMesa {
    /// Creates the context and makes it current on this thread.
    pub unsafe fn new(width: i32, height: i32) -> Result<OSMesa, String> {
        let ctx = OSMesaCreateContextExt(OSMESA_RGBA, 16, 0, 0, std::ptr::null_mut());
        let mut buffer = vec![0u8; (width * height * 4) as usize];
        if ctx.is_null() || OSMesaMakeCurrent(ctx, buffer.as_mut_ptr().cast(), GL_UNSIGNED_BYTE, width, height) == 0 {
            return Err("cannot create or bind an OSMesa context".into());
        }
        Ok(OSMesa { ctx, buffer })
    }

    /// The image so far, RGB bottom-up.
    pub fn rgb(&self) -> Vec<u8> {
        self.buffer.chunks(4).flat_map(|p| [p[0], p[1], p[2]]).collect()
    }
}

impl Drop for OSMesa {
    fn drop(&mut self) {
        unsafe { OSMesaDestroyContext(self.ctx) }
    }
}
