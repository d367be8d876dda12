//! The lighting state of a lit draw (`Lighting`), so that the lighting equation can run again
//! where the tracer needs it (an instance's corners, lighting per pixel): the enabled lights
//! in eye coordinates, the model, both materials and glColorMaterial, with what every vertex
//! would otherwise work out again derived once.

use std::borrow::Cow;

use glam::DVec4;
use serde::{Deserialize, Serialize};

use crate::lighting::{prepare, ColorMaterial, Light, LightModel, Material, PreparedLight};
use crate::sunlit::Sunlit;

/// The lighting state of a draw, so that the lighting equation can also run per pixel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "LightingInputs", into = "LightingInputs")]
pub struct Lighting {
    // Every field is private: `prepared` and `positional` are derived from the others in `new`
    // and would go stale if those changed afterwards.
    /// The enabled lights, in eye coordinates.
    lights: Vec<Light>,
    model: LightModel,
    /// Front and back.
    materials: [Material; 2],
    /// glColorMaterial's face and mode when GL_COLOR_MATERIAL is on.
    color_material: Option<ColorMaterial>,
    /// `lighting::prepare` of the lights and model: what every vertex would otherwise work out
    /// again. Private, so that every `Lighting` is made by `new`, which derives it.
    prepared: Vec<PreparedLight>,
    /// Whether the lighting reads a vertex's position (`reads_position`), derived in `new`.
    positional: bool,
    /// The equation in single precision when every light is at infinity (`sunlit`), derived
    /// in `new`.
    sunlit: Option<Sunlit>,
}

impl Lighting {
    /// A draw's lighting: the enabled `lights` (eye coordinates), the model, the front and back
    /// materials and glColorMaterial's face and mode.
    pub fn new(
        lights: Vec<Light>,
        model: LightModel,
        materials: [Material; 2],
        color_material: Option<ColorMaterial>,
    ) -> Lighting {
        let prepared = prepare(&lights, &model);
        let positional =
            model.local_viewer || model.phong_specular || lights.iter().any(|l| l.enabled && l.position.w != 0.0);
        let sunlit = Sunlit::new(&lights, &model, &materials, color_material);
        Lighting { lights, model, materials, color_material, prepared, positional, sunlit }
    }

    /// Whether `new` would make this lighting of these inputs (`lights`, the enabled ones):
    /// the same inputs make the same derived parts.
    pub fn is_made_of<'a>(
        &self,
        mut lights: impl Iterator<Item = &'a Light>,
        model: &LightModel,
        materials: &[Material; 2],
        color_material: Option<ColorMaterial>,
    ) -> bool {
        self.model == *model
            && self.materials == *materials
            && self.color_material == color_material
            && self.lights.iter().all(|l| lights.next() == Some(l))
            && lights.next().is_none()
    }

    /// The lighting made ready for many vertices in single precision, when every enabled light
    /// is at infinity and not a spotlight and the viewer is at infinity (`sunlit::Sunlit`).
    pub fn sunlit(&self) -> Option<&Sunlit> {
        self.sunlit.as_ref()
    }

    /// Whether a vertex's lit colour depends on where it is: a light at a point (not at
    /// infinity) or a local viewer. Otherwise only its normal and material count.
    pub fn reads_position(&self) -> bool {
        self.positional
    }

    /// The enabled lights, in eye coordinates.
    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// The light model.
    pub fn model(&self) -> &LightModel {
        &self.model
    }

    /// The lights made ready for many vertices (`lighting::prepare`), one entry per light.
    pub fn prepared(&self) -> &[PreparedLight] {
        &self.prepared
    }

    /// The materials with `color` put in by glColorMaterial, as GL does at each vertex.
    pub fn materials(&self, color: DVec4) -> Cow<'_, [Material; 2]> {
        color_materials(&self.materials, self.color_material, color)
    }
}

/// Front and back `materials` with `color` put in by glColorMaterial's face and mode, if on:
/// without glColorMaterial, `materials` themselves, not a copy (this runs for every vertex and
/// every corner of every hit, and the two materials are 336 bytes).
pub fn color_materials(
    materials: &[Material; 2],
    color_material: Option<ColorMaterial>,
    color: DVec4,
) -> Cow<'_, [Material; 2]> {
    let Some(cm) = color_material else { return Cow::Borrowed(materials) };
    let mut mats = *materials;
    let t = cm.mode.target();
    for (m, on) in mats.iter_mut().zip(cm.face.sides()) {
        if on {
            m.ambient = if t.ambient { color } else { m.ambient };
            m.diffuse = if t.diffuse { color } else { m.diffuse };
            m.specular = if t.specular { color } else { m.specular };
            m.emission = if t.emission { color } else { m.emission };
        }
    }
    Cow::Owned(mats)
}

/// What a `Lighting` is made of, as its byte encoding holds it (the derived parts are made
/// again by `Lighting::new` when it is read).
#[derive(Serialize, Deserialize)]
struct LightingInputs {
    lights: Vec<Light>,
    model: LightModel,
    materials: [Material; 2],
    color_material: Option<ColorMaterial>,
}

impl From<LightingInputs> for Lighting {
    fn from(i: LightingInputs) -> Lighting {
        Lighting::new(i.lights, i.model, i.materials, i.color_material)
    }
}

impl From<Lighting> for LightingInputs {
    fn from(l: Lighting) -> LightingInputs {
        LightingInputs { lights: l.lights, model: l.model, materials: l.materials, color_material: l.color_material }
    }
}
