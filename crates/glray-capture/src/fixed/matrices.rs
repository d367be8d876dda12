//! The fixed-function matrix stacks and every operation on them, as Mesa implements them
//! (src/mesa/main/matrix.c): stack depths, the errors of each call, glRotate's normalisation,
//! glFrustum/glOrtho's argument checks. All math is in f64, as glLoadMatrixd/glFrustum take
//! it; the float entry points convert on the way in.

use glam::{DMat4, DVec3, DVec4};
use glray_gl::{GL_COLOR, GL_MODELVIEW, GL_PROJECTION, GL_TEXTURE};

use glray_core::trace::Value;

use crate::args;
use crate::error::{GlError, GlResult};
use crate::ops::Op;

/// Mesa's stack depths (MAX_MODELVIEW_STACK_DEPTH and friends), as glGet reports them.
pub const MODELVIEW_DEPTH: usize = 32;
pub const PROJECTION_DEPTH: usize = 32;
pub const TEXTURE_DEPTH: usize = 10;
pub const COLOR_DEPTH: usize = 4;
/// Texture units with a texture matrix stack.
pub const TEXTURE_UNITS: usize = 8;

/// One matrix stack: never empty; the last entry is the current matrix.
#[derive(Debug, Clone)]
pub struct Stack {
    entries: Vec<DMat4>,
    max: usize,
}

impl Stack {
    fn new(max: usize) -> Stack {
        Stack { entries: vec![DMat4::IDENTITY], max }
    }

    pub fn top(&self) -> &DMat4 {
        self.entries.last().expect("a matrix stack is never empty")
    }

    pub(crate) fn top_mut(&mut self) -> &mut DMat4 {
        self.entries.last_mut().expect("a matrix stack is never empty")
    }

    pub fn depth(&self) -> usize {
        self.entries.len()
    }
}

/// Which stack glMatrixMode selected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    ModelView,
    Projection,
    Texture,
    Color,
}

/// All stacks of a context, the current mode and the active texture unit.
#[derive(Debug, Clone)]
pub struct Matrices {
    pub mode: Mode,
    pub modelview: Stack,
    pub projection: Stack,
    pub texture: Vec<Stack>,
    pub color: Stack,
    /// glActiveTexture's unit: which texture stack GL_TEXTURE means.
    pub active_texture: usize,
}

impl Default for Matrices {
    fn default() -> Self {
        Matrices {
            mode: Mode::ModelView,
            modelview: Stack::new(MODELVIEW_DEPTH),
            projection: Stack::new(PROJECTION_DEPTH),
            texture: (0..TEXTURE_UNITS).map(|_| Stack::new(TEXTURE_DEPTH)).collect(),
            color: Stack::new(COLOR_DEPTH),
            active_texture: 0,
        }
    }
}

/// A matrix as GL passes it: 16 values, column-major.
pub fn from_gl(m: &[f64; 16]) -> DMat4 {
    DMat4::from_cols_array(m)
}

/// What a display list can change of the matrix state (`Matrices::seen`): the mode, and the
/// top and depth of the modelview, projection and active texture unit's stacks. The real GL
/// misses these changes when glray takes a glCallList from it (see src/raytrace/lists.rs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seen {
    /// GL_MODELVIEW, GL_PROJECTION, GL_TEXTURE or GL_COLOR.
    pub mode: u32,
    /// The modelview, projection and texture stacks, in that order: (GL mode, top, depth).
    pub stacks: [(u32, DMat4, usize); 3],
}

impl Matrices {
    /// The state `Seen` describes, as it is now.
    pub fn seen(&self) -> Seen {
        let texture = &self.texture[self.active_texture];
        Seen {
            mode: match self.mode {
                Mode::ModelView => GL_MODELVIEW,
                Mode::Projection => GL_PROJECTION,
                Mode::Texture => GL_TEXTURE,
                Mode::Color => GL_COLOR,
            },
            stacks: [
                (GL_MODELVIEW, *self.modelview.top(), self.modelview.depth()),
                (GL_PROJECTION, *self.projection.top(), self.projection.depth()),
                (GL_TEXTURE, *texture.top(), texture.depth()),
            ],
        }
    }

    fn current(&mut self) -> &mut Stack {
        match self.mode {
            Mode::ModelView => &mut self.modelview,
            Mode::Projection => &mut self.projection,
            Mode::Texture => &mut self.texture[self.active_texture],
            Mode::Color => &mut self.color,
        }
    }

    /// The matrix the current mode selects.
    pub fn top(&self) -> &DMat4 {
        match self.mode {
            Mode::ModelView => self.modelview.top(),
            Mode::Projection => self.projection.top(),
            Mode::Texture => self.texture[self.active_texture].top(),
            Mode::Color => self.color.top(),
        }
    }

    pub fn matrix_mode(&mut self, mode: u32) -> GlResult {
        self.mode = match mode {
            GL_MODELVIEW => Mode::ModelView,
            GL_PROJECTION => Mode::Projection,
            GL_TEXTURE => Mode::Texture,
            GL_COLOR => Mode::Color,
            _ => return Err(GlError::InvalidEnum),
        };
        Ok(())
    }

    /// glActiveTexture(GL_TEXTURE0 + unit) as far as the texture stacks care.
    pub fn active_texture(&mut self, texture: u32) -> GlResult {
        let unit = texture.wrapping_sub(0x84C0) as usize;
        if unit >= TEXTURE_UNITS {
            return Err(GlError::InvalidEnum);
        }
        self.active_texture = unit;
        Ok(())
    }

    pub fn push(&mut self) -> GlResult {
        let s = self.current();
        if s.entries.len() >= s.max {
            return Err(GlError::StackOverflow);
        }
        let top = *s.top();
        s.entries.push(top);
        Ok(())
    }

    pub fn pop(&mut self) -> GlResult {
        let s = self.current();
        if s.entries.len() <= 1 {
            return Err(GlError::StackUnderflow);
        }
        s.entries.pop();
        Ok(())
    }

    pub fn load_identity(&mut self) {
        *self.current().top_mut() = DMat4::IDENTITY;
    }

    pub fn load(&mut self, m: DMat4) {
        *self.current().top_mut() = m;
    }

    /// glMultMatrix: current = current * m (GL post-multiplies).
    pub fn mult(&mut self, m: DMat4) {
        let top = self.current().top_mut();
        *top *= m;
    }

    pub fn load_transpose(&mut self, m: DMat4) {
        self.load(m.transpose());
    }

    pub fn mult_transpose(&mut self, m: DMat4) {
        self.mult(m.transpose());
    }

    pub fn translate(&mut self, x: f64, y: f64, z: f64) {
        self.mult(DMat4::from_translation(DVec3::new(x, y, z)));
    }

    pub fn scale(&mut self, x: f64, y: f64, z: f64) {
        self.mult(DMat4::from_scale(DVec3::new(x, y, z)));
    }

    /// glRotate: `angle` degrees about (x, y, z), normalised; a zero axis leaves the matrix as
    /// it is (Mesa's _math_matrix_rotate does nothing for it).
    pub fn rotate(&mut self, angle: f64, x: f64, y: f64, z: f64) {
        let axis = DVec3::new(x, y, z);
        let len = axis.length();
        if len == 0.0 || !len.is_finite() {
            return;
        }
        self.mult(DMat4::from_axis_angle(axis / len, angle.to_radians()));
    }

    /// glFrustum, with its INVALID_VALUE cases.
    pub fn frustum(&mut self, l: f64, r: f64, b: f64, t: f64, n: f64, f: f64) -> GlResult {
        if n <= 0.0 || f <= 0.0 || n == f || l == r || b == t {
            return Err(GlError::InvalidValue);
        }
        let m = DMat4::from_cols(
            DVec4::new(2.0 * n / (r - l), 0.0, 0.0, 0.0),
            DVec4::new(0.0, 2.0 * n / (t - b), 0.0, 0.0),
            DVec4::new((r + l) / (r - l), (t + b) / (t - b), -(f + n) / (f - n), -1.0),
            DVec4::new(0.0, 0.0, -2.0 * f * n / (f - n), 0.0),
        );
        self.mult(m);
        Ok(())
    }

    /// glOrtho, with its INVALID_VALUE cases.
    pub fn ortho(&mut self, l: f64, r: f64, b: f64, t: f64, n: f64, f: f64) -> GlResult {
        if l == r || b == t || n == f {
            return Err(GlError::InvalidValue);
        }
        let m = DMat4::from_cols(
            DVec4::new(2.0 / (r - l), 0.0, 0.0, 0.0),
            DVec4::new(0.0, 2.0 / (t - b), 0.0, 0.0),
            DVec4::new(0.0, 0.0, -2.0 / (f - n), 0.0),
            DVec4::new(-(r + l) / (r - l), -(t + b) / (t - b), -(f + n) / (f - n), 1.0),
        );
        self.mult(m);
        Ok(())
    }

    /// glGet of a matrix: GL_MODELVIEW_MATRIX etc., column-major.
    pub fn get(&self, which: Mode) -> [f64; 16] {
        match which {
            Mode::ModelView => self.modelview.top(),
            Mode::Projection => self.projection.top(),
            Mode::Texture => self.texture[self.active_texture].top(),
            Mode::Color => self.color.top(),
        }
        .to_cols_array()
    }
}

impl Matrices {
    /// Follows a matrix command (`Concern::Matrices`).
    pub(crate) fn command(&mut self, op: Op, ty: u32, a: &[Value]) -> GlResult {
        match op {
            Op::MatrixMode => self.matrix_mode(args::uint(a, 0))?,
            Op::LoadIdentity => self.load_identity(),
            Op::LoadMatrix => {
                if let Some(m) = matrix_arg(a, ty) {
                    self.load(m)
                }
            }
            Op::MultMatrix => {
                if let Some(m) = matrix_arg(a, ty) {
                    self.mult(m)
                }
            }
            Op::LoadTransposeMatrix => {
                if let Some(m) = matrix_arg(a, ty) {
                    self.load_transpose(m)
                }
            }
            Op::MultTransposeMatrix => {
                if let Some(m) = matrix_arg(a, ty) {
                    self.mult_transpose(m)
                }
            }
            Op::Rotate => self.rotate(args::float(a, 0), args::float(a, 1), args::float(a, 2), args::float(a, 3)),
            Op::Translate => self.translate(args::float(a, 0), args::float(a, 1), args::float(a, 2)),
            Op::Scale => self.scale(args::float(a, 0), args::float(a, 1), args::float(a, 2)),
            Op::Frustum | Op::Ortho => {
                let v: [f64; 6] = std::array::from_fn(|i| args::float(a, i));
                if op == Op::Frustum {
                    self.frustum(v[0], v[1], v[2], v[3], v[4], v[5])?
                } else {
                    self.ortho(v[0], v[1], v[2], v[3], v[4], v[5])?
                }
            }
            Op::PushMatrix => self.push()?,
            Op::PopMatrix => self.pop()?,
            Op::ActiveTexture => self.active_texture(args::uint(a, 0))?,
            _ => unreachable!("{op:?} is not a matrix command"),
        }
        Ok(())
    }
}

/// A matrix argument of 16 values of type `ty` (column-major, as GL takes it).
fn matrix_arg(a: &[Value], ty: u32) -> Option<DMat4> {
    let v = args::floats(a, 0, ty, 16);
    let m: [f64; 16] = v.try_into().ok()?;
    Some(from_gl(&m))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &DMat4, b: &DMat4) -> bool {
        a.abs_diff_eq(*b, 1e-12)
    }

    #[test]
    fn stacks_overflow_and_underflow_at_mesas_depths() {
        let mut m = Matrices::default();
        assert_eq!(m.pop(), Err(GlError::StackUnderflow));
        for _ in 1..MODELVIEW_DEPTH {
            m.push().unwrap();
        }
        assert_eq!(m.push(), Err(GlError::StackOverflow));
        assert_eq!(m.modelview.depth(), MODELVIEW_DEPTH);
        m.matrix_mode(GL_TEXTURE).unwrap();
        for _ in 1..TEXTURE_DEPTH {
            m.push().unwrap();
        }
        assert_eq!(m.push(), Err(GlError::StackOverflow));
        m.active_texture(0x84C1).unwrap();
        m.push().unwrap(); // unit 1 has its own stack
        assert_eq!(m.matrix_mode(0x1234), Err(GlError::InvalidEnum));
        assert_eq!(m.mode, Mode::Texture, "a bad mode changes nothing");
        assert_eq!(m.active_texture(0x84C0 + TEXTURE_UNITS as u32), Err(GlError::InvalidEnum));
    }

    #[test]
    fn push_copies_and_pop_restores() {
        let mut m = Matrices::default();
        m.translate(1.0, 2.0, 3.0);
        let before = *m.top();
        m.push().unwrap();
        assert!(close(m.top(), &before));
        m.scale(2.0, 2.0, 2.0);
        assert!(!close(m.top(), &before));
        m.pop().unwrap();
        assert!(close(m.top(), &before));
    }

    #[test]
    fn operations_post_multiply_like_gl() {
        // glTranslate then glRotate: a point is rotated first, then translated.
        let mut m = Matrices::default();
        m.translate(10.0, 0.0, 0.0);
        m.rotate(90.0, 0.0, 0.0, 2.0); // axis normalised
        let p = m.top().transform_point3(DVec3::new(1.0, 0.0, 0.0));
        assert!(p.abs_diff_eq(DVec3::new(10.0, 1.0, 0.0), 1e-12), "{p}");
        // A zero axis does nothing.
        let before = *m.top();
        m.rotate(45.0, 0.0, 0.0, 0.0);
        assert!(close(m.top(), &before));
    }

    #[test]
    fn transpose_variants_match_their_plain_forms() {
        let cols: [f64; 16] = [1., 2., 3., 4., 5., 6., 7., 8., 9., 10., 11., 12., 13., 14., 15., 16.];
        let mut a = Matrices::default();
        a.load_transpose(from_gl(&cols).transpose());
        assert_eq!(a.get(Mode::ModelView), cols);
        let mut b = Matrices::default();
        b.scale(2.0, 3.0, 4.0);
        let mut c = b.clone();
        b.mult(from_gl(&cols));
        c.mult_transpose(from_gl(&cols).transpose());
        assert!(close(b.top(), c.top()));
    }

    #[test]
    fn frustum_and_ortho_match_the_gl_formulas_and_reject_bad_values() {
        let mut m = Matrices::default();
        m.frustum(-1.0, 1.0, -1.0, 1.0, 1.0, 10.0).unwrap();
        // A point on the near plane's corner maps to clip (-1,-1,-1) after the divide.
        let clip = *m.top() * DVec4::new(-1.0, -1.0, -1.0, 1.0);
        let ndc = clip.truncate() / clip.w;
        assert!(ndc.abs_diff_eq(DVec3::new(-1.0, -1.0, -1.0), 1e-12), "{ndc}");
        let far = *m.top() * DVec4::new(0.0, 0.0, -10.0, 1.0);
        assert!((far.z / far.w - 1.0).abs() < 1e-12);
        let before = *m.top();
        for bad in [(0.0, 10.0), (-1.0, 10.0), (1.0, 0.0), (2.0, 2.0)] {
            assert_eq!(m.frustum(-1.0, 1.0, -1.0, 1.0, bad.0, bad.1), Err(GlError::InvalidValue));
        }
        assert_eq!(m.frustum(1.0, 1.0, -1.0, 1.0, 1.0, 2.0), Err(GlError::InvalidValue));
        assert!(close(m.top(), &before), "a rejected call changes nothing");

        let mut o = Matrices::default();
        o.ortho(0.0, 200.0, 0.0, 100.0, -1.0, 1.0).unwrap();
        let p = o.top().transform_point3(DVec3::new(200.0, 100.0, 0.0));
        assert!(p.abs_diff_eq(DVec3::new(1.0, 1.0, 0.0), 1e-12), "{p}");
        assert_eq!(o.ortho(0.0, 0.0, 0.0, 1.0, 0.0, 1.0), Err(GlError::InvalidValue));
        // Unlike glFrustum, glOrtho takes a negative near plane.
        assert_eq!(o.ortho(0.0, 1.0, 0.0, 1.0, -5.0, -1.0), Ok(()));
    }
}
