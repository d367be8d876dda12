//! `glray replay TRACE --renderer glray`: plays a trace into glray's capture (the same state
//! machine the live library feeds) and writes each frame as glray's ray tracer renders it.
//! With `--readpixels`, what a glReadPixels of the frame so far would return is written too.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glray_capture::events::Capture;
use glray_core::image::Image;
use glray_core::trace::{Event, Reader};
use glray_render::{Options, Rendered, Renderer};
use glray_scene::frame::Frame;

use crate::replay::FrameSet;

#[derive(Debug, Default)]
pub struct Summary {
    pub calls: u64,
    pub frames_written: u64,
    /// Frames ray traced: the ones written, and those a later written one drew over.
    pub frames_traced: u64,
    pub readpixels_written: u64,
    pub triangles: u64,
}

/// The frame rendered (over `previous` if it did not clear), and as a top-down RGB image.
pub fn picture(frame: &Frame, previous: Option<&Rendered>, renderer: &mut Renderer) -> Option<(Rendered, Image)> {
    let (w, h) = frame.size();
    if w == 0 || h == 0 {
        return None;
    }
    let r = renderer.render(frame, w, h, previous);
    let image = Image::from_bottom_up(w, h, &r.rgba, 4);
    Some((r, image))
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

pub fn run(data: &[u8], out: &Path, frames: &FrameSet, readpixels: bool, options: &Options) -> Result<Summary, String> {
    std::fs::create_dir_all(out).map_err(|e| format!("--out {}: {e}", out.display()))?;
    let mut reader = Reader::new(data).map_err(|e| e.to_string())?;
    let mut capture = Capture::default();
    let mut summary = Summary::default();
    let mut read_pixels: Vec<bool> = Vec::new();
    // With progressive refinement of effects, a frame's picture holds the samples of the
    // unchanged frames before it, as the live program's would: every frame is traced then.
    let every = options.effects.progressive && options.effects.beyond_gl();
    let mut last = Pictures { every, ..Pictures::default() };
    let mut renderer = Renderer::new(*options);
    // Offline renders with many samples take long: show how far they are on a terminal.
    renderer.progress = std::io::IsTerminal::is_terminal(&std::io::stderr());
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
                let image = picture(&frame, last.under(*thread, &frame, &mut renderer), &mut renderer)
                    .and_then(|(_, i)| crop(&i, a[0], a[1], a[2], a[3]));
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
            if !frames.contains(number) {
                // Traced only if a later frame draws over it, or a glReadPixels reads it.
                last.pending(thread, frame, &mut renderer);
                continue;
            }
            if let Some((rendered, image)) = picture(&frame, last.under(thread, &frame, &mut renderer), &mut renderer) {
                summary.triangles += frame.triangle_count() as u64;
                image.write_png(&out.join(format!("frame-{number:04}.png")))?;
                summary.frames_written += 1;
                last.traced += 1;
                last.written(thread, rendered);
            }
        }
    }
    summary.frames_traced = last.traced;
    Ok(summary)
}

/// The most frames drawn over one another, not traced yet, kept per thread: past it, the oldest
/// is traced (a program that never clears would otherwise keep all its frames).
const MOST_PENDING: usize = 4;

/// Each thread's last picture, and the frames after it not traced yet: a frame that is not
/// written is traced only when a later one draws over it (no clear) and is needed itself.
#[derive(Default)]
struct Pictures {
    rendered: HashMap<u32, Rendered>,
    /// Per thread, oldest first: each draws over the one before (all but the first).
    pending: HashMap<u32, Vec<Frame>>,
    /// Frames traced so far.
    traced: u64,
    /// Trace every frame, written or not (progressive refinement adds their samples up).
    every: bool,
}

impl Pictures {
    /// What `frame`, `thread`'s next, is drawn over: nothing if it clears its colour buffer
    /// (what came before is dropped untraced), else the thread's last picture.
    fn under(&mut self, thread: u32, frame: &Frame, renderer: &mut Renderer) -> Option<&Rendered> {
        if frame.cleared {
            self.pending.remove(&thread);
            self.rendered.remove(&thread);
            return None;
        }
        self.get(thread, renderer)
    }

    /// `thread`'s last picture, tracing the frames left pending first.
    fn get(&mut self, thread: u32, renderer: &mut Renderer) -> Option<&Rendered> {
        for frame in self.pending.remove(&thread).unwrap_or_default() {
            self.trace(thread, &frame, renderer);
        }
        self.rendered.get(&thread)
    }

    /// Traces `frame` over `thread`'s last picture, which it becomes.
    fn trace(&mut self, thread: u32, frame: &Frame, renderer: &mut Renderer) {
        match picture(frame, self.rendered.get(&thread), renderer) {
            Some((rendered, _)) => {
                self.traced += 1;
                self.rendered.insert(thread, rendered);
            }
            None => {
                self.rendered.remove(&thread);
            }
        }
    }

    /// `thread`'s picture traced and written.
    fn written(&mut self, thread: u32, r: Rendered) {
        self.pending.remove(&thread);
        self.rendered.insert(thread, r);
    }

    /// `frame` is `thread`'s last, not traced (yet). One that clears its colour buffer does
    /// not depend on what came before, which is dropped untraced.
    fn pending(&mut self, thread: u32, frame: Frame, renderer: &mut Renderer) {
        if self.every {
            let _ = self.under(thread, &frame, renderer);
            self.trace(thread, &frame, renderer);
            return;
        }
        let chain = self.pending.entry(thread).or_default();
        if frame.cleared {
            chain.clear();
            self.rendered.remove(&thread);
        }
        chain.push(frame);
        if chain.len() > MOST_PENDING {
            let oldest = chain.remove(0);
            self.trace(thread, &oldest, renderer);
        }
    }
}
