//! Live ray tracing inside the host program: the recorder hands every call's events to
//! `feed` (the same events a trace file holds), capture follows them per thread, and at the
//! frame trigger (`before`, called before the real swap, finish, flush or read-back) the
//! frame is ray traced and put into the real framebuffer (`present`), where the swap shows it
//! and glReadPixels reads it.
//!
//! Frames capture cannot follow (shaders, generic attributes) are left as the real GL drew
//! them. Nothing here may stop the host: errors are logged and ray tracing turns off.

mod copied;
mod dump;
mod lists;
mod stats;

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

use glray_capture::events::{Capture, LiveCall};
use glray_core::config::Config;
use glray_core::trace::{Event, Reader, Value};

use crate::abi::commands::{cmd, Ends, COMMANDS};
use crate::abi::dispatch::{self, Backend};
use crate::present;
use glray_capture::ops::AttrForm;

static ON: AtomicBool = AtomicBool::new(false);

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Trigger {
    Auto,
    Swap,
    Finish,
    Flush,
    ReadPixels,
}

/// What live ray tracing holds: capture, the tracer, what was shown. The recorder owns it
/// (`record::with_live`), so that a call is recorded and followed under one lock.
pub struct Live {
    capture: Capture,
    /// Command names by the recorder's numbers.
    names: Vec<Vec<u8>>,
    trigger: Trigger,
    /// The tracer, with the BVHs of display-list meshes kept across frames.
    renderer: glray_render::Renderer,
    dump: Option<PathBuf>,
    /// The most frames dumped (setting `dump_frames`; None: every one).
    dump_frames: Option<u64>,
    /// GLRAY_PRESENT.
    present: present::Way,
    /// The frame revision each thread presented last.
    presented: HashMap<u32, u64>,
    /// Threads that had a frame left to the real GL (shader draws, or a present that failed):
    /// told once, and their draws are rasterized until a frame of theirs is presented again.
    fell_back: std::collections::HashSet<u32>,
    /// Threads that have had a frame presented.
    shown: std::collections::HashSet<u32>,
    /// Each thread's last ray-traced frame, for frames drawn without a clear.
    last: HashMap<u32, glray_render::Rendered>,
    frames: u64,
    /// GLRAY_STATS, and the time capture took since the last frame (measured only for it).
    stats: Option<stats::StatsSink>,
    capture_time: std::time::Duration,
    /// The threads that trace frames: glray's own, not rayon's global pool, so that a forked
    /// child (which has none of its parent's threads) can be given new ones (`forked`);
    /// published for capture's work too (`glray_core::threads`).
    pool: Option<&'static rayon::ThreadPool>,
    threads: usize,
    /// In an MPI rank: frames shared with the other ranks.
    distribution: crate::distribute::Distribution,
    /// Passes traced at once for an offscreen program's frame (setting `batch_passes`), and the
    /// swaps seen so far (an offscreen program swaps a window at most once).
    batch_passes: u32,
    swaps: u64,
    /// Each thread's context's `passed_total` at its last statistics line.
    passed_seen: HashMap<u32, u64>,
    /// The live control panel (setting `panel`; rank 0's under MPI), started with the first
    /// frame (`panel_config` until then): not in processes that load glray and draw nothing
    /// (`glray run --np`'s mpirun, shells).
    panel: Option<crate::panel::Panel>,
    panel_config: Option<Config>,
}

/// The tracer's threads (None, logged, if the system gives none: frames are then traced on
/// rayon's global pool).
fn tracer_pool(threads: usize) -> Option<&'static rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|i| format!("glray-trace-{i}"))
        .build()
        .map_err(|e| glray_core::warn!("cannot start the tracer's threads ({e}); using rayon's"))
        .ok()
        .map(glray_core::threads::publish)
}

/// Turns live ray tracing on with the settings in force; the recorder, started next, keeps
/// what it returns.
pub fn configure(config: &Config) -> Live {
    let trigger = trigger_of(config);
    let threads = crate::distribute::tracer_threads(config);
    // Rank 0 serves the panel; the other ranks take its changes from rank 0 (`Distribution`).
    let rank0 = crate::distribute::env_rank().is_none_or(|r| r == 0);
    let live = Live {
        capture: Capture::default(),
        names: Vec::new(),
        trigger,
        renderer: glray_render::Renderer::new(glray_render::Options::from_config(config).unwrap_or_default()),
        dump: config.dump_scene().map(PathBuf::from),
        dump_frames: config.dump_frames(),
        present: present::Way::from_setting(config.present()),
        presented: HashMap::new(),
        last: HashMap::new(),
        shown: Default::default(),
        fell_back: Default::default(),
        frames: 0,
        stats: config.stats().and_then(|spec| stats::StatsSink::open(spec).map_err(|e| glray_core::warn!("{e}")).ok()),
        capture_time: std::time::Duration::ZERO,
        pool: tracer_pool(threads),
        threads,
        distribution: crate::distribute::Distribution::configure(config),
        batch_passes: config.batch_passes(),
        swaps: 0,
        passed_seen: HashMap::new(),
        panel: None,
        panel_config: (rank0 && config.panel().is_some()).then(|| config.clone()),
    };
    ON.store(true, Ordering::Relaxed);
    live
}

/// The frame trigger `config` sets.
fn trigger_of(config: &Config) -> Trigger {
    match config.trigger() {
        "swap" => Trigger::Swap,
        "finish" => Trigger::Finish,
        "flush" => Trigger::Flush,
        "readpixels" => Trigger::ReadPixels,
        _ => Trigger::Auto,
    }
}

fn stop(why: &str) {
    ON.store(false, Ordering::Relaxed);
    glray_core::error!("ray tracing stopped: {why}; the program's own frames are shown from here on");
}

/// Capture follows the events of one recorded call, read from the trace bytes the recorder
/// made of them; returns how many commands are named.
pub fn feed(live: &mut Live, bytes: &[u8], named: usize) -> usize {
    if !ON.load(Ordering::Relaxed) {
        return named;
    }
    let mut reader = Reader::events(bytes, named);
    guarded(live, |live| {
        while let Some(event) = reader.next_event().map_err(|e| format!("capture could not read a call: {e}"))? {
            if let Event::Name { number } = event {
                live.names.resize(number + 1, Vec::new());
                live.names[number] = reader.name(number).to_vec();
            }
            let names = &live.names;
            follow_in(&mut live.capture, &event, &|n| names.get(n).map_or(&[][..], |v| &v[..]));
        }
        Ok(())
    });
    reader.named()
}

/// Capture follows one event the recorder made without encoding it (no trace file is
/// written); `name` gives a Name event's command name.
pub fn follow<'a>(live: &mut Option<Live>, event: &Event, name: &dyn Fn(usize) -> &'a [u8]) {
    following(live, |capture| follow_in(capture, event, name));
}

/// Runs `f` on capture (`guarded`), when ray tracing.
#[inline]
fn following(live: &mut Option<Live>, f: impl FnOnce(&mut Capture)) {
    if !ON.load(Ordering::Relaxed) {
        return;
    }
    if let Some(live) = live.as_mut() {
        guarded(live, |live| {
            f(&mut live.capture);
            Ok(())
        });
    }
}

/// Runs `f` on the live state, timed for the statistics; an error it returns, or a panic,
/// stops ray tracing, not the program.
#[inline]
fn guarded(live: &mut Live, f: impl FnOnce(&mut Live) -> Result<(), String>) {
    let started = (live.stats.is_some() || live.panel.is_some()).then(std::time::Instant::now);
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| f(&mut *live)));
    if let Some(t) = started {
        live.capture_time += t.elapsed();
    }
    match result {
        Ok(Ok(())) => {}
        Ok(Err(e)) => stop(&e),
        Err(_) => stop("internal error in capture"),
    }
}

/// `capture` follows one event of the calling thread's.
fn follow_in<'a>(capture: &mut Capture, event: &Event, name: &dyn Fn(usize) -> &'a [u8]) {
    match event {
        Event::Call { cmd, thread, args, ret } => follow_live(capture, *cmd, *thread, args, ret.as_ref()),
        _ => {
            capture.event(event, name);
        }
    }
}

/// What capture is to know of the call this thread just made.
fn live_call() -> LiveCall {
    LiveCall {
        unseen: UNSEEN.with(|u| u.replace(false)) || in_skipped_begin(),
        core_profile: crate::abi::profile::core(),
    }
}

/// Capture follows attribute commands of `thread`'s handed over typed (`calls::given`), in
/// the order they were made: each one's form, glMultiTexCoord's target, its components, and
/// whether the real GL did not get it.
pub fn follow_given<'a>(live: &mut Live, thread: u32, calls: impl Iterator<Item = (AttrForm, u32, &'a [f64], bool)>) {
    if !ON.load(Ordering::Relaxed) {
        return;
    }
    let core_profile = crate::abi::profile::core();
    guarded(live, |live| {
        live.capture.given(thread, core_profile, calls);
        Ok(())
    });
}

/// Capture follows one call the recorder made without encoding it (no trace file is
/// written), as `follow` does an event.
pub fn follow_call(live: &mut Option<Live>, cmd: usize, thread: u32, args: &[Value], ret: Option<&Value>) {
    following(live, |capture| follow_live(capture, cmd, thread, args, ret));
}

/// Capture follows one call of this thread's; then the real GL is brought up to what the call
/// did without it (a list it did not run) or capture to what it did without capture (a copy
/// from the framebuffer).
#[inline]
fn follow_live(capture: &mut Capture, cmd: usize, thread: u32, args: &[Value], ret: Option<&Value>) {
    let call = live_call();
    let list = lists::before(capture, cmd, thread, call.unseen);
    capture.call(cmd, thread, args, ret, Some(call));
    lists::after(capture, thread, list);
    copied::follow(capture, cmd, thread, args);
}

/// Says once per process, at the default log level, that this program's frames are not ray
/// traced and why: a user who runs a program under glray and gets the real GL's pictures back
/// must not have to guess (ParaView's shaders, a core profile). Whichever reason comes first
/// is told; threads and contexts after it add nothing.
fn tell_left_alone(why: &str) {
    static TOLD: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
    if !TOLD.swap(true, Ordering::Relaxed) {
        glray_core::warn!(
            "frames are left to the real GL, not ray traced: {why}; glray ray traces fixed-function GL \
             and the shader programs of VTK 9 (ParaView 5.11), see docs/compatibility.md"
        );
    }
}

thread_local! {
    /// The real GL did not get this thread's open glBegin: its vertices and glEnd skip it too.
    static SKIPPED_BEGIN: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    /// The real GL did not get this thread's last call (capture, following it next, reports
    /// its errors instead).
    static UNSEEN: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Whether this thread is between a glBegin and glEnd the real GL did not get.
#[inline]
pub fn in_skipped_begin() -> bool {
    SKIPPED_BEGIN.with(|s| s.get())
}

/// What a command is to the live feed before its real call (`before`).
#[derive(Debug, Clone, Copy)]
pub enum Before {
    /// Nothing to do: the real call goes ahead unless this says to skip it (a vertex of a
    /// glBegin the real GL did not get, and its glEnd).
    Decided(bool),
    /// The live state is needed (`fire`, under the stream's lock).
    Fire(Firing),
}

/// What `fire` does for a command: take geometry from the real GL, present the frame before
/// something draws over it, or at a trigger.
#[derive(Debug, Clone, Copy)]
pub struct Firing {
    geometry: bool,
    raster: bool,
    at: Option<Trigger>,
}

/// Called before the real call of every geometry, client, context and frame command: whether
/// the live state is needed (`fire`) or what to do without it.
pub fn before(c: usize) -> Before {
    if !ON.load(Ordering::Relaxed) {
        return Before::Decided(false);
    }
    if c == cmd::glEnd {
        return Before::Decided(SKIPPED_BEGIN.with(|s| s.replace(false)));
    }
    if matches!(c, cmd::glArrayElement | cmd::glArrayElementEXT) {
        return Before::Decided(in_skipped_begin());
    }
    // What gl-spec/classes.txt says of the command: geometry glray takes (`taken`), and where
    // it ends a frame or draws over it (`ends=`).
    let info = &COMMANDS[c];
    let geometry = info.taken;
    let at = match info.ends {
        Ends::Swap => Some(Trigger::Swap),
        Ends::Finish => Some(Trigger::Finish),
        Ends::Flush => Some(Trigger::Flush),
        Ends::ReadPixels => Some(Trigger::ReadPixels),
        Ends::Raster | Ends::No => None,
    };
    let raster = info.ends == Ends::Raster;
    if !geometry && at.is_none() && !raster {
        return Before::Decided(false);
    }
    Before::Fire(Firing { geometry, raster, at })
}

/// Notes whether the real GL is skipping this thread's call (capture, following it next,
/// reports its errors instead).
pub fn skipped(skip: bool) {
    UNSEEN.with(|u| u.set(skip));
}

/// Whether every way a program can see what it drew fires `trigger`, so that its draws need
/// not be rasterized before one of its frames has been presented: an OSMesa buffer holds the
/// picture only after glFinish or glFlush (or gives it through glReadPixels), each of which
/// ends a frame by default. Not GLX or EGL: a single-buffered window shows what a glFlush
/// left, which does not end a frame there. At 10M triangles the first frame's rasterizing,
/// drawn over by the ray-traced picture, was a fifth of the time to the first picture.
fn triggers_all(trigger: Trigger) -> bool {
    trigger == Trigger::Auto && dispatch::backend() == Backend::OSMesa
}

/// Presents the frame when command `c` of `thread` is the trigger (or a raster operation about
/// to draw over it), and says whether the real call is to be skipped: geometry the ray tracer
/// takes is not rasterized as well. Called with the stream's lock held; a panic stops ray
/// tracing, not the program.
pub fn fire(live: &mut Live, c: usize, thread: u32, firing: Firing) -> bool {
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| fire_in(live, c, thread, firing)));
    result.unwrap_or_else(|_| {
        stop("internal error while ray tracing a frame");
        false
    })
}

fn fire_in(live: &mut Live, c: usize, thread: u32, Firing { geometry, raster, at }: Firing) -> bool {
    if geometry {
        // A draw through a program no profile recognises, after the frame's 3D scene (VTK's
        // orientation axes, scalar bar, FXAA): the scene goes in first, the draw lands on it.
        if live.capture.context(thread).draw_passes_over() {
            live.present(thread);
        }
        // Only where this thread's frames are known to reach a trigger, so that what is not
        // rasterized will be shown: once one of its frames has been presented, or from the
        // first frame on where every way of seeing the pixels is a trigger (`triggers_all`).
        let proven = live.shown.contains(&thread) || (triggers_all(live.trigger) && !live.fell_back.contains(&thread));
        let skip = proven && live.capture.context(thread).takes_draws();
        if c == cmd::glBegin {
            SKIPPED_BEGIN.with(|s| s.set(skip));
        }
        return skip;
    }
    if raster {
        // Text and images drawn over the scene, and copies that read it: the scene goes in
        // first.
        if !live.capture.context(thread).compiling() {
            live.present(thread);
        }
        return false;
    }
    let fires = match (live.trigger, at) {
        // A GLX/EGL frame ends at its swap; an OSMesa one (no swap) at glFinish or glFlush.
        (Trigger::Auto, Some(Trigger::Swap | Trigger::ReadPixels)) => true,
        (Trigger::Auto, Some(_)) => dispatch::backend() == Backend::OSMesa,
        (t, Some(a)) => t == a,
        _ => false,
    };
    if at == Some(Trigger::Swap) {
        live.swaps += 1;
    }
    if fires {
        live.present(thread);
    }
    false
}

/// `frame` traced at its size on the tracer's threads (rayon's global pool without them).
fn traced(
    pool: Option<&rayon::ThreadPool>,
    renderer: &mut glray_render::Renderer,
    frame: &glray_scene::frame::Frame,
    last: Option<&glray_render::Rendered>,
) -> glray_render::Rendered {
    let (w, h) = frame.size();
    match pool {
        Some(pool) => pool.install(|| renderer.render(frame, w, h, last)),
        None => renderer.render(frame, w, h, last),
    }
}

/// The first error `thread`'s context raised that the real GL could not (0: none).
pub fn take_unseen_error(live: &mut Live, thread: u32) -> u32 {
    if !ON.load(Ordering::Relaxed) {
        return 0;
    }
    live.capture.context(thread).take_unseen_error()
}

impl Live {
    /// The settings the panel changed since the last frame, made from this frame on: here, and
    /// (in an MPI job) on every rank with it.
    fn take_panel_changes(&mut self) {
        let Some((config, changes)) = self.panel.as_ref().and_then(|p| p.take_changes()) else { return };
        let Some(options) = glray_render::Options::from_config(&config) else { return };
        glray_core::info!(
            "panel: {}",
            changes.iter().map(|(k, v)| format!("{k} = {v:?}")).collect::<Vec<_>>().join(", ")
        );
        self.renderer.set_options(options);
        self.trigger = trigger_of(&config);
        if self.distribution.active() {
            self.distribution.announce(&config, changes);
        }
    }

    /// In a child just forked: the parent's tracer threads do not exist here (waiting on them
    /// hung the child's first new frame); the child gets threads of its own. The old pool is
    /// not dropped (`glray_core::threads` never drops one): that would signal threads that
    /// are not there.
    pub fn forked(&mut self) {
        self.pool = tracer_pool(self.threads);
    }

    fn present(&mut self, thread: u32) {
        if let Some(config) = self.panel_config.take() {
            self.panel = crate::panel::Panel::start(&config);
        }
        self.take_panel_changes();
        let ctx = self.capture.context(thread);
        let revision = ctx.revision();
        if self.presented.get(&thread) == Some(&revision) {
            return;
        }
        self.presented.insert(thread, revision);
        let frame = ctx.frame();
        if frame.unsupported_draws > 0 {
            if self.fell_back.insert(thread) {
                tell_left_alone(&format!(
                    "it draws with shaders or draws glray does not follow yet: shader programs in a fixed-function \
                     frame, instanced draws, VTK's translucent surfaces and surfaces without normals (glyphs) ({} \
                     draws in its first such frame)",
                    frame.unsupported_draws
                ));
            }
            // The real GL rasterizes everything again from the next frame on.
            self.shown.remove(&thread);
            return;
        }
        if frame.is_empty() {
            if frame.passed_draws > 0 && frame.cleared && self.shown.is_empty() {
                tell_left_alone("it draws with shader programs no profile recognises");
            }
            return;
        }
        let (w, h) = frame.size();
        if w == 0 || h == 0 {
            return;
        }
        let passed_total = ctx.passed_total;
        // An offscreen program reads one frame back as its picture: traced with several passes
        // at once (the first ones here, the last below), as a still view converges over frames.
        let offscreen = ctx.draws_offscreen() && self.swaps <= 1;
        let (renderer, last) = (&mut self.renderer, self.last.get(&thread));
        // Decided from what every rank of an MPI job has alike (settings, an offscreen frame
        // that clears), so that all of them share the same number of frames.
        let batch =
            offscreen && renderer.options.effects.beyond_gl() && renderer.options.effects.progressive && frame.cleared;
        let extra = if batch { self.batch_passes - 1 } else { 0 };
        // What the extra passes did, for the statistics (the last pass's are the renderer's).
        let mut extra_work = glray_render::Stats::default();
        if extra > 0 && !self.distribution.active() {
            for _ in 0..extra {
                traced(self.pool, renderer, frame, last);
                extra_work = renderer.stats().and_before(&extra_work);
            }
        }
        // In an MPI rank: each pass a frame shared with the others (a fault ends them), its
        // share reported with the last pass's.
        let mut extra_report: Option<glray_distribute::FrameReport> = None;
        if extra > 0 && self.distribution.active() {
            for _ in 0..extra {
                let Some(pass) = self.distribution.frame(frame, last, renderer, self.pool, false) else { break };
                extra_work = renderer.stats().and_before(&extra_work);
                extra_report = Some(extra_report.map_or(pass.report, |r| r.and(pass.report)));
            }
        }
        // In an MPI rank, shared with the other ranks (None: traced here alone).
        let shared = self.distribution.frame(frame, last, renderer, self.pool, true);
        if let Some(changed) = self.distribution.take_changed() {
            // Rank 0's panel changed the settings (made on this rank's renderer already).
            self.trigger = trigger_of(&changed);
        }
        let (rendered, ranks) = match shared {
            Some(crate::distribute::Shared { picture: Some(picture), report, rank, ranks }) => {
                let report = extra_report.map_or(report, |r| r.and(report));
                (picture, Some(stats::RankStats { rank, ranks, report }))
            }
            _ => (traced(self.pool, renderer, frame, last), None),
        };
        if let Some(dir) = &self.dump {
            match self.dump_frames {
                Some(most) if self.frames >= most => {
                    if self.frames == most {
                        glray_core::warn!(
                            "dump_scene: the first {} written to {}; dump_frames (GLRAY_DUMP_FRAMES) writes more \
                             (0: every frame)",
                            glray_core::log::plural(most, "frame"),
                            dir.display()
                        );
                    }
                }
                _ => {
                    if let Err(e) = dump::write(dir, self.frames, frame) {
                        glray_core::warn!("dump_scene: {e}");
                    }
                }
            }
        }
        let number = self.frames;
        self.frames += 1;
        let start = std::time::Instant::now();
        // SAFETY: called on the thread whose context is current, before its swap/finish/read.
        if !unsafe { present::draw(&rendered, self.present) } {
            // Not put in place: the real GL rasterizes from the next frame on.
            self.shown.remove(&thread);
            self.fell_back.insert(thread);
            return;
        }
        if self.stats.is_some() || self.panel.is_some() {
            let line = stats::FrameStats {
                frame: number,
                thread,
                width: w,
                height: h,
                capture: std::mem::take(&mut self.capture_time),
                render: self.renderer.stats().and_before(&extra_work),
                present: start.elapsed(),
                passed_draws: passed_total - self.passed_seen.insert(thread, passed_total).unwrap_or(0),
                ranks,
            };
            if let Some(sink) = self.stats.as_mut() {
                sink.write(&line);
            }
            if let Some(panel) = &self.panel {
                panel.publish(number, &rendered, Some(stats::json(&line)));
            }
        }
        self.shown.insert(thread);
        self.last.insert(thread, rendered);
    }
}
