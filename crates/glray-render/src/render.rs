//! Rendering a captured frame: rays through the pixels inside the viewport (the first sample of
//! a pixel at its centre, where the rasterizer samples; more, jittered, with the effects that
//! ask for them), rows in parallel on rayon. Every sample depends only on the frame and on
//! where it is taken, so the image is the same for any number of threads.

use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::Vec4;
use glray_scene::camera::Camera;
use glray_scene::frame::{Frame, TriangleId};

use crate::bvh_choice::ray_work;
use crate::denoise::{AoPixel, Band, Denoiser, HeldRows, Motion, Past};
use crate::gouraud::Gouraud;
use crate::meshes::Meshes;
use crate::options::{Options, MAX_PASSES};
use crate::paged::Pager;
use crate::parking;
use crate::pieces::{self, for_each_block, Piece};
use crate::progress::Progress;
use crate::resolve::closest_hit_suffices;
use crate::scene::{Hit, Scene};
use crate::signature::signature;
use crate::tiles::{Layers, TileWork};
use crate::tracer::{count, Scratch, Tracer};

/// A rendered frame, laid out as GL's framebuffer: rows bottom-up.
#[derive(Debug, Clone, PartialEq)]
pub struct Rendered {
    pub width: u32,
    pub height: u32,
    /// RGBA, 8 bits per channel.
    pub rgba: Vec<u8>,
    /// Window depth per pixel (1.0 where nothing was drawn).
    pub depth: Vec<f32>,
}

fn to_u8(c: Vec4) -> [u8; 4] {
    // Halves round to even, as llvmpipe converts to 8-bit unorm (0.3 clears to 76, not 77).
    // Adding and taking away 2^23 rounds a float in [0, 2^23) to an integer in the current
    // rounding mode (to nearest, ties to even): `round_ties_even` without SSE4.1 is a call
    // into libm per channel. A NaN channel still comes out 0.
    const SHIFT: f32 = (1u32 << 23) as f32;
    let x = c.clamp(Vec4::ZERO, Vec4::ONE) * 255.0;
    ((x + SHIFT) - SHIFT).to_array().map(|x| x as u8)
}

/// Colours rounded to RGBA bytes as the tracer rounds them.
pub fn rgba_of(colors: &[Vec4]) -> Vec<u8> {
    colors.iter().flat_map(|&c| to_u8(c)).collect()
}

fn from_u8(c: &[u8]) -> Vec4 {
    Vec4::from_array(std::array::from_fn(|i| c[i] as f32 / 255.0))
}

/// What rendering a frame took.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Stats {
    /// Building the frame's BVHs (new meshes' included).
    pub build: Duration,
    pub trace: Duration,
    /// Rays traced: camera rays and secondary ones.
    pub rays: u64,
    pub triangles: u64,
    /// Samples per pixel accumulated so far (progressive refinement).
    pub samples: u32,
    /// The picture is the last one's, shown again: nothing changed since, and it had all its
    /// samples (DESIGN rule 5: render only if something changed).
    pub reused: bool,
    /// Meshes' BVHs built for the frame (`Scene::builds`): none where every mesh was drawn
    /// before and kept its tree.
    pub builds: u32,
    /// BVHs built fast (`bvh_choice`) for the frame.
    pub fast_builds: u32,
    /// Meshes whose tree was refitted from the last frame's (a time step of the same mesh)
    /// rather than built.
    pub refits: u32,
    /// Triangles of the frame's own (immediate mode, small draws, and draws carried over from
    /// another camera: `Frame::unified`), whose tree is built every frame: none where everything
    /// is drawn from kept meshes.
    pub loose: u64,
    /// Bytes of freed big arrays kept for the next frame's (`glray_core::reuse`), as the frame
    /// ends: more than none only while the program replaces its meshes.
    pub kept_bytes: u64,
    /// Denoising the frame's AO (`denoise`), and composing its picture.
    pub denoise: Duration,
}

impl Stats {
    /// An `earlier` pass's work added to this one's: the passes of a batch program's frame
    /// reported as one frame (times, rays and trees made add up; the rest is this pass's).
    pub fn and_before(self, earlier: &Stats) -> Stats {
        Stats {
            build: self.build + earlier.build,
            trace: self.trace + earlier.trace,
            rays: self.rays + earlier.rays,
            builds: self.builds + earlier.builds,
            fast_builds: self.fast_builds + earlier.fast_builds,
            refits: self.refits + earlier.refits,
            loose: self.loose + earlier.loose,
            denoise: self.denoise + earlier.denoise,
            ..self
        }
    }
}

/// Samples added up over frames that show the same scene (for the GL look, one pass: the
/// picture, shown again while the scene stays the same).
struct Accumulation {
    key: u64,
    passes: u32,
    /// The passes' colours added up (empty for the GL look, which takes one pass).
    sum: Vec<Vec4>,
    last: Rendered,
}

/// Renders frames, keeping what outlives a frame: the BVHs of display-list meshes, and the
/// samples of a scene that has not changed.
pub struct Renderer {
    pub options: Options,
    /// Show the progress of renders that take long on standard error.
    pub progress: bool,
    /// Frames with at most this many triangles in instances are traced as flat triangles when
    /// only camera rays are traced (default `FLATTEN_INSTANCES`; 0: always through instances).
    pub flatten_below: usize,
    meshes: Meshes,
    accumulation: Option<Accumulation>,
    /// The AO of frames before, for denoising the next (`denoise`).
    denoiser: Denoiser,
    /// Frames rendered, or passed over while another rank showed them (`pass_frame`): a
    /// denoised frame's AO rays are seeded by it, so that each frame's go new ways, and ranks
    /// sharing a frame (each counting every frame) trace with the same seed.
    frames: u32,
    stats: Stats,
    /// Where paged meshes' blocks come from (`set_pager`).
    pager: Option<Arc<dyn Pager>>,
}

/// A pass's AO kept apart (of its band's `layer_rows`), and what the denoiser needs of its
/// frame.
struct Denoised {
    layer: Vec<AoPixel>,
    camera: Camera,
    motion: Motion,
}

/// The picture of `passes` passes' colours added up (`sum`), where `ao` has a pixel's denoised
/// fraction hidden, the share of its colour AO darkens (`AoPixel::lit`) darkened by it (a NaN
/// leaves the colour alone).
fn compose(rgba: &mut [u8], sum: &[Vec4], passes: u32, ao: Option<(&[f32], &[AoPixel])>, intensity: f32) {
    let passes = passes as f32;
    match ao {
        Some((hidden, layer)) => {
            for (((px, s), h), a) in rgba.chunks_mut(4).zip(sum).zip(hidden).zip(layer) {
                let c = *s / passes;
                px.copy_from_slice(&to_u8(if h.is_nan() { c } else { a.darken(c, *h, intensity) }));
            }
        }
        None => {
            for (px, s) in rgba.chunks_mut(4).zip(sum) {
                px.copy_from_slice(&to_u8(*s / passes));
            }
        }
    }
}

impl Default for Renderer {
    fn default() -> Self {
        Renderer::new(Options::default())
    }
}

impl Renderer {
    pub fn new(options: Options) -> Renderer {
        Renderer {
            options,
            progress: false,
            flatten_below: FLATTEN_INSTANCES,
            meshes: Meshes::default(),
            accumulation: None,
            denoiser: Denoiser::default(),
            frames: 0,
            stats: Stats::default(),
            pager: None,
        }
    }

    /// Traces the meshes `pager` has layouts for as paged meshes (`paged`), from now on.
    pub fn set_pager(&mut self, pager: Option<Arc<dyn Pager>>) {
        self.pager = pager;
    }

    /// Renders `frame` into a `width` x `height` image. A frame that did not clear the colour
    /// buffer is drawn over `previous` (the last frame of the same drawable), as GL would.
    pub fn render(&mut self, frame: &Frame, width: u32, height: u32, previous: Option<&Rendered>) -> Rendered {
        // Big arrays freed before the last frame began, and not taken since, go back.
        glray_core::reuse::frame_begins();
        self.meshes.prune();
        let seed = self.next_seed();
        let key = self.accumulation_key(frame, width, height);
        let pass = key.map_or(0, |k| self.passes(k));
        if pass >= self.converged_passes() {
            self.converged(frame.triangle_count() as u64);
            return self.accumulation.as_ref().expect("accumulated").last.clone();
        }
        let mut job = Job {
            frame,
            width,
            height,
            previous,
            options: &self.options,
            pass,
            progress: self.progress,
            flatten_below: self.flatten_below,
            work: None,
            seed,
            pager: self.pager.as_ref(),
        };
        let linear = self.linear(key);
        let (rendered, linear, stats, ao) = job.run(&mut self.meshes, linear);
        // A frame that built its scene took what it could refit; one that did not (no camera)
        // has no use for the trees either.
        self.meshes.forget_gone();
        self.stats = Stats { kept_bytes: glray_core::reuse::kept_bytes() as u64, ..stats };
        self.add_pass(frame, key, rendered, linear, ao)
    }

    /// Whether frames under accumulation key `key` keep their colours before rounding: to add
    /// passes up, or to put denoised AO on them.
    pub fn linear(&self, key: Option<u64>) -> bool {
        (key.is_some() && self.options.effects.beyond_gl()) || self.denoises()
    }

    /// Whether AO is kept apart and denoised (`denoise`, with AO on).
    pub fn denoises(&self) -> bool {
        let e = &self.options.effects;
        e.denoise && e.ao_samples > 0
    }

    /// The next frame's seed for its AO rays (0: not denoised, none).
    fn next_seed(&mut self) -> u32 {
        self.frames = self.frames.wrapping_add(1).max(1);
        if self.denoises() {
            self.frames
        } else {
            0
        }
    }

    /// A frame of `triangles` whose picture has all its samples (`converged_passes`) and is
    /// shown again, untraced (by `render`, or by each MPI rank from its own last picture):
    /// counted as any frame, its statistics those of a frame shown again.
    pub fn shown_again(&mut self, triangles: u64) {
        self.next_seed();
        self.converged(triangles);
    }

    /// The statistics of a converged frame shown again; the trees set aside for refits go (as
    /// after any frame).
    fn converged(&mut self, triangles: u64) {
        self.meshes.forget_gone();
        let passes = self.accumulation.as_ref().map_or(1, |a| a.passes);
        let kept_bytes = glray_core::reuse::kept_bytes() as u64;
        let samples = passes * self.options.effects.samples.max(1);
        self.stats = Stats { samples, reused: true, triangles, kept_bytes, ..Stats::default() };
    }

    /// A frame of `triangles` this renderer takes no part in (another rank traces and shows
    /// it): counted all the same, so that the next frame's AO rays are every rank's (see
    /// `frames`); its statistics are of a frame that built and traced nothing here (they kept the
    /// last traced frame's, and a rank's statistics lines repeated them).
    pub fn pass_frame(&mut self, triangles: u64) {
        self.next_seed();
        let samples = self.options.effects.samples.max(1);
        self.stats =
            Stats { triangles, samples, kept_bytes: glray_core::reuse::kept_bytes() as u64, ..Stats::default() };
    }

    /// Traces this rank's share of `frame` (pass `pass` of its progressive refinement): the
    /// tiles `work` hands out, each handed back as it is done, with its colours before
    /// rounding when kept (`linear(key)`) and its AO apart when denoised. Nothing is added up
    /// here: the rank that gathers the tiles does that (`add_pass`). Only for a frame that
    /// clears and is drawn in one view (`shares`). Every rank sharing the frame calls this (or
    /// `pass_frame`) once per frame.
    pub fn render_tiles(
        &mut self,
        frame: &Frame,
        width: u32,
        height: u32,
        pass: u32,
        linear: bool,
        work: &dyn TileWork,
    ) -> Stats {
        glray_core::reuse::frame_begins();
        self.meshes.prune();
        let seed = self.next_seed();
        let mut job = Job {
            frame,
            width,
            height,
            previous: None,
            options: &self.options,
            pass,
            progress: false,
            flatten_below: self.flatten_below,
            work: Some(work),
            seed,
            pager: self.pager.as_ref(),
        };
        let (_, _, stats, _) = job.run(&mut self.meshes, linear);
        self.meshes.forget_gone();
        let samples = self.options.effects.samples.max(1);
        self.stats = Stats { kept_bytes: glray_core::reuse::kept_bytes() as u64, samples, ..stats };
        self.stats
    }

    /// Whether `frame` can be traced in shares (`render_tiles`): it clears (no picture under
    /// it) and is drawn through one viewport.
    pub fn shares(frame: &Frame) -> bool {
        frame.cleared && frame.by_viewport().is_none()
    }

    /// Adds one pass of `frame` (`rendered`, its colours before rounding when kept, and its AO
    /// apart when denoised) to the passes added up under `key`, and returns the picture of them
    /// all: `render` after tracing a whole frame, the rank that gathers a frame's tiles after
    /// gathering them. The AO is denoised as seen from the frame's camera (`camera_of`, the one
    /// it was traced from).
    pub fn add_pass(
        &mut self,
        frame: &Frame,
        key: Option<u64>,
        rendered: Rendered,
        linear: Option<Vec<Vec4>>,
        ao: Option<Vec<AoPixel>>,
    ) -> Rendered {
        let band = Band::whole(rendered.width as usize, rendered.height as usize);
        self.add_band_pass(frame, key, &band, rendered, linear, ao)
    }

    /// `add_pass` for the rows of `band` alone: an MPI rank's band of a frame the ranks
    /// share, added up and denoised where it was traced. `rendered` and `linear` are the
    /// band's rows, `ao` its `layer_rows`; the rows of the last frame its denoising follows
    /// back into must be held (`history_missing`, `take_history_rows`). Every band of a frame
    /// comes out as that part of the frame added whole (`add_pass`), bit for bit.
    pub fn add_band_pass(
        &mut self,
        frame: &Frame,
        key: Option<u64>,
        band: &Band,
        rendered: Rendered,
        linear: Option<Vec<Vec4>>,
        ao: Option<Vec<AoPixel>>,
    ) -> Rendered {
        let start = Instant::now();
        let denoised =
            ao.zip(camera_of(frame)).map(|(layer, camera)| Denoised { layer, camera, motion: Motion::of(frame) });
        let picture = self.add_pass_with(key, band, rendered, linear, denoised);
        self.stats.denoise = start.elapsed();
        picture
    }

    /// The rows of the last frame that denoising `band` of `frame` (its AO `layer`, the band's
    /// `layer_rows`) follows back into and this renderer does not hold (another rank's band
    /// held them).
    pub fn history_missing(&self, frame: &Frame, band: &Band, layer: &[AoPixel]) -> Vec<std::ops::Range<usize>> {
        self.denoiser.missing(layer, band, &Motion::of(frame))
    }

    /// The last frame's denoising rows from `first`, fetched from the rank that held them.
    pub fn take_history_rows(&mut self, first: usize, past: &[Past]) {
        self.denoiser.take_rows(first, past);
    }

    /// The rows of the last frame's denoising this renderer holds, for other ranks to fetch.
    pub fn held_history(&self) -> HeldRows {
        self.denoiser.held()
    }

    /// `add_band_pass`, with the pass's AO kept apart (`denoised`): the colours (without AO)
    /// are added up as ever, the AO denoised, and the picture is the one times the other.
    fn add_pass_with(
        &mut self,
        key: Option<u64>,
        band: &Band,
        mut rendered: Rendered,
        linear: Option<Vec<Vec4>>,
        denoised: Option<Denoised>,
    ) -> Rendered {
        let samples = self.options.effects.samples.max(1);
        let mut hidden = |passes: u32| {
            let d = denoised.as_ref()?;
            // A still scene (the same as the last frame's: a pass added to its samples) keeps
            // its averages; a moving one's are followed and held to what the frame shows.
            let rays = self.options.effects.ao_samples * samples;
            Some(self.denoiser.denoise_band(&d.layer, band, &d.camera, &d.motion, rays, passes > 1))
        };
        // The band's own rows of the layer (what AO darkens of each pixel).
        let own = (band.rows.start - band.layer_rows().start) * band.width..;
        let layer = denoised.as_ref().map(|d| &d.layer[own.start..own.start + band.rows.len() * band.width]);
        let intensity = self.options.effects.ao_intensity;
        match (key, linear) {
            (Some(key), Some(linear)) => {
                let (passes, sum) = match self.accumulation.take() {
                    Some(a) if a.key == key => {
                        let mut sum = a.sum;
                        for (s, c) in sum.iter_mut().zip(&linear) {
                            *s += *c;
                        }
                        (a.passes + 1, sum)
                    }
                    _ => (1, linear),
                };
                let h = hidden(passes);
                compose(&mut rendered.rgba, &sum, passes, h.as_deref().zip(layer), intensity);
                self.stats.samples = passes * samples;
                self.accumulation = Some(Accumulation { key, passes, sum, last: rendered.clone() });
            }
            (Some(key), None) => {
                // The GL look: shown again as long as nothing changes. The copy goes into the
                // last one's buffers (no fresh pages: this is every frame of a moving camera).
                self.stats.samples = samples;
                let last = match self.accumulation.take() {
                    Some(Accumulation { mut last, .. }) => {
                        // Field by field: a derived `clone_from` would allocate anew.
                        (last.width, last.height) = (rendered.width, rendered.height);
                        last.rgba.clone_from(&rendered.rgba);
                        last.depth.clone_from(&rendered.depth);
                        last
                    }
                    None => rendered.clone(),
                };
                self.accumulation = Some(Accumulation { key, passes: 1, sum: Vec::new(), last });
            }
            (None, Some(linear)) if denoised.is_some() => {
                let h = hidden(1);
                compose(&mut rendered.rgba, &linear, 1, h.as_deref().zip(layer), intensity);
                self.accumulation = None;
                self.stats.samples = samples;
            }
            _ => {
                self.accumulation = None;
                self.stats.samples = samples;
            }
        }
        rendered
    }

    /// The key under which progressive refinement adds up the passes of `frame` rendered at
    /// `width` x `height`, the same for every frame that shows the same scene; None when each
    /// render of it is a picture of its own (progressive is off, or the frame draws over the
    /// last one: only a cleared frame is all its own).
    pub fn accumulation_key(&self, frame: &Frame, width: u32, height: u32) -> Option<u64> {
        (self.options.effects.progressive && frame.cleared).then(|| signature(frame, width, height, &self.options))
    }

    /// The passes added up so far under `key` (0: none; the next render starts afresh).
    pub fn passes(&self, key: u64) -> u32 {
        self.accumulation.as_ref().filter(|a| a.key == key).map_or(0, |a| a.passes)
    }

    /// The passes after which a picture has all its samples and is shown again untraced: one
    /// for the GL look, `MAX_PASSES` with effects.
    pub fn converged_passes(&self) -> u32 {
        if self.options.effects.beyond_gl() {
            MAX_PASSES
        } else {
            1
        }
    }

    /// New options while the program runs (the live control panel): the samples and AO history
    /// so far were traced with the old ones and go.
    pub fn set_options(&mut self, options: Options) {
        self.options = options;
        self.restart();
    }

    /// Forgets the samples added up: the next render starts a picture afresh (a replay that
    /// skipped frames showing another scene since).
    pub fn restart(&mut self) {
        self.accumulation = None;
        self.denoiser.restart();
    }

    /// What the last `render` took.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// The display-list meshes whose BVHs are kept.
    pub fn kept_meshes(&self) -> usize {
        self.meshes.len()
    }

    /// How many trees of gone meshes are held for a refit (none between frames).
    #[cfg(test)]
    fn set_aside(&self) -> usize {
        self.meshes.set_aside()
    }
}

/// Renders one frame with nothing kept for the next (see `Renderer`).
pub fn render(frame: &Frame, width: u32, height: u32, previous: Option<&Rendered>, options: &Options) -> Rendered {
    Renderer::new(*options).render(frame, width, height, previous)
}

/// How many hits ahead of the shading its loads are started (`Job::run`): in passes over a
/// row's hits before shading them, the loads waited on the CPU's fill buffers with nothing
/// else to do; started a few hits ahead, their misses overlap the shading of the hits before
/// them. A 10M GL-look frame: 2% faster than with the passes (6 runs alternated; 8 to 32
/// measured alike, 4 slower).
const AHEAD: usize = 8;

/// A 4x2 block of pixels whose camera rays are traced together (`Tracer::centers`), and what
/// they hit where `traced`.
struct PixelBlock {
    pixels: [(usize, usize); 8],
    /// A bit for each pixel not to shade: one repeated (a block cut by the piece's last columns
    /// or row), or outside the viewport.
    skip: u8,
    traced: bool,
    hits: [Option<Hit>; 8],
}

/// The loads of what shading reads, started `AHEAD` hits ahead of it: hit n's vertex
/// indices when hit n - 2 AHEAD is shaded, its vertices (which need the indices) at n - AHEAD.
/// Only for frames whose triangles and meshes are `PREFETCH_FROM` bytes or more: smaller ones
/// stay in the caches, and the loads were 4% of a 98K frame's instructions for nothing.
struct Ahead<'a> {
    tracer: &'a Tracer<'a>,
    /// The hits' triangles in the order they are shaded.
    ids: Vec<TriangleId>,
    /// Hits shaded so far.
    shaded: usize,
}

/// See `Ahead`.
const PREFETCH_FROM: usize = 16 << 20;

impl<'a> Ahead<'a> {
    /// Starts the loads of the first hits of `ids` (when `on`; else there is nothing to do).
    fn new(tracer: &'a Tracer<'a>, on: bool, ids: impl Iterator<Item = TriangleId>) -> Ahead<'a> {
        let ids: Vec<_> = if on { ids.collect() } else { Vec::new() };
        for (n, &id) in ids.iter().enumerate().take(2 * AHEAD) {
            tracer.prefetch(id, false);
            if n < AHEAD {
                tracer.prefetch(id, true);
            }
        }
        Ahead { tracer, ids, shaded: 0 }
    }

    /// One more hit is about to be shaded.
    #[inline]
    fn step(&mut self) {
        if let Some(&id) = self.ids.get(self.shaded + 2 * AHEAD) {
            self.tracer.prefetch(id, false);
        }
        if let Some(&id) = self.ids.get(self.shaded + AHEAD) {
            self.tracer.prefetch(id, true);
        }
        self.shaded += 1;
    }
}

/// The frame's clears within a scissor box (`Frame::scissored_clears`), in order: each fills its
/// box, cut to the image, with its colour and a depth of 1 where it cleared those.
fn fill_scissored_clears(frame: &Frame, w: usize, rgba: &mut [u8], depth: &mut [f32], mut colors: Option<&mut [Vec4]>) {
    let h = depth.len() / w.max(1);
    for c in &frame.scissored_clears {
        let r = c.rect;
        let (x0, x1) = ((r.x.max(0) as usize).min(w), ((r.x as i64 + r.width as i64).max(0) as usize).min(w));
        let (y0, y1) = ((r.y.max(0) as usize).min(h), ((r.y as i64 + r.height as i64).max(0) as usize).min(h));
        for y in y0..y1 {
            for x in x0..x1 {
                let k = y * w + x;
                if let Some(color) = c.color {
                    rgba[4 * k..4 * k + 4].copy_from_slice(&to_u8(color));
                    if let Some(colors) = colors.as_deref_mut() {
                        colors[k] = color;
                    }
                }
                if let Some(d) = c.depth {
                    depth[k] = d;
                }
            }
        }
    }
}

/// The camera `frame`'s pixels are traced from (None: nothing to trace). A frame drawn with
/// several cameras is traced from its main one's (`Frame::unified`).
fn camera_of(frame: &Frame) -> Option<Camera> {
    if frame.is_empty() {
        return None;
    }
    let (projection, viewport) = match frame.cameras.len() {
        0 | 1 => (frame.projection?, frame.viewport?),
        _ => {
            let main = frame.cameras[frame.main_camera() as usize];
            (main.projection, main.viewport)
        }
    };
    Camera::new(projection, viewport, frame.depth_range)
}

/// Up to this many triangles in instances, a frame of camera rays alone is traced as flat
/// triangles (see `Renderer::flatten_below`).
pub const FLATTEN_INSTANCES: usize = 8192;

/// One frame to render.
struct Job<'a> {
    frame: &'a Frame,
    width: u32,
    height: u32,
    previous: Option<&'a Rendered>,
    options: &'a Options,
    /// Which pass of progressive refinement: the samples taken are the pass's.
    pass: u32,
    progress: bool,
    flatten_below: usize,
    /// Only the tiles handed out here, when tracing a share of the frame (`render_tiles`).
    work: Option<&'a dyn TileWork>,
    /// Which frame of a denoised sequence (0: not denoised): the AO rays' seed.
    seed: u32,
    /// Where paged meshes' blocks come from (`distribute = paged`).
    pager: Option<&'a Arc<dyn Pager>>,
}

/// What `Job::run` gives: the image, its colours before rounding (when asked), what it took,
/// and the AO kept apart for the denoiser (when it was).
type Traced = (Rendered, Option<Vec<Vec4>>, Stats, Option<Vec<AoPixel>>);

impl Job<'_> {
    /// The image, its colours before rounding (when asked), what it took, and its AO kept apart
    /// (see `Traced`).
    fn run(&mut self, meshes: &mut Meshes, linear: bool) -> Traced {
        if let Some(views) = self.frame.by_viewport() {
            return self.run_views(&views, meshes, linear);
        }
        let unified;
        let frame = if self.frame.cameras.len() > 1 {
            unified = self.frame.unified();
            &unified
        } else {
            self.frame
        };
        // For camera rays alone, a few thousand instanced triangles (glxgears' gears) trace
        // faster made flat, in one small BVH built now, than through instances (a kept BVH pays
        // off for big meshes). Not with secondary rays: made flat, culled faces are gone, and
        // they still cast shadows and occlude.
        let flat;
        let instanced = frame.triangle_count() - frame.triangles.len();
        let secondary = self.options.effects.secondary_rays();
        // (A paged mesh's triangles are not here to be made flat.)
        let paged = self.pager.is_some_and(|p| frame.instances.iter().any(|i| p.layout(i.mesh.id).is_some()));
        let frame = if !secondary && !paged && instanced > 0 && instanced <= self.flatten_below {
            flat = Frame { triangles: frame.all_triangles(), instances: Vec::new(), ..frame.clone() };
            &flat
        } else {
            frame
        };
        let (width, height) = (self.width, self.height);
        let (w, h) = (width as usize, height as usize);
        let clear = to_u8(frame.clear_color);
        let (mut rgba, mut depth) = match self.previous {
            Some(p) if !frame.cleared && (p.width, p.height) == (width, height) => {
                let depth = frame.depth_cleared.map_or_else(|| p.depth.clone(), |d| vec![d; w * h]);
                (p.rgba.clone(), depth)
            }
            _ => (clear.repeat(w * h), vec![frame.depth_cleared.unwrap_or(1.0); w * h]),
        };
        // The colours before rounding start as the picture under the frame: the clear colour,
        // or (a view after the first of a frame drawn in several viewports) what is there.
        let mut colors = linear.then(|| match self.previous {
            Some(p) if !frame.cleared && (p.width, p.height) == (width, height) => {
                p.rgba.chunks_exact(4).map(from_u8).collect()
            }
            _ => vec![frame.clear_color; w * h],
        });
        fill_scissored_clears(frame, w, &mut rgba, &mut depth, colors.as_deref_mut());
        let mut stats = Stats { triangles: frame.triangle_count() as u64, ..Stats::default() };
        let Some(camera) = camera_of(frame) else {
            return (Rendered { width, height, rgba, depth }, colors, stats, None);
        };
        let start = Instant::now();
        let pixels = u64::from(width) * u64::from(height);
        let work = ray_work(pixels, &self.options.effects);
        let scene = Scene::build_paged(frame, meshes, self.options.bvh, work, self.pager);
        stats.builds = scene.builds;
        stats.fast_builds = scene.fast_builds;
        stats.loose = frame.triangles.len() as u64;
        stats.refits = scene.refits;
        stats.build = start.elapsed();
        let start = Instant::now();
        let diagonal = scene.diagonal().max(1e-6);
        let simple = closest_hit_suffices(frame);
        // The AO kept apart for the denoiser (with its colours before rounding).
        let split = self.seed != 0 && colors.is_some();
        let mut ao = split.then(|| vec![AoPixel::NONE; w * h]);
        let tracer = Tracer {
            frame,
            camera: &camera,
            scene: &scene,
            options: self.options,
            simple,
            depth_starts_near: frame.depth_starts_near(),
            gouraud: Gouraud::new(frame, &camera, self.options, simple),
            eps: diagonal * 1e-4,
            ao_distance: diagonal * self.options.effects.ao_distance,
            pass: self.pass,
            split_ao: split,
            seed: self.seed,
        };
        let rays = AtomicU64::new(0);
        let prefetch = frame.shading_bytes() >= PREFETCH_FROM;
        let v = camera.viewport;
        let x0 = v.x.max(0) as usize;
        let x1 = ((v.x as i64 + v.width as i64).max(0) as usize).min(w);
        let done = AtomicUsize::new(0);
        let progress = Progress::new(self.progress, w * h);
        let one_sample = self.options.effects.samples <= 1;
        let inside = |y: usize| (y as i64) >= v.y as i64 && (y as i64) < v.y as i64 + v.height as i64;
        // Pieces of the image (`pieces`), each piece's pixels in 4x2 blocks: the camera rays of
        // a block are traced together (eight to a packet where the CPU has AVX, else two packets
        // of four). With secondary rays, pieces are tiled.
        let process = |piece: &mut Piece| {
            let (rows, columns) = (piece.rows(), piece.columns());
            let (y0, last) = (*rows.start(), *rows.end());
            let (left, right) = (columns.start.max(x0), columns.end.min(x1));
            if rows.clone().any(inside) && left < right {
                let mut scratch = Scratch::default();
                // The piece's camera rays first, then the shading, with the cache lines a hit's
                // shading reads (big meshes miss on every hit) loaded ahead of it.
                let mut blocks: Vec<PixelBlock> = Vec::with_capacity((right - left).div_ceil(4) * (last - y0 + 2) / 2);
                for_each_block(left..right, rows.clone(), |x, ya, yb| {
                    if inside(ya) || inside(yb) {
                        let pixels: [(usize, usize); 8] =
                            std::array::from_fn(|k| ((x + k % 4).min(right - 1), if k < 4 { ya } else { yb }));
                        let skip = (0..8).fold(0u8, |skip, k| {
                            let (px, py) = pixels[k];
                            // A block cut by the piece's last columns or row repeats pixels.
                            let repeated = (k % 4 > 0 && px == pixels[k - 1].0) || (k >= 4 && py == pixels[0].1);
                            skip | (u8::from(repeated || !inside(py)) << k)
                        });
                        blocks.push(PixelBlock { pixels, skip, traced: false, hits: [None; 8] });
                    }
                });
                for b in &mut blocks {
                    b.traced = tracer.centers(&b.pixels, &mut b.hits);
                }
                let mut ahead = Ahead::new(
                    &tracer,
                    prefetch,
                    blocks.iter().filter(|b| b.traced).flat_map(|b| b.hits.iter().flatten()).map(|h| h.id),
                );
                for PixelBlock { pixels, skip, traced, hits } in &blocks {
                    for (k, &(px, py)) in pixels.iter().enumerate() {
                        let center = traced.then_some(hits[k]);
                        if let Some(Some(_)) = center {
                            ahead.step();
                        }
                        if skip & (1 << k) != 0 {
                            continue;
                        }
                        if one_sample && matches!(center, Some(None)) {
                            // Known to miss with no other sample to take: the pixel keeps
                            // what it held (most pixels of many frames). Its ray counts.
                            count(&scratch.rays, 1);
                            continue;
                        }
                        let (row, at) = (py - y0, px - columns.start);
                        let rgba = &mut piece.rgba[row][4 * at..4 * at + 4];
                        let depth = &mut piece.depth[row][at];
                        if let Some((color, d)) =
                            tracer.pixel(px, py, from_u8(rgba), *depth as f64, center, &mut scratch)
                        {
                            rgba.copy_from_slice(&to_u8(color));
                            if let Some(c) = piece.colors.as_mut() {
                                c[row][at] = color.clamp(Vec4::ZERO, Vec4::ONE);
                            }
                            if let (Some(ao), Some(a)) = (piece.ao.as_mut(), scratch.take_ao()) {
                                ao[row][at] = a;
                            }
                            if let Some(d) = d {
                                *depth = d as f32;
                            }
                        }
                    }
                }
                rays.fetch_add(scratch.rays.get(), Ordering::Relaxed);
            }
            let pixels = rows.count() * columns.len();
            progress.done(done.fetch_add(pixels, Ordering::Relaxed) + pixels);
        };
        // Called, not inlined into rayon's loop: inlined, the pixel loop compiled ~1% slower,
        // and a piece's work is one frame of a profile.
        let process: &(dyn Fn(&mut Piece) + Sync) = &process;
        match self.work {
            None => {
                let (c, a) = (colors.as_deref_mut(), ao.as_deref_mut());
                let all = pieces::split(&mut rgba, &mut depth, c, a, w, secondary.then_some(pieces::SEGMENT));
                parking::trace(all, process, self.pager)
            }
            Some(work) => {
                // Chunk by chunk as they are handed out: each chunk's pieces on every thread,
                // then its tiles cut out and handed back.
                let grid = work.grid(width, height);
                let mut wanted = vec![false; grid.count() as usize];
                while let Some(chunk) = work.next() {
                    let chunk: Vec<u32> = chunk.into_iter().filter(|&t| t < grid.count()).collect();
                    chunk.iter().for_each(|&t| wanted[t as usize] = true);
                    let (c, a) = (colors.as_deref_mut(), ao.as_deref_mut());
                    let mine: Vec<Piece> = pieces::split(&mut rgba, &mut depth, c, a, w, Some(grid.side()))
                        .into_iter()
                        .filter(|p| wanted[grid.tile_at(p.x0, p.y0) as usize])
                        .collect();
                    parking::trace(mine, process, self.pager);
                    let image = Layers { rgba: &rgba, depth: &depth, colors: colors.as_deref(), ao: ao.as_deref() };
                    for &t in &chunk {
                        wanted[t as usize] = false;
                        work.done(grid.cut(t, image));
                    }
                }
            }
        }
        progress.finish();
        stats.trace = start.elapsed();
        stats.rays = rays.load(Ordering::Relaxed);
        (Rendered { width, height, rgba, depth }, colors, stats, ao)
    }

    /// A frame drawn in several viewports (`Frame::by_viewport`): each view traced in turn, over
    /// the picture the ones before left (their colours before rounding too: each view's start
    /// from the picture under it).
    fn run_views(&self, views: &[Frame], meshes: &mut Meshes, linear: bool) -> Traced {
        let mut last: Option<(Rendered, Option<Vec<Vec4>>)> = None;
        let mut stats = Stats::default();
        for view in views {
            let previous = last.as_ref().map(|(r, _)| r).or(self.previous);
            // Each view's AO stays in its colours: the views' layers are not put together for
            // the denoiser (a frame in several viewports is not denoised).
            let mut job = Job { frame: view, previous, seed: 0, ..*self };
            let (rendered, colors, s, _) = job.run(meshes, linear);
            (stats.build, stats.trace) = (stats.build + s.build, stats.trace + s.trace);
            (stats.rays, stats.triangles) = (stats.rays + s.rays, stats.triangles + s.triangles);
            stats.builds += s.builds;
            stats.fast_builds += s.fast_builds;
            stats.loose += s.loose;
            stats.refits += s.refits;
            last = Some((rendered, colors));
        }
        let (rendered, colors) = last.expect("by_viewport gives two views or more");
        (rendered, colors, stats, None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::options::Effects;
    use crate::tiles::TileGrid;
    use glam::{DMat4, Vec2, Vec3};
    use glray_gl::{GL_COLOR_MATERIAL, GL_DEPTH_TEST, GL_LIGHT0, GL_LIGHTING};
    use glray_scene::camera::Viewport;
    use glray_scene::surface::{Fog, Surface};
    use glray_scene::triangle::Triangle;

    fn surface() -> Surface {
        Surface::depth_tested()
    }

    fn quad(z: f32, color: Vec4, surface: u32, sequence: u32) -> [Triangle; 2] {
        let corners =
            [Vec3::new(-1.0, -1.0, z), Vec3::new(1.0, -1.0, z), Vec3::new(1.0, 1.0, z), Vec3::new(-1.0, 1.0, z)];
        let tri = |a: usize, b: usize, c: usize| Triangle {
            positions: [corners[a], corners[b], corners[c]],
            colors: [color; 3],
            secondary: [Vec3::ZERO; 3],
            texcoords: [Vec2::ZERO; 3],
            surface,
            sequence,
            camera: 0,
            clip_w: [1.0; 3],
            normals: [Vec3::Z; 3],
            base_colors: [color; 3],
            lighting: glray_scene::triangle::NO_LIGHTING,
            back: false,
        };
        [tri(0, 1, 2), tri(0, 2, 3)]
    }

    /// An orthographic frame (eye z from -1 near to -10 far) of 8x8 pixels.
    fn frame(triangles: Vec<Triangle>, surfaces: Vec<Surface>) -> Frame {
        // glOrtho(-1, 1, -1, 1, 1, 10).
        let mut m = glray_capture::fixed::matrices::Matrices::default();
        m.matrix_mode(0x1701).unwrap();
        m.ortho(-1.0, 1.0, -1.0, 1.0, 1.0, 10.0).unwrap();
        let projection: DMat4 = *m.top();
        let viewport = Viewport { x: 0, y: 0, width: 8, height: 8 };
        Frame {
            triangles,
            surfaces,
            projection: Some(projection),
            viewport: Some(viewport),
            cameras: vec![glray_scene::frame::View { projection, viewport }],
            depth_range: (0.0, 1.0),
            clear_color: Vec4::new(0.0, 0.0, 1.0, 1.0),
            cleared: true,
            width: 8,
            height: 8,
            ..Frame::default()
        }
    }

    fn pixel(r: &Rendered, x: usize, y: usize) -> [u8; 4] {
        let i = 4 * (y * r.width as usize + x);
        r.rgba[i..i + 4].try_into().unwrap()
    }

    #[test]
    fn the_nearest_surface_wins_and_depth_is_written() {
        let red = quad(-5.0, Vec4::new(1.0, 0.0, 0.0, 1.0), 0, 0);
        let green = quad(-3.0, Vec4::new(0.0, 1.0, 0.0, 1.0), 0, 1);
        let f = frame([red, green].concat(), vec![surface()]);
        let r = render(&f, 8, 8, None, &Options::default());
        assert_eq!(pixel(&r, 4, 4), [0, 255, 0, 255]);
        // Window depth of eye z = -3 between near 1 and far 10 (orthographic: linear).
        assert!((r.depth[4 * 8 + 4] - 2.0 / 9.0).abs() < 1e-5, "{}", r.depth[36]);
        let empty = render(&frame(vec![], vec![surface()]), 8, 8, None, &Options::default());
        assert_eq!(pixel(&empty, 0, 0), [0, 0, 255, 255], "the clear colour");
    }

    /// A red quad over a `width` x `height` window whose viewport starts at column 1, rendered
    /// with `options`: every pixel of the viewport is red, column 0 keeps the clear colour.
    fn fills_a_viewport_from_column_one(width: u32, height: u32, options: &Options) {
        let red = quad(-5.0, Vec4::new(1.0, 0.0, 0.0, 1.0), 0, 0);
        let mut f = frame(red.to_vec(), vec![surface()]);
        let viewport = Viewport { x: 1, y: 0, width: width as i32 - 1, height: height as i32 };
        (f.width, f.height, f.viewport) = (width, height, Some(viewport));
        f.cameras[0].viewport = viewport;
        let r = render(&f, width, height, None, options);
        for y in 0..height as usize {
            assert_eq!(pixel(&r, 0, y), [0, 0, 255, 255], "the clear colour outside the viewport, row {y}");
            for x in 1..width as usize {
                assert_eq!(pixel(&r, x, y), [255, 0, 0, 255], "pixel ({x}, {y})");
            }
        }
    }

    #[test]
    fn every_pixel_of_a_window_cut_across_the_camera_ray_blocks_is_traced() {
        // Camera rays go in 4x2 blocks: a 7x5 window with a viewport from column 1 cuts
        // blocks at its left edge, its right edge and its last row.
        fills_a_viewport_from_column_one(7, 5, &Options::default());
    }

    #[test]
    fn with_secondary_rays_every_pixel_of_a_window_cut_across_the_tiles_is_traced() {
        // With ambient occlusion, pixels go in pieces of eight rows by 64 columns, tiles of
        // eight: a 70x13 window with a viewport from column 1 cuts tiles at both edges and a
        // block at the first piece's edge (column 64), and leaves a last band of five rows, the
        // last of them without a pair. Nothing occludes the quad.
        let options = Options { effects: Effects { ao_samples: 4, ..Effects::GL }, ..Options::default() };
        fills_a_viewport_from_column_one(70, 13, &options);
    }

    #[test]
    fn blending_and_disabled_depth_test_follow_drawing_order() {
        // A half-transparent white quad drawn last, behind the red one, with depth test off.
        let mut over = surface();
        over.depth_test = false;
        over.blend =
            Some((glray_scene::surface::BlendFactor::SrcAlpha, glray_scene::surface::BlendFactor::OneMinusSrcAlpha));
        let red = quad(-3.0, Vec4::new(1.0, 0.0, 0.0, 1.0), 0, 0);
        let white = quad(-5.0, Vec4::new(1.0, 1.0, 1.0, 0.5), 1, 1);
        let r = render(&frame([red, white].concat(), vec![surface(), over]), 8, 8, None, &Options::default());
        // Alpha blends too: 0.5 * 0.5 + 1 * 0.5.
        assert_eq!(pixel(&r, 4, 4), [255, 128, 128, 191]);
    }

    #[test]
    fn user_clip_planes_cut_surfaces_away() {
        // The green quad in front is clipped where x < 0 (plane (1, 0, 0, 0)): red shows there.
        let mut clipped = surface();
        clipped.clip_planes = vec![glam::DVec4::new(1.0, 0.0, 0.0, 0.0)];
        let red = quad(-5.0, Vec4::new(1.0, 0.0, 0.0, 1.0), 0, 0);
        let green = quad(-3.0, Vec4::new(0.0, 1.0, 0.0, 1.0), 1, 1);
        let r = render(&frame([red, green].concat(), vec![surface(), clipped]), 8, 8, None, &Options::default());
        assert_eq!(pixel(&r, 1, 4), [255, 0, 0, 255]);
        assert_eq!(pixel(&r, 6, 4), [0, 255, 0, 255]);
    }

    #[test]
    fn fog_mixes_by_eye_distance() {
        let mut fogged = surface();
        fogged.fog = Some(Fog {
            mode: glray_scene::surface::FogMode::Linear,
            density: 1.0,
            start: 2.0,
            end: 6.0,
            color: Vec4::ONE,
        });
        let black = quad(-4.0, Vec4::new(0.0, 0.0, 0.0, 1.0), 0, 0);
        let r = render(&frame(black.to_vec(), vec![fogged]), 8, 8, None, &Options::default());
        // Linear fog at distance 4 between 2 and 6: half fog colour.
        assert_eq!(pixel(&r, 4, 4)[..3], [128, 128, 128]);
    }

    #[test]
    fn lighting_per_pixel_catches_a_highlight_between_vertices() {
        use glray_scene::draw_lighting::Lighting;
        use glray_scene::lighting::{Light, LightModel, Material};
        // A big quad and a close positional light over its centre: at the corners the light
        // grazes, so per-vertex lighting leaves the centre dark; per pixel it is bright.
        let light = Light { enabled: true, position: glam::DVec4::new(0.0, 0.0, -4.0, 1.0), ..Light::new(0) };
        let lighting = Lighting::new(
            vec![light],
            LightModel { ambient: glam::DVec4::ZERO, ..LightModel::default() },
            [Material::default(); 2],
            None,
        );
        let mut q = quad(-5.0, Vec4::new(0.0, 0.0, 0.0, 1.0), 0, 0);
        for t in &mut q {
            t.lighting = 0;
            for p in &mut t.positions {
                p.x *= 100.0;
                p.y *= 100.0;
            }
        }
        let mut f = frame(q.to_vec(), vec![surface()]);
        f.lightings = vec![lighting];
        // The camera sees only the middle of the quad.
        let vertex = render(&f, 8, 8, None, &Options::default());
        let pixel = render(&f, 8, 8, None, &Options { per_pixel_lighting: true, ..Options::default() });
        assert_eq!(pixel_of(&vertex, 4, 4)[..3], [0, 0, 0], "the interpolated corner colours");
        assert!(pixel_of(&pixel, 4, 4)[0] > 180, "{:?}", pixel_of(&pixel, 4, 4));
    }

    fn pixel_of(r: &Rendered, x: usize, y: usize) -> [u8; 4] {
        pixel(r, x, y)
    }

    #[test]
    fn images_do_not_depend_on_the_thread_count() {
        let mut tris = Vec::new();
        for k in 0..50 {
            let z = -2.0 - k as f32 * 0.1;
            let mut q = quad(z, Vec4::new(k as f32 / 50.0, 0.5, 0.2, 1.0), 0, k);
            for t in &mut q {
                for p in &mut t.positions {
                    *p *= 0.2 + 0.015 * k as f32;
                    p.z = z;
                }
            }
            tris.extend(q);
        }
        let f = frame(tris, vec![surface()]);
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| render(&f, 8, 8, None, &Options::default()))
        };
        let one = run(1);
        assert_eq!(one, run(2));
        assert_eq!(one, run(8));
    }

    /// Hands out a frame's tiles in chunks of `chunk` from the last, and keeps what comes back.
    struct Chunks {
        grid: TileGrid,
        left: std::sync::Mutex<Vec<u32>>,
        chunk: usize,
        back: std::sync::Mutex<Vec<crate::tiles::TilePixels>>,
    }

    impl crate::tiles::TileWork for Chunks {
        fn grid(&self, _: u32, _: u32) -> TileGrid {
            self.grid
        }
        fn next(&self) -> Option<Vec<u32>> {
            let mut left = self.left.lock().unwrap();
            let at = left.len().saturating_sub(self.chunk);
            (at < left.len()).then(|| left.split_off(at))
        }
        fn done(&self, pixels: crate::tiles::TilePixels) {
            self.back.lock().unwrap().push(pixels);
        }
    }

    #[test]
    fn a_frame_traced_in_handed_out_tiles_is_the_frame_traced_whole() {
        use glray_core::trace::Value::Int;
        let mut calls = box_list();
        calls.push(("glClear", vec![Int(0x4100)]));
        for k in 0..5 {
            calls.extend(box_calls(-3.0 + 1.5 * k as f64, [0.9, 0.2 + 0.15 * k as f64, 0.3]));
        }
        let c = followed_at(150, 100, &calls);
        let frame = c.frame().clone();
        assert!(!frame.is_empty() && Renderer::shares(&frame));
        // Tiles of 64, 32 and 16 pixels (0, 1 and 2 ranks to share 150x100 by 16 tiles each).
        for (preset, ranks) in [("gl", 0), ("ao", 0), ("full", 0), ("ao", 1), ("full", 2)] {
            // Twice: the second pass adds up to the first (and the AO's history is followed).
            let options = Options { effects: Effects::preset(preset).unwrap(), ..Options::default() };
            let (mut whole, mut shared) = (Renderer::new(options), Renderer::new(options));
            for pass in 0..2 {
                let key = whole.accumulation_key(&frame, 150, 100);
                if key.is_some_and(|k| whole.passes(k) >= whole.converged_passes()) {
                    // Converged (the GL look after one pass): shown again, not traced.
                    break;
                }
                let expected = whole.render(&frame, 150, 100, None);
                let grid = TileGrid::for_ranks(150, 100, ranks);
                assert_eq!(grid.side(), [64, 32, 16][ranks]);
                let left = std::sync::Mutex::new((0..grid.count()).collect());
                let work = Chunks { grid, left, chunk: 2, back: Default::default() };
                let linear = shared.linear(key);
                let ao = shared.denoises();
                assert_eq!(ao, preset != "gl");
                shared.render_tiles(&frame, 150, 100, pass, linear, &work);
                let n = 150 * 100;
                let (mut rgba, mut depth) = (vec![0u8; 4 * n], vec![0f32; n]);
                let (mut colors, mut layer) = (vec![Vec4::ZERO; n], vec![AoPixel::NONE; n]);
                let back = work.back.into_inner().unwrap();
                assert_eq!(back.len(), grid.count() as usize);
                for t in &back {
                    let into = crate::tiles::LayersMut {
                        rgba: &mut rgba,
                        depth: &mut depth,
                        colors: linear.then_some(&mut colors[..]),
                        ao: ao.then_some(&mut layer[..]),
                    };
                    assert!(grid.paste(t, into));
                }
                let gathered = Rendered { width: 150, height: 100, rgba, depth };
                let gathered = shared.add_pass(&frame, key, gathered, linear.then_some(colors), ao.then_some(layer));
                assert!(
                    gathered == expected,
                    "{preset}, pass {pass}, tiles of {}: the tiles gathered are the whole frame's picture",
                    grid.side()
                );
            }
        }
    }

    /// Follows calls (scalar arguments: integers, or floats as F64) in a fresh context with
    /// a perspective camera; returns the context.
    fn followed(calls: &[(&str, Vec<glray_core::trace::Value<'static>>)]) -> glray_capture::fixed::Context {
        followed_at(48, 48, calls)
    }

    fn followed_at(
        width: u32,
        height: u32,
        calls: &[(&str, Vec<glray_core::trace::Value<'static>>)],
    ) -> glray_capture::fixed::Context {
        use glray_core::trace::Value;
        let mut c = glray_capture::fixed::Context::default();
        c.set_drawable(width, height);
        let setup: Vec<(&str, Vec<Value>)> = vec![
            ("glMatrixMode", vec![Value::Int(0x1701)]),
            ("glFrustum", [-0.5, 0.5, -0.5, 0.5, 1.0, 20.0].map(Value::F64).to_vec()),
            ("glMatrixMode", vec![Value::Int(0x1700)]),
            ("glEnable", vec![Value::Int(GL_LIGHTING as i64)]), // GL_LIGHTING
            ("glEnable", vec![Value::Int(GL_LIGHT0 as i64)]),   // GL_LIGHT0
            ("glEnable", vec![Value::Int(GL_COLOR_MATERIAL as i64)]), // GL_COLOR_MATERIAL
            ("glEnable", vec![Value::Int(GL_DEPTH_TEST as i64)]), // GL_DEPTH_TEST
        ];
        for (name, args) in setup.iter().chain(calls) {
            let (op, ty) = glray_capture::ops::op_for(name).unwrap();
            c.call(op, ty, args);
        }
        c
    }

    /// A box of quads at (x, 0, -6), in a colour, with normals: four sides and a top.
    fn box_calls(x: f64, color: [f64; 3]) -> Vec<(&'static str, Vec<glray_core::trace::Value<'static>>)> {
        use glray_core::trace::Value::{Int, F64};
        vec![
            ("glPushMatrix", vec![]),
            ("glTranslatef", vec![F64(x), F64(0.0), F64(-6.0)]),
            ("glRotatef", vec![F64(30.0), F64(1.0), F64(1.0), F64(0.0)]),
            ("glColor3f", color.map(F64).to_vec()),
            ("glCallList", vec![Int(1)]),
            ("glPopMatrix", vec![]),
        ]
    }

    fn box_list() -> Vec<(&'static str, Vec<glray_core::trace::Value<'static>>)> {
        use glray_core::trace::Value::{Int, F64};
        let faces: [([f64; 3], [[f64; 3]; 4]); 3] = [
            ([0.0, 0.0, 1.0], [[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [1.0, 1.0, 1.0], [-1.0, 1.0, 1.0]]),
            ([1.0, 0.0, 0.0], [[1.0, -1.0, 1.0], [1.0, -1.0, -1.0], [1.0, 1.0, -1.0], [1.0, 1.0, 1.0]]),
            ([0.0, 1.0, 0.0], [[-1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, 1.0, -1.0], [-1.0, 1.0, -1.0]]),
        ];
        // Each face as two triangles, not a quad: a list's quads and the same quads drawn in
        // place are cut along different diagonals (as Mesa cuts them), which shows under a
        // local light; the tests here compare the two ways of shading the same triangles.
        let mut v = vec![("glNewList", vec![Int(1), Int(0x1300)]), ("glBegin", vec![Int(4)])];
        for (n, corners) in faces {
            v.push(("glNormal3f", n.map(F64).to_vec()));
            for k in [0, 1, 2, 0, 2, 3] {
                v.push(("glVertex3f", corners[k].map(F64).to_vec()));
            }
        }
        v.push(("glEnd", vec![]));
        v.push(("glEndList", vec![]));
        v
    }

    #[test]
    fn hits_shaded_from_corner_colours_look_as_the_same_boxes_drawn_immediately() {
        use glray_core::trace::Value::{self, Blob, Int, F64};
        type Calls = Vec<(&'static str, Vec<Value<'static>>)>;
        let floats = |v: [f32; 4]| Blob(Box::leak(v.iter().flat_map(|x| x.to_ne_bytes()).collect::<Box<[u8]>>()));
        let light_model = |what: i64, value: i64| ("glLightModeli", vec![Int(what), Int(value)]);
        let two_sided = light_model(0x0B52, 1);
        let local_light = ("glLightfv", vec![Int(0x4000), Int(0x1203), floats([1.0, 2.0, -3.0, 1.0])]);
        // Each state, and the state before it in the list whose picture it must change.
        let states: [(&str, Calls, usize); 7] = [
            ("a light at infinity", vec![], 0),
            // GL_CW: every face seen is a back face, lit from behind.
            ("two-sided lighting of back faces", vec![two_sided.clone(), ("glFrontFace", vec![Int(0x0900)])], 0),
            (
                "a local light and viewer, separate specular",
                vec![
                    local_light.clone(),
                    light_model(0x0B51, 1),
                    light_model(0x81F8, 0x81FA),
                    ("glMaterialfv", vec![Int(0x0408), Int(0x1202), floats([0.8, 0.7, 0.6, 1.0])]),
                    ("glMaterialf", vec![Int(0x0408), Int(0x1601), F64(20.0)]),
                ],
                0,
            ),
            ("a local light", vec![local_light.clone()], 0),
            // The corners of a face differ under a local light; flat shading takes one.
            ("flat shading under a local light", vec![local_light, ("glShadeModel", vec![Int(0x1D00)])], 3),
            ("no lighting", vec![("glDisable", vec![Int(0x0B50)])], 0),
            (
                "a projection that mirrors, two-sided",
                vec![
                    ("glMatrixMode", vec![Int(0x1701)]),
                    ("glScalef", vec![F64(-1.0), F64(1.0), F64(1.0)]),
                    ("glMatrixMode", vec![Int(0x1700)]),
                    two_sided,
                ],
                0,
            ),
        ];
        // The boxes drawn from the list (instances, shaded from their corners' colours), and
        // with the list's calls made in place (eye-space triangles lit by capture, shaded whole).
        let draws = |state: &Calls, listed: bool| {
            let mut calls = state.clone();
            calls.extend(box_list());
            for (x, color) in [(-1.2, [1.0, 0.5, 0.0]), (1.2, [0.0, 0.5, 1.0])] {
                for call in box_calls(x, color) {
                    if call.0 == "glCallList" && !listed {
                        calls.extend(box_list().into_iter().filter(|c| !c.0.ends_with("List")));
                    } else {
                        calls.push(call);
                    }
                }
            }
            followed(&calls).take_frame()
        };
        let mut pictures = Vec::new();
        for (what, state, _) in &states {
            let listed = draws(state, true);
            let inline = draws(state, false);
            assert_eq!((listed.instances.len(), inline.instances.len()), (2, 0), "{what}");
            let camera = Camera::new(listed.projection.unwrap(), listed.viewport.unwrap(), listed.depth_range).unwrap();
            let short = Gouraud::new(&listed, &camera, &Options::default(), true).expect("the GL look");
            assert!((0..2).all(|i| short.takes(glray_scene::frame::TriangleId { instance: i, index: 0 })), "{what}");
            let traced = Renderer { flatten_below: 0, ..Renderer::default() }.render(&listed, 48, 48, None);
            let reference = render(&inline, 48, 48, None, &Options::default());
            let differ = traced.rgba.iter().zip(&reference.rgba).filter(|(a, b)| a.abs_diff(**b) > 1).count();
            assert_eq!(differ, 0, "{what}: the short way and the full way differ");
            let lit = traced.rgba.chunks(4).filter(|p| p[..3] != [0, 0, 0]).count();
            assert!(lit > 300, "{what}: both boxes are seen: {lit} pixels");
            pictures.push(traced.rgba);
        }
        // The states do change the picture (back faces lit from behind, the light's place).
        for (k, (what, _, before)) in states.iter().enumerate().skip(1) {
            assert!(pictures[k] != pictures[*before], "{what}: the same picture as {}", states[*before].0);
        }
    }

    #[test]
    fn list_instances_render_as_their_triangles_would_and_keep_their_bvh() {
        let mut calls = box_list();
        calls.extend(box_calls(-1.2, [1.0, 0.5, 0.0]));
        calls.extend(box_calls(1.2, [0.0, 0.5, 1.0]));
        let mut c = followed(&calls);
        let frame = c.take_frame();
        assert_eq!((frame.instances.len(), frame.triangles.len()), (2, 0));
        // Through instances (small frames are otherwise made flat).
        let mut renderer = Renderer { flatten_below: 0, ..Renderer::default() };
        assert_eq!(Renderer::default().flatten_below, FLATTEN_INSTANCES);
        let traced = renderer.render(&frame, 48, 48, None);
        assert_eq!(renderer.kept_meshes(), 1, "one mesh, two instances");
        // The same triangles, made flat: the picture must not change.
        let flat = Frame { triangles: frame.all_triangles(), instances: Vec::new(), ..frame.clone() };
        let reference = render(&flat, 48, 48, None, &Options::default());
        let differ = traced.rgba.iter().zip(&reference.rgba).filter(|(a, b)| a.abs_diff(**b) > 1).count();
        assert_eq!(differ, 0, "instances and flat triangles differ");
        let lit = traced.rgba.chunks(4).filter(|p| p[..3] != [0, 0, 0]).count();
        assert!(lit > 300, "both boxes are seen: {lit} pixels");
        // Deleting the list frees its mesh, and the tracer its BVH, at the next frame.
        let delete = [("glDeleteLists", vec![glray_core::trace::Value::Int(1), glray_core::trace::Value::Int(1)])];
        for (name, args) in &delete {
            let (op, ty) = glray_capture::ops::op_for(name).unwrap();
            c.call(op, ty, args);
        }
        drop((frame, flat));
        // A frame with nothing to trace (no camera) keeps no tree for a refit either.
        renderer.render(&Frame::default(), 48, 48, None);
        assert_eq!((renderer.kept_meshes(), renderer.set_aside()), (0, 0));
        renderer.render(&c.take_frame(), 48, 48, None);
        assert_eq!(renderer.kept_meshes(), 0);
    }
}
