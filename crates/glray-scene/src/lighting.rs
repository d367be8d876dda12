//! The fixed-function lighting equation (OpenGL 2.1 spec, section 2.14.1), evaluated the way
//! a rasterizer does per vertex, so that the GL look can match it: emission, the scene ambient,
//! and for each enabled light attenuation x spotlight x (ambient + diffuse + specular). Light
//! positions and spot directions are in eye coordinates (GL transforms them by the modelview of
//! the moment glLight is called; the caller does that). Colour material and two-sided lighting
//! are the caller's choice of `Material` and normal.

use glam::{DMat3, DVec3, DVec4};
use serde::{Deserialize, Serialize};

use crate::facing::Face;
use crate::gl_enum::gl_enum;

/// One light's parameters, with GL's initial values (`Light::new(0)` is GL_LIGHT0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Light {
    pub enabled: bool,
    pub ambient: DVec4,
    pub diffuse: DVec4,
    pub specular: DVec4,
    /// Eye coordinates; w = 0 for a directional light.
    pub position: DVec4,
    /// Eye coordinates.
    pub spot_direction: DVec3,
    pub spot_exponent: f64,
    /// Degrees; 180 means no spotlight.
    pub spot_cutoff: f64,
    pub constant_attenuation: f64,
    pub linear_attenuation: f64,
    pub quadratic_attenuation: f64,
}

impl Light {
    /// GL's initial state of light `index`: light 0 is white, the others black.
    pub fn new(index: usize) -> Light {
        let white = if index == 0 { DVec4::ONE } else { DVec4::new(0.0, 0.0, 0.0, 1.0) };
        Light {
            enabled: false,
            ambient: DVec4::new(0.0, 0.0, 0.0, 1.0),
            diffuse: white,
            specular: white,
            position: DVec4::new(0.0, 0.0, 1.0, 0.0),
            spot_direction: DVec3::new(0.0, 0.0, -1.0),
            spot_exponent: 0.0,
            spot_cutoff: 180.0,
            constant_attenuation: 1.0,
            linear_attenuation: 0.0,
            quadratic_attenuation: 0.0,
        }
    }
}

/// A material, with GL's initial values.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Material {
    pub ambient: DVec4,
    pub diffuse: DVec4,
    pub specular: DVec4,
    pub emission: DVec4,
    pub shininess: f64,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            ambient: DVec4::new(0.2, 0.2, 0.2, 1.0),
            diffuse: DVec4::new(0.8, 0.8, 0.8, 1.0),
            specular: DVec4::new(0.0, 0.0, 0.0, 1.0),
            emission: DVec4::new(0.0, 0.0, 0.0, 1.0),
            shininess: 0.0,
        }
    }
}

/// glLightModel state, with GL's initial values.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LightModel {
    pub ambient: DVec4,
    pub local_viewer: bool,
    pub two_side: bool,
    /// GL_SEPARATE_SPECULAR_COLOR: specular goes to the secondary colour (added after texturing).
    pub separate_specular: bool,
    /// Lit per pixel, not per vertex: what a shader program computes per fragment (VTK's),
    /// drawn by glray as a fixed-function draw (`programs` in glray-capture). Not GL state.
    pub per_fragment: bool,
    /// The specular term as VTK's shader has it (Phong: the light reflected about the normal,
    /// against the true direction to the eye), not GL's half vector (Blinn). Not GL state.
    pub phong_specular: bool,
}

impl Default for LightModel {
    fn default() -> Self {
        LightModel {
            ambient: DVec4::new(0.2, 0.2, 0.2, 1.0),
            local_viewer: false,
            two_side: false,
            separate_specular: false,
            per_fragment: false,
            phong_specular: false,
        }
    }
}

/// The colours of a material glColorMaterial's mode replaces with the current colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ColorTarget {
    pub ambient: bool,
    pub diffuse: bool,
    pub specular: bool,
    pub emission: bool,
}

gl_enum! {
    /// Which colours of a material glColorMaterial replaces with the current colour.
    pub enum ColorMaterialMode {
        Emission = GL_EMISSION,
        Ambient = GL_AMBIENT,
        Diffuse = GL_DIFFUSE,
        Specular = GL_SPECULAR,
        AmbientAndDiffuse = GL_AMBIENT_AND_DIFFUSE,
    }
}

impl ColorMaterialMode {
    /// The colours it replaces.
    pub fn target(self) -> ColorTarget {
        let only = |ambient, diffuse, specular, emission| ColorTarget { ambient, diffuse, specular, emission };
        match self {
            ColorMaterialMode::Ambient => only(true, false, false, false),
            ColorMaterialMode::Diffuse => only(false, true, false, false),
            ColorMaterialMode::Specular => only(false, false, true, false),
            ColorMaterialMode::Emission => only(false, false, false, true),
            ColorMaterialMode::AmbientAndDiffuse => only(true, true, false, false),
        }
    }
}

/// glColorMaterial's face and mode, when GL_COLOR_MATERIAL is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct ColorMaterial {
    pub face: Face,
    pub mode: ColorMaterialMode,
}

/// An object-space normal in eye coordinates, as lighting uses it: through the normal matrix,
/// then GL_NORMALIZE (to unit length) or GL_RESCALE_NORMAL (by the modelview's scale).
#[inline]
pub fn eye_normal(nm: &DMat3, n: DVec3, normalize: bool, rescale: bool) -> DVec3 {
    let n = *nm * n;
    if normalize {
        return n.normalize_or_zero();
    }
    if rescale {
        // The inverse modelview's third row: the normal matrix's third column.
        let len = nm.col(2).length();
        if len > 0.0 {
            return n / len;
        }
    }
    n
}

/// What the lighting equation needs of a directional light that no vertex changes, worked out
/// once per frame: its unit direction and, for a viewer at infinity, its half vector (two
/// square roots and divisions per light and vertex otherwise; the tracer lights every hit's
/// three corners). See `prepare`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PreparedLight {
    /// The light is directional (`direction` holds its unit direction).
    directional: bool,
    /// `half` holds the half vector (a directional light and a viewer at infinity).
    fixed_half: bool,
    direction: DVec3,
    half: DVec3,
}

/// `lights` made ready for many vertices under `model`, one entry per light, in order.
pub fn prepare(lights: &[Light], model: &LightModel) -> Vec<PreparedLight> {
    lights
        .iter()
        .map(|l| {
            let directional = l.position.w == 0.0;
            let direction = if directional { l.position.truncate().normalize_or_zero() } else { DVec3::ZERO };
            let fixed_half = directional && !model.local_viewer;
            let half = if fixed_half { (direction + DVec3::Z).normalize_or_zero() } else { DVec3::ZERO };
            PreparedLight { directional, fixed_half, direction, half }
        })
        .collect()
}

/// The lit colour of a vertex at `position` (eye coordinates) with unit `normal` (eye
/// coordinates, already flipped for a back face): the primary colour and the secondary
/// (specular) colour, both clamped to [0, 1]. The alpha is the material's diffuse alpha.
#[inline]
pub fn light_vertex(
    position: DVec3,
    normal: DVec3,
    m: &Material,
    lights: &[Light],
    model: &LightModel,
) -> (DVec4, DVec4) {
    light_vertex_prepared(position, normal, m, lights, &[], model)
}

/// `light_vertex` with `prepared` (`prepare` of the same lights and model; lights it has no
/// entry for are worked out at the vertex): the same numbers, the per-light work done once.
#[inline]
pub fn light_vertex_prepared(
    position: DVec3,
    normal: DVec3,
    m: &Material,
    lights: &[Light],
    prepared: &[PreparedLight],
    model: &LightModel,
) -> (DVec4, DVec4) {
    let mut primary = m.emission.truncate() + m.ambient.truncate() * model.ambient.truncate();
    let mut specular = DVec3::ZERO;
    let eye = if model.local_viewer { (-position).normalize_or_zero() } else { DVec3::Z };
    for (k, l) in lights.iter().enumerate().filter(|(_, l)| l.enabled) {
        let ready = prepared.get(k);
        let (to_light, attenuation) = if l.position.w != 0.0 {
            let p = l.position.truncate() / l.position.w;
            let d = p - position;
            let dist = d.length();
            let att =
                1.0 / (l.constant_attenuation + l.linear_attenuation * dist + l.quadratic_attenuation * dist * dist);
            (d.normalize_or_zero(), att)
        } else {
            match ready {
                Some(r) if r.directional => (r.direction, 1.0),
                _ => (l.position.truncate().normalize_or_zero(), 1.0),
            }
        };
        let spot = if l.spot_cutoff == 180.0 {
            1.0
        } else {
            let cos_angle = (-to_light).dot(l.spot_direction.normalize_or_zero());
            if cos_angle < l.spot_cutoff.to_radians().cos() {
                0.0
            } else {
                cos_angle.max(0.0).powf(l.spot_exponent)
            }
        };
        let factor = attenuation * spot;
        if factor == 0.0 {
            continue;
        }
        let n_dot_l = normal.dot(to_light);
        let mut term = m.ambient.truncate() * l.ambient.truncate();
        if n_dot_l > 0.0 {
            term += n_dot_l * m.diffuse.truncate() * l.diffuse.truncate();
            let colour = m.specular.truncate() * l.specular.truncate();
            // No specular colour (VTK's default material): no power to raise (a pow was an
            // eighth of a ParaView frame's ambient occlusion, its result multiplied by zero).
            if colour != DVec3::ZERO && model.phong_specular {
                // VTK: pow(max(1e-5, dot(reflect(-to_light, n), normalize(-position))), power).
                let reflected = 2.0 * n_dot_l * normal - to_light;
                let power = reflected.dot((-position).normalize_or_zero()).max(1e-5).powf(m.shininess);
                specular += factor * power * colour;
            } else if colour != DVec3::ZERO {
                let half = match ready {
                    Some(r) if r.fixed_half => r.half,
                    _ => (to_light + eye).normalize_or_zero(),
                };
                let n_dot_h = normal.dot(half).max(0.0);
                // 0^0 is 1 in GL's equation: a shininess of 0 gives the full specular colour.
                let power = if m.shininess == 0.0 { 1.0 } else { n_dot_h.powf(m.shininess) };
                specular += factor * power * colour;
            }
        }
        primary += factor * term;
    }
    let alpha = m.diffuse.w.clamp(0.0, 1.0);
    let clamp = |c: DVec3| c.clamp(DVec3::ZERO, DVec3::ONE);
    if model.separate_specular {
        (clamp(primary).extend(alpha), clamp(specular).extend(0.0))
    } else {
        (clamp(primary + specular).extend(alpha), DVec4::ZERO)
    }
}

/// The lit colours (primary, secondary) of one face of a vertex: the front with `materials[0]`,
/// or, for face 1 with two-sided lighting, the back with the reversed normal and
/// `materials[1]` (one-sided lighting gives the back face the front's colours). `prepared` as
/// for `light_vertex_prepared` (empty: everything worked out at the vertex).
#[inline]
pub fn light_face(
    position: DVec3,
    normal: DVec3,
    materials: &[Material; 2],
    lights: &[Light],
    prepared: &[PreparedLight],
    model: &LightModel,
    face: usize,
) -> (DVec4, DVec4) {
    if face == 1 && model.two_side {
        light_vertex_prepared(position, -normal, &materials[1], lights, prepared, model)
    } else {
        light_vertex_prepared(position, normal, &materials[0], lights, prepared, model)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn light0() -> Light {
        Light { enabled: true, ..Light::new(0) }
    }

    fn close(a: DVec4, b: DVec4) -> bool {
        a.abs_diff_eq(b, 1e-12)
    }

    #[test]
    fn a_default_light_on_a_default_material_gives_gl_numbers() {
        let m = Material::default();
        let (c, s) = light_vertex(DVec3::new(0.0, 0.0, -5.0), DVec3::Z, &m, &[light0()], &LightModel::default());
        // 0.2*0.2 scene ambient + 0.8 diffuse; no specular (material specular is black).
        assert!(close(c, DVec4::new(0.84, 0.84, 0.84, 1.0)), "{c}");
        assert_eq!(s, DVec4::ZERO);
        // Facing away: only ambient terms.
        let (c, _) = light_vertex(DVec3::ZERO, -DVec3::Z, &m, &[light0()], &LightModel::default());
        assert!(close(c, DVec4::new(0.04, 0.04, 0.04, 1.0)), "{c}");
        // Disabled lights do nothing; light 1 is black by default.
        let (c, _) = light_vertex(
            DVec3::ZERO,
            DVec3::Z,
            &m,
            &[Light::new(0), Light { enabled: true, ..Light::new(1) }],
            &LightModel::default(),
        );
        assert!(close(c, DVec4::new(0.04, 0.04, 0.04, 1.0)), "{c}");
    }

    #[test]
    fn positional_lights_attenuate_and_spotlights_cut_off() {
        let m = Material { ambient: DVec4::ZERO.with_w(1.0), diffuse: DVec4::ONE, ..Material::default() };
        let model = LightModel { ambient: DVec4::ZERO, ..LightModel::default() };
        let point = Light {
            position: DVec4::new(0.0, 0.0, 2.0, 1.0),
            constant_attenuation: 0.0,
            quadratic_attenuation: 1.0,
            ..light0()
        };
        let (c, _) = light_vertex(DVec3::ZERO, DVec3::Z, &m, &[point], &model);
        assert!(close(c, DVec4::new(0.25, 0.25, 0.25, 1.0)), "1/d^2 at d = 2: {c}");
        let spot = Light { spot_cutoff: 30.0, spot_direction: DVec3::new(0.0, 0.0, -1.0), spot_exponent: 2.0, ..point };
        let (inside, _) = light_vertex(DVec3::ZERO, DVec3::Z, &m, &[spot], &model);
        assert!(close(inside, DVec4::new(0.25, 0.25, 0.25, 1.0)), "on the axis: {inside}");
        let (outside, _) = light_vertex(DVec3::new(2.0, 0.0, 0.0), DVec3::Z, &m, &[spot], &model);
        assert!(close(outside, DVec4::new(0.0, 0.0, 0.0, 1.0)), "45 degrees off a 30-degree cone: {outside}");
    }

    #[test]
    fn specular_highlights_follow_the_half_vector_and_can_be_separate() {
        let m = Material { specular: DVec4::ONE, shininess: 10.0, ..Material::default() };
        let model = LightModel { ambient: DVec4::ZERO, ..LightModel::default() };
        // Infinite viewer, light along +z: the half vector is +z, the full highlight.
        let (c, _) = light_vertex(DVec3::new(0.0, 0.0, -5.0), DVec3::Z, &m, &[light0()], &model);
        assert!(close(c, DVec4::ONE), "0.8 diffuse + 1.0 specular, clamped: {c}");
        let separate = LightModel { separate_specular: true, ..model };
        let (p, s) = light_vertex(DVec3::new(0.0, 0.0, -5.0), DVec3::Z, &m, &[light0()], &separate);
        assert!(close(p, DVec4::new(0.8, 0.8, 0.8, 1.0)), "{p}");
        assert!(close(s, DVec4::new(1.0, 1.0, 1.0, 0.0)), "{s}");
        // A light at 45 degrees: n.h = cos(22.5 degrees), raised to the shininess.
        let tilted = Light { position: DVec4::new(1.0, 0.0, 1.0, 0.0), ..light0() };
        let (_, s) = light_vertex(DVec3::ZERO, DVec3::Z, &m, &[tilted], &separate);
        let expect = 22.5f64.to_radians().cos().powf(10.0);
        assert!((s.x - expect).abs() < 1e-12, "{} vs {expect}", s.x);
        // A local viewer sees the same highlight from straight above the vertex.
        let local = LightModel { local_viewer: true, ..separate };
        let (_, s) = light_vertex(DVec3::new(0.0, 0.0, -5.0), DVec3::Z, &m, &[tilted], &local);
        assert!((s.x - expect).abs() < 1e-12);
    }

    #[test]
    fn prepared_lights_give_the_same_colours_as_lighting_from_scratch() {
        let directional = Light { position: DVec4::new(0.3, 0.8, 0.5, 0.0), ..light0() };
        let positional = Light { position: DVec4::new(1.0, 2.0, 1.0, 1.0), linear_attenuation: 0.2, ..light0() };
        let spot =
            Light { spot_cutoff: 40.0, spot_exponent: 3.0, spot_direction: DVec3::new(0.0, -1.0, -0.5), ..positional };
        let off = Light { enabled: false, ..directional };
        let lights = [off, directional, positional, spot];
        let m = Material { specular: DVec4::new(0.6, 0.5, 0.4, 1.0), shininess: 12.0, ..Material::default() };
        for local_viewer in [false, true] {
            let model = LightModel { local_viewer, separate_specular: true, ..LightModel::default() };
            let prepared = prepare(&lights, &model);
            for (p, n) in [
                (DVec3::new(0.0, 0.0, -5.0), DVec3::Z),
                (DVec3::new(0.5, 1.5, -2.0), DVec3::new(0.2, 0.9, 0.3).normalize()),
                (DVec3::new(-1.0, 0.0, -3.0), DVec3::new(-0.6, 0.0, 0.8)),
            ] {
                let scratch = light_vertex(p, n, &m, &lights, &model);
                assert_eq!(light_vertex_prepared(p, n, &m, &lights, &prepared, &model), scratch);
                // Fewer entries than lights: the rest worked out at the vertex.
                assert_eq!(light_vertex_prepared(p, n, &m, &lights, &prepared[..2], &model), scratch);
                assert_ne!(scratch.0, DVec4::ZERO);
            }
        }
    }
}
