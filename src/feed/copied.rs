//! Textures a program fills from its framebuffer (glCopyTexImage2D, glCopyTexSubImage2D: a blur,
//! a reflection or a picture-in-picture rendered first and then drawn as a texture). The frame
//! drawn so far is presented before the copy (classes.txt's `ends=raster`, as for glReadPixels), so
//! the real GL copies the ray-traced picture; capture cannot see what the copy took, so the
//! texture level is read back from the real GL afterwards (`follow`) and handed to capture.

use glray_gl::{
    GL_CLIENT_PIXEL_STORE_BIT, GL_FLOAT, GL_PACK_ALIGNMENT, GL_PACK_LSB_FIRST, GL_PACK_ROW_LENGTH, GL_PACK_SKIP_PIXELS,
    GL_PACK_SKIP_ROWS, GL_PACK_SWAP_BYTES, GL_PIXEL_PACK_BUFFER, GL_PIXEL_PACK_BUFFER_BINDING, GL_RGBA, GL_TEXTURE_2D,
    GL_TEXTURE_HEIGHT, GL_TEXTURE_INTERNAL_FORMAT, GL_TEXTURE_WIDTH,
};
use std::ffi::c_void;

use glam::Vec4;
use glray_capture::args;
use glray_capture::events::Capture;
use glray_core::trace::Value;

use crate::abi::real::{self, get_int};

/// glPixelStore's pack state, and what a read into a tight float array wants of it.
const PACK: &[(u32, i32)] = &[
    (GL_PACK_ALIGNMENT, 4),   // PACK_ALIGNMENT
    (GL_PACK_ROW_LENGTH, 0),  // PACK_ROW_LENGTH
    (GL_PACK_SKIP_ROWS, 0),   // PACK_SKIP_ROWS
    (GL_PACK_SKIP_PIXELS, 0), // PACK_SKIP_PIXELS
    (GL_PACK_SWAP_BYTES, 0),  // PACK_SWAP_BYTES
    (GL_PACK_LSB_FIRST, 0),   // PACK_LSB_FIRST
];
/// The largest texture level read back (GL implementations stop at 16K).
const MOST_TEXELS: usize = 16384 * 16384;

/// After the real GL made call number `c` (the recorder's numbering) with `a` on `thread`: a copy
/// into a 2D texture is read back into capture's texture. Every call a program makes comes
/// through here: the test is inlined, the work is not.
#[inline]
pub fn follow(capture: &mut Capture, c: usize, thread: u32, a: &[Value]) {
    if capture.copies_texture(c) {
        read_into(capture, thread, a);
    }
}

/// `follow` for a copy.
#[cold]
fn read_into(capture: &mut Capture, thread: u32, a: &[Value]) {
    if args::uint(a, 0) != GL_TEXTURE_2D || crate::abi::profile::core() {
        return;
    }
    let ctx = capture.context(thread);
    // Compiled into a list (Mesa compiles the copies), it copies nothing until the list runs.
    if ctx.compiling() {
        return;
    }
    let Ok(level) = usize::try_from(args::int(a, 1)) else { return };
    // SAFETY: the live layer follows a call on the thread that made it, whose context is
    // current (the call just went to it).
    if let Some((internal, width, height, texels)) = unsafe { read_back(level) } {
        glray_core::debug!("a copy from the framebuffer: texture level {level} ({width}x{height}) read back");
        ctx.copied_texture(level, internal, width, height, texels);
    }
}

/// Whether internal format `internal` holds depth or stencil (no colour to read back):
/// DEPTH_COMPONENT, 16/24/32, 32F; DEPTH_STENCIL, DEPTH24_STENCIL8, DEPTH32F_STENCIL8;
/// STENCIL_INDEX, STENCIL_INDEX1/4/8/16.
fn depth_or_stencil(internal: u32) -> bool {
    matches!(internal, 0x1902 | 0x81A5..=0x81A7 | 0x8CAC | 0x84F9 | 0x88F0 | 0x8CAD | 0x1901 | 0x8D46..=0x8D49)
}

/// Level `level` of the bound 2D texture: its internal format, size and texels in RGBA.
///
/// # Safety
/// A compatibility-profile GL context must be current on this thread.
unsafe fn read_back(level: usize) -> Option<(u32, usize, usize, Vec<Vec4>)> {
    let level = i32::try_from(level).ok()?;
    let parameter = |pname: u32| {
        let mut v = 0i32;
        real::glGetTexLevelParameteriv(GL_TEXTURE_2D, level, pname, (&mut v as *mut i32).cast());
        v
    };
    let (width, height) =
        (usize::try_from(parameter(GL_TEXTURE_WIDTH)).ok()?, usize::try_from(parameter(GL_TEXTURE_HEIGHT)).ok()?);
    let internal = parameter(GL_TEXTURE_INTERNAL_FORMAT) as u32;
    // Depth and stencil textures have no colour to read (glGetTexImage as RGBA would raise
    // GL_INVALID_OPERATION, an error the program never caused); capture keeps none of them.
    if depth_or_stencil(internal) {
        return None;
    }
    let count = width.checked_mul(height).filter(|&n| n > 0 && n <= MOST_TEXELS)?;
    let mut floats = vec![0.0f32; count * 4];
    let pack_buffer = get_int(GL_PIXEL_PACK_BUFFER_BINDING);
    if pack_buffer != 0 {
        real::glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    }
    real::glPushClientAttrib(GL_CLIENT_PIXEL_STORE_BIT);
    for &(pname, value) in PACK {
        real::glPixelStorei(pname, value);
    }
    real::glGetTexImage(GL_TEXTURE_2D, level, GL_RGBA, GL_FLOAT, floats.as_mut_ptr() as *mut c_void);
    real::glPopClientAttrib();
    if pack_buffer != 0 {
        real::glBindBuffer(GL_PIXEL_PACK_BUFFER, pack_buffer as u32);
    }
    let texels = floats.chunks_exact(4).map(Vec4::from_slice).collect();
    Some((internal, width, height, texels))
}
