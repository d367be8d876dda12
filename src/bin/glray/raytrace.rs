//! `glray replay TRACE --renderer glray`: plays a trace into glray's capture (the same state
//! machine the live library feeds) and writes each frame as glray's ray tracer renders it.
//! With `--readpixels`, what a glReadPixels of the frame so far would return is written too.
//!
//! Only what the frames asked for need is traced. A frame that is not written is traced only
//! when a later written one draws over it (no clear). With progressive refinement, a frame's
//! picture holds the samples of the unchanged frames before it, as the live program's would:
//! the replay counts those frames as it goes and, at a written frame, traces the passes it
//! must have, all at once (`Passes`).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glray_capture::events::Capture;
use glray_core::image::Image;
use glray_core::trace::{Event, Reader};
use glray_render::{Options, Rendered, Renderer};
use glray_scene::frame::Frame;

use crate::progress::ReplayProgress;
use crate::replay::FrameSet;

#[derive(Debug, Default)]
pub struct Summary {
    pub calls: u64,
    pub frames_written: u64,
    /// Frames ray traced: the ones written, and those a later written one drew over.
    pub frames_traced: u64,
    /// Passes traced over those frames (more than frames when samples were gathered).
    pub passes_traced: u64,
    pub readpixels_written: u64,
    pub triangles: u64,
}

/// The part of a top-down image a glReadPixels(x, y, w, h) reads (y counts from the bottom).
fn crop(image: &Image, x: i64, y: i64, w: i64, h: i64) -> Option<Image> {
    let (iw, ih) = (image.width as i64, image.height as i64);
    if w <= 0 || h <= 0 || x < 0 || y < 0 || x + w > iw || y + h > ih {
        return None;
    }
    let mut rgb = Vec::with_capacity((w * h * 3) as usize);
    for row in 0..h {
        let top = ih - 1 - (y + h - 1 - row);
        let start = ((top * iw + x) * 3) as usize;
        rgb.extend_from_slice(&image.rgb[start..start + (w * 3) as usize]);
    }
    Some(Image { width: w as u32, height: h as u32, rgb })
}

pub fn run(
    data: &[u8],
    out: &Path,
    frames: &FrameSet,
    readpixels: bool,
    options: &Options,
    quiet: bool,
) -> Result<Summary, String> {
    std::fs::create_dir_all(out).map_err(|e| format!("--out {}: {e}", out.display()))?;
    // Past the last frame asked for there is nothing to write (glReadPixels images are, at
    // any frame): the replay stops there.
    let stop_after = frames.last().filter(|_| !readpixels);
    let total = count_frames(data)?.min(stop_after.map_or(u64::MAX, |l| l + 1));
    let progress = ReplayProgress::new(total, quiet);
    let mut reader = Reader::new(data).map_err(|e| e.to_string())?;
    let mut capture = Capture::default();
    let mut summary = Summary::default();
    let mut read_pixels: Vec<bool> = Vec::new();
    let mut passes = Passes::new(Renderer::new(*options), &progress);
    let mut pictures = Pictures::default();
    let mut frames_seen = 0u64;
    while let Some(event) = reader.next_event().map_err(|e| e.to_string())? {
        if let Event::Name { number } = event {
            read_pixels.resize(number + 1, false);
            read_pixels[number] = reader.name(number) == b"glReadPixels";
        }
        if let Event::Call { cmd, thread, args, .. } = &event {
            summary.calls += 1;
            let a: Vec<i64> = args.iter().map(|v| v.as_int()).collect();
            // As the OSMesa replay does: reads of RGB or RGBA bytes, cropped to the rectangle.
            if readpixels
                && read_pixels.get(*cmd) == Some(&true)
                && a.len() >= 6
                && matches!(a[4], 0x1907 | 0x1908)
                && a[5] == 0x1401
            {
                let frame = capture.context(*thread).frame().clone();
                let wanted = passes.follow(&frame);
                let under = pictures.under(*thread, &frame, &mut passes);
                let image =
                    passes.trace(&frame, under, wanted, None).and_then(|r| crop(&image_of(&r), a[0], a[1], a[2], a[3]));
                if let Some(image) = image {
                    let path: PathBuf = out.join(format!("readpixels-{:04}.png", summary.readpixels_written));
                    image.write_png(&path)?;
                    summary.readpixels_written += 1;
                }
            }
        }
        let number = if let Event::Frame { number } = event { Some(number) } else { None };
        if let Some((thread, frame)) = capture.event(&event, |n| reader.name(n)) {
            let number = number.unwrap_or_default();
            let wanted = passes.follow(&frame);
            if frames.contains(number) {
                let under = pictures.under(thread, &frame, &mut passes);
                if let Some(rendered) = passes.trace(&frame, under, wanted, Some(number)) {
                    summary.triangles += frame.triangle_count() as u64;
                    image_of(&rendered).write_png(&out.join(format!("frame-{number:04}.png")))?;
                    summary.frames_written += 1;
                    pictures.written(thread, rendered);
                }
            } else {
                // Traced only if a later written frame draws over it.
                pictures.skipped(thread, frame, wanted, &mut passes);
            }
        }
        if let Some(number) = number {
            frames_seen += 1;
            progress.frames(frames_seen, summary.frames_written);
            if stop_after.is_some_and(|last| number >= last) {
                break;
            }
        }
    }
    summary.frames_traced = passes.frames;
    summary.passes_traced = passes.traced;
    drop(passes);
    progress.finish();
    Ok(summary)
}

/// The frame ends in the trace (a damaged one stops with its message here, before any work).
fn count_frames(data: &[u8]) -> Result<u64, String> {
    let mut reader = Reader::new(data).map_err(|e| e.to_string())?;
    let mut frames = 0;
    while let Some(event) = reader.next_event().map_err(|e| e.to_string())? {
        frames += matches!(event, Event::Frame { .. }) as u64;
    }
    Ok(frames)
}

/// A rendered frame as a top-down RGB image.
fn image_of(r: &Rendered) -> Image {
    Image::from_bottom_up(r.width, r.height, &r.rgba, 4)
}

/// The renderer, and the run of frames that show the same scene: with progressive refinement
/// the live program's Nth frame of a run holds N passes (up to convergence), so a replay that
/// skips frames must know how many it would have traced.
struct Passes<'p> {
    renderer: Renderer,
    /// The accumulation key of the last frame followed, and how many in a row had it.
    run: Option<(u64, u32)>,
    /// Frames traced, and passes traced over them.
    frames: u64,
    traced: u64,
    progress: &'p ReplayProgress,
}

impl<'p> Passes<'p> {
    fn new(renderer: Renderer, progress: &'p ReplayProgress) -> Passes<'p> {
        Passes { renderer, run: None, frames: 0, traced: 0, progress }
    }

    /// `frame` comes next, traced or not: the passes its picture holds in the live program.
    /// A frame of another scene (or one drawn over the last, whose picture is never added up)
    /// ends the run, and the renderer forgets what it had added up.
    fn follow(&mut self, frame: &Frame) -> u32 {
        let (w, h) = frame.size();
        let key = self.renderer.accumulation_key(frame, w, h);
        let count = match (key, self.run) {
            (Some(k), Some((run, n))) if k == run => n + 1,
            _ => {
                self.renderer.restart();
                1
            }
        };
        self.run = key.map(|k| (k, count));
        count.min(self.renderer.converged_passes())
    }

    /// Traces `frame` (over `under`, if it does not clear) until its picture holds `wanted`
    /// passes, starting from those the renderer added up already; None for a frame of no size.
    fn trace(&mut self, frame: &Frame, under: Option<&Rendered>, wanted: u32, number: Option<u64>) -> Option<Rendered> {
        let (w, h) = frame.size();
        if w == 0 || h == 0 {
            return None;
        }
        let mut have = self.renderer.accumulation_key(frame, w, h).map_or(0, |k| self.renderer.passes(k));
        if have > wanted {
            // Added up from a later frame of the same scene (frames traced out of order).
            self.renderer.restart();
            have = 0;
        }
        // One render at least: a converged picture is shown again, untraced.
        let todo = wanted.saturating_sub(have).max(1);
        let samples = self.renderer.options.effects.samples.max(1);
        if todo > 1 {
            let what = number.map_or("a glReadPixels image".to_string(), |n| format!("frame {n}"));
            self.progress.say(&format!(
                "{what}: gathering {todo} passes ({} samples per pixel), as the unchanged frames before it did",
                todo * samples
            ));
        }
        let mut rendered = None;
        for pass in 0..todo {
            if todo > 1 {
                let what = number.map_or(String::new(), |n| format!("frame {n}: "));
                self.progress.now(format!("{what}pass {} of {todo}", pass + 1));
            }
            rendered = Some(self.renderer.render(frame, w, h, under));
            self.traced += !self.renderer.stats().reused as u64;
        }
        self.frames += 1;
        rendered
    }
}

/// The most frames drawn over one another, not traced yet, kept per thread: past it, the oldest
/// is traced (a program that never clears would otherwise keep all its frames).
const MOST_PENDING: usize = 4;

/// A frame not traced (yet), with the passes its picture holds.
struct Pending {
    frame: Frame,
    passes: u32,
}

/// Each thread's last picture, and the frames after it not traced yet: a frame that is not
/// written is traced only when a later one draws over it (no clear) and is needed itself.
#[derive(Default)]
struct Pictures {
    rendered: HashMap<u32, Rendered>,
    /// Per thread, oldest first: each draws over the one before (all but the first).
    pending: HashMap<u32, Vec<Pending>>,
}

impl Pictures {
    /// What `frame`, `thread`'s next, is drawn over: nothing if it clears its colour buffer
    /// (what came before is dropped untraced), else the thread's last picture, tracing the
    /// frames left pending first.
    fn under(&mut self, thread: u32, frame: &Frame, passes: &mut Passes) -> Option<&Rendered> {
        if frame.cleared {
            self.pending.remove(&thread);
            self.rendered.remove(&thread);
            return None;
        }
        for p in self.pending.remove(&thread).unwrap_or_default() {
            self.trace(thread, &p, passes);
        }
        self.rendered.get(&thread)
    }

    /// Traces a pending frame over `thread`'s last picture, which it becomes.
    fn trace(&mut self, thread: u32, p: &Pending, passes: &mut Passes) {
        let under = if p.frame.cleared { None } else { self.rendered.get(&thread) };
        match passes.trace(&p.frame, under, p.passes, None) {
            Some(rendered) => self.rendered.insert(thread, rendered),
            None => self.rendered.remove(&thread),
        };
    }

    /// `thread`'s picture traced and written.
    fn written(&mut self, thread: u32, r: Rendered) {
        self.pending.remove(&thread);
        self.rendered.insert(thread, r);
    }

    /// `frame`, holding `wanted` passes, is `thread`'s last, not traced (yet). One that clears
    /// its colour buffer does not depend on what came before, which is dropped untraced.
    fn skipped(&mut self, thread: u32, frame: Frame, wanted: u32, passes: &mut Passes) {
        let chain = self.pending.entry(thread).or_default();
        if frame.cleared {
            chain.clear();
            self.rendered.remove(&thread);
        }
        chain.push(Pending { frame, passes: wanted });
        if chain.len() > MOST_PENDING {
            let oldest = chain.remove(0);
            self.trace(thread, &oldest, passes);
        }
    }
}
