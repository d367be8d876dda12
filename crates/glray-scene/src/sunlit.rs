//! The lighting equation (`lighting`) for the case most programs draw with, lights at infinity
//! seen by a viewer at infinity and no spotlights, in single precision and with everything a
//! vertex does not change worked out once: the tracer's short way lights three corners for
//! every hit of a GL-look frame, and on a big mesh no two hits share a corner (a 10M-triangle
//! frame spent ~15% of its time in the double-precision equation, docs/performance.md).
//!
//! With every light at infinity and no spotlight, attenuation and spot factors are 1, a light's
//! direction and half vector are the same for every vertex, and the equation is, per face,
//!
//!   primary  = emission + ambient * (scene ambient + sum of the lights' ambient)
//!              + diffuse * sum over lights of max(n.l, 0) * light diffuse
//!   specular = specular * sum over lights with n.l > 0 of max(n.h, 0)^shininess * light specular
//!
//! so the lights' sums are taken per vertex and the material multiplied in once. The numbers
//! differ from `light_vertex_prepared`'s by single-precision rounding (a test holds them
//! within 1e-5).

use glam::{DVec3, DVec4, Mat3, Vec3, Vec3A, Vec4};

use crate::lighting::{ColorMaterial, ColorTarget, Light, LightModel, Material};

/// One light at infinity, as the equation reads it.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Sun {
    /// Unit direction towards the light.
    direction: Vec3A,
    /// Unit half vector between the direction and the viewer's (+z).
    half: Vec3A,
    diffuse: Vec3A,
    specular: Vec3A,
}

/// A material in single precision.
#[derive(Debug, Clone, Copy, PartialEq)]
struct FaceMaterial {
    ambient: Vec3A,
    diffuse: Vec4,
    specular: Vec3A,
    emission: Vec3A,
    shininess: f32,
}

impl FaceMaterial {
    fn new(m: &Material) -> FaceMaterial {
        let v3 = |v: DVec4| v.truncate().as_vec3a();
        FaceMaterial {
            ambient: v3(m.ambient),
            diffuse: m.diffuse.as_vec4(),
            specular: v3(m.specular),
            emission: v3(m.emission),
            shininess: m.shininess as f32,
        }
    }

    /// This face with `color` put in where glColorMaterial's target says (`frame::color_materials`).
    #[inline]
    fn with_color(mut self, t: ColorTarget, color: Vec4) -> FaceMaterial {
        let rgb = Vec3A::from(color.truncate());
        self.ambient = if t.ambient { rgb } else { self.ambient };
        self.diffuse = if t.diffuse { color } else { self.diffuse };
        self.specular = if t.specular { rgb } else { self.specular };
        self.emission = if t.emission { rgb } else { self.emission };
        self
    }
}

/// A lighting state of lights at infinity only, seen from infinity, made ready for many
/// vertices (`Sunlit::new`).
#[derive(Debug, Clone, PartialEq)]
pub struct Sunlit {
    suns: Vec<Sun>,
    /// The scene's ambient plus every light's ambient: what a material's ambient is lit by.
    ambient: Vec3A,
    /// Front and back materials.
    faces: [FaceMaterial; 2],
    /// Which faces glColorMaterial's colour goes into, and as what (`Lighting::color_material`).
    color_material: Option<([bool; 2], ColorTarget)>,
    two_side: bool,
    separate_specular: bool,
}

impl Sunlit {
    /// `lights` (the enabled ones count) under `model` with `materials` and glColorMaterial's
    /// face and mode; None unless every enabled light is at infinity and not a spotlight and the
    /// viewer is at infinity.
    pub fn new(
        lights: &[Light],
        model: &LightModel,
        materials: &[Material; 2],
        color_material: Option<ColorMaterial>,
    ) -> Option<Sunlit> {
        let lights: Vec<&Light> = lights.iter().filter(|l| l.enabled).collect();
        // (VTK's Phong specular reads the direction to the eye: not a sunlit equation.)
        let reads_position = model.local_viewer || model.phong_specular;
        if reads_position || lights.iter().any(|l| l.position.w != 0.0 || l.spot_cutoff != 180.0) {
            return None;
        }
        let suns = lights
            .iter()
            .map(|l| {
                let direction = l.position.truncate().normalize_or_zero();
                Sun {
                    direction: direction.as_vec3a(),
                    half: (direction + DVec3::Z).normalize_or_zero().as_vec3a(),
                    diffuse: l.diffuse.truncate().as_vec3a(),
                    specular: l.specular.truncate().as_vec3a(),
                }
            })
            .collect();
        let ambient = lights.iter().fold(model.ambient.truncate(), |a, l| a + l.ambient.truncate());
        let color_material = color_material.map(|c| (c.face.sides(), c.mode.target()));
        Some(Sunlit {
            suns,
            ambient: ambient.as_vec3a(),
            faces: materials.each_ref().map(FaceMaterial::new),
            color_material,
            two_side: model.two_side,
            separate_specular: model.separate_specular,
        })
    }

    /// The lit colours (primary, secondary) of `face` (0 front, 1 back) of a vertex with unit
    /// eye-space normal `normal` (its front face's) and colour `color`: what `light_face` gives
    /// it.
    #[inline]
    pub fn light(&self, normal: Vec3A, color: Vec4, face: usize) -> (Vec4, Vec3) {
        // One-sided lighting lights the back face as the front.
        let (side, normal) = if face == 1 && self.two_side { (1, -normal) } else { (0, normal) };
        let mut m = self.faces[side];
        if let Some((faces, target)) = self.color_material {
            if faces[side] {
                m = m.with_color(target, color);
            }
        }
        let mut diffuse = Vec3A::ZERO;
        let mut specular = Vec3A::ZERO;
        for sun in &self.suns {
            let n_dot_l = normal.dot(sun.direction);
            if n_dot_l > 0.0 {
                diffuse += n_dot_l * sun.diffuse;
                // 0^0 is 1 in GL's equation: a shininess of 0 gives the full specular colour.
                let power = if m.shininess == 0.0 { 1.0 } else { normal.dot(sun.half).max(0.0).powf(m.shininess) };
                specular += power * sun.specular;
            }
        }
        let primary = m.emission + m.ambient * self.ambient + Vec3A::from(m.diffuse.truncate()) * diffuse;
        let specular = m.specular * specular;
        let alpha = m.diffuse.w.clamp(0.0, 1.0);
        let clamp = |c: Vec3A| c.clamp(Vec3A::ZERO, Vec3A::ONE);
        if self.separate_specular {
            (clamp(primary).extend(alpha), clamp(specular).into())
        } else {
            (clamp(primary + specular).extend(alpha), Vec3::ZERO)
        }
    }
}

/// Object-space normal `n` in eye space through normal matrix `nm`, normalized or rescaled as
/// GL_NORMALIZE and GL_RESCALE_NORMAL ask (`vertex::eye_normal`, in single precision).
#[inline]
pub fn eye_normal(nm: &Mat3, n: Vec3A, normalize: bool, rescale: bool) -> Vec3A {
    let n = *nm * n;
    if normalize {
        return n.normalize_or_zero();
    }
    if rescale {
        let len = nm.z_axis.length();
        if len > 0.0 {
            return n / len;
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lighting::{light_face, prepare};
    use glam::DMat3;

    /// Numbers spread over [lo, hi) from a counter (no randomness: the same cases every run).
    struct Spread(u64);

    impl Spread {
        fn next(&mut self, lo: f64, hi: f64) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
        }
        fn color(&mut self) -> DVec4 {
            DVec4::new(self.next(0.0, 1.0), self.next(0.0, 1.0), self.next(0.0, 1.0), self.next(0.0, 1.0))
        }
        fn unit(&mut self) -> DVec3 {
            DVec3::new(self.next(-1.0, 1.0), self.next(-1.0, 1.0), self.next(-1.0, 1.0)).normalize()
        }
    }

    #[test]
    fn lights_at_infinity_give_the_double_precision_equations_colours() {
        let mut s = Spread(7);
        use crate::facing::Face;
        use crate::lighting::ColorMaterialMode as Mode;
        let faces = [Face::Front, Face::Back, Face::FrontAndBack];
        let modes = [Mode::Ambient, Mode::Diffuse, Mode::Specular, Mode::Emission, Mode::AmbientAndDiffuse];
        for case in 0..400 {
            let lights: Vec<Light> = (0..1 + case % 3)
                .map(|k| {
                    let mut l = Light::new(k);
                    l.enabled = case % 7 != k;
                    l.ambient = s.color() * 0.3;
                    l.diffuse = s.color();
                    l.specular = if case % 5 == 0 { DVec4::ZERO } else { s.color() };
                    l.position = (s.unit() * s.next(0.5, 3.0)).extend(0.0);
                    l
                })
                .collect();
            let model = LightModel {
                ambient: s.color() * 0.3,
                two_side: case % 2 == 0,
                separate_specular: case % 4 < 2,
                ..LightModel::default()
            };
            let material = |s: &mut Spread| Material {
                ambient: s.color(),
                diffuse: s.color(),
                specular: s.color(),
                emission: s.color() * 0.2,
                shininess: if case % 9 == 0 { 0.0 } else { s.next(1.0, 128.0) },
            };
            let materials = [material(&mut s), material(&mut s)];
            let color_material =
                (case % 3 == 0).then(|| ColorMaterial { face: faces[case / 3 % 3], mode: modes[case / 3 % 5] });
            let sunlit = Sunlit::new(&lights, &model, &materials, color_material).expect("lights at infinity");
            let prepared = prepare(&lights, &model);
            for _ in 0..8 {
                let normal = s.unit();
                let color = s.color();
                let mats = crate::draw_lighting::color_materials(&materials, color_material, color);
                for face in 0..2 {
                    let (p, q) = light_face(DVec3::ZERO, normal, &mats, &lights, &prepared, &model, face);
                    let (a, b) = sunlit.light(normal.as_vec3a(), color.as_vec4(), face);
                    assert!(a.as_dvec4().abs_diff_eq(p, 1e-5), "case {case} face {face}: {a} against {p}");
                    assert!(b.as_dvec3().abs_diff_eq(q.truncate(), 1e-5), "case {case} face {face}: {b} against {q}");
                }
            }
        }
    }

    #[test]
    fn local_lights_spotlights_and_a_local_viewer_are_not_for_it() {
        let materials = [Material::default(); 2];
        let mut light = Light::new(0);
        light.enabled = true;
        assert!(Sunlit::new(&[light], &LightModel::default(), &materials, None).is_some());
        let mut local = light;
        local.position.w = 1.0;
        assert!(Sunlit::new(&[local], &LightModel::default(), &materials, None).is_none());
        let mut spot = light;
        spot.spot_cutoff = 30.0;
        assert!(Sunlit::new(&[spot], &LightModel::default(), &materials, None).is_none());
        let viewer = LightModel { local_viewer: true, ..LightModel::default() };
        assert!(Sunlit::new(&[light], &viewer, &materials, None).is_none());
        // A disabled local light does not count.
        local.enabled = false;
        assert!(Sunlit::new(&[light, local], &LightModel::default(), &materials, None).is_some());
    }

    #[test]
    fn eye_normals_match_the_double_precision_ones() {
        let nm = DMat3::from_cols_array(&[0.9, 0.1, -0.2, 0.3, 1.7, 0.4, -0.5, 0.2, 2.1]);
        let n = DVec3::new(0.3, -0.8, 0.5);
        for (normalize, rescale) in [(false, false), (true, false), (false, true), (true, true)] {
            let want = crate::lighting::eye_normal(&nm, n, normalize, rescale);
            let got = eye_normal(&nm.as_mat3(), n.as_vec3a(), normalize, rescale);
            assert!(got.as_dvec3().abs_diff_eq(want, 1e-6), "{normalize} {rescale}: {got} against {want}");
        }
    }
}
