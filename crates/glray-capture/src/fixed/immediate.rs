//! Immediate mode: the current vertex attributes, and whether a glBegin is open (each glVertex
//! goes through the vertex stage with the attributes current at the call: `Context::vertex`).
//! GL's rules: glBegin inside glBegin,
//! glEnd outside, and any command that is not per-vertex between them are INVALID_OPERATION; a
//! bad mode is INVALID_ENUM; glVertex outside glBegin/glEnd does nothing (Mesa ignores it).
//!
//! Integer forms of glColor/glNormal are normalised the way Mesa does (`convert`); integer
//! glVertex/glTexCoord values are taken as they are.

use crate::args;
use crate::fixed::Context;
use crate::fixed::EyeVertex;
use crate::ops::Op;
use crate::primitive::QuadSplit;
use glam::{DVec3, DVec4};
use glray_core::trace::Value;
use glray_gl::GL_POLYGON;

use crate::error::{GlError, GlResult};

/// Texture units with their own current texture coordinate.
pub const TEXCOORD_UNITS: usize = 8;

/// GL's conversions of integer attribute values to floats (Mesa's *_TO_FLOAT macros).
pub mod convert {
    /// GLubyte: c / 255.
    pub fn ubyte(c: u8) -> f64 {
        c as f64 / 255.0
    }
    /// GLbyte: (2c + 1) / 255, so that -128 and 127 map to -1 and 1.
    pub fn byte(c: i8) -> f64 {
        (2.0 * c as f64 + 1.0) / 255.0
    }
    /// GLushort: c / 65535.
    pub fn ushort(c: u16) -> f64 {
        c as f64 / 65535.0
    }
    /// GLshort: (2c + 1) / 65535.
    pub fn short(c: i16) -> f64 {
        (2.0 * c as f64 + 1.0) / 65535.0
    }
    /// GLuint: c / (2^32 - 1).
    pub fn uint(c: u32) -> f64 {
        c as f64 / u32::MAX as f64
    }
    /// GLint: (2c + 1) / (2^32 - 1).
    pub fn int(c: i32) -> f64 {
        (2.0 * c as f64 + 1.0) / u32::MAX as f64
    }
}

/// The current attributes: what glNormal, glColor, glTexCoord and glEdgeFlag set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Current {
    pub normal: DVec3,
    pub color: DVec4,
    pub texcoords: [DVec4; TEXCOORD_UNITS],
    pub edge: bool,
}

impl Default for Current {
    /// GL's initial values: normal (0,0,1), color (1,1,1,1), texture coordinates (0,0,0,1).
    fn default() -> Self {
        Current {
            normal: DVec3::Z,
            color: DVec4::ONE,
            texcoords: [DVec4::new(0.0, 0.0, 0.0, 1.0); TEXCOORD_UNITS],
            edge: true,
        }
    }
}

/// Immediate-mode state of a context.
#[derive(Debug, Default, Clone)]
pub struct Immediate {
    pub current: Current,
    /// The mode of the open glBegin.
    open: Option<u32>,
}

impl Immediate {
    /// Whether a glBegin is open.
    pub fn inside(&self) -> bool {
        self.open.is_some()
    }

    /// For every command that is not allowed between glBegin and glEnd.
    pub fn outside(&self) -> GlResult {
        if self.inside() {
            Err(GlError::InvalidOperation)
        } else {
            Ok(())
        }
    }

    pub fn begin(&mut self, mode: u32) -> GlResult {
        self.outside()?;
        if mode > GL_POLYGON {
            return Err(GlError::InvalidEnum);
        }
        self.open = Some(mode);
        Ok(())
    }

    /// The mode of the open glBegin.
    pub fn mode(&self) -> Option<u32> {
        self.open
    }

    /// glEnd: the mode of the glBegin it closes.
    pub fn end(&mut self) -> GlResult<u32> {
        self.open.take().ok_or(GlError::InvalidOperation)
    }

    pub fn normal(&mut self, n: DVec3) {
        self.current.normal = n;
    }

    /// glColor: the 3-component forms pass alpha 1.
    pub fn color(&mut self, c: DVec4) {
        self.current.color = c;
    }

    /// glTexCoord (unit 0) and glMultiTexCoord(GL_TEXTURE0 + unit).
    pub fn tex_coord(&mut self, unit: usize, t: DVec4) -> GlResult {
        *self.current.texcoords.get_mut(unit).ok_or(GlError::InvalidEnum)? = t;
        Ok(())
    }

    pub fn edge_flag(&mut self, edge: bool) {
        self.current.edge = edge;
    }
}

impl Context {
    /// Follows glBegin, glEnd, glRect or a per-vertex attribute command (`Concern::Immediate`).
    pub(crate) fn immediate_command(&mut self, op: Op, ty: u32, a: &[Value]) -> GlResult {
        match op {
            Op::Attr(form) => self.attribute(form, a)?,
            Op::Begin => {
                let mode = args::uint(a, 0);
                self.imm.begin(mode)?;
                self.record_begin(mode);
            }
            Op::End => {
                let mode = self.imm.end()?;
                if !self.end_recording(mode) {
                    self.draw_open(mode);
                }
            }
            Op::Rect => {
                let v = if a.len() == 2 {
                    let p = args::floats(a, 0, ty, 2);
                    let q = args::floats(a, 1, ty, 2);
                    [p.first(), p.get(1), q.first(), q.get(1)].map(|x| x.copied().unwrap_or(0.0))
                } else {
                    [0, 1, 2, 3].map(|i| args::float(a, i))
                };
                let corners = [(v[0], v[1]), (v[2], v[1]), (v[2], v[3]), (v[0], v[3])];
                let verts: Vec<EyeVertex> =
                    corners.iter().map(|&(x, y)| self.vertex_stage(DVec4::new(x, y, 0.0, 1.0))).collect();
                self.draw(GL_POLYGON, &verts, QuadSplit::Direct);
            }
            _ => unreachable!("{op:?} is not an immediate-mode command"),
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glray_gl::{GL_QUADS, GL_TRIANGLES};

    #[test]
    fn the_current_attributes_outlive_glend() {
        let mut im = Immediate::default();
        assert_eq!(im.current.normal, DVec3::Z, "the initial normal");
        im.begin(GL_TRIANGLES).unwrap();
        im.color(DVec4::new(1.0, 0.0, 0.0, 1.0));
        im.normal(DVec3::X);
        im.tex_coord(1, DVec4::new(0.5, 0.5, 0.0, 1.0)).unwrap();
        assert_eq!(im.end(), Ok(GL_TRIANGLES));
        assert_eq!(im.current.normal, DVec3::X);
        assert_eq!(im.current.color, DVec4::new(1.0, 0.0, 0.0, 1.0));
        assert_eq!(im.current.texcoords[1], DVec4::new(0.5, 0.5, 0.0, 1.0));
    }

    #[test]
    fn begin_end_errors_follow_gl() {
        let mut im = Immediate::default();
        assert_eq!(im.end().unwrap_err(), GlError::InvalidOperation);
        assert_eq!(im.begin(10), Err(GlError::InvalidEnum));
        assert!(!im.inside());
        im.begin(GL_QUADS).unwrap();
        assert_eq!(im.begin(GL_QUADS), Err(GlError::InvalidOperation));
        assert_eq!(im.outside(), Err(GlError::InvalidOperation));
        assert_eq!(im.tex_coord(TEXCOORD_UNITS, DVec4::ZERO), Err(GlError::InvalidEnum));
        assert_eq!(im.end(), Ok(GL_QUADS));
        assert!(!im.inside());
    }

    #[test]
    fn integer_forms_normalise_like_mesa() {
        assert_eq!(convert::ubyte(255), 1.0);
        assert_eq!(convert::ubyte(0), 0.0);
        assert_eq!(convert::byte(127), 1.0);
        assert_eq!(convert::byte(-128), -1.0);
        assert_eq!(convert::ushort(65535), 1.0);
        assert_eq!(convert::short(-32768), -1.0);
        assert_eq!(convert::uint(u32::MAX), 1.0);
        assert!((convert::int(i32::MAX) - 1.0).abs() < 1e-12);
    }
}
