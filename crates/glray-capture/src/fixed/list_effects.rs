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

use crate::fixed::Context;
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
        let light = |i: usize| (GL_LIGHT0 + i as u32, self.lighting.lights[i].enabled);
        let plane = |i: usize| (GL_CLIP_PLANE0 + i as u32, self.raster.clip_planes[i].0);
        let enables = [
            (GL_LIGHTING, self.lighting.lighting),
            light(0),
            light(1),
            light(2),
            light(3),
            light(4),
            light(5),
            light(6),
            light(7),
            (GL_COLOR_MATERIAL, self.lighting.color_material),
            (GL_NORMALIZE, self.lighting.normalize),
            (GL_RESCALE_NORMAL, self.lighting.rescale_normal),
            (GL_CULL_FACE, self.raster.cull),
            (GL_POLYGON_OFFSET_FILL, self.raster.polygon_offset_fill),
            (GL_DEPTH_TEST, self.raster.depth_test),
            (GL_SCISSOR_TEST, self.raster.scissor_test),
            (GL_BLEND, self.raster.blend),
            (GL_ALPHA_TEST, self.raster.alpha_test),
            (GL_COLOR_LOGIC_OP, self.raster.logic_op_enabled),
            (GL_TEXTURE_2D, self.texturing.texture_2d),
            (GL_TEXTURE_1D, self.texturing.texture_1d),
            (GL_FOG, self.raster.fog_enabled),
            (GL_LINE_SMOOTH, self.raster.line_smooth),
            (GL_POINT_SMOOTH, self.raster.point_smooth),
            plane(0),
            plane(1),
            plane(2),
            plane(3),
            plane(4),
            plane(5),
        ];
        StateSeen {
            enables,
            front_face: if self.raster.front_ccw { GL_CCW } else { GL_CW },
            cull_face: self.raster.cull_face.gl(),
            shade_model: if self.lighting.flat { GL_FLAT } else { GL_SMOOTH },
            polygon_mode: self.raster.polygon_mode,
            depth_func: self.raster.depth_func.gl(),
            depth_mask: self.raster.depth_mask,
            blend_func: (self.raster.blend_func.0.gl(), self.raster.blend_func.1.gl()),
            alpha_func: (self.raster.alpha_func.0.gl(), self.raster.alpha_func.1),
            line_width: self.raster.line_width,
            point_size: self.raster.point_size,
            bound_texture: self.texturing.bound_texture,
            color: self.imm.current.color,
            normal: self.imm.current.normal,
            lights: self.lighting.lights,
            materials: self.lighting.materials,
            light_model: self.lighting.model,
            color_material: (self.lighting.color_material_face.gl(), self.lighting.color_material_mode.gl()),
        }
    }
}
