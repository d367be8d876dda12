//! What capture hands the renderer for one frame: triangles in eye coordinates with the colours
//! the rasterizer would interpolate (already lit, with the face and flat shading decided), the
//! surface state each was drawn with, and the camera. Lines and points arrive as the
//! screen-aligned quads a rasterizer fills for them, so that the GL look needs no other
//! primitive.

use std::sync::Arc;

use glam::{DMat4, Vec2, Vec3, Vec4};

use crate::camera::Viewport;
use crate::texture::Texture;

/// One triangle, ready to trace.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Triangle {
    /// Corners in eye coordinates, in the winding order that faces the viewer.
    pub positions: [Vec3; 3],
    /// RGBA at each corner (all three the provoking vertex's under flat shading).
    pub colors: [Vec4; 3],
    /// Specular colour added after texturing (GL_SEPARATE_SPECULAR_COLOR), per corner.
    pub secondary: [Vec3; 3],
    /// Texture coordinates (s/q, t/q) of unit 0 at each corner.
    pub texcoords: [Vec2; 3],
    /// Index into `Frame::surfaces`.
    pub surface: u32,
    /// The draw's place in the frame, for ties and for painter's order.
    pub sequence: u32,
}

/// glFog state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fog {
    pub mode: u32,
    pub density: f32,
    pub start: f32,
    pub end: f32,
    pub color: Vec4,
}

/// Texturing of a draw: the texture object's image and sampling state, and the environment.
#[derive(Debug, Clone)]
pub struct Texturing {
    pub texture: Arc<Texture>,
    /// GL_TEXTURE_ENV_MODE: MODULATE, REPLACE, DECAL, BLEND, ADD.
    pub env_mode: u32,
    pub env_color: Vec4,
}

/// The per-fragment state of a draw: what the tracer needs besides the triangle.
#[derive(Debug, Clone)]
pub struct Surface {
    pub texturing: Option<Texturing>,
    pub fog: Option<Fog>,
    pub depth_test: bool,
    pub depth_func: u32,
    pub depth_mask: bool,
    /// (src, dst) factors when GL_BLEND is on.
    pub blend: Option<(u32, u32)>,
    /// (func, reference) when GL_ALPHA_TEST is on.
    pub alpha_test: Option<(u32, f32)>,
}

/// A captured frame.
#[derive(Debug, Clone, Default)]
pub struct Frame {
    pub triangles: Vec<Triangle>,
    pub surfaces: Vec<Surface>,
    /// The projection and viewport of the frame's first 3D draw: the camera.
    pub projection: Option<DMat4>,
    pub viewport: Option<Viewport>,
    pub depth_range: (f64, f64),
    /// glClearColor at the last glClear of the colour buffer.
    pub clear_color: Vec4,
    /// Draws left out of the ray-traced scene (another projection or viewport than the
    /// camera's: 2D overlays), counted for the log.
    pub skipped_draws: u32,
    /// Draws capture cannot follow (shaders, generic vertex attributes): a frame with any
    /// is not ray traced, the real GL's picture stands.
    pub unsupported_draws: u32,
    /// Drawable size, when known.
    pub width: u32,
    pub height: u32,
}

impl Frame {
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }
}
