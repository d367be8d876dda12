//! What a display list can leave changed, beside the matrices (`matrix::Seen`), that the real GL
//! must be told when glray takes a glCallList from it (src/raytrace/lists.rs): the enables,
//! the face, shading, depth, blending, line and point state, the bound 2D texture, and the
//! current colour and normal. A program that reads one back (glGetIntegerv(GL_FRONT_FACE) after
//! blocktube's list set GL_CW), or draws with the real GL after the list (glBitmap text in the
//! colour a list left current, fed through glRasterPos), gets what the list did.
//!
//! Lights' and materials' values are not among them (a list's glLight or glMaterial stays
//! capture's only).

use glam::{DVec3, DVec4};

use crate::context::Context;
use crate::gl::*;

/// GL's capabilities capture follows, in the order `StateSeen::enables` holds them.
pub const CAPS: [u32; 30] = [
    GL_LIGHTING,
    GL_LIGHT0,
    GL_LIGHT0 + 1,
    GL_LIGHT0 + 2,
    GL_LIGHT0 + 3,
    GL_LIGHT0 + 4,
    GL_LIGHT0 + 5,
    GL_LIGHT0 + 6,
    GL_LIGHT0 + 7,
    GL_COLOR_MATERIAL,
    GL_NORMALIZE,
    GL_RESCALE_NORMAL,
    GL_CULL_FACE,
    GL_POLYGON_OFFSET_FILL,
    GL_DEPTH_TEST,
    GL_SCISSOR_TEST,
    GL_BLEND,
    GL_ALPHA_TEST,
    GL_COLOR_LOGIC_OP,
    GL_TEXTURE_2D,
    GL_TEXTURE_1D,
    GL_FOG,
    GL_LINE_SMOOTH,
    GL_POINT_SMOOTH,
    GL_CLIP_PLANE0,
    GL_CLIP_PLANE0 + 1,
    GL_CLIP_PLANE0 + 2,
    GL_CLIP_PLANE0 + 3,
    GL_CLIP_PLANE0 + 4,
    GL_CLIP_PLANE0 + 5,
];

/// The state a list can leave changed that the real GL answers queries with and draws with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StateSeen {
    /// Whether each of `CAPS` is enabled.
    pub enables: [bool; 30],
    /// GL_CW or GL_CCW.
    pub front_face: u32,
    pub cull_face: u32,
    /// GL_FLAT or GL_SMOOTH.
    pub shade_model: u32,
    /// Front and back.
    pub polygon_mode: [u32; 2],
    pub depth_func: u32,
    pub depth_mask: bool,
    pub blend_func: (u32, u32),
    pub alpha_func: (u32, f32),
    pub line_width: f64,
    pub point_size: f64,
    pub bound_texture: u32,
    pub color: DVec4,
    pub normal: DVec3,
}

impl Context {
    /// The state `StateSeen` describes, as capture has it now.
    pub fn state_seen(&self) -> StateSeen {
        let s = &self.s;
        let lights: [bool; 8] = std::array::from_fn(|i| s.lights[i].enabled);
        let planes: [bool; 6] = std::array::from_fn(|i| s.clip_planes[i].0);
        let mut enables = [false; 30];
        let listed = [
            s.lighting,
            s.color_material,
            s.normalize,
            s.rescale_normal,
            s.cull,
            s.polygon_offset_fill,
            s.depth_test,
            s.scissor_test,
            s.blend,
            s.alpha_test,
            s.logic_op_enabled,
            s.texture_2d,
            s.texture_1d,
            s.fog_enabled,
            s.line_smooth,
            s.point_smooth,
        ];
        // In `CAPS`' order: lighting, the eight lights, the rest, the six clip planes.
        enables[0] = listed[0];
        enables[1..9].copy_from_slice(&lights);
        enables[9..24].copy_from_slice(&listed[1..]);
        enables[24..].copy_from_slice(&planes);
        StateSeen {
            enables,
            front_face: if s.front_ccw { GL_CCW } else { GL_CW },
            cull_face: s.cull_face,
            shade_model: if s.flat { GL_FLAT } else { GL_SMOOTH },
            polygon_mode: s.polygon_mode,
            depth_func: s.depth_func,
            depth_mask: s.depth_mask,
            blend_func: s.blend_func,
            alpha_func: s.alpha_func,
            line_width: s.line_width,
            point_size: s.point_size,
            bound_texture: s.bound_texture,
            color: self.imm.current.color,
            normal: self.imm.current.normal,
        }
    }
}
