//! Lighting and materials (Mesa's light.c): the lights, both faces' materials, the light
//! model, glColorMaterial, glShadeModel and the normal's treatment (GL_NORMALIZE,
//! GL_RESCALE_NORMAL), with the commands that set them and what glPopAttrib takes back. A
//! light's position and spot direction go to eye coordinates through the modelview of the
//! moment glLight is called, as GL does.

use glam::{DMat3, DMat4, DVec3, DVec4};
use glray_core::trace::Value;
use glray_gl::{
    GL_AMBIENT, GL_AMBIENT_AND_DIFFUSE, GL_BACK, GL_COLOR_INDEXES, GL_COLOR_MATERIAL, GL_CONSTANT_ATTENUATION,
    GL_DIFFUSE, GL_EMISSION, GL_ENABLE_BIT, GL_FLAT, GL_FRONT, GL_FRONT_AND_BACK, GL_LIGHT0, GL_LIGHTING,
    GL_LIGHTING_BIT, GL_LIGHT_MODEL_AMBIENT, GL_LIGHT_MODEL_COLOR_CONTROL, GL_LIGHT_MODEL_LOCAL_VIEWER,
    GL_LIGHT_MODEL_TWO_SIDE, GL_LINEAR_ATTENUATION, GL_NORMALIZE, GL_POSITION, GL_QUADRATIC_ATTENUATION,
    GL_RESCALE_NORMAL, GL_SEPARATE_SPECULAR_COLOR, GL_SHININESS, GL_SMOOTH, GL_SPECULAR, GL_SPOT_CUTOFF,
    GL_SPOT_DIRECTION, GL_SPOT_EXPONENT, GL_TRANSFORM_BIT,
};
use glray_scene::draw_lighting::Lighting;
use glray_scene::facing::Face;
use glray_scene::lighting::{ColorMaterial, ColorMaterialMode, Light, LightModel, Material};

use crate::args::{self, color_param, floats};
use crate::error::{GlError, GlResult};
use crate::ops::Op;

/// The lighting state of a context, with GL's initial values.
#[derive(Debug, Clone)]
pub(crate) struct LightingState {
    /// GL_LIGHTING.
    pub(crate) lighting: bool,
    pub(crate) lights: [Light; 8],
    pub(crate) model: LightModel,
    /// Front and back.
    pub(crate) materials: [Material; 2],
    /// GL_COLOR_MATERIAL, and glColorMaterial's face and mode.
    pub(crate) color_material: bool,
    pub(crate) color_material_face: Face,
    pub(crate) color_material_mode: ColorMaterialMode,
    /// glShadeModel(GL_FLAT).
    pub(crate) flat: bool,
    pub(crate) normalize: bool,
    pub(crate) rescale_normal: bool,
}

impl Default for LightingState {
    fn default() -> Self {
        LightingState {
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
        }
    }
}

impl LightingState {
    /// Follows a lighting command (`Concern::Lighting`); `modelview` is the modelview of the
    /// moment.
    pub(crate) fn command(&mut self, op: Op, ty: u32, a: &[Value], modelview: &DMat4) -> GlResult {
        match op {
            Op::Material => self.material(a, ty)?,
            Op::ColorMaterial => {
                let face = Face::from_gl(args::uint(a, 0)).ok_or(GlError::InvalidEnum)?;
                let mode = ColorMaterialMode::from_gl(args::uint(a, 1)).ok_or(GlError::InvalidEnum)?;
                self.color_material_face = face;
                self.color_material_mode = mode;
            }
            Op::Light => self.light(a, ty, modelview)?,
            Op::LightModel => {
                let pname = args::uint(a, 0);
                let v = floats(a, 1, ty, 4);
                let first = v.first().copied().unwrap_or(0.0);
                match pname {
                    GL_LIGHT_MODEL_AMBIENT => self.model.ambient = color_param(a, 1, ty),
                    GL_LIGHT_MODEL_LOCAL_VIEWER => self.model.local_viewer = first != 0.0,
                    GL_LIGHT_MODEL_TWO_SIDE => self.model.two_side = first != 0.0,
                    GL_LIGHT_MODEL_COLOR_CONTROL => {
                        self.model.separate_specular = first as u32 == GL_SEPARATE_SPECULAR_COLOR
                    }
                    _ => return Err(GlError::InvalidEnum),
                }
            }
            Op::ShadeModel => match args::uint(a, 0) {
                GL_FLAT => self.flat = true,
                GL_SMOOTH => self.flat = false,
                _ => return Err(GlError::InvalidEnum),
            },
            _ => unreachable!("{op:?} is not a lighting command"),
        }
        Ok(())
    }

    /// glEnable/glDisable of a capability of lighting's; false for any other.
    pub(crate) fn set_cap(&mut self, cap: u32, on: bool) -> bool {
        match cap {
            GL_LIGHTING => self.lighting = on,
            c if (GL_LIGHT0..GL_LIGHT0 + 8).contains(&c) => self.lights[(c - GL_LIGHT0) as usize].enabled = on,
            GL_COLOR_MATERIAL => self.color_material = on,
            GL_NORMALIZE => self.normalize = on,
            GL_RESCALE_NORMAL => self.rescale_normal = on,
            _ => return false,
        }
        true
    }

    /// glPopAttrib: takes back what the groups in `mask` saved.
    pub(crate) fn restore(&mut self, mask: u32, s: &LightingState) {
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
        }
    }

    /// glColorMaterial's face and mode when GL_COLOR_MATERIAL is on.
    pub(crate) fn color_material(&self) -> Option<ColorMaterial> {
        self.color_material.then_some(ColorMaterial { face: self.color_material_face, mode: self.color_material_mode })
    }

    /// The lighting of the moment, as a frame keeps it.
    pub(crate) fn lighting(&self) -> Lighting {
        Lighting::new(
            self.lights.iter().filter(|l| l.enabled).copied().collect(),
            self.model,
            self.materials,
            self.color_material(),
        )
    }

    fn material(&mut self, a: &[Value], ty: u32) -> GlResult {
        let (face, pname) = (args::uint(a, 0), args::uint(a, 1));
        let faces: &[usize] = match face {
            GL_FRONT => &[0],
            GL_BACK => &[1],
            GL_FRONT_AND_BACK => &[0, 1],
            _ => return Err(GlError::InvalidEnum),
        };
        let c = color_param(a, 2, ty);
        let first = floats(a, 2, ty, 1).first().copied().unwrap_or(0.0);
        for &f in faces {
            let m = &mut self.materials[f];
            match pname {
                GL_AMBIENT => m.ambient = c,
                GL_DIFFUSE => m.diffuse = c,
                GL_SPECULAR => m.specular = c,
                GL_EMISSION => m.emission = c,
                GL_AMBIENT_AND_DIFFUSE => {
                    m.ambient = c;
                    m.diffuse = c;
                }
                GL_SHININESS => {
                    if !(0.0..=128.0).contains(&first) {
                        return Err(GlError::InvalidValue);
                    }
                    m.shininess = first
                }
                GL_COLOR_INDEXES => {}
                _ => return Err(GlError::InvalidEnum),
            }
        }
        Ok(())
    }

    fn light(&mut self, a: &[Value], ty: u32, modelview: &DMat4) -> GlResult {
        let index = args::uint(a, 0).wrapping_sub(GL_LIGHT0) as usize;
        if index >= 8 {
            return Err(GlError::InvalidEnum);
        }
        let v = floats(a, 2, ty, 4);
        let get = |k: usize| v.get(k).copied().unwrap_or(0.0);
        let mv = *modelview;
        let c = color_param(a, 2, ty);
        let l = &mut self.lights[index];
        match args::uint(a, 1) {
            GL_AMBIENT => l.ambient = c,
            GL_DIFFUSE => l.diffuse = c,
            GL_SPECULAR => l.specular = c,
            // Positions and directions are taken through the modelview of the moment.
            GL_POSITION => l.position = mv * DVec4::new(get(0), get(1), get(2), get(3)),
            GL_SPOT_DIRECTION => l.spot_direction = DMat3::from_mat4(mv) * DVec3::new(get(0), get(1), get(2)),
            GL_SPOT_EXPONENT => {
                if !(0.0..=128.0).contains(&get(0)) {
                    return Err(GlError::InvalidValue);
                }
                l.spot_exponent = get(0)
            }
            GL_SPOT_CUTOFF => {
                let c = get(0);
                if !((0.0..=90.0).contains(&c) || c == 180.0) {
                    return Err(GlError::InvalidValue);
                }
                l.spot_cutoff = c
            }
            p @ (GL_CONSTANT_ATTENUATION | GL_LINEAR_ATTENUATION | GL_QUADRATIC_ATTENUATION) => {
                if get(0) < 0.0 {
                    return Err(GlError::InvalidValue);
                }
                match p {
                    GL_CONSTANT_ATTENUATION => l.constant_attenuation = get(0),
                    GL_LINEAR_ATTENUATION => l.linear_attenuation = get(0),
                    _ => l.quadratic_attenuation = get(0),
                }
            }
            _ => return Err(GlError::InvalidEnum),
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ops::op_for;
    use glray_core::trace::Value::{Blob, Int};
    use glray_gl::*;

    fn command(l: &mut LightingState, name: &str, a: &[Value], modelview: &DMat4) -> GlResult {
        let (op, ty) = op_for(name).unwrap();
        l.command(op, ty, a, modelview)
    }

    fn floats4(v: [f32; 4]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_ne_bytes()).collect()
    }

    #[test]
    fn lights_are_placed_by_the_modelview_of_the_moment_and_bad_values_refused() {
        let mut l = LightingState::default();
        let mv = DMat4::from_translation(DVec3::new(1.0, 2.0, 3.0));
        let at = floats4([0.0, 0.0, 0.0, 1.0]);
        command(&mut l, "glLightfv", &[Int(GL_LIGHT0 as i64 + 1), Int(GL_POSITION as i64), Blob(&at)], &mv).unwrap();
        assert_eq!(l.lights[1].position, DVec4::new(1.0, 2.0, 3.0, 1.0));
        let cutoff = floats4([95.0, 0.0, 0.0, 0.0]);
        let r = command(&mut l, "glLightfv", &[Int(GL_LIGHT0 as i64), Int(GL_SPOT_CUTOFF as i64), Blob(&cutoff)], &mv);
        assert_eq!(r, Err(GlError::InvalidValue), "a cut-off between 90 and 180");
        assert_eq!(l.lights[0].spot_cutoff, 180.0, "left as it was");
        let r = command(&mut l, "glLightf", &[Int(GL_LIGHT0 as i64 + 8), Int(GL_SPOT_EXPONENT as i64)], &mv);
        assert_eq!(r, Err(GlError::InvalidEnum), "light 8");
    }

    #[test]
    fn materials_color_material_and_what_pop_attrib_takes_back() {
        let mut l = LightingState::default();
        let mv = DMat4::IDENTITY;
        let red = floats4([1.0, 0.0, 0.0, 1.0]);
        command(&mut l, "glMaterialfv", &[Int(GL_BACK as i64), Int(GL_DIFFUSE as i64), Blob(&red)], &mv).unwrap();
        assert_eq!(
            (l.materials[0].diffuse, l.materials[1].diffuse),
            (Material::default().diffuse, DVec4::X + DVec4::W)
        );
        command(&mut l, "glColorMaterial", &[Int(GL_FRONT as i64), Int(GL_EMISSION as i64)], &mv).unwrap();
        assert_eq!(l.color_material(), None, "GL_COLOR_MATERIAL is off");
        let saved = l.clone();
        assert!(l.set_cap(GL_COLOR_MATERIAL, true) && l.set_cap(GL_LIGHT0 + 2, true) && !l.set_cap(GL_BLEND, true));
        assert_eq!(l.color_material(), Some(ColorMaterial { face: Face::Front, mode: ColorMaterialMode::Emission }));
        command(&mut l, "glShadeModel", &[Int(GL_FLAT as i64)], &mv).unwrap();
        l.restore(GL_ENABLE_BIT, &saved);
        assert!(!l.color_material && !l.lights[2].enabled && l.flat, "the enables back, not the shade model");
        l.restore(GL_LIGHTING_BIT, &saved);
        assert!(!l.flat);
        assert_eq!(
            command(&mut l, "glColorMaterial", &[Int(GL_FRONT as i64), Int(GL_POSITION as i64)], &mv),
            Err(GlError::InvalidEnum)
        );
    }

    // Through the context, as a program calls them.
    use crate::fixed::tests::*;
    use glam::{DMat4, DVec3, DVec4, Vec4};
    use glray_core::trace::Value;

    #[test]
    fn lighting_uses_color_material_and_two_sides() {
        let mut c = context();
        call(&mut c, "glEnable", &[i(GL_LIGHTING as i64)]);
        call(&mut c, "glEnable", &[i(GL_LIGHT0 as i64)]);
        call(&mut c, "glEnable", &[i(GL_COLOR_MATERIAL as i64)]);
        call(&mut c, "glLightModeli", &[i(GL_LIGHT_MODEL_TWO_SIDE as i64), i(1)]);
        call(&mut c, "glColor3f", &[f(1.0), f(0.0), f(0.0)]);
        triangle(&mut c, true);
        triangle(&mut c, false);
        let t = &c.frame().triangles;
        // Front: red diffuse 1 * light 1 * n.l 1 + ambient 0.2 * 1 (scene ambient).
        assert!((t[0].colors[0] - Vec4::new(1.0, 0.0, 0.0, 1.0)).length() < 1e-6, "{:?}", t[0].colors[0]);
        // Back face: the normal is flipped, the light does not reach it; only ambient is left.
        assert!((t[1].colors[0] - Vec4::new(0.2, 0.0, 0.0, 1.0)).length() < 1e-6, "{:?}", t[1].colors[0]);
    }
    #[test]
    fn draws_share_a_lighting_while_its_state_is_unchanged() {
        let mut c = context();
        call(&mut c, "glEnable", &[i(GL_LIGHTING as i64)]);
        call(&mut c, "glEnable", &[i(GL_LIGHT0 as i64)]);
        triangle(&mut c, true);
        triangle(&mut c, true);
        // Each change below makes the next draw's lighting a new one.
        call(&mut c, "glLightf", &[i(GL_LIGHT0 as i64), i(GL_CONSTANT_ATTENUATION as i64), f(2.0)]); // GL_CONSTANT_ATTENUATION
        triangle(&mut c, true);
        call(&mut c, "glMaterialf", &[i(GL_FRONT_AND_BACK as i64), i(GL_SHININESS as i64), f(50.0)]); // GL_FRONT_AND_BACK, GL_SHININESS
        triangle(&mut c, true);
        call(&mut c, "glEnable", &[i(GL_LIGHT0 as i64 + 1)]);
        triangle(&mut c, true);
        call(&mut c, "glDisable", &[i(GL_LIGHT0 as i64 + 1)]);
        triangle(&mut c, true);
        call(&mut c, "glEnable", &[i(GL_COLOR_MATERIAL as i64)]);
        triangle(&mut c, true);
        call(&mut c, "glLightModeli", &[i(GL_LIGHT_MODEL_TWO_SIDE as i64), i(1)]);
        triangle(&mut c, true);
        let frame = c.frame();
        let used: Vec<u32> = frame.triangles.iter().map(|t| t.lighting).collect();
        assert_eq!(used, [0, 0, 1, 2, 3, 4, 5, 6]);
        let l = &frame.lightings;
        assert_eq!(l.len(), 7);
        assert_eq!(l[1].lights()[0].constant_attenuation, 2.0);
        assert_eq!(l[0].lights()[0].constant_attenuation, 1.0);
        assert_eq!((l[3].lights().len(), l[4].lights().len()), (2, 1));
        assert_eq!(l[4], l[2], "the same state again, after another");
        assert!(l[6].model().two_side && !l[5].model().two_side);
        // Each is what the state of its draw makes.
        assert_eq!(l[6], c.lighting.lighting());
    }
}
