//! How far a ray-traced replay is, on standard error: on a terminal, one bar for the whole
//! replay (the trace's frames gone through, frames written, the time left); otherwise (a batch
//! job's log) a plain line every `PLAIN_EVERY`, so that a long replay is never silent.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use glray_core::log::plural;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// How often a plain line is written when standard error is not a terminal.
const PLAIN_EVERY: Duration = Duration::from_secs(10);

/// What the plain lines report, updated by the replay and read by their thread.
#[derive(Default)]
struct Counts {
    /// Frames of the trace gone through.
    done: AtomicU64,
    written: AtomicU64,
    /// What is being done now ("frame 12: pass 3 of 64").
    now: Mutex<String>,
}

pub struct ReplayProgress {
    bar: Option<ProgressBar>,
    counts: Arc<Counts>,
    /// Stops the plain lines' thread (dropped or sent to: it ends).
    stop: Option<Sender<()>>,
    plain: Option<std::thread::JoinHandle<()>>,
}

impl ReplayProgress {
    /// Progress over `total` frames (the trace's, up to the last one asked for), shown on a
    /// terminal as a bar, else as plain lines; `quiet`: nothing at all.
    pub fn new(total: u64, quiet: bool) -> ReplayProgress {
        let counts = Arc::new(Counts::default());
        let mut p = ReplayProgress { bar: None, counts: counts.clone(), stop: None, plain: None };
        if quiet {
            return p;
        }
        if std::io::IsTerminal::is_terminal(&std::io::stderr()) {
            let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
            let style = ProgressStyle::with_template(
                "glray: {bar:30} frame {pos}/{len} · {elapsed} · about {eta} left · {msg}",
            )
            .expect("a valid template");
            bar.set_style(style);
            bar.enable_steady_tick(Duration::from_millis(250));
            p.bar = Some(bar);
        } else {
            let (tx, rx) = mpsc::channel::<()>();
            let start = Instant::now();
            p.stop = Some(tx);
            p.plain = Some(std::thread::spawn(move || {
                while let Err(RecvTimeoutError::Timeout) = rx.recv_timeout(PLAIN_EVERY) {
                    eprintln!("glray: {}", plain_line(&counts, total, start.elapsed()));
                }
            }));
        }
        p
    }

    /// `done` frames of the trace are gone through, `written` of them written.
    pub fn frames(&self, done: u64, written: u64) {
        self.counts.done.store(done, Ordering::Relaxed);
        self.counts.written.store(written, Ordering::Relaxed);
        if let Some(bar) = &self.bar {
            bar.set_position(done);
            bar.set_message(format!("{} written", plural(written, "frame")));
        }
    }

    /// What is being done now, for the bar's message or the next plain line.
    pub fn now(&self, what: String) {
        if let Some(bar) = &self.bar {
            bar.set_message(what.clone());
        }
        if let Ok(mut now) = self.counts.now.lock() {
            *now = what;
        }
    }

    /// A line to keep (printed above the bar, or as is).
    pub fn say(&self, line: &str) {
        match &self.bar {
            Some(bar) => bar.suspend(|| eprintln!("glray: {line}")),
            None => eprintln!("glray: {line}"),
        }
    }

    /// Ends the bar or the plain lines.
    pub fn finish(mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
        self.stop.take();
        if let Some(thread) = self.plain.take() {
            let _ = thread.join();
        }
    }
}

/// "replay: frame 45 of 90 (12 written), 30 s so far, about 30 s left; frame 45: pass 3 of 64".
fn plain_line(counts: &Counts, total: u64, elapsed: Duration) -> String {
    let (done, written) = (counts.done.load(Ordering::Relaxed), counts.written.load(Ordering::Relaxed));
    let secs = elapsed.as_secs_f64();
    let left = if done > 0 && total > done {
        format!(", about {:.0} s left", secs / done as f64 * (total - done) as f64)
    } else {
        String::new()
    };
    let now = counts.now.lock().map(|n| n.clone()).unwrap_or_default();
    let now = if now.is_empty() { String::new() } else { format!("; {now}") };
    format!("replay: frame {done} of {total} ({written} written), {secs:.0} s so far{left}{now}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_lines_say_where_the_replay_is_and_what_is_left() {
        let counts = Counts::default();
        counts.done.store(45, Ordering::Relaxed);
        counts.written.store(12, Ordering::Relaxed);
        *counts.now.lock().unwrap() = "frame 45: pass 3 of 64".into();
        assert_eq!(
            plain_line(&counts, 90, Duration::from_secs(30)),
            "replay: frame 45 of 90 (12 written), 30 s so far, about 30 s left; frame 45: pass 3 of 64"
        );
    }
}
