//! A profile: a family of GLSL programs described by the names of its inputs (a table, not
//! code: another VTK version or another program family is another table), and what a draw of
//! one of its programs is in fixed-function terms (`ProgramDraw`): where the mesh's positions,
//! normals, colours and texture coordinates are, the transforms, the lights, the material and
//! the colour map. The fixed machine then draws it as it would a glDrawElements of its own
//! (`fixed::program_draws`), so both kinds of draw make the same scene.

use glam::{DMat3, DMat4, DVec3, DVec4};
use glray_scene::lighting::{Light, Material};

use super::program::Program;
use super::vertex_arrays::AttribArray;
use super::Programs;

/// The names of a program family's inputs.
#[derive(Debug, Clone, Copy)]
pub struct Profile {
    /// Said in messages and statistics.
    pub name: &'static str,
    /// Attributes: object-space positions (required), normals, texture coordinates of the
    /// colour map, per-vertex colours.
    pub position: &'static str,
    pub normal: &'static str,
    pub texcoord: &'static str,
    pub color: &'static str,
    /// Uniforms: object to eye (view) coordinates and object to clip coordinates (both
    /// required), and the normal matrix (when absent, the first's inverse transpose, as GL's).
    /// VTK's is not that: its positions are shifted and scaled per axis into the buffer, its
    /// normals are not, so its normal matrix leaves the scale out.
    pub object_to_eye: &'static str,
    pub object_to_clip: &'static str,
    pub normal_matrix: &'static str,
    /// Light `k`'s colour and direction of travel in eye coordinates: the name with `k` after it.
    pub light_color: &'static str,
    pub light_direction: &'static str,
    /// How many lights the family's programs have at most.
    pub lights: usize,
    /// The material: colours (already weighted by their intensities, or not: `intensities`),
    /// the specular power and the opacity.
    pub ambient_color: &'static str,
    pub diffuse_color: &'static str,
    pub specular_color: &'static str,
    pub specular_power: &'static str,
    pub opacity: &'static str,
    /// Intensities the colours are multiplied by (ambient, diffuse, specular), when separate.
    pub intensities: [&'static str; 3],
    /// The sampler of the colour map looked up by `texcoord` (its value: the texture unit).
    pub color_map: &'static str,
    /// A uniform that, when set to non-zero, makes the solid diffuse colour win over mapped
    /// colours (VTK's OverridesColor).
    pub overrides_color: &'static str,
    /// Uniforms only the passes of a translucent draw have (VTK's depth peeling).
    pub peeling: &'static [&'static str],
}

/// Where a draw's per-vertex inputs are.
#[derive(Debug, Clone, Copy, Default)]
pub struct Inputs {
    pub position: AttribArray,
    pub normal: Option<AttribArray>,
    pub texcoord: Option<AttribArray>,
    pub color: Option<AttribArray>,
}

/// What a draw through a recognised program is, in fixed-function terms.
#[derive(Debug, Clone)]
pub struct ProgramDraw {
    pub inputs: Inputs,
    pub modelview: DMat4,
    pub projection: DMat4,
    /// Object-space normals to eye space, when the program is given its own.
    pub normal_matrix: Option<DMat3>,
    /// Lights in eye coordinates (w = 0: at infinity).
    pub lights: Vec<Light>,
    pub material: Material,
    /// Lit per pixel (the family's lighting is computed per fragment).
    pub per_fragment: bool,
    /// The colour map's texture, when the draw's colours are looked up in it.
    pub color_map: Option<u32>,
    /// A pass of a translucent draw (`Profile::peeling`).
    pub peeling: bool,
}

fn matrix4(v: Option<&[f64]>) -> Option<DMat4> {
    v.filter(|v| v.len() == 16).map(DMat4::from_cols_slice)
}

fn vec3(v: Option<&[f64]>) -> Option<DVec3> {
    v.filter(|v| v.len() >= 3).map(|v| DVec3::new(v[0], v[1], v[2]))
}

fn scalar(v: Option<&[f64]>) -> Option<f64> {
    v.and_then(|v| v.first().copied())
}

impl Profile {
    /// Whether `program` is one of the family's: it reads positions and the two transforms.
    pub fn recognises(&self, program: &Program) -> bool {
        program.attribute(self.position).is_some()
            && program.has_uniform(self.object_to_eye)
            && program.has_uniform(self.object_to_clip)
    }

    /// The draw `programs` would make now, when a program of the family is in use and its
    /// inputs are set; None otherwise (the draw is left to the real GL).
    pub fn draw(&self, programs: &Programs) -> Option<ProgramDraw> {
        let program = programs.current().filter(|p| self.recognises(p))?;
        let arrays = &programs.vertex_arrays;
        let attrib = |name: &str| -> Option<AttribArray> {
            let at = program.attribute(name)?;
            arrays.attrib(at).filter(|a| a.enabled && a.buffer != 0 && a.divisor == 0)
        };
        let inputs = Inputs {
            position: attrib(self.position)?,
            normal: attrib(self.normal),
            texcoord: attrib(self.texcoord),
            color: attrib(self.color),
        };
        let modelview = matrix4(program.uniform(self.object_to_eye))?;
        let object_to_clip = matrix4(program.uniform(self.object_to_clip))?;
        if modelview.determinant().abs() < 1e-300 {
            return None;
        }
        let projection = object_to_clip * modelview.inverse();
        let normal_matrix = program.uniform(self.normal_matrix).filter(|v| v.len() == 9).map(DMat3::from_cols_slice);
        let u = |name: &str| program.uniform(name);
        let lights: Vec<Light> = (0..self.lights)
            .filter_map(|k| {
                let color = vec3(u(&format!("{}{k}", self.light_color)))?;
                let travel = vec3(u(&format!("{}{k}", self.light_direction)))?;
                // GL's directional light is given by where it comes from.
                let from = -travel.normalize_or_zero();
                Some(Light {
                    enabled: true,
                    ambient: DVec4::new(0.0, 0.0, 0.0, 1.0),
                    diffuse: color.extend(1.0),
                    specular: color.extend(1.0),
                    position: from.extend(0.0),
                    ..Light::new(1)
                })
            })
            .collect();
        let intensity = |k: usize| {
            if self.intensities[k].is_empty() {
                Some(1.0)
            } else {
                scalar(u(self.intensities[k]))
            }
        };
        let color = |name: &str, k: usize| -> DVec3 {
            let c = vec3(u(name)).unwrap_or(DVec3::ZERO);
            c * intensity(k).unwrap_or(if k == 1 { 1.0 } else { 0.0 })
        };
        let opacity = scalar(u(self.opacity)).unwrap_or(1.0);
        let overridden = scalar(u(self.overrides_color)).is_some_and(|v| v != 0.0);
        let color_map = (inputs.texcoord.is_some() && !overridden)
            .then(|| scalar(u(self.color_map)))
            .flatten()
            .map(|unit| programs.texture_on(unit as usize))
            .filter(|&t| t != 0);
        // GL's terms for VTK's: ambient + sum(df * light) * diffuse + sum(sf * light) * specular.
        // VTK's ambient is added as it is (GL's emission); a mapped colour multiplies ambient
        // and diffuse (GL_MODULATE) and not specular (GL_SEPARATE_SPECULAR_COLOR); per-vertex
        // colours are the diffuse colour (glColorMaterial), their diffuse intensity moved into
        // the lights.
        let vertex_colors = inputs.color.is_some() && !overridden;
        let white = |k: usize| DVec3::splat(intensity(k).unwrap_or(if k == 1 { 1.0 } else { 0.0 }));
        let (ambient, diffuse) = if color_map.is_some() || vertex_colors {
            (if vertex_colors { DVec3::ZERO } else { white(0) }, white(1))
        } else {
            (color(self.ambient_color, 0), color(self.diffuse_color, 1))
        };
        let mut lights: Vec<Light> = lights;
        if vertex_colors {
            for l in &mut lights {
                l.diffuse = (l.diffuse.truncate() * diffuse).extend(1.0);
            }
        }
        let material = Material {
            ambient: DVec4::new(0.0, 0.0, 0.0, opacity),
            diffuse: diffuse.extend(opacity),
            specular: color(self.specular_color, 2).extend(1.0),
            emission: ambient.extend(1.0),
            shininess: scalar(u(self.specular_power)).unwrap_or(1.0).clamp(0.0, 128.0),
        };
        let inputs = Inputs { color: if overridden { None } else { inputs.color }, ..inputs };
        let peeling = self.peeling.iter().any(|u| program.has_uniform(u));
        Some(ProgramDraw {
            inputs,
            modelview,
            projection,
            normal_matrix,
            lights,
            material,
            per_fragment: true,
            color_map,
            peeling,
        })
    }
}
