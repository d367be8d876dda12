//! Presenting with glDrawPixels (compatibility contexts): colour at window position (0, 0),
//! then depth, with every piece of state that affects pixel drawing saved and restored around it
//! (glPushAttrib), so that the program's GL state is as it left it.

use glray_gl::{
    GL_ALL_ATTRIB_BITS, GL_ALPHA_TEST, GL_ALWAYS, GL_BLEND, GL_CLIENT_ALL_ATTRIB_BITS, GL_COLOR_LOGIC_OP, GL_CULL_FACE,
    GL_CURRENT_PROGRAM, GL_DEPTH_COMPONENT, GL_DEPTH_TEST, GL_FLOAT, GL_FOG, GL_FRAGMENT_PROGRAM_ARB, GL_LIGHTING,
    GL_PIXEL_UNPACK_BUFFER, GL_PIXEL_UNPACK_BUFFER_BINDING, GL_RGBA, GL_SCISSOR_TEST, GL_STENCIL_TEST, GL_TEXTURE_1D,
    GL_TEXTURE_2D, GL_TEXTURE_3D, GL_TEXTURE_CUBE_MAP, GL_UNPACK_ALIGNMENT, GL_UNPACK_LSB_FIRST, GL_UNPACK_ROW_LENGTH,
    GL_UNPACK_SKIP_PIXELS, GL_UNPACK_SKIP_ROWS, GL_UNPACK_SWAP_BYTES, GL_UNSIGNED_BYTE, GL_VERTEX_PROGRAM_ARB,
};
use std::ffi::c_void;

use glray_render::Rendered;

use crate::abi::real::{self, get_int};

/// Per-fragment and pixel-path state glDrawPixels fragments pass through.
const OFF: &[u32] = &[
    GL_DEPTH_TEST,           // DEPTH_TEST (turned on again for the depth pass)
    GL_BLEND,                // BLEND
    GL_ALPHA_TEST,           // ALPHA_TEST
    GL_TEXTURE_2D,           // TEXTURE_2D
    GL_TEXTURE_1D,           // TEXTURE_1D
    GL_TEXTURE_3D,           // TEXTURE_3D
    GL_TEXTURE_CUBE_MAP,     // TEXTURE_CUBE_MAP
    GL_LIGHTING,             // LIGHTING
    GL_FOG,                  // FOG
    GL_STENCIL_TEST,         // STENCIL_TEST
    GL_SCISSOR_TEST,         // SCISSOR_TEST
    GL_COLOR_LOGIC_OP,       // COLOR_LOGIC_OP
    GL_CULL_FACE,            // CULL_FACE
    GL_VERTEX_PROGRAM_ARB,   // VERTEX_PROGRAM_ARB
    GL_FRAGMENT_PROGRAM_ARB, // FRAGMENT_PROGRAM_ARB
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
