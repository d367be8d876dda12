//! The server state glPushAttrib saves, grouped by the attribute bit that saves it, with GL's
//! initial values, and glPopAttrib's restore by mask.

use glam::{DVec4, Vec4};
use glray_gl::{
    GL_COLOR_BUFFER_BIT, GL_DEPTH_BUFFER_BIT, GL_ENABLE_BIT, GL_EYE_LINEAR, GL_FILL, GL_FOG_BIT, GL_LIGHTING_BIT,
    GL_LINE_BIT, GL_POINT_BIT, GL_POLYGON_BIT, GL_SCISSOR_BIT, GL_TEXTURE_BIT, GL_TRANSFORM_BIT, GL_VIEWPORT_BIT,
};

use glray_scene::camera::Viewport;
use glray_scene::facing::Face;
use glray_scene::lighting::{ColorMaterialMode, Light, LightModel, Material};
use glray_scene::surface::{BlendFactor, CompareFunc, Fog, FogMode, LogicOp, TexEnvMode};

/// How deep glPushAttrib's stack goes (GL_MAX_ATTRIB_STACK_DEPTH, 16 in Mesa).
pub(crate) const MAX_ATTRIB_DEPTH: usize = 16;

/// Texture coordinate generation of one coordinate (s or t).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct TexGen {
    pub(crate) enabled: bool,
    pub(crate) mode: u32,
    pub(crate) object_plane: DVec4,
    pub(crate) eye_plane: DVec4,
}

/// The server state glPushAttrib saves, grouped by the attribute bit that saves it.
#[derive(Debug, Clone)]
pub(crate) struct State {
    // GL_LIGHTING_BIT
    pub(crate) lighting: bool,
    pub(crate) lights: [Light; 8],
    pub(crate) model: LightModel,
    pub(crate) materials: [Material; 2],
    pub(crate) color_material: bool,
    pub(crate) color_material_face: Face,
    pub(crate) color_material_mode: ColorMaterialMode,
    pub(crate) flat: bool,
    // GL_TRANSFORM_BIT
    pub(crate) normalize: bool,
    pub(crate) rescale_normal: bool,
    pub(crate) clip_planes: [(bool, DVec4); 6],
    // GL_POLYGON_BIT
    pub(crate) cull: bool,
    pub(crate) cull_face: Face,
    pub(crate) front_ccw: bool,
    pub(crate) polygon_mode: [u32; 2],
    /// GL_POLYGON_OFFSET_FILL, and glPolygonOffset's (factor, units).
    pub(crate) polygon_offset_fill: bool,
    pub(crate) polygon_offset: (f32, f32),
    // GL_DEPTH_BUFFER_BIT
    pub(crate) depth_test: bool,
    pub(crate) depth_func: CompareFunc,
    pub(crate) depth_mask: bool,
    // GL_SCISSOR_BIT
    /// GL_SCISSOR_TEST, and glScissor's box (None until it is given: the whole drawable).
    pub(crate) scissor_test: bool,
    pub(crate) scissor: Option<Viewport>,
    // GL_VIEWPORT_BIT
    pub(crate) viewport: Viewport,
    pub(crate) depth_range: (f64, f64),
    // GL_COLOR_BUFFER_BIT
    pub(crate) clear_color: Vec4,
    /// glClearDepth, clamped to [0, 1].
    pub(crate) clear_depth: f32,
    pub(crate) blend: bool,
    pub(crate) blend_func: (BlendFactor, BlendFactor),
    pub(crate) alpha_test: bool,
    pub(crate) alpha_func: (CompareFunc, f32),
    /// glColorMask: which of red, green, blue and alpha draws write.
    pub(crate) color_mask: [bool; 4],
    /// GL_COLOR_LOGIC_OP's enable and glLogicOp's operation.
    pub(crate) logic_op_enabled: bool,
    pub(crate) logic_op: LogicOp,
    // GL_TEXTURE_BIT
    pub(crate) texture_2d: bool,
    pub(crate) bound_texture: u32,
    /// GL_TEXTURE_1D's enable and binding (a 2D texture, enabled, takes precedence).
    pub(crate) texture_1d: bool,
    pub(crate) bound_texture_1d: u32,
    pub(crate) env_mode: TexEnvMode,
    pub(crate) env_color: Vec4,
    pub(crate) texgen: [TexGen; 2],
    // GL_FOG_BIT
    pub(crate) fog_enabled: bool,
    pub(crate) fog: Fog,
    // GL_LINE_BIT, GL_POINT_BIT
    pub(crate) line_width: f64,
    pub(crate) point_size: f64,
    /// GL_LINE_SMOOTH and GL_POINT_SMOOTH: antialiased lines and round points.
    pub(crate) line_smooth: bool,
    pub(crate) point_smooth: bool,
}

impl Default for State {
    fn default() -> Self {
        let texgen = TexGen { enabled: false, mode: GL_EYE_LINEAR, object_plane: DVec4::X, eye_plane: DVec4::X };
        State {
            lighting: false,
            lights: std::array::from_fn(Light::new),
            model: LightModel::default(),
            materials: [Material::default(); 2],
            color_material: false,
            color_material_face: Face::FrontAndBack,
            color_material_mode: ColorMaterialMode::AmbientAndDiffuse,
            flat: false,
            normalize: false,
            rescale_normal: false,
            clip_planes: [(false, DVec4::ZERO); 6],
            cull: false,
            cull_face: Face::Back,
            front_ccw: true,
            polygon_mode: [GL_FILL; 2],
            polygon_offset_fill: false,
            polygon_offset: (0.0, 0.0),
            depth_test: false,
            depth_func: CompareFunc::Less,
            depth_mask: true,
            scissor_test: false,
            scissor: None,
            viewport: Viewport { x: 0, y: 0, width: 0, height: 0 },
            depth_range: (0.0, 1.0),
            clear_color: Vec4::ZERO,
            clear_depth: 1.0,
            blend: false,
            blend_func: (BlendFactor::One, BlendFactor::Zero),
            alpha_test: false,
            alpha_func: (CompareFunc::Always, 0.0),
            color_mask: [true; 4],
            logic_op_enabled: false,
            logic_op: LogicOp::Copy,
            texture_2d: false,
            bound_texture: 0,
            texture_1d: false,
            bound_texture_1d: 0,
            env_mode: TexEnvMode::Modulate,
            env_color: Vec4::ZERO,
            texgen: [texgen, TexGen { object_plane: DVec4::Y, eye_plane: DVec4::Y, ..texgen }],
            fog_enabled: false,
            fog: Fog { mode: FogMode::Exp, density: 1.0, start: 0.0, end: 1.0, color: Vec4::ZERO },
            line_width: 1.0,
            point_size: 1.0,
            line_smooth: false,
            point_smooth: false,
        }
    }
}

impl State {
    /// glPopAttrib: takes back the groups `mask` saved.
    pub(crate) fn restore(&mut self, mask: u32, saved: State) {
        let s = saved;
        if mask & (GL_LIGHTING_BIT | GL_ENABLE_BIT) != 0 {
            self.lighting = s.lighting;
            self.color_material = s.color_material;
            for (l, o) in self.lights.iter_mut().zip(&s.lights) {
                l.enabled = o.enabled;
            }
        }
        if mask & GL_LIGHTING_BIT != 0 {
            self.lights = s.lights;
            self.model = s.model;
            self.materials = s.materials;
            self.color_material_face = s.color_material_face;
            self.color_material_mode = s.color_material_mode;
            self.flat = s.flat;
        }
        if mask & (GL_TRANSFORM_BIT | GL_ENABLE_BIT) != 0 {
            self.normalize = s.normalize;
            self.rescale_normal = s.rescale_normal;
            for (p, o) in self.clip_planes.iter_mut().zip(&s.clip_planes) {
                p.0 = o.0;
            }
        }
        if mask & GL_TRANSFORM_BIT != 0 {
            self.clip_planes = s.clip_planes;
        }
        if mask & (GL_POLYGON_BIT | GL_ENABLE_BIT) != 0 {
            self.cull = s.cull;
            self.polygon_offset_fill = s.polygon_offset_fill;
        }
        if mask & GL_POLYGON_BIT != 0 {
            self.cull_face = s.cull_face;
            self.front_ccw = s.front_ccw;
            self.polygon_mode = s.polygon_mode;
            self.polygon_offset = s.polygon_offset;
        }
        if mask & (GL_DEPTH_BUFFER_BIT | GL_ENABLE_BIT) != 0 {
            self.depth_test = s.depth_test;
        }
        if mask & GL_DEPTH_BUFFER_BIT != 0 {
            self.depth_func = s.depth_func;
            self.depth_mask = s.depth_mask;
            self.clear_depth = s.clear_depth;
        }
        if mask & (GL_SCISSOR_BIT | GL_ENABLE_BIT) != 0 {
            self.scissor_test = s.scissor_test;
        }
        if mask & GL_SCISSOR_BIT != 0 {
            self.scissor = s.scissor;
        }
        if mask & GL_VIEWPORT_BIT != 0 {
            self.viewport = s.viewport;
            self.depth_range = s.depth_range;
        }
        if mask & (GL_COLOR_BUFFER_BIT | GL_ENABLE_BIT) != 0 {
            self.blend = s.blend;
            self.alpha_test = s.alpha_test;
            self.logic_op_enabled = s.logic_op_enabled;
        }
        if mask & GL_COLOR_BUFFER_BIT != 0 {
            self.clear_color = s.clear_color;
            self.blend_func = s.blend_func;
            self.alpha_func = s.alpha_func;
            self.color_mask = s.color_mask;
            self.logic_op = s.logic_op;
        }
        if mask & (GL_TEXTURE_BIT | GL_ENABLE_BIT) != 0 {
            self.texture_2d = s.texture_2d;
            self.texture_1d = s.texture_1d;
            self.texgen[0].enabled = s.texgen[0].enabled;
            self.texgen[1].enabled = s.texgen[1].enabled;
        }
        if mask & GL_TEXTURE_BIT != 0 {
            self.bound_texture = s.bound_texture;
            self.bound_texture_1d = s.bound_texture_1d;
            self.env_mode = s.env_mode;
            self.env_color = s.env_color;
            self.texgen = s.texgen;
        }
        if mask & (GL_FOG_BIT | GL_ENABLE_BIT) != 0 {
            self.fog_enabled = s.fog_enabled;
        }
        if mask & GL_FOG_BIT != 0 {
            self.fog = s.fog;
        }
        if mask & (GL_LINE_BIT | GL_ENABLE_BIT) != 0 {
            self.line_smooth = s.line_smooth;
        }
        if mask & GL_LINE_BIT != 0 {
            self.line_width = s.line_width;
        }
        if mask & (GL_POINT_BIT | GL_ENABLE_BIT) != 0 {
            self.point_smooth = s.point_smooth;
        }
        if mask & GL_POINT_BIT != 0 {
            self.point_size = s.point_size;
        }
    }
}
