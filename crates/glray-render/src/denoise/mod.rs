//! Denoising ambient occlusion: one pass's few AO rays per pixel made into a clean picture.
//!
//! The tracer keeps a frame's AO apart from its colours (`AoPixel`: the fraction of the
//! hemisphere hidden at the surface a pixel sees, and where that surface is), so that only
//! the AO is filtered and the GL look under it stays exact. Then, per frame:
//! - `temporal`: each pixel's surface point is followed back into the last frame (through its
//!   instance's motion and the last camera) and the AO found there is averaged with the new
//!   one, unless the point was not seen there (another object, another place, a turned
//!   normal): a moving scene keeps its samples instead of starting over. What is followed is
//!   also held to what the new frame shows around the point (something may have moved near
//!   it), and shortened when it was not;
//! - `atrous`: an edge-aware à-trous wavelet filter, guided by the surfaces' planes, normals
//!   and objects, and by how noisy each pixel's average still is (few samples: wide; many:
//!   hardly at all, so a still scene converges to the unfiltered picture).

mod atrous;
mod temporal;

use glam::Vec3;

pub use temporal::Motion;

/// One pixel's AO as the tracer leaves it for the denoiser (plain bytes: tiles traced on other
/// ranks carry it).
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct AoPixel {
    /// Where the surface the pixel's first sample hit is, in eye coordinates.
    pub eye: Vec3,
    /// Its facet's normal, facing the camera.
    pub normal: Vec3,
    /// Which object: an instance's index in the frame (`TriangleId::instance`), or
    /// `TriangleId::FLAT` for the frame's own triangles (`Motion` knows each instance across
    /// frames).
    pub object: u32,
    /// The fraction of the hemisphere hidden (averaged over the pixel's samples that hit);
    /// NaN where no surface was hit (the pixel's colour is left alone).
    pub hidden: f32,
    /// The share of the pixel's colour that AO darkens (its surfaces' own colour, averaged over
    /// all its samples; not what they reflect, nor the background a sample missed to).
    pub lit: Vec3,
}

impl AoPixel {
    pub const NONE: AoPixel =
        AoPixel { eye: Vec3::ZERO, normal: Vec3::ZERO, object: 0, hidden: f32::NAN, lit: Vec3::ZERO };

    pub fn is_surface(&self) -> bool {
        !self.hidden.is_nan()
    }

    /// `color` with the share AO darkens (`lit`) darkened by `hidden` at `intensity`.
    pub fn darken(&self, color: glam::Vec4, hidden: f32, intensity: f32) -> glam::Vec4 {
        color - (self.lit * (intensity * hidden)).extend(0.0)
    }
}

/// What the denoiser keeps from frame to frame: the last frame's averages, for the next to
/// follow back.
#[derive(Default)]
pub struct Denoiser {
    history: temporal::History,
}

/// The most frames a moving scene's average spans: more, and AO that changes as objects
/// move against each other (gears turning) lags behind them.
pub const MOVING_HISTORY: f32 = 16.0;

impl Denoiser {
    /// The denoised fraction hidden of every pixel of a `width` x `height` frame (NaN where
    /// `layer` has no surface). `rays` is the AO rays one pass traced per pixel (all its
    /// samples'), which says how noisy one pass's value is; `camera` and `motion` are the
    /// frame's; `still`: the frame shows what the last one did (the same scene and camera), so
    /// the last frame's averages are all valid and go on up to `MAX_PASSES` (else up to
    /// `MOVING_HISTORY`, held to what this frame shows around each point).
    pub fn denoise(
        &mut self,
        layer: &[AoPixel],
        width: usize,
        camera: &glray_scene::camera::Camera,
        motion: &Motion,
        rays: u32,
        still: bool,
    ) -> Vec<f32> {
        let guides = atrous::Guides::new(layer, camera, motion);
        let raw: Vec<f32> = layer.iter().map(|a| if a.is_surface() { a.hidden } else { 0.0 }).collect();
        let raw_near = atrous::neighbourhood(&guides, &raw, width);
        let span = if still { crate::options::MAX_PASSES as f32 } else { MOVING_HISTORY };
        let near = (!still).then_some(&raw_near[..]);
        let averaged = self.history.follow(layer, near, width, camera, motion, span, rays.max(1));
        atrous::filter(&guides, &averaged, &raw_near, width, rays.max(1))
    }

    /// Forgets the frames before: the next starts afresh.
    pub fn restart(&mut self) {
        self.history = temporal::History::default();
    }
}

#[cfg(test)]
mod tests;
