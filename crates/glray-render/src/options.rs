//! How to render: the effects and their presets (`Effects`), lighting per pixel, how BVHs are
//! built (`Options`), from the settings.

/// The effects a frame is rendered with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Effects {
    /// Ambient-occlusion rays per visible point (0: none).
    pub ao_samples: u32,
    /// How far an occluder counts, as a fraction of the scene's diagonal.
    pub ao_distance: f32,
    /// How dark a fully occluded point becomes: its colour times 1 - intensity.
    pub ao_intensity: f32,
    /// Hard shadows from every enabled GL light (lit surfaces are then lit per pixel).
    pub shadows: bool,
    /// Reflection bounces (0: none), and how much of each surface is mirror.
    pub reflections: u32,
    pub reflectivity: f32,
    /// Samples per pixel: the first at the pixel centre (where GL samples), the others jittered
    /// over the pixel (antialiasing).
    pub samples: u32,
    /// While the scene and camera stay the same from frame to frame, each frame adds `samples`
    /// more to the ones before (up to `MAX_PASSES` frames): the picture converges.
    pub progressive: bool,
    /// Denoise ambient occlusion (`denoise`): averaged over frames through motion, filtered
    /// along surfaces.
    pub denoise: bool,
}

/// The frames progressive refinement keeps adding samples for.
pub const MAX_PASSES: u32 = 64;

impl Effects {
    /// The GL look alone: one sample at the pixel centre, what the rasterizer shows.
    pub const GL: Effects = Effects {
        ao_samples: 0,
        ao_distance: 0.1,
        ao_intensity: 1.0,
        shadows: false,
        reflections: 0,
        reflectivity: 0.04,
        samples: 1,
        progressive: true,
        denoise: true,
    };

    /// A preset by name: `gl`; `ao`, the GL look times ambient occlusion; `full`, the advanced
    /// look of the GLuRay paper (36 AO rays, shadows, one reflection, 4 samples per pixel).
    pub fn preset(name: &str) -> Option<Effects> {
        Some(match name {
            "gl" => Effects::GL,
            "ao" => Effects { ao_samples: 16, ..Effects::GL },
            "full" => Effects { ao_samples: 36, shadows: true, reflections: 1, samples: 4, ..Effects::GL },
            _ => return None,
        })
    }

    /// Whether pixels depend on more than the GL look (random samples, secondary rays).
    pub fn beyond_gl(&self) -> bool {
        self.secondary_rays() || self.samples > 1
    }

    /// Whether rays leave the surfaces camera rays hit (shadows, ambient occlusion,
    /// reflections).
    pub fn secondary_rays(&self) -> bool {
        self.ao_samples > 0 || self.shadows || self.reflections > 0
    }
}

impl Default for Effects {
    fn default() -> Self {
        Effects::GL
    }
}

/// How to render.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Options {
    /// Evaluate lighting per pixel instead of interpolating per-vertex colours.
    pub per_pixel_lighting: bool,
    pub effects: Effects,
    /// How BVHs are built (setting `bvh`).
    pub bvh: BvhBuild,
}

impl Options {
    /// The options the settings ask for: the preset's effects, each overridden by its own
    /// setting when that is set. None for preset `off` (nothing is ray traced).
    pub fn from_config(config: &glray_core::config::Config) -> Option<Options> {
        let mut e = Effects::preset(config.preset())?;
        let int = |key: &str, v: &mut u32| {
            if let Some(x) = config.number(key) {
                *v = x as u32;
            }
        };
        let float = |key: &str, v: &mut f32| {
            if let Some(x) = config.number(key) {
                *v = x as f32;
            }
        };
        int("ao_samples", &mut e.ao_samples);
        float("ao_distance", &mut e.ao_distance);
        float("ao_intensity", &mut e.ao_intensity);
        int("reflections", &mut e.reflections);
        float("reflectivity", &mut e.reflectivity);
        int("samples", &mut e.samples);
        if let Some(on) = config.flag("shadows") {
            e.shadows = on;
        }
        e.progressive = config.flag("progressive").unwrap_or(true);
        e.denoise = config.flag("denoise").unwrap_or(true);
        let bvh = BvhBuild::from_setting(config.bvh()).unwrap_or_default();
        Some(Options { per_pixel_lighting: config.per_pixel_lighting(), effects: e, bvh })
    }
}

/// The values of setting `bvh`.
pub const BVH_CHOICES: &[&str] = glray_core::config::BVH_BUILDS;

/// How BVHs are built (setting `bvh`; `bvh_choice` says what each choice does).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum BvhBuild {
    #[default]
    Auto,
    Sah,
    Fast,
}

impl BvhBuild {
    /// The setting's value as a choice (None for a value outside `CHOICES`; the settings
    /// reject those before this is asked).
    pub fn from_setting(value: &str) -> Option<BvhBuild> {
        match value {
            "auto" => Some(BvhBuild::Auto),
            "sah" => Some(BvhBuild::Sah),
            "fast" => Some(BvhBuild::Fast),
            _ => None,
        }
    }
}
