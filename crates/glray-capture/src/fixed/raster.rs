//! Rasterization and per-fragment state (Mesa's polygon.c, depth.c, blend.c, fog.c, scissor.c,
//! viewport.c, clip.c): how polygons are faced, culled, filled and offset; the depth, alpha and
//! scissor tests; blending, logic ops and the colour mask; fog; line and point size and
//! smoothing; user clip planes; the viewport, depth range and clear values. Their commands, and
//! what glPopAttrib takes back.

use glam::{DMat4, DVec4, Vec4};
use glray_core::trace::Value;
use glray_gl::{
    GL_ALPHA_TEST, GL_BACK, GL_BLEND, GL_CCW, GL_CLIP_PLANE0, GL_COLOR_BUFFER_BIT, GL_COLOR_LOGIC_OP, GL_CULL_FACE,
    GL_CW, GL_DEPTH_BUFFER_BIT, GL_DEPTH_TEST, GL_DOUBLE, GL_ENABLE_BIT, GL_FILL, GL_FOG, GL_FOG_BIT, GL_FOG_COLOR,
    GL_FOG_DENSITY, GL_FOG_END, GL_FOG_MODE, GL_FOG_START, GL_FRONT, GL_FRONT_AND_BACK, GL_LINE, GL_LINE_BIT,
    GL_LINE_SMOOTH, GL_POINT, GL_POINT_BIT, GL_POINT_SMOOTH, GL_POLYGON_BIT, GL_POLYGON_OFFSET_FILL, GL_SCISSOR_BIT,
    GL_SCISSOR_TEST, GL_TRANSFORM_BIT, GL_VIEWPORT_BIT,
};
use glray_scene::camera::Viewport;
use glray_scene::facing::Face;
use glray_scene::surface::{BlendFactor, CompareFunc, Fog, FogMode, LogicOp};

use crate::args::{self, color_param, floats};
use crate::error::{GlError, GlResult};
use crate::ops::Op;

/// A context's rasterization and fragment state, with GL's initial values.
#[derive(Debug, Clone)]
pub(crate) struct Raster {
    // GL_POLYGON_BIT
    pub(crate) cull: bool,
    pub(crate) cull_face: Face,
    pub(crate) front_ccw: bool,
    /// Front and back.
    pub(crate) polygon_mode: [u32; 2],
    /// GL_POLYGON_OFFSET_FILL, and glPolygonOffset's (factor, units).
    pub(crate) polygon_offset_fill: bool,
    pub(crate) polygon_offset: (f32, f32),
    // GL_TRANSFORM_BIT: enabled user clip planes, in eye coordinates.
    pub(crate) clip_planes: [(bool, DVec4); 6],
    // GL_DEPTH_BUFFER_BIT
    pub(crate) depth_test: bool,
    pub(crate) depth_func: CompareFunc,
    pub(crate) depth_mask: bool,
    /// glClearDepth, clamped to [0, 1].
    pub(crate) clear_depth: f32,
    // GL_SCISSOR_BIT
    /// GL_SCISSOR_TEST, and glScissor's box (None until it is given: the whole drawable).
    pub(crate) scissor_test: bool,
    pub(crate) scissor: Option<Viewport>,
    // GL_VIEWPORT_BIT
    pub(crate) viewport: Viewport,
    pub(crate) depth_range: (f64, f64),
    // GL_COLOR_BUFFER_BIT
    pub(crate) clear_color: Vec4,
    pub(crate) blend: bool,
    pub(crate) blend_func: (BlendFactor, BlendFactor),
    pub(crate) alpha_test: bool,
    pub(crate) alpha_func: (CompareFunc, f32),
    /// glColorMask: which of red, green, blue and alpha draws write.
    pub(crate) color_mask: [bool; 4],
    /// GL_COLOR_LOGIC_OP's enable and glLogicOp's operation.
    pub(crate) logic_op_enabled: bool,
    pub(crate) logic_op: LogicOp,
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

impl Default for Raster {
    fn default() -> Self {
        Raster {
            cull: false,
            cull_face: Face::Back,
            front_ccw: true,
            polygon_mode: [GL_FILL; 2],
            polygon_offset_fill: false,
            polygon_offset: (0.0, 0.0),
            clip_planes: [(false, DVec4::ZERO); 6],
            depth_test: false,
            depth_func: CompareFunc::Less,
            depth_mask: true,
            clear_depth: 1.0,
            scissor_test: false,
            scissor: None,
            viewport: Viewport { x: 0, y: 0, width: 0, height: 0 },
            depth_range: (0.0, 1.0),
            clear_color: Vec4::ZERO,
            blend: false,
            blend_func: (BlendFactor::One, BlendFactor::Zero),
            alpha_test: false,
            alpha_func: (CompareFunc::Always, 0.0),
            color_mask: [true; 4],
            logic_op_enabled: false,
            logic_op: LogicOp::Copy,
            fog_enabled: false,
            fog: Fog { mode: FogMode::Exp, density: 1.0, start: 0.0, end: 1.0, color: Vec4::ZERO },
            line_width: 1.0,
            point_size: 1.0,
            line_smooth: false,
            point_smooth: false,
        }
    }
}

impl Raster {
    /// Follows a rasterization or fragment command (`Concern::Raster`); `modelview` is the
    /// modelview of the moment (clip planes are taken through it).
    pub(crate) fn command(&mut self, op: Op, ty: u32, a: &[Value], modelview: &DMat4) -> GlResult {
        match op {
            Op::Viewport => {
                let (width, height) = (args::int(a, 2) as i32, args::int(a, 3) as i32);
                if width < 0 || height < 0 {
                    return Err(GlError::InvalidValue);
                }
                self.viewport = Viewport { x: args::int(a, 0) as i32, y: args::int(a, 1) as i32, width, height };
            }
            Op::DepthRange => self.depth_range = (args::float(a, 0).clamp(0.0, 1.0), args::float(a, 1).clamp(0.0, 1.0)),
            Op::FrontFace => match args::uint(a, 0) {
                GL_CCW => self.front_ccw = true,
                GL_CW => self.front_ccw = false,
                _ => return Err(GlError::InvalidEnum),
            },
            Op::CullFace => self.cull_face = Face::from_gl(args::uint(a, 0)).ok_or(GlError::InvalidEnum)?,
            Op::ClearColor => {
                self.clear_color =
                    Vec4::from_array(std::array::from_fn(|i| args::float(a, i) as f32)).clamp(Vec4::ZERO, Vec4::ONE)
            }
            Op::ClearDepth => self.clear_depth = (args::float(a, 0) as f32).clamp(0.0, 1.0),
            Op::Fog => {
                let v = floats(a, 1, ty, 4);
                let first = v.first().copied().unwrap_or(0.0);
                let color = color_param(a, 1, ty).as_vec4();
                let f = &mut self.fog;
                match args::uint(a, 0) {
                    GL_FOG_MODE => f.mode = FogMode::from_gl(first as u32).ok_or(GlError::InvalidEnum)?,
                    GL_FOG_DENSITY => f.density = first as f32,
                    GL_FOG_START => f.start = first as f32,
                    GL_FOG_END => f.end = first as f32,
                    GL_FOG_COLOR => f.color = color,
                    _ => {}
                }
            }
            Op::BlendFunc => {
                let factor = |k| BlendFactor::from_gl(args::uint(a, k)).ok_or(GlError::InvalidEnum);
                self.blend_func = (factor(0)?, factor(1)?)
            }
            Op::AlphaFunc => {
                let func = CompareFunc::from_gl(args::uint(a, 0)).ok_or(GlError::InvalidEnum)?;
                self.alpha_func = (func, args::float(a, 1).clamp(0.0, 1.0) as f32)
            }
            Op::DepthFunc => self.depth_func = CompareFunc::from_gl(args::uint(a, 0)).ok_or(GlError::InvalidEnum)?,
            Op::DepthMask => self.depth_mask = args::int(a, 0) != 0,
            Op::ColorMask => self.color_mask = std::array::from_fn(|k| args::int(a, k) != 0),
            Op::LogicOp => self.logic_op = LogicOp::from_gl(args::uint(a, 0)).ok_or(GlError::InvalidEnum)?,
            Op::Scissor => {
                let (width, height) = (args::int(a, 2), args::int(a, 3));
                if width < 0 || height < 0 {
                    return Err(GlError::InvalidValue);
                }
                let (x, y) = (args::int(a, 0) as i32, args::int(a, 1) as i32);
                self.scissor = Some(Viewport { x, y, width: width as i32, height: height as i32 });
            }
            Op::PolygonOffset => {
                let (factor, units) = (args::float(a, 0), args::float(a, 1));
                self.polygon_offset = (factor as f32, units as f32);
            }
            Op::PolygonMode => {
                let mode = args::uint(a, 1);
                if !matches!(mode, GL_POINT | GL_LINE | GL_FILL) {
                    return Err(GlError::InvalidEnum);
                }
                match args::uint(a, 0) {
                    GL_FRONT => self.polygon_mode[0] = mode,
                    GL_BACK => self.polygon_mode[1] = mode,
                    GL_FRONT_AND_BACK => self.polygon_mode = [mode; 2],
                    _ => return Err(GlError::InvalidEnum),
                }
            }
            Op::LineWidth | Op::PointSize => {
                let v = args::float(a, 0);
                if v <= 0.0 {
                    return Err(GlError::InvalidValue);
                }
                if op == Op::LineWidth {
                    self.line_width = v
                } else {
                    self.point_size = v
                }
            }
            Op::ClipPlane => {
                let i = args::uint(a, 0).wrapping_sub(GL_CLIP_PLANE0) as usize;
                if i >= 6 {
                    return Err(GlError::InvalidEnum);
                }
                if let Ok(p) = <[f64; 4]>::try_from(floats(a, 1, GL_DOUBLE, 4)) {
                    self.clip_planes[i].1 = modelview.inverse().transpose() * DVec4::from_array(p);
                }
            }
            _ => unreachable!("{op:?} is not a rasterization command"),
        }
        Ok(())
    }

    /// glEnable/glDisable of a capability of the raster state's; false for any other.
    pub(crate) fn set_cap(&mut self, cap: u32, on: bool) -> bool {
        match cap {
            GL_CULL_FACE => self.cull = on,
            GL_POLYGON_OFFSET_FILL => self.polygon_offset_fill = on,
            GL_LINE_SMOOTH => self.line_smooth = on,
            GL_SCISSOR_TEST => self.scissor_test = on,
            GL_POINT_SMOOTH => self.point_smooth = on,
            GL_DEPTH_TEST => self.depth_test = on,
            GL_FOG => self.fog_enabled = on,
            GL_BLEND => self.blend = on,
            GL_COLOR_LOGIC_OP => self.logic_op_enabled = on,
            GL_ALPHA_TEST => self.alpha_test = on,
            c if (GL_CLIP_PLANE0..GL_CLIP_PLANE0 + 6).contains(&c) => {
                self.clip_planes[(c - GL_CLIP_PLANE0) as usize].0 = on
            }
            _ => return false,
        }
        true
    }

    /// glCullFace's face when GL_CULL_FACE is on.
    pub(crate) fn culling(&self) -> Option<Face> {
        self.cull.then_some(self.cull_face)
    }

    /// glPopAttrib: takes back what the groups in `mask` saved.
    pub(crate) fn restore(&mut self, mask: u32, s: &Raster) {
        if mask & (GL_TRANSFORM_BIT | GL_ENABLE_BIT) != 0 {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ops::op_for;
    use glray_core::trace::Value::{Int, F64 as Float};
    use glray_gl::{GL_EQUAL, GL_EXP2, GL_LIGHTING, GL_ONE, GL_SRC_ALPHA, GL_XOR};

    fn call(r: &mut Raster, name: &str, a: &[Value]) -> GlResult {
        let (op, ty) = op_for(name).unwrap();
        r.command(op, ty, a, &DMat4::IDENTITY)
    }

    #[test]
    fn fragment_state_is_typed_and_values_gl_refuses_leave_it_as_it_was() {
        let mut r = Raster::default();
        call(&mut r, "glBlendFunc", &[Int(GL_SRC_ALPHA as i64), Int(GL_ONE as i64)]).unwrap();
        assert_eq!(r.blend_func, (BlendFactor::SrcAlpha, BlendFactor::One));
        assert_eq!(call(&mut r, "glBlendFunc", &[Int(GL_SRC_ALPHA as i64), Int(0x1234)]), Err(GlError::InvalidEnum));
        assert_eq!(r.blend_func, (BlendFactor::SrcAlpha, BlendFactor::One), "unchanged");
        call(&mut r, "glDepthFunc", &[Int(GL_EQUAL as i64)]).unwrap();
        assert_eq!(r.depth_func, CompareFunc::Equal);
        call(&mut r, "glLogicOp", &[Int(GL_XOR as i64)]).unwrap();
        assert_eq!(r.logic_op, LogicOp::Xor);
        call(&mut r, "glFogi", &[Int(GL_FOG_MODE as i64), Int(GL_EXP2 as i64)]).unwrap();
        assert_eq!(r.fog.mode, FogMode::Exp2);
        assert_eq!(call(&mut r, "glFogi", &[Int(GL_FOG_MODE as i64), Int(GL_FRONT as i64)]), Err(GlError::InvalidEnum));
        assert_eq!(call(&mut r, "glLineWidth", &[Float(0.0)]), Err(GlError::InvalidValue));
        assert_eq!(call(&mut r, "glScissor", &[Int(0), Int(0), Int(-1), Int(4)]), Err(GlError::InvalidValue));
        assert_eq!(call(&mut r, "glCullFace", &[Int(GL_CCW as i64)]), Err(GlError::InvalidEnum));
    }

    #[test]
    fn pop_attrib_takes_back_the_groups_pushed() {
        let mut r = Raster::default();
        let saved = r.clone();
        assert!(r.set_cap(GL_BLEND, true) && r.set_cap(GL_CLIP_PLANE0 + 3, true) && !r.set_cap(GL_LIGHTING, true));
        call(&mut r, "glDepthMask", &[Int(0)]).unwrap();
        call(&mut r, "glPointSize", &[Float(4.0)]).unwrap();
        r.restore(GL_ENABLE_BIT, &saved);
        assert!(!r.blend && !r.clip_planes[3].0 && !r.depth_mask && r.point_size == 4.0);
        r.restore(GL_DEPTH_BUFFER_BIT | GL_POINT_BIT, &saved);
        assert!(r.depth_mask && r.point_size == 1.0);
    }
}
