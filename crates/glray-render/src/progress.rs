//! Progress of a long render on a terminal: after the first second, the share of pixels done,
//! rewritten in place on standard error, at most a few times a second.

use std::io::Write;
use std::sync::Mutex;
use std::time::{Duration, Instant};

pub(crate) struct Progress {
    on: bool,
    /// The pixels to render.
    pixels: usize,
    start: Instant,
    /// When it was last shown (None: not yet).
    shown: Mutex<Option<Instant>>,
}

impl Progress {
    pub fn new(on: bool, pixels: usize) -> Progress {
        Progress { on, pixels, start: Instant::now(), shown: Mutex::new(None) }
    }

    /// `done` pixels are rendered.
    pub fn done(&self, done: usize) {
        if !self.on || self.start.elapsed() < Duration::from_secs(1) {
            return;
        }
        let Ok(mut shown) = self.shown.try_lock() else { return };
        if shown.is_some_and(|t| t.elapsed() < Duration::from_millis(250)) {
            return;
        }
        *shown = Some(Instant::now());
        // (At most 100: pieces set aside for a missing block (paging) are traced and counted twice.)
        let pct = (100.0 * done as f64 / self.pixels.max(1) as f64).min(100.0);
        let _ = write!(std::io::stderr(), "\rglray: tracing {pct:5.1}% ({:.1} s)", self.start.elapsed().as_secs_f64());
    }

    /// Ends the line, if progress was shown.
    pub fn finish(&self) {
        if self.shown.lock().is_ok_and(|s| s.is_some()) {
            let _ =
                writeln!(std::io::stderr(), "\rglray: tracing 100.0% ({:.1} s)", self.start.elapsed().as_secs_f64());
        }
    }
}
