//! Presenting with glDrawPixels (compatibility contexts): colour at window position (0, 0),
//! then depth, with every piece of state that affects pixel drawing saved and restored around it
//! (glPushAttrib), so that the program's GL state is as it left it.

use std::ffi::c_void;

use glray_render::Rendered;

use crate::real::{self, get_int};

const GL_ALL_ATTRIB_BITS: u32 = 0x000F_FFFF;
const GL_CLIENT_ALL_ATTRIB_BITS: u32 = 0xFFFF_FFFF;
const GL_PIXEL_UNPACK_BUFFER: u32 = 0x88EC;
const GL_PIXEL_UNPACK_BUFFER_BINDING: u32 = 0x88EF;
const GL_CURRENT_PROGRAM: u32 = 0x8B8D;
const GL_RGBA: u32 = 0x1908;
const GL_UNSIGNED_BYTE: u32 = 0x1401;
const GL_FLOAT: u32 = 0x1406;
const GL_DEPTH_COMPONENT: u32 = 0x1902;
const GL_ALWAYS: u32 = 0x0207;
const GL_UNPACK_ALIGNMENT: u32 = 0x0CF5;
const GL_UNPACK_ROW_LENGTH: u32 = 0x0CF2;
const GL_UNPACK_SKIP_ROWS: u32 = 0x0CF3;
const GL_UNPACK_SKIP_PIXELS: u32 = 0x0CF4;
const GL_UNPACK_SWAP_BYTES: u32 = 0x0CF0;
const GL_UNPACK_LSB_FIRST: u32 = 0x0CF1;
/// Per-fragment and pixel-path state glDrawPixels fragments pass through.
const OFF: &[u32] = &[
    0x0B71, // DEPTH_TEST (turned on again for the depth pass)
    0x0BE2, // BLEND
    0x0BC0, // ALPHA_TEST
    0x0DE1, // TEXTURE_2D
    0x0DE0, // TEXTURE_1D
    0x806F, // TEXTURE_3D
    0x8513, // TEXTURE_CUBE_MAP
    0x0B50, // LIGHTING
    0x0B60, // FOG
    0x0B90, // STENCIL_TEST
    0x0C11, // SCISSOR_TEST
    0x0BF2, // COLOR_LOGIC_OP
    0x0B44, // CULL_FACE
    0x8620, // VERTEX_PROGRAM_ARB
    0x8804, // FRAGMENT_PROGRAM_ARB
];

/// Draws `r` over the whole drawable.
///
/// # Safety
/// A GL context must be current on this thread.
pub unsafe fn draw(r: &Rendered) {
    let program = get_int(GL_CURRENT_PROGRAM);
    let unpack_buffer = get_int(GL_PIXEL_UNPACK_BUFFER_BINDING);
    real::glPushAttrib(GL_ALL_ATTRIB_BITS);
    real::glPushClientAttrib(GL_CLIENT_ALL_ATTRIB_BITS);
    if program != 0 {
        real::glUseProgram(0);
    }
    if unpack_buffer != 0 {
        real::glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
    }
    for cap in OFF {
        real::glDisable(*cap);
    }
    real::glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    for p in
        [GL_UNPACK_ROW_LENGTH, GL_UNPACK_SKIP_ROWS, GL_UNPACK_SKIP_PIXELS, GL_UNPACK_SWAP_BYTES, GL_UNPACK_LSB_FIRST]
    {
        real::glPixelStorei(p, 0);
    }
    real::glPixelZoom(1.0, 1.0);
    real::glColorMask(1, 1, 1, 1);
    real::glWindowPos2i(0, 0);
    let (w, h) = (r.width as i32, r.height as i32);
    real::glDrawPixels(w, h, GL_RGBA, GL_UNSIGNED_BYTE, r.rgba.as_ptr() as *mut c_void);
    // Depth, for programs that read it back or draw over the frame with depth testing.
    real::glColorMask(0, 0, 0, 0);
    real::glEnable(0x0B71);
    real::glDepthFunc(GL_ALWAYS);
    real::glDepthMask(1);
    real::glWindowPos2i(0, 0);
    real::glDrawPixels(w, h, GL_DEPTH_COMPONENT, GL_FLOAT, r.depth.as_ptr() as *mut c_void);
    real::glPopClientAttrib();
    real::glPopAttrib();
    if unpack_buffer != 0 {
        real::glBindBuffer(GL_PIXEL_UNPACK_BUFFER, unpack_buffer as u32);
    }
    if program != 0 {
        real::glUseProgram(program as u32);
    }
}
