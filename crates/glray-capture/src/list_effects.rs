//! What a display list can leave changed, beside the matrices (`matrix::Seen`), that the real GL
//! must be told when glray takes a glCallList from it (src/raytrace/lists.rs): the enables,
//! the face, shading, depth, blending, line and point state, the bound 2D texture, the current
//! colour and normal, and the lights, materials and light model. A program that reads one back
//! (glGetIntegerv(GL_FRONT_FACE) after blocktube's list set GL_CW), or draws with the real GL
//! after the list (glBitmap text in the colour a list left current, fed through glRasterPos, lit
//! by the lights a set-up list gave), gets what the list did.

use glam::{DVec3, DVec4};
use glray_gl::{
    GL_ALPHA_TEST, GL_BLEND, GL_CCW, GL_CLIP_PLANE0, GL_COLOR_LOGIC_OP, GL_COLOR_MATERIAL, GL_CULL_FACE, GL_CW,
    GL_DEPTH_TEST, GL_FLAT, GL_FOG, GL_LIGHT0, GL_LIGHTING, GL_LINE_SMOOTH, GL_NORMALIZE, GL_POINT_SMOOTH,
    GL_POLYGON_OFFSET_FILL, GL_RESCALE_NORMAL, GL_SCISSOR_TEST, GL_SMOOTH, GL_TEXTURE_1D, GL_TEXTURE_2D,
};

use crate::context::Context;
use glray_scene::lighting::{Light, LightModel, Material};

/// The state a list can leave changed that the real GL answers queries with and draws with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StateSeen {
    /// Each capability capture follows, and whether it is enabled.
    pub enables: [(u32, bool); 30],
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
    /// Each light's colours, position and spot direction (eye coordinates), and attenuation.
    pub lights: [Light; 8],
    /// Front and back.
    pub materials: [Material; 2],
    pub light_model: LightModel,
    /// glColorMaterial's face and mode.
    pub color_material: (u32, u32),
}

impl Context {
    /// The state `StateSeen` describes, as capture has it now.
    pub fn state_seen(&self) -> StateSeen {
        let s = &self.s;
        let light = |i: usize| (GL_LIGHT0 + i as u32, s.lights[i].enabled);
        let plane = |i: usize| (GL_CLIP_PLANE0 + i as u32, s.clip_planes[i].0);
        let enables = [
            (GL_LIGHTING, s.lighting),
            light(0),
            light(1),
            light(2),
            light(3),
            light(4),
            light(5),
            light(6),
            light(7),
            (GL_COLOR_MATERIAL, s.color_material),
            (GL_NORMALIZE, s.normalize),
            (GL_RESCALE_NORMAL, s.rescale_normal),
            (GL_CULL_FACE, s.cull),
            (GL_POLYGON_OFFSET_FILL, s.polygon_offset_fill),
            (GL_DEPTH_TEST, s.depth_test),
            (GL_SCISSOR_TEST, s.scissor_test),
            (GL_BLEND, s.blend),
            (GL_ALPHA_TEST, s.alpha_test),
            (GL_COLOR_LOGIC_OP, s.logic_op_enabled),
            (GL_TEXTURE_2D, s.texture_2d),
            (GL_TEXTURE_1D, s.texture_1d),
            (GL_FOG, s.fog_enabled),
            (GL_LINE_SMOOTH, s.line_smooth),
            (GL_POINT_SMOOTH, s.point_smooth),
            plane(0),
            plane(1),
            plane(2),
            plane(3),
            plane(4),
            plane(5),
        ];
        StateSeen {
            enables,
            front_face: if s.front_ccw { GL_CCW } else { GL_CW },
            cull_face: s.cull_face.gl(),
            shade_model: if s.flat { GL_FLAT } else { GL_SMOOTH },
            polygon_mode: s.polygon_mode,
            depth_func: s.depth_func.gl(),
            depth_mask: s.depth_mask,
            blend_func: (s.blend_func.0.gl(), s.blend_func.1.gl()),
            alpha_func: (s.alpha_func.0.gl(), s.alpha_func.1),
            line_width: s.line_width,
            point_size: s.point_size,
            bound_texture: s.bound_texture,
            color: self.imm.current.color,
            normal: self.imm.current.normal,
            lights: s.lights,
            materials: s.materials,
            light_model: s.model,
            color_material: (s.color_material_face.gl(), s.color_material_mode.gl()),
        }
    }
}
