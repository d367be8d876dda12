//! GL's numbers by name: every enum value of the Khronos GL, GLX and EGL registries and OSMesa's
//! (gl-spec/osmesa.txt), generated at build time by glray-spec's `gen::enums`. glray never writes
//! a GL number by hand: `glray_gl::GL_LESS`, `glray_gl::GLX_WIDTH`, `glray_gl::EGL_HEIGHT`.
//!
//! GL and GLX values are `u32` (GLenum, and GLX's attributes as they are compared), EGL's `i32`
//! (EGLint); a value too wide for its type is `u64` (GL_TIMEOUT_IGNORED).
#![allow(non_upper_case_globals, clippy::unreadable_literal)]

include!(concat!(env!("OUT_DIR"), "/enums.rs"));

#[cfg(test)]
mod tests {
    #[test]
    fn registry_values_are_named() {
        assert_eq!(super::GL_LESS, 0x0201);
        assert_eq!(super::GL_TRIANGLES, 4);
        assert_eq!(super::GL_TIMEOUT_IGNORED, u64::MAX);
        // gl.xml gives GL_ACTIVE_PROGRAM_EXT one value for GL and another for GLES: GL's.
        assert_eq!(super::GL_ACTIVE_PROGRAM_EXT, 0x8B8D);
        assert_eq!(super::GLX_WIDTH, 0x801D);
        assert_eq!(super::EGL_HEIGHT, 0x3056);
        assert_eq!(super::EGL_DONT_CARE, -1);
        assert_eq!(super::OSMESA_RGBA, 0x1908);
    }
}
