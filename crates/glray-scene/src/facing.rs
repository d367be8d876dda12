//! Which face of a triangle is seen, as the rasterizer decides it: from the winding of its
//! corners on the window (so a mirroring modelview or projection turns it around), and whether
//! glCullFace removes it.

use glam::{DMat3, DMat4, DVec3, DVec4};

use crate::gl_enum::gl_enum;

gl_enum! {
    /// A polygon face (glCullFace, glColorMaterial, glPolygonMode).
    pub enum Face {
        Front = GL_FRONT,
        Back = GL_BACK,
        FrontAndBack = GL_FRONT_AND_BACK,
    }
}

impl Face {
    /// Which sides (front, back) it names.
    pub fn sides(self) -> [bool; 2] {
        match self {
            Face::Front => [true, false],
            Face::Back => [false, true],
            Face::FrontAndBack => [true, true],
        }
    }
}

/// Whether a triangle with these clip-space corners faces front, from its window-space winding
/// (from clip coordinates: exact even for triangles that cross the near plane, which clipping
/// keeps on the same plane); None for one with no area on the screen.
#[inline]
pub fn window_facing(clip: [DVec4; 3], front_ccw: bool) -> Option<bool> {
    let [a, b, c] = clip;
    let det =
        DMat3::from_cols(DVec3::new(a.x, a.y, a.w), DVec3::new(b.x, b.y, b.w), DVec3::new(c.x, c.y, c.w)).determinant();
    (det != 0.0).then_some((det > 0.0) == front_ccw)
}

/// Whether glCullFace's face `cull` (when GL_CULL_FACE is on) removes a triangle of this facing.
#[inline]
pub fn culled(cull: Option<Face>, front: bool) -> bool {
    match cull {
        Some(Face::FrontAndBack) => true,
        Some(face) => (face == Face::Front) == front,
        None => false,
    }
}

/// Whether `modelview` and `projection` together turn a triangle's winding around on the
/// window, compared with how it winds seen from the eye in object space. With it, a ray from
/// the eye tells a triangle's facing from the sign of one dot product (`Instance::keeps_seen`).
pub fn facing_flip(modelview: &DMat4, projection: &DMat4) -> bool {
    (DMat3::from_mat4(*modelview).determinant() < 0.0) != projection_flips(projection)
}

/// Whether `projection` turns a triangle's winding around on the window, compared with how it
/// winds seen from the eye in eye space.
pub fn projection_flips(projection: &DMat4) -> bool {
    // A counter-clockwise triangle facing the eye, in front of it: front unless the projection
    // turns the window around.
    let probe = [DVec4::new(0.0, 0.0, -1.0, 1.0), DVec4::new(0.1, 0.0, -1.0, 1.0), DVec4::new(0.0, 0.1, -1.0, 1.0)];
    window_facing(probe.map(|p| *projection * p), true) == Some(false)
}
