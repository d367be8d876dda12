//! Presenting with a shader (core profiles, which have no glDrawPixels and no glPushAttrib):
//! the colour and depth images become two textures, and one triangle covering the drawable
//! copies them texel for texel (texelFetch at gl_FragCoord) into colour and gl_FragDepth. Both
//! round-trip exactly: 8-bit colour through a normalized texture into an 8-bit framebuffer, and
//! float depth through an R32F texture, as glDrawPixels would write them.
//!
//! Every piece of state the draw touches is read first and put back after, one by one. The GL
//! objects live for one frame (a context's names are not shared with another, and the thread
//! may bind another context by the next frame); compiling the two small shaders costs well under
//! a millisecond against the frame's ray tracing.

use glray_gl::{
    GL_ACTIVE_TEXTURE, GL_ALPHA_TEST, GL_ALWAYS, GL_BACK, GL_BLEND, GL_CLIP_DISTANCE0, GL_COLOR_LOGIC_OP,
    GL_COLOR_WRITEMASK, GL_COMPILE_STATUS, GL_CULL_FACE, GL_CURRENT_PROGRAM, GL_DEPTH_CLAMP, GL_DEPTH_FUNC,
    GL_DEPTH_TEST, GL_DEPTH_WRITEMASK, GL_FILL, GL_FLOAT, GL_FRAGMENT_SHADER, GL_FRAMEBUFFER_SRGB, GL_FRONT,
    GL_FRONT_AND_BACK, GL_INFO_LOG_LENGTH, GL_LINK_STATUS, GL_NEAREST, GL_PIXEL_UNPACK_BUFFER,
    GL_PIXEL_UNPACK_BUFFER_BINDING, GL_POLYGON_MODE, GL_POLYGON_OFFSET_FILL, GL_POLYGON_STIPPLE, GL_R32F,
    GL_RASTERIZER_DISCARD, GL_RED, GL_RGBA, GL_RGBA8, GL_SAMPLER_BINDING, GL_SAMPLE_ALPHA_TO_COVERAGE,
    GL_SAMPLE_COVERAGE, GL_SAMPLE_MASK, GL_SCISSOR_TEST, GL_STENCIL_TEST, GL_TEXTURE0, GL_TEXTURE_2D,
    GL_TEXTURE_BINDING_2D, GL_TEXTURE_MAG_FILTER, GL_TEXTURE_MIN_FILTER, GL_TRIANGLES, GL_UNPACK_ALIGNMENT,
    GL_UNPACK_ROW_LENGTH, GL_UNPACK_SKIP_PIXELS, GL_UNPACK_SKIP_ROWS, GL_UNPACK_SWAP_BYTES, GL_UNSIGNED_BYTE,
    GL_VERTEX_ARRAY_BINDING, GL_VERTEX_SHADER, GL_VIEWPORT,
};
use std::ffi::c_void;

use glray_render::Rendered;

use super::Kind;
use crate::abi::real::{self, get_int, get_ints};

const VERTEX: &str = "#version 140
// One triangle that covers the viewport: (-1,-1), (3,-1), (-1,3).
void main() {
    vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);
    gl_Position = vec4(p, 0.0, 1.0);
}
";

const FRAGMENT: &str = "#version 140
uniform sampler2D colour_image;
uniform sampler2D depth_image;
out vec4 colour;
void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    colour = texelFetch(colour_image, p, 0);
    gl_FragDepth = texelFetch(depth_image, p, 0).r;
}
";

/// Unpack state that would change how the images are read, with the value they are read with.
const UNPACK: &[(u32, i32)] = &[
    (GL_UNPACK_ALIGNMENT, 4),   // UNPACK_ALIGNMENT (rows of 4-byte texels)
    (GL_UNPACK_ROW_LENGTH, 0),  // UNPACK_ROW_LENGTH
    (GL_UNPACK_SKIP_ROWS, 0),   // UNPACK_SKIP_ROWS
    (GL_UNPACK_SKIP_PIXELS, 0), // UNPACK_SKIP_PIXELS
    (GL_UNPACK_SWAP_BYTES, 0),  // UNPACK_SWAP_BYTES
];

/// Fragment and rasterizer state of every desktop GL 3.1+ context that the triangle must not
/// meet (depth test is turned on, with GL_ALWAYS, to write depth).
const OFF: &[u32] = &[
    GL_BLEND,                    // BLEND
    GL_STENCIL_TEST,             // STENCIL_TEST
    GL_SCISSOR_TEST,             // SCISSOR_TEST
    GL_CULL_FACE,                // CULL_FACE
    GL_COLOR_LOGIC_OP,           // COLOR_LOGIC_OP
    GL_RASTERIZER_DISCARD,       // RASTERIZER_DISCARD
    GL_SAMPLE_ALPHA_TO_COVERAGE, // SAMPLE_ALPHA_TO_COVERAGE
    GL_SAMPLE_COVERAGE,          // SAMPLE_COVERAGE
    GL_FRAMEBUFFER_SRGB,         // FRAMEBUFFER_SRGB
    GL_POLYGON_OFFSET_FILL,      // POLYGON_OFFSET_FILL
    GL_CLIP_DISTANCE0,
    0x3001,
    0x3002,
    0x3003,
    0x3004,
    0x3005,
    0x3006,
    0x3007, // CLIP_DISTANCE0..7
];

/// What GL 3.2 added (a 3.1 context answers GL_INVALID_ENUM for these).
const OFF_32: &[u32] = &[
    GL_SAMPLE_MASK, // SAMPLE_MASK
    GL_DEPTH_CLAMP, // DEPTH_CLAMP
];

/// What compatibility contexts add (when `shader` is forced there): per-fragment fixed-function
/// state that still applies behind a GLSL program.
const OFF_COMPAT: &[u32] = &[
    GL_ALPHA_TEST,      // ALPHA_TEST
    GL_POLYGON_STIPPLE, // POLYGON_STIPPLE
];

/// The capabilities to turn off (and put back) in a context of kind `kind`.
fn capabilities_off(kind: Kind) -> Vec<u32> {
    let mut off = OFF.to_vec();
    if (kind.major, kind.minor) >= (3, 2) {
        off.extend_from_slice(OFF_32);
    }
    if !kind.core {
        off.extend_from_slice(OFF_COMPAT);
    }
    off
}

/// The program's state, as it was before the present.
struct Saved {
    program: i32,
    vertex_array: i32,
    active_texture: i32,
    /// GL_TEXTURE_2D bindings of units 0 and 1.
    textures: [i32; 2],
    /// Sampler objects bound to units 0 and 1 (GL 3.3+).
    samplers: Option<[i32; 2]>,
    unpack_buffer: i32,
    unpack: Vec<i32>,
    viewport: [i32; 4],
    enabled: Vec<(u32, bool)>,
    depth_test: bool,
    depth_func: i32,
    depth_mask: u8,
    colour_mask: [u8; 4],
    /// Core profiles have one mode for both faces (the first); compatibility answers front, back.
    polygon_mode: [i32; 2],
    core: bool,
}

fn bools<const N: usize>(pname: u32) -> [u8; N] {
    let mut v = [0u8; 4];
    // SAFETY: glGetBooleanv writes at most 4 booleans for the names asked here.
    unsafe { real::glGetBooleanv(pname, v.as_mut_ptr().cast()) };
    std::array::from_fn(|i| v[i])
}

/// # Safety
/// A GL context must be current on this thread.
unsafe fn save(kind: Kind, off: &[u32]) -> Saved {
    let active_texture = get_int(GL_ACTIVE_TEXTURE);
    let has_samplers = has_samplers(kind);
    let mut textures = [0; 2];
    let mut samplers = [0; 2];
    for unit in 0..2 {
        real::glActiveTexture(GL_TEXTURE0 + unit as u32);
        textures[unit] = get_int(GL_TEXTURE_BINDING_2D);
        if has_samplers {
            samplers[unit] = get_int(GL_SAMPLER_BINDING);
        }
    }
    real::glActiveTexture(active_texture as u32);
    Saved {
        program: get_int(GL_CURRENT_PROGRAM),
        vertex_array: get_int(GL_VERTEX_ARRAY_BINDING),
        active_texture,
        textures,
        samplers: has_samplers.then_some(samplers),
        unpack_buffer: get_int(GL_PIXEL_UNPACK_BUFFER_BINDING),
        unpack: UNPACK.iter().map(|&(p, _)| get_int(p)).collect(),
        viewport: get_ints(GL_VIEWPORT),
        enabled: off.iter().map(|&cap| (cap, real::glIsEnabled(cap) != 0)).collect(),
        core: kind.core,
        depth_test: real::glIsEnabled(GL_DEPTH_TEST) != 0,
        depth_func: get_int(GL_DEPTH_FUNC),
        depth_mask: bools::<1>(GL_DEPTH_WRITEMASK)[0],
        colour_mask: bools(GL_COLOR_WRITEMASK),
        polygon_mode: get_ints(GL_POLYGON_MODE),
    }
}

/// # Safety
/// A GL context must be current on this thread.
unsafe fn restore(s: &Saved) {
    for unit in 0..2 {
        real::glActiveTexture(GL_TEXTURE0 + unit as u32);
        real::glBindTexture(GL_TEXTURE_2D, s.textures[unit] as u32);
        if let Some(samplers) = s.samplers {
            real::glBindSampler(unit as u32, samplers[unit] as u32);
        }
    }
    real::glActiveTexture(s.active_texture as u32);
    real::glUseProgram(s.program as u32);
    real::glBindVertexArray(s.vertex_array as u32);
    real::glBindBuffer(GL_PIXEL_UNPACK_BUFFER, s.unpack_buffer as u32);
    for (&(pname, _), &value) in UNPACK.iter().zip(&s.unpack) {
        real::glPixelStorei(pname, value);
    }
    let [x, y, w, h] = s.viewport;
    real::glViewport(x, y, w, h);
    for &(cap, on) in &s.enabled {
        set_enabled(cap, on);
    }
    set_enabled(GL_DEPTH_TEST, s.depth_test);
    real::glDepthFunc(s.depth_func as u32);
    real::glDepthMask(s.depth_mask);
    let [r, g, b, a] = s.colour_mask;
    real::glColorMask(r, g, b, a);
    let [front, back] = s.polygon_mode;
    if s.core {
        real::glPolygonMode(GL_FRONT_AND_BACK, front as u32);
    } else {
        real::glPolygonMode(GL_FRONT, front as u32);
        real::glPolygonMode(GL_BACK, back as u32);
    }
}

/// Sampler objects (which would override the textures' filtering) exist from GL 3.3 on.
fn has_samplers(kind: Kind) -> bool {
    (kind.major, kind.minor) >= (3, 3)
}

unsafe fn set_enabled(cap: u32, on: bool) {
    if on {
        real::glEnable(cap)
    } else {
        real::glDisable(cap)
    }
}

/// The GL objects of one present, deleted when dropped.
struct Objects {
    program: u32,
    vertex_array: u32,
    textures: [u32; 2],
}

impl Drop for Objects {
    fn drop(&mut self) {
        // SAFETY: made in this context by `Objects::make`, which is still current; deleting 0 is
        // ignored by GL.
        unsafe {
            real::glDeleteProgram(self.program);
            real::glDeleteVertexArrays(1, (&mut self.vertex_array as *mut u32).cast());
            real::glDeleteTextures(2, self.textures.as_mut_ptr().cast());
        }
    }
}

/// # Safety
/// A GL context must be current on this thread.
unsafe fn compile(stage: u32, source: &str) -> Result<u32, String> {
    let shader = real::glCreateShader(stage);
    if shader == 0 {
        return Err("glCreateShader returned 0".into());
    }
    let mut text = source.as_ptr();
    let mut length = source.len() as i32;
    real::glShaderSource(shader, 1, (&mut text as *mut *const u8).cast(), (&mut length as *mut i32).cast());
    real::glCompileShader(shader);
    let mut ok = 0i32;
    real::glGetShaderiv(shader, GL_COMPILE_STATUS, (&mut ok as *mut i32).cast());
    if ok == 0 {
        let log = info_log(shader, real::glGetShaderiv, real::glGetShaderInfoLog);
        real::glDeleteShader(shader);
        return Err(format!("compiling the present shader: {log}"));
    }
    Ok(shader)
}

/// A shader's or program's info log.
unsafe fn info_log(
    object: u32,
    get: unsafe fn(u32, u32, *mut c_void),
    read: unsafe fn(u32, i32, *mut c_void, *mut c_void),
) -> String {
    let mut length = 0i32;
    get(object, GL_INFO_LOG_LENGTH, (&mut length as *mut i32).cast());
    let mut log = vec![0u8; length.max(1) as usize];
    let mut written = 0i32;
    read(object, log.len() as i32, (&mut written as *mut i32).cast(), log.as_mut_ptr().cast());
    log.truncate(written.max(0) as usize);
    String::from_utf8_lossy(&log).trim().to_string()
}

impl Objects {
    /// # Safety
    /// A GL context must be current on this thread.
    unsafe fn make() -> Result<Objects, String> {
        let mut objects = Objects { program: 0, vertex_array: 0, textures: [0; 2] };
        let vertex = compile(GL_VERTEX_SHADER, VERTEX)?;
        let fragment = match compile(GL_FRAGMENT_SHADER, FRAGMENT) {
            Ok(f) => f,
            Err(e) => {
                real::glDeleteShader(vertex);
                return Err(e);
            }
        };
        objects.program = real::glCreateProgram();
        real::glAttachShader(objects.program, vertex);
        real::glAttachShader(objects.program, fragment);
        real::glLinkProgram(objects.program);
        // Flagged for deletion: they go with the program.
        real::glDeleteShader(vertex);
        real::glDeleteShader(fragment);
        let mut ok = 0i32;
        real::glGetProgramiv(objects.program, GL_LINK_STATUS, (&mut ok as *mut i32).cast());
        if ok == 0 {
            let log = info_log(objects.program, real::glGetProgramiv, real::glGetProgramInfoLog);
            return Err(format!("linking the present shader: {log}"));
        }
        real::glGenVertexArrays(1, (&mut objects.vertex_array as *mut u32).cast());
        real::glGenTextures(2, objects.textures.as_mut_ptr().cast());
        Ok(objects)
    }
}

/// Uploads `pixels` (w x h texels of `format`/`ty`, bottom row first) into `texture` on `unit`.
///
/// # Safety
/// A GL context must be current on this thread; `pixels` holds w x h texels.
#[allow(clippy::too_many_arguments)]
unsafe fn upload(unit: u32, texture: u32, internal: i32, format: u32, ty: u32, w: i32, h: i32, pixels: *const c_void) {
    real::glActiveTexture(GL_TEXTURE0 + unit);
    real::glBindTexture(GL_TEXTURE_2D, texture);
    // One level, never filtered: NEAREST keeps the texture complete without mipmaps.
    real::glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST as i32);
    real::glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST as i32);
    real::glTexImage2D(GL_TEXTURE_2D, 0, internal, w, h, 0, format, ty, pixels as *mut c_void);
}

/// Draws `r` over the whole drawable.
///
/// # Safety
/// A GL context (desktop GL 3.1 or later) must be current on this thread.
pub unsafe fn draw(r: &Rendered, kind: Kind) -> Result<(), String> {
    let off = capabilities_off(kind);
    let saved = save(kind, &off);
    let result = draw_saved(r, kind, &off);
    restore(&saved);
    result
}

/// The draw itself, between `save` and `restore`; the objects are deleted at its end.
unsafe fn draw_saved(r: &Rendered, kind: Kind, off: &[u32]) -> Result<(), String> {
    let objects = Objects::make()?;
    let (w, h) = (r.width as i32, r.height as i32);
    real::glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
    for &(pname, value) in UNPACK {
        real::glPixelStorei(pname, value);
    }
    if has_samplers(kind) {
        real::glBindSampler(0, 0);
        real::glBindSampler(1, 0);
    }
    upload(0, objects.textures[0], GL_RGBA8 as i32, GL_RGBA, GL_UNSIGNED_BYTE, w, h, r.rgba.as_ptr().cast());
    upload(1, objects.textures[1], GL_R32F as i32, GL_RED, GL_FLOAT, w, h, r.depth.as_ptr().cast());
    real::glUseProgram(objects.program);
    real::glUniform1i(real::glGetUniformLocation(objects.program, c"colour_image".as_ptr() as *mut c_void), 0);
    real::glUniform1i(real::glGetUniformLocation(objects.program, c"depth_image".as_ptr() as *mut c_void), 1);
    real::glBindVertexArray(objects.vertex_array);
    real::glViewport(0, 0, w, h);
    for &cap in off {
        real::glDisable(cap);
    }
    real::glEnable(GL_DEPTH_TEST);
    real::glDepthFunc(GL_ALWAYS);
    real::glDepthMask(1);
    real::glColorMask(1, 1, 1, 1);
    real::glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    real::glDrawArrays(GL_TRIANGLES, 0, 3);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_capabilities_the_context_knows_are_turned_off() {
        const SAMPLE_MASK: u32 = 0x8E51;
        const ALPHA_TEST: u32 = 0x0BC0;
        // A bare 3.1 context: no GL 3.2 capabilities, no fixed-function ones.
        let off = capabilities_off(Kind::desktop(3, 1, true));
        assert!(!off.contains(&SAMPLE_MASK) && !off.contains(&ALPHA_TEST));
        assert!(off.contains(&0x0BE2), "blending is always off");
        // 3.3 core: GL 3.2's too.
        let off = capabilities_off(Kind::desktop(3, 3, true));
        assert!(off.contains(&SAMPLE_MASK) && !off.contains(&ALPHA_TEST));
        // A compatibility context (shader forced): the fixed-function fragment state as well.
        let off = capabilities_off(Kind::desktop(4, 5, false));
        assert!(off.contains(&SAMPLE_MASK) && off.contains(&ALPHA_TEST));
        let mut unique = off.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), off.len());
    }
}
