//! One triangle as the rasterizer would draw it (`Triangle`): eye-space corners in the winding
//! that faces the viewer, the colours it would interpolate, texture coordinates, and what
//! lighting per pixel and the per-fragment state need. A frame's own triangles are made so by
//! capture; an instance's are made when a ray hits them.

use glam::{Vec2, Vec3, Vec4};
use serde::{Deserialize, Serialize};

/// One triangle, ready to trace.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
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
    /// Index into `Frame::cameras`: the projection and viewport it was drawn with.
    pub camera: u32,
    /// Clip-space w of each corner under its own projection: the rasterizer interpolates
    /// perspective-correctly with these (1 for orthographic draws: linear on the screen).
    pub clip_w: [f32; 3],
    /// For lighting per pixel: eye-space normals (facing the viewer's side already), the
    /// colour glColorMaterial would use, and the draw's lighting (`NO_LIGHTING` if unlit).
    pub normals: [Vec3; 3],
    pub base_colors: [Vec4; 3],
    pub lighting: u32,
    /// Whether the back face is the one seen (two-sided lighting uses the back material).
    pub back: bool,
}

/// `Triangle::lighting` of a triangle drawn without GL_LIGHTING.
pub const NO_LIGHTING: u32 = u32::MAX;
