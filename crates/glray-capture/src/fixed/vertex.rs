//! The fixed-function vertex stage: per-vertex attribute commands, and each vertex transformed,
//! lit (both faces) and given its texture coordinates when it is given, with the state of that
//! moment, as the pipeline does.

use glam::{DMat3, DMat4, DVec3, DVec4};
use glray_core::trace::Value;
use glray_gl::{
    GL_EYE_LINEAR, GL_LINES, GL_OBJECT_LINEAR, GL_POINTS, GL_QUADS, GL_SPHERE_MAP, GL_TEXTURE0, GL_TRIANGLES,
};

use crate::args;
use crate::error::{GlError, GlResult};
use crate::fixed::immediate::TEXCOORD_UNITS;
use crate::fixed::{Context, EyeVertex};
use crate::ops::{Attr, AttrForm, Op};
use crate::primitive::QuadSplit;
use glray_scene::draw_lighting::color_materials;
use glray_scene::lighting::{eye_normal, light_face};

/// How many vertices of a glBegin of separate primitives are drawn at once (a multiple of 1,
/// 2, 3 and 4, so that no primitive is cut; 3 MB of vertices).
pub(crate) const IMMEDIATE_CHUNK: usize = 12 * 1024;

/// What an attribute command gives, decoded from its arguments.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Given {
    Vertex(DVec4),
    Normal(DVec3),
    Color(DVec4),
    /// A texture unit's coordinates.
    TexCoord(usize, DVec4),
    SecondaryColor,
    EdgeFlag(bool),
}

/// Decodes glVertex*, glNormal*, glColor*, glTexCoord*, glMultiTexCoord*, ... from a recorded
/// call's arguments (`given_from` makes what they give).
pub(crate) fn decode_attribute(f: AttrForm, a: &[Value]) -> GlResult<Given> {
    let (first, target) = match f.attr {
        Attr::MultiTexCoord => (1, args::uint(a, 0)),
        _ => (0, 0),
    };
    // At most four values, on the stack: this runs for every glVertex, glNormal and glColor a
    // display list compiles (tens of millions in a big list).
    let mut values = [0.0f64; 4];
    // A vector's components read with its type decided once (`args::elements`), not per
    // component.
    let len = if f.vector {
        args::elements(args::bytes(a, first), f.ty, &mut values[..f.n.min(4)])
    } else {
        let n = f.n.min(4);
        for (k, slot) in values[..n].iter_mut().enumerate() {
            *slot = args::float(a, first + k);
        }
        n
    };
    given_from(f, target, &values[..len])
}

/// What an attribute command of form `f` gives with its components `raw` as the program passed
/// them (integers not yet normalised) and, for glMultiTexCoord, its `target`: missing
/// components take GL's defaults, integer colours and normals are normalised. The one place
/// both the recorded calls (`decode_attribute`) and the typed ones (`Context::take_given`)
/// make their values.
pub(crate) fn given_from(f: AttrForm, target: u32, raw: &[f64]) -> GlResult<Given> {
    let unit = match f.attr {
        Attr::MultiTexCoord => {
            let unit = target.wrapping_sub(GL_TEXTURE0) as usize;
            if unit >= TEXCOORD_UNITS {
                return Err(GlError::InvalidEnum);
            }
            unit
        }
        _ => 0,
    };
    let get = |k: usize, default: f64| raw.get(k).copied().unwrap_or(default);
    let norm = |k: usize, default: f64| raw.get(k).map_or(default, |x| args::normalize(*x, f.ty));
    Ok(match f.attr {
        Attr::Vertex => Given::Vertex(DVec4::new(
            get(0, 0.0),
            get(1, 0.0),
            if f.n > 2 { get(2, 0.0) } else { 0.0 },
            if f.n > 3 { get(3, 1.0) } else { 1.0 },
        )),
        Attr::Normal => Given::Normal(DVec3::new(norm(0, 0.0), norm(1, 0.0), norm(2, 1.0))),
        Attr::Color => {
            let alpha = if f.n > 3 { norm(3, 1.0) } else { 1.0 };
            Given::Color(DVec4::new(norm(0, 0.0), norm(1, 0.0), norm(2, 0.0), alpha))
        }
        Attr::TexCoord | Attr::MultiTexCoord => Given::TexCoord(
            unit,
            DVec4::new(
                get(0, 0.0),
                if f.n > 1 { get(1, 0.0) } else { 0.0 },
                if f.n > 2 { get(2, 0.0) } else { 0.0 },
                if f.n > 3 { get(3, 1.0) } else { 1.0 },
            ),
        ),
        Attr::SecondaryColor => Given::SecondaryColor,
        Attr::EdgeFlag => Given::EdgeFlag(get(0, 1.0) != 0.0),
    })
}

impl Context {
    pub(crate) fn attribute(&mut self, f: AttrForm, a: &[Value]) -> GlResult {
        self.give(decode_attribute(f, a)?)
    }

    /// An attribute command the live layer hands over typed, not as a recorded call (no trace
    /// file is written): `raw` its components as the program passed them, `target` a
    /// glMultiTexCoord's unit. Does what `call` does with the same command.
    pub fn take_given(&mut self, f: AttrForm, target: u32, raw: &[f64]) {
        if self.core_profile {
            return;
        }
        let given = given_from(f, target, raw);
        if let Some((_, execute)) = self.shared.lists.compiling() {
            if !given.as_ref().is_ok_and(|g| self.compile_given(g)) {
                // A call the list keeps as a call: the recorded way, with the components as
                // the scalar form's arguments (which the list decodes back to the same).
                let mut a = [Value::UInt(target as u64), Value::Null, Value::Null, Value::Null, Value::Null];
                let first = usize::from(f.attr == Attr::MultiTexCoord);
                for (slot, x) in a[first..].iter_mut().zip(raw) {
                    *slot = Value::F64(*x);
                }
                let scalar = AttrForm { vector: false, ..f };
                self.call(Op::Attr(scalar), f.ty, &a[..first + raw.len()]);
                return;
            }
            if !execute {
                self.arrays.clear();
                return;
            }
        }
        let r = given.and_then(|g| self.give(g));
        self.raise(r);
    }

    /// What an attribute command gives, taken: by the glBegin recorded as a mesh, if it takes
    /// it, else by the current values and the vertex stage.
    fn give(&mut self, given: Given) -> GlResult {
        if self.recording.is_open() && self.record_given(&given) {
            return Ok(());
        }
        match given {
            Given::Vertex(p) => self.vertex(p),
            Given::Normal(n) => self.imm.normal(n),
            Given::Color(c) => self.imm.color(c),
            Given::TexCoord(unit, t) => self.imm.tex_coord(unit, t)?,
            Given::SecondaryColor => {}
            Given::EdgeFlag(e) => self.imm.edge_flag(e),
        }
        Ok(())
    }

    /// glVertex: a vertex of the open glBegin (outside one it does nothing). A glBegin of
    /// separate points, lines, triangles or quads is drawn every `IMMEDIATE_CHUNK` vertices, as
    /// Mesa flushes its immediate-mode buffer when it fills: held to its glEnd, a glBegin of a
    /// million triangles was 750 MB of vertices, grown and copied anew every frame.
    pub(crate) fn vertex(&mut self, p: DVec4) {
        let Some(mode) = self.imm.mode() else { return };
        let out = self.vertex_stage(p);
        self.open.push(out);
        if self.open.len() >= IMMEDIATE_CHUNK && matches!(mode, GL_POINTS | GL_LINES | GL_TRIANGLES | GL_QUADS) {
            self.draw_open(mode);
        }
    }

    /// Draws the open glBegin's vertices so far, and keeps their room for the next ones.
    pub(crate) fn draw_open(&mut self, mode: u32) {
        let mut verts = std::mem::take(&mut self.open);
        self.draw(mode, &verts, QuadSplit::Direct);
        verts.clear();
        // A long strip, fan or polygon's room is not kept.
        if verts.capacity() <= 4 * IMMEDIATE_CHUNK {
            self.open = verts;
        }
    }

    /// glArrayElement: the enabled arrays' element `i` given as glNormal, glColor,
    /// glTexCoord and glVertex would give it.
    pub(crate) fn array_element(&mut self, i: i64) {
        if i < 0 {
            return;
        }
        let v = self.element(i as u64);
        self.arrays.clear();
        let given = [
            v.normal.map(Given::Normal),
            v.color.map(Given::Color),
            v.tex.map(|t| Given::TexCoord(0, t)),
            v.position.map(Given::Vertex),
        ];
        for g in given.into_iter().flatten() {
            // (Unit 0 exists: no error.)
            let _ = self.give(g);
        }
    }

    /// The inverse transpose of the modelview's upper 3x3, cached per modelview.
    pub(crate) fn normal_matrix(&mut self, mv: &DMat4) -> DMat3 {
        if let Some((m, n)) = &self.normal_matrix {
            if m == mv {
                return *n;
            }
        }
        let n = DMat3::from_mat4(*mv).inverse().transpose();
        self.normal_matrix = Some((*mv, n));
        n
    }

    /// The fixed-function vertex stage: eye position, lighting of both faces, texture
    /// coordinates (texgen, texture matrix).
    pub(crate) fn vertex_stage(&mut self, object: DVec4) -> EyeVertex {
        let mv = *self.matrices.modelview.top();
        let eye = mv * object;
        // The three current values a vertex reads (the whole of `current`, with every unit's
        // texture coordinates, was a 320-byte copy per vertex).
        let cur = &self.imm.current;
        let (cur_normal, cur_color, cur_tex) = (cur.normal, cur.color, cur.texcoords[0]);
        let mut normal = DVec3::Z;
        let (colors, secondary) = if self.lighting.lighting {
            let nm = self.normal_matrix(&mv);
            normal = eye_normal(&nm, cur_normal, self.lighting.normalize, self.lighting.rescale_normal);
            // (Not `LightingState::lighting()`: that copies the lights, at every vertex.)
            let color_material = self.lighting.color_material();
            let mats = color_materials(&self.lighting.materials, color_material, cur_color);
            let p = eye.truncate() / if eye.w != 0.0 { eye.w } else { 1.0 };
            let (f0, f1) = light_face(p, normal, &mats, &self.lighting.lights, &[], &self.lighting.model, 0);
            let (b0, b1) = if self.lighting.model.two_side {
                light_face(p, normal, &mats, &self.lighting.lights, &[], &self.lighting.model, 1)
            } else {
                (f0, f1)
            };
            ([f0, b0], [f1, b1])
        } else {
            let c = cur_color.clamp(DVec4::ZERO, DVec4::ONE);
            ([c, c], [DVec4::ZERO; 2])
        };
        let sphere_map = self.texturing.texgen.iter().any(|g| g.enabled && g.mode == GL_SPHERE_MAP);
        let sphere_nm = if sphere_map { self.normal_matrix(&mv) } else { DMat3::IDENTITY };
        let mut tex = cur_tex;
        for (k, g) in self.texturing.texgen.iter().enumerate() {
            if g.enabled {
                tex[k] = match g.mode {
                    GL_OBJECT_LINEAR => g.object_plane.dot(object),
                    GL_EYE_LINEAR => g.eye_plane.dot(eye),
                    GL_SPHERE_MAP => {
                        // The eye normal as lighting takes it: GL normalizes it only when
                        // asked to (GL_NORMALIZE, GL_RESCALE_NORMAL), and a normal shorter than
                        // 1 reflects less (xscreensaver's blocktube gives 0.7).
                        let n =
                            eye_normal(&sphere_nm, cur_normal, self.lighting.normalize, self.lighting.rescale_normal);
                        let u = (eye.truncate() / if eye.w != 0.0 { eye.w } else { 1.0 }).normalize_or_zero();
                        let r = u - 2.0 * n.dot(u) * n;
                        let m = 2.0 * (r.x * r.x + r.y * r.y + (r.z + 1.0) * (r.z + 1.0)).sqrt();
                        if m == 0.0 {
                            0.5
                        } else {
                            r[k] / m + 0.5
                        }
                    }
                    _ => tex[k],
                };
            }
        }
        let tex = *self.matrices.texture[0].top() * tex;
        EyeVertex { eye, colors, secondary, tex, normal, base: cur_color }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ops::attr_form;

    /// `v`'s bytes as a recorded pointer argument.
    fn blob<const N: usize, T: Copy>(v: [T; N], to_bytes: fn(T) -> Vec<u8>) -> Vec<u8> {
        v.iter().flat_map(|x| to_bytes(*x)).collect()
    }

    #[test]
    fn float_vectors_decode_as_every_other_type_does_and_stop_where_the_memory_does() {
        let decode = |name: &str, bytes: &[u8]| {
            let f = attr_form(name).expect(name);
            decode_attribute(f, &[Value::Blob(bytes)]).expect(name)
        };
        let floats = blob([0.5f32, -2.0, 3.25, 0.75], |x| x.to_ne_bytes().to_vec());
        let doubles = blob([0.5f64, -2.0, 3.25, 0.75], |x| x.to_ne_bytes().to_vec());
        // glVertex3fv (from floats) as glVertex3dv (from doubles): the same values.
        assert_eq!(decode("glVertex3fv", &floats[..12]), decode("glVertex3dv", &doubles[..24]));
        assert_eq!(decode("glVertex3fv", &floats[..12]), Given::Vertex(DVec4::new(0.5, -2.0, 3.25, 1.0)));
        assert_eq!(decode("glVertex4fv", &floats), Given::Vertex(DVec4::new(0.5, -2.0, 3.25, 0.75)));
        assert_eq!(decode("glColor4fv", &floats), decode("glColor4dv", &doubles));
        // Fewer bytes recorded than components: the rest take GL's defaults, in both ways.
        assert_eq!(decode("glNormal3fv", &floats[..8]), Given::Normal(DVec3::new(0.5, -2.0, 1.0)));
        assert_eq!(decode("glNormal3fv", &floats[..10]), decode("glNormal3dv", &doubles[..16]));
        assert_eq!(decode("glTexCoord2fv", &floats[..4]), decode("glTexCoord2dv", &doubles[..8]));
    }
}
