//! 2D texture objects as glTexImage2D/glTexSubImage2D/glTexParameter leave them, and sampling
//! them the way GL does (nearest or linear, mipmapped, REPEAT or CLAMP wraps). Texels are kept
//! as RGBA floats expanded from the client's format (capture decodes them); the base internal
//! format is kept too, because the texture environment treats LUMINANCE, ALPHA and INTENSITY
//! differently.

use glam::{Vec2, Vec4};
use serde::{Deserialize, Serialize};

use crate::gl_enum::gl_enum;

gl_enum! {
    /// A texture's minification or magnification filter (magnification takes the first two).
    pub enum Filter {
        Nearest = GL_NEAREST,
        Linear = GL_LINEAR,
        NearestMipmapNearest = GL_NEAREST_MIPMAP_NEAREST,
        LinearMipmapNearest = GL_LINEAR_MIPMAP_NEAREST,
        NearestMipmapLinear = GL_NEAREST_MIPMAP_LINEAR,
        LinearMipmapLinear = GL_LINEAR_MIPMAP_LINEAR,
    }
}

gl_enum! {
    /// How texture coordinates outside [0, 1] wrap (the clamps sample alike: no border colour).
    pub enum Wrap {
        Repeat = GL_REPEAT,
        MirroredRepeat = GL_MIRRORED_REPEAT,
        Clamp = GL_CLAMP,
        ClampToEdge = GL_CLAMP_TO_EDGE,
        ClampToBorder = GL_CLAMP_TO_BORDER,
    }
}

gl_enum! {
    /// The base internal format GL keeps a texture in (the texture environment treats each
    /// differently).
    pub enum BaseFormat {
        Alpha = GL_ALPHA,
        Luminance = GL_LUMINANCE,
        LuminanceAlpha = GL_LUMINANCE_ALPHA,
        Intensity = GL_INTENSITY,
        Rgb = GL_RGB,
        Rgba = GL_RGBA,
    }
}

/// One mipmap level.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Level {
    pub width: usize,
    pub height: usize,
    #[serde(with = "crate::pod_vec")]
    pub texels: Vec<Vec4>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Texture {
    pub levels: Vec<Level>,
    pub base_format: BaseFormat,
    pub min_filter: Filter,
    pub mag_filter: Filter,
    pub wrap_s: Wrap,
    pub wrap_t: Wrap,
    /// Made by glTexImage1D: one row, sampled by s alone (its level of detail ignores t).
    pub one_d: bool,
    /// How the level of detail is moved and bounded (glTexParameterf's GL_TEXTURE_LOD_BIAS,
    /// GL_TEXTURE_MIN_LOD and GL_TEXTURE_MAX_LOD).
    pub lod: LodRange,
    /// Which state of the texture this is: a number no state of any texture in the process
    /// has had before, renewed at every change (`changed`). The renderer knows a frame's
    /// textures by it (an address would be taken again by a texture made after one is freed,
    /// and a texture no frame holds is changed in place).
    pub version: u64,
}

/// A texture's level-of-detail parameters. GL adds the bias to the level of detail worked out
/// from the pixel's footprint, then clamps the sum to [min, max] (OpenGL 2.1, 3.8.8); the
/// result picks both the levels and whether the texture is magnified or minified. Programs
/// set a small positive bias to soften minified text (xscreensaver's texture fonts: 0.25).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LodRange {
    pub bias: f32,
    pub min: f32,
    pub max: f32,
}

impl Default for LodRange {
    fn default() -> Self {
        LodRange { bias: 0.0, min: -1000.0, max: 1000.0 }
    }
}

impl LodRange {
    /// The level of detail a sample takes, from the one of the pixel's footprint.
    pub fn apply(&self, lod: f32) -> f32 {
        (lod + self.bias).clamp(self.min, self.max.max(self.min))
    }
}

/// A version no texture has had (`Texture::version`).
fn next_version() -> u64 {
    crate::ids::next()
}

impl Texture {
    /// Marks a change: the texture is a new state to the renderer.
    pub fn changed(&mut self) {
        self.version = next_version();
    }
}

impl Default for Texture {
    fn default() -> Self {
        Texture {
            levels: Vec::new(),
            base_format: BaseFormat::Rgba,
            min_filter: Filter::NearestMipmapLinear,
            mag_filter: Filter::Linear,
            wrap_s: Wrap::Repeat,
            wrap_t: Wrap::Repeat,
            one_d: false,
            lod: LodRange::default(),
            version: next_version(),
        }
    }
}

impl Texture {
    /// Whether the texture can be sampled (GL: "complete"): level 0 exists, and when the
    /// minification filter uses mipmaps, every level down to 1x1.
    pub fn complete(&self) -> bool {
        let Some(base) = self.levels.first().filter(|l| l.width > 0 && l.height > 0) else {
            return false;
        };
        if !self.mipmapped() {
            return true;
        }
        let (mut w, mut h) = (base.width, base.height);
        for level in &self.levels {
            if level.width != w || level.height != h {
                return false;
            }
            if w == 1 && h == 1 {
                return true;
            }
            w = (w / 2).max(1);
            h = (h / 2).max(1);
        }
        false
    }

    fn mipmapped(&self) -> bool {
        !matches!(self.min_filter, Filter::Nearest | Filter::Linear)
    }

    fn wrap(mode: Wrap, i: i64, n: usize) -> usize {
        let n = n as i64;
        let i = match mode {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::MirroredRepeat => {
                let m = i.rem_euclid(2 * n);
                if m < n {
                    m
                } else {
                    2 * n - 1 - m
                }
            }
            Wrap::Clamp | Wrap::ClampToEdge | Wrap::ClampToBorder => i.clamp(0, n - 1), // no border colour
        };
        i as usize
    }

    fn texel(&self, l: &Level, x: i64, y: i64) -> Vec4 {
        let x = Self::wrap(self.wrap_s, x, l.width);
        let y = Self::wrap(self.wrap_t, y, l.height);
        l.texels[y * l.width + x]
    }

    fn sample_level(&self, level: usize, uv: Vec2, linear: bool) -> Vec4 {
        let l = &self.levels[level];
        let x = uv.x * l.width as f32;
        let y = uv.y * l.height as f32;
        if !linear {
            return self.texel(l, x.floor() as i64, y.floor() as i64);
        }
        let (x, y) = (x - 0.5, y - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let a = self.texel(l, x0, y0).lerp(self.texel(l, x0 + 1, y0), fx);
        let b = self.texel(l, x0, y0 + 1).lerp(self.texel(l, x0 + 1, y0 + 1), fx);
        a.lerp(b, fy)
    }

    /// Whether `sample` depends on its level of detail: with mipmaps, or with one filter for
    /// magnification and another for minification. Without, the level of detail (worked out
    /// from the triangle's derivatives on the screen at every pixel) can be left out.
    pub fn reads_lod(&self) -> bool {
        self.mipmapped() || (self.mag_filter == Filter::Linear) != (self.min_filter == Filter::Linear)
    }

    /// The filtered texel at `uv` for a level of detail `lod` (log2 of texels per pixel).
    pub fn sample(&self, uv: Vec2, lod: f32) -> Vec4 {
        if !self.complete() {
            return Vec4::ONE;
        }
        let lod = self.lod.apply(lod);
        if lod <= 0.0 || !self.mipmapped() {
            let filter = if lod <= 0.0 { self.mag_filter } else { self.min_filter };
            return self.sample_level(0, uv, filter == Filter::Linear);
        }
        let last = (self.levels.len() - 1) as f32;
        let linear = matches!(self.min_filter, Filter::LinearMipmapNearest | Filter::LinearMipmapLinear);
        match self.min_filter {
            Filter::NearestMipmapNearest | Filter::LinearMipmapNearest => {
                let level = (lod + 0.5).floor().clamp(0.0, last) as usize;
                self.sample_level(level, uv, linear)
            }
            _ => {
                let lod = lod.min(last);
                let l0 = lod.floor() as usize;
                let l1 = (l0 + 1).min(last as usize);
                self.sample_level(l0, uv, linear).lerp(self.sample_level(l1, uv, linear), lod.fract())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampling_wraps_and_filters() {
        let texels = vec![Vec4::ZERO, Vec4::ONE];
        let t = Texture {
            levels: vec![Level { width: 2, height: 1, texels }],
            min_filter: Filter::Nearest,
            mag_filter: Filter::Nearest,
            ..Texture::default()
        };
        assert_eq!(t.sample(Vec2::new(0.25, 0.5), 0.0), Vec4::ZERO);
        assert_eq!(t.sample(Vec2::new(1.75, 0.5), 0.0), Vec4::ONE, "REPEAT");
        let t = Texture { mag_filter: Filter::Linear, ..t };
        assert_eq!(t.sample(Vec2::new(0.5, 0.5), 0.0), Vec4::splat(0.5));
        let incomplete = Texture { min_filter: Filter::LinearMipmapLinear, ..t };
        assert!(!incomplete.complete());
    }

    #[test]
    fn the_level_of_detail_is_read_only_where_it_changes_a_sample() {
        // Two levels: 2x1 (black, white) and 1x1 grey.
        let levels = vec![
            Level { width: 2, height: 1, texels: vec![Vec4::ZERO, Vec4::ONE] },
            Level { width: 1, height: 1, texels: vec![Vec4::splat(0.5)] },
        ];
        let base = Texture { levels, ..Texture::default() };
        let at = Vec2::new(0.4, 0.5);
        let lods = [-3.0, 0.0, 0.5, 1.0, 6.0];
        for (min, mag) in [
            (Filter::Nearest, Filter::Nearest),
            (Filter::Linear, Filter::Linear),
            (Filter::Nearest, Filter::Linear),
            (Filter::Linear, Filter::Nearest),
            (Filter::NearestMipmapNearest, Filter::Nearest),
            (Filter::LinearMipmapLinear, Filter::Linear),
        ] {
            let t = Texture { min_filter: min, mag_filter: mag, ..base.clone() };
            let samples: Vec<Vec4> = lods.iter().map(|&lod| t.sample(at, lod)).collect();
            let varies = samples.iter().any(|s| *s != samples[0]);
            assert_eq!(t.reads_lod(), varies, "min {min:?}, mag {mag:?}: {samples:?}");
        }
    }

    #[test]
    fn the_level_of_detail_is_biased_then_clamped() {
        // Two levels: 1x1 white and 1x1 black (level 1 of a 1x1 texture is not complete, but
        // sampling reads the levels given).
        let levels = vec![
            Level { width: 2, height: 2, texels: vec![Vec4::ONE; 4] },
            Level { width: 1, height: 1, texels: vec![Vec4::ZERO] },
        ];
        let t = Texture { levels, min_filter: Filter::LinearMipmapLinear, ..Texture::default() };
        let at = Vec2::new(0.5, 0.5);
        assert_eq!(t.sample(at, 0.5), Vec4::splat(0.5));
        let biased = Texture { lod: LodRange { bias: 0.25, ..LodRange::default() }, ..t.clone() };
        assert_eq!(biased.sample(at, 0.5), Vec4::splat(0.25), "half way plus a quarter");
        // A bias past zero makes a magnified sample minified: it reads the mipmaps.
        assert_eq!(biased.sample(at, -0.125), Vec4::splat(0.875));
        let clamped = Texture { lod: LodRange { bias: 0.25, min: 0.0, max: 0.5 }, ..t.clone() };
        assert_eq!(clamped.sample(at, 0.5), Vec4::splat(0.5), "at most max");
        let raised = Texture { lod: LodRange { min: 1.0, ..LodRange::default() }, ..t };
        assert_eq!(raised.sample(at, -3.0), Vec4::ZERO, "at least min");
    }
}
