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

use std::ops::Range;

use glam::Vec3;

use temporal::Rows;
pub use temporal::{HeldRows, Motion, Past};

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

/// The rows of a frame one denoising works out (`rows`, its band) and the frame they lie in.
/// A frame traced by one process is one band; a frame shared by MPI ranks is cut into a band
/// per rank, each denoised where it was traced: a band reads the AO of `layer_rows` (the rows
/// around it the filter and the neighbourhood reach) and follows `followed_rows` back into the
/// last frame, so that each of its pixels comes out as in the whole frame, bit for bit.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Band {
    pub rows: Range<usize>,
    pub width: usize,
    pub height: usize,
}

impl Band {
    /// The whole of a `width` x `height` frame.
    pub fn whole(width: usize, height: usize) -> Band {
        Band { rows: 0..height, width, height }
    }

    fn around(&self, reach: usize) -> Range<usize> {
        self.rows.start.saturating_sub(reach)..(self.rows.end + reach).min(self.height)
    }

    /// The rows whose AO the band's denoising reads (`AoPixel`s from the tracer).
    pub fn layer_rows(&self) -> Range<usize> {
        self.around(atrous::FILTER_REACH + atrous::NEAR_REACH)
    }

    /// The rows whose average over frames the band's filter reads: followed back into the last
    /// frame, and kept as this band's history.
    pub fn followed_rows(&self) -> Range<usize> {
        self.around(atrous::FILTER_REACH)
    }

    fn layer_at(&self) -> Rows {
        Rows { first: self.layer_rows().start, height: self.height }
    }
}

impl Denoiser {
    /// The denoised fraction hidden of every pixel of a `width` x `height` frame (NaN where
    /// `layer` has no surface): `denoise_band` of the whole frame.
    pub fn denoise(
        &mut self,
        layer: &[AoPixel],
        width: usize,
        camera: &glray_scene::camera::Camera,
        motion: &Motion,
        rays: u32,
        still: bool,
    ) -> Vec<f32> {
        let band = Band::whole(width, layer.len() / width.max(1));
        self.denoise_band(layer, &band, camera, motion, rays, still)
    }

    /// The denoised fraction hidden of every pixel of `band` (NaN where it has no surface), from
    /// `layer`, the AO of its `layer_rows`. `rays` is the AO rays one pass traced per pixel (all
    /// its samples'), which says how noisy one pass's value is; `camera` and `motion` are the
    /// frame's; `still`: the frame shows what the last one did (the same scene and camera), so
    /// the last frame's averages are all valid and go on up to `MAX_PASSES` (else up to
    /// `MOVING_HISTORY`, held to what this frame shows around each point). The last frame's
    /// rows it follows back into must be held (`missing`, `take_rows`).
    pub fn denoise_band(
        &mut self,
        layer: &[AoPixel],
        band: &Band,
        camera: &glray_scene::camera::Camera,
        motion: &Motion,
        rays: u32,
        still: bool,
    ) -> Vec<f32> {
        let (width, at) = (band.width, band.layer_at());
        let guides = atrous::Guides::new(layer, camera, motion);
        let raw: Vec<f32> = layer.iter().map(|a| if a.is_surface() { a.hidden } else { 0.0 }).collect();
        let raw_near = atrous::neighbourhood(&guides, &raw, width, at);
        let span = if still { crate::options::MAX_PASSES as f32 } else { MOVING_HISTORY };
        let near = (!still).then_some(&raw_near[..]);
        let followed = band.followed_rows();
        let averaged = self.history.follow(layer, near, width, at, followed, camera, motion, span, rays.max(1));
        atrous::filter(&guides, &averaged, &raw_near, width, rays.max(1), at, band.rows.clone())
    }

    /// The rows of the last frame `band`'s denoising (of `layer`, its `layer_rows`) follows
    /// back into and this denoiser does not hold: to be fetched from the ranks whose bands
    /// held them (`take_rows`) before `denoise_band`.
    pub fn missing(&self, layer: &[AoPixel], band: &Band, motion: &Motion) -> Vec<Range<usize>> {
        self.history.missing(layer, band.width, band.layer_at(), band.followed_rows(), motion)
    }

    /// The last frame's rows from `first`, fetched from the rank that held them.
    pub fn take_rows(&mut self, first: usize, past: &[Past]) {
        self.history.take_rows(first, past);
    }

    /// The rows the last denoising kept, for other ranks to fetch (`missing`) while the next
    /// frame is denoised.
    pub fn held(&self) -> HeldRows {
        self.history.held()
    }

    /// Forgets the frames before: the next starts afresh.
    pub fn restart(&mut self) {
        self.history = temporal::History::default();
    }
}

#[cfg(test)]
mod tests;
