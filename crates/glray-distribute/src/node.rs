//! One rank's part in a frame (`Node::frame`), image-parallel over a replicated scene:
//!
//! 1. every rank sends the frame it captured to every other (meshes and textures the others
//!    lack go with it, once: `glray_scene::encode`), and merges all of them in rank order
//!    (`glray_scene::merge`): every rank holds the same whole scene;
//! 2. rank 0, the master, hands out tiles (`Master`); each rank traces what it is given on its
//!    threads, asking for more while it traces, and sends each finished tile straight to rank
//!    0, the display;
//! 3. rank 0 puts the tiles together, adds the pass to the ones before (progressive
//!    refinement) and sends the picture to every other rank: each returns it (a sort-last
//!    compositor such as IceT takes a rank's pixels only where its own data projects).
//!
//! The thread that calls `frame` is the one that moves messages (the tracing runs on the
//! tracer's threads), and every wait on another rank has a time limit: a rank that stops
//! answering ends the frame with a `Fault` naming it, never a hang.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError, Sender};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use glray_render::denoise::AoPixel;
use glray_render::tiles::{LayersMut, TileGrid, TilePixels, TileWork};
use glray_render::{Rendered, Renderer};
use glray_scene::encode::{decode, encode, ObjectStore};
use glray_scene::frame::Frame;

use crate::master::{imbalance, Master};
use crate::protocol::{picture, picture_message, tile_message, tile_pixels, Message, RankReport};
use crate::transport::Transport;

/// How long a rank waits for another on the first frame (each rank loads its data and builds
/// its meshes before it; their sizes differ) unless told (`Limits::fixed`).
pub const FIRST_FRAME_LIMIT: Duration = Duration::from_secs(120);
/// Beyond the last frame's time, how long a rank waits for another on later frames.
pub const SLACK: Duration = Duration::from_secs(10);

/// Why a frame could not be traced across the ranks.
#[derive(Debug, Clone, PartialEq)]
pub enum Fault {
    /// These ranks sent nothing for this long while they were waited for.
    Silent { ranks: Vec<usize>, waited: Duration, frame: u64, waiting_for: &'static str },
    /// A rank whose glray is set differently (its pictures would not match).
    Refused { rank: usize, why: String },
    /// A message from a rank could not be read.
    Damaged { rank: usize, why: String },
    /// The message layer failed.
    Transport(String),
}

impl std::fmt::Display for Fault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Fault::Silent { ranks, waited, frame, waiting_for } => {
                let names: Vec<String> = ranks.iter().map(|r| r.to_string()).collect();
                write!(
                    f,
                    "rank{} {} did not answer within {:.1} s (frame {frame}, waiting for {waiting_for}): it stopped, \
                     died or skipped the frame",
                    if ranks.len() > 1 { "s" } else { "" },
                    names.join(", "),
                    waited.as_secs_f64()
                )
            }
            Fault::Refused { rank, why } => write!(f, "rank {rank} refused: {why}"),
            Fault::Damaged { rank, why } => write!(f, "rank {rank} sent {why}"),
            Fault::Transport(e) => write!(f, "MPI failed: {e}"),
        }
    }
}

/// What one frame took on this rank (and, on rank 0, across the ranks).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameReport {
    pub frame: u64,
    /// Tiles this rank traced, of all the frame's.
    pub tiles: u32,
    pub tiles_total: u32,
    pub rays: u64,
    pub bytes_sent: u64,
    pub bytes_received: u64,
    /// Time spent waiting for other ranks: for their scenes, for tiles, at the end.
    pub wait: Duration,
    /// Step 1: this rank's scene sent, every other rank's received, decoded and merged (on the
    /// first frame, the replication of every mesh).
    pub exchange: Duration,
    /// This rank's tracing of its tiles.
    pub trace: Duration,
    /// Slowest rank's tracing time over the mean (rank 0 only).
    pub imbalance: Option<f64>,
    /// The picture was the last one's again (converged), or traced by rank 0 alone.
    pub untraced: bool,
}

impl FrameReport {
    /// This frame's report and a `later` one's, as one frame's: the passes of a batch
    /// program's frame (each a frame shared by the ranks) reported on one line. Counts and
    /// times add up; the rest is the later frame's.
    pub fn and(self, later: FrameReport) -> FrameReport {
        FrameReport {
            tiles: self.tiles + later.tiles,
            tiles_total: self.tiles_total + later.tiles_total,
            rays: self.rays + later.rays,
            bytes_sent: self.bytes_sent + later.bytes_sent,
            bytes_received: self.bytes_received + later.bytes_received,
            wait: self.wait + later.wait,
            exchange: self.exchange + later.exchange,
            trace: self.trace + later.trace,
            untraced: self.untraced && later.untraced,
            ..later
        }
    }
}

/// What every rank must agree on: the version of glray and every setting that shapes the
/// picture, as one number (`settings`), and a description to name them when they differ.
#[derive(Debug, Clone)]
pub struct Agreement {
    pub settings: u64,
}

/// Whether rank 0 traces too (`Shared`, the default) or only hands out tiles and gathers them
/// (`Dedicated`: the master and display on a rank of their own, as the paper's roles).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Roles {
    #[default]
    Shared,
    Dedicated,
}

/// How long a rank waits for another: `fixed` (the setting `mpi_timeout`) or, when not set,
/// `FIRST_FRAME_LIMIT`, then the last frame's time plus `SLACK`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Limits {
    pub fixed: Option<Duration>,
}

/// A rank of the job: its messages, what it has sent and been sent, the master's queue.
pub struct Node<T: Transport> {
    transport: T,
    frame: u64,
    agreement: Agreement,
    limits: Limits,
    /// What every other rank holds of this rank's meshes and textures.
    sent: ObjectStore,
    /// What this rank holds of each rank's.
    held: Vec<ObjectStore>,
    /// Messages of frames this rank has not reached yet.
    ahead: VecDeque<(usize, Message)>,
    master: Master,
    /// The accumulation key of the last frame and the passes traced under it.
    run: Option<(u64, u32)>,
    last_frame: Option<Duration>,
    bytes_sent: u64,
    bytes_received: u64,
    /// Rank 0: settings changes to hand on with the next frame (`announce`).
    announced: Announced,
    /// Other ranks: how to make rank 0's changes (`on_settings`).
    hook: Option<SettingsHook>,
}

/// Settings changes waiting to go with the next frame: the agreement number after the last of
/// them, and all of them in order (two changes before a frame both go).
#[derive(Debug, Default)]
pub struct Announced(Option<(u64, Vec<(String, String)>)>);

impl Announced {
    pub fn add(&mut self, settings: u64, changes: Vec<(String, String)>) {
        match self.0.as_mut() {
            Some((s, c)) => {
                *s = settings;
                c.extend(changes);
            }
            None => self.0 = Some((settings, changes)),
        }
    }

    pub fn take(&mut self) -> Option<(u64, Vec<(String, String)>)> {
        self.0.take()
    }
}

/// Makes rank 0's settings changes (setting, value) on this rank: to its renderer and wherever
/// else they matter; the new settings' agreement number, or why they cannot be made.
pub type SettingsHook = Box<dyn FnMut(&[(String, String)], &mut Renderer) -> Result<u64, String> + Send>;

/// How long the message loop sleeps when there is nothing to do.
const IDLE: Duration = Duration::from_micros(50);
/// How long the tracing's message loop waits for the tracer before it looks at MPI again. Other
/// ranks' asks wait at most this long, hidden by the chunk each keeps in reserve; polled every
/// 200 us, Open MPI's progress over TCP slowed a one-rank frame's tracing by ~14% (on the
/// other core), every 1 ms by ~3% (docs/distributed.md).
const POLL: Duration = Duration::from_millis(1);

impl<T: Transport> Node<T> {
    pub fn new(transport: T, agreement: Agreement, limits: Limits) -> Node<T> {
        Node::with_roles(transport, agreement, limits, Roles::Shared)
    }

    pub fn with_roles(transport: T, agreement: Agreement, limits: Limits, roles: Roles) -> Node<T> {
        let size = transport.size();
        let mut master = Master::new(size);
        if roles == Roles::Dedicated {
            master.leave_out(0);
        }
        Node {
            transport,
            frame: 0,
            agreement,
            limits,
            sent: ObjectStore::default(),
            held: (0..size).map(|_| ObjectStore::default()).collect(),
            ahead: VecDeque::new(),
            master,
            run: None,
            last_frame: None,
            bytes_sent: 0,
            bytes_received: 0,
            announced: Announced::default(),
            hook: None,
        }
    }

    /// Rank 0: its settings changed (already made here, `settings` their new agreement
    /// number); every other rank makes `changes` before it traces the next frame.
    pub fn announce(&mut self, settings: u64, changes: Vec<(String, String)>) {
        self.announced.add(settings, changes);
    }

    /// How this rank makes rank 0's settings changes (`Message::Settings`).
    pub fn on_settings(&mut self, hook: SettingsHook) {
        self.hook = Some(hook);
    }

    pub fn rank(&self) -> usize {
        self.transport.rank()
    }

    pub fn size(&self) -> usize {
        self.transport.size()
    }

    /// The time limit of any wait on another rank this frame.
    pub fn limit(&self) -> Duration {
        self.limits.fixed.unwrap_or_else(|| self.last_frame.map_or(FIRST_FRAME_LIMIT, |t| t + SLACK))
    }

    fn send(&mut self, to: usize, message: Message) -> Result<(), Fault> {
        self.send_bytes(to, message.encode())
    }

    fn send_bytes(&mut self, to: usize, bytes: Vec<u8>) -> Result<(), Fault> {
        self.bytes_sent += bytes.len() as u64;
        self.transport.send(to, bytes).map_err(Fault::Transport)
    }

    /// The next message of frame `frame`, if one is here: those of earlier frames (a frame
    /// this rank gave up on) are dropped, those of later ones kept for then.
    fn receive(&mut self, frame: u64) -> Result<Option<(usize, Message)>, Fault> {
        if let Some(k) = self.ahead.iter().position(|(_, m)| m.frame() == frame) {
            return Ok(self.ahead.remove(k));
        }
        while let Some((from, bytes)) = self.transport.poll().map_err(Fault::Transport)? {
            self.bytes_received += bytes.len() as u64;
            let message = Message::decode(bytes).map_err(|why| Fault::Damaged { rank: from, why })?;
            match message.frame() {
                f if f == frame => return Ok(Some((from, message))),
                f if f > frame => self.ahead.push_back((from, message)),
                _ => {}
            }
        }
        Ok(None)
    }

    /// Traces `mine` (this rank's captured frame) with every other rank's: rank 0 gets the
    /// picture, the others None. `previous` is the picture under a frame that does not clear.
    pub fn frame(
        &mut self,
        mine: &Frame,
        previous: Option<&Rendered>,
        renderer: &mut Renderer,
        pool: Option<&rayon::ThreadPool>,
    ) -> Result<(Option<Rendered>, FrameReport), Fault> {
        let frame = self.frame;
        self.frame += 1;
        let started = Instant::now();
        let (sent0, received0) = (self.bytes_sent, self.bytes_received);
        let mut report = FrameReport { frame, ..FrameReport::default() };
        let (merged, waited) = self.exchange(frame, mine, renderer)?;
        report.wait += waited;
        report.exchange = started.elapsed();
        let (w, h) = merged.size();
        let key = renderer.accumulation_key(&merged, w, h);
        let pass = match (key, self.run) {
            (Some(k), Some((run, n))) if k == run => n,
            _ => 0,
        };
        let me = self.rank();
        let alone = w == 0 || h == 0 || merged.is_empty() || pass >= renderer.converged_passes();
        let picture = if alone || !Renderer::shares(&merged) {
            // Nothing to trace (rank 0 shows what the frame cleared to), converged (the last
            // picture again), or a frame drawn over the last or in several viewports: rank 0
            // renders it alone, as one process would.
            report.untraced = true;
            if me != 0 {
                // Counted all the same: every rank's AO rays stay rank 0's.
                renderer.pass_frame(merged.triangle_count() as u64);
            }
            (me == 0).then(|| renderer.render(&merged, w, h, previous))
        } else {
            self.run = key.map(|k| (k, pass + 1));
            let (linear, ao) = (renderer.linear(key), renderer.denoises());
            let shared = Shared { frame, merged: &merged, key, pass, linear, ao };
            self.trace(&shared, renderer, pool, &mut report)?
        };
        // Every rank's framebuffer gets the picture (see `Message::Picture`).
        let picture = if me == 0 {
            if let Some(p) = &picture {
                let bytes = picture_message(frame, p).encode();
                for r in 1..self.size() {
                    self.send_bytes(r, bytes.clone())?;
                }
            }
            picture
        } else {
            let (p, waited) = self.await_picture(frame)?;
            report.wait += waited;
            Some(p)
        };
        if !report.untraced {
            self.last_frame = Some(started.elapsed());
        }
        report.bytes_sent = self.bytes_sent - sent0;
        report.bytes_received = self.bytes_received - received0;
        Ok((picture, report))
    }

    /// Step 1: every rank's frame to every rank, merged in rank order; and the time waited.
    fn exchange(&mut self, frame: u64, mine: &Frame, renderer: &mut Renderer) -> Result<(Frame, Duration), Fault> {
        let (me, size) = (self.rank(), self.size());
        // Scenes sent before a settings change reached their rank carry the settings before it:
        // agreed to for this frame.
        let mut before = None;
        if let Some((settings, changes)) = self.announced.take() {
            before = Some(std::mem::replace(&mut self.agreement.settings, settings));
            if me == 0 {
                let m = Message::Settings { frame, settings, changes };
                for r in 1..size {
                    self.send(r, m.clone())?;
                }
            }
        }
        if size > 1 {
            let scene = encode(mine, &mut self.sent);
            // Encoded once for every rank (the first frame's may be hundreds of megabytes).
            // Encoded once for every rank (the first frame's may be hundreds of megabytes),
            // moved to the last one.
            let bytes = Message::Scene { frame, settings: self.agreement.settings, scene }.encode();
            let others: Vec<usize> = (0..size).filter(|&r| r != me).collect();
            let mut bytes = Some(bytes);
            for (k, &r) in others.iter().enumerate() {
                let b = if k + 1 == others.len() { bytes.take() } else { bytes.clone() };
                self.send_bytes(r, b.expect("bytes for every rank"))?;
            }
        }
        // What the others hold of ours is what this frame draws (the rest they forget, below).
        let (meshes, textures) = ids_of(mine);
        self.sent.retain(&meshes, &textures);
        let mut scenes: Vec<Option<Vec<u8>>> = vec![None; size];
        // The master's first tiles may come before the last scene: kept for the tracing.
        let mut early = Vec::new();
        let begun = Instant::now();
        let mut last_heard = Instant::now();
        while scenes.iter().enumerate().any(|(r, s)| r != me && s.is_none()) {
            match self.receive(frame)? {
                Some((0, Message::Settings { settings, changes, .. })) if me != 0 => {
                    let made = match self.hook.as_mut() {
                        Some(hook) => hook(&changes, renderer),
                        None => Err("this rank takes no settings changes".to_string()),
                    };
                    match made {
                        Ok(mine) if mine == settings => {
                            before = Some(std::mem::replace(&mut self.agreement.settings, settings));
                        }
                        Ok(_) => {
                            return Err(Fault::Refused {
                                rank: 0,
                                why: format!("its settings changed ({changes:?}) and this rank's no longer agree"),
                            })
                        }
                        Err(why) => {
                            return Err(Fault::Refused {
                                rank: 0,
                                why: format!("a settings change {changes:?}: {why}"),
                            })
                        }
                    }
                    last_heard = Instant::now();
                }
                Some((from, Message::Scene { settings, scene, .. })) => {
                    if settings != self.agreement.settings && Some(settings) != before {
                        return Err(Fault::Refused {
                            rank: from,
                            why: format!(
                                "its glray or its settings differ from rank {me}'s: every rank must run the same \
                                 glray with the same GLRAY_* settings (`glray run --np` forwards them)"
                            ),
                        });
                    }
                    scenes[from] = Some(scene);
                    last_heard = Instant::now();
                }
                Some(early_message) => early.push(early_message),
                None => {
                    if last_heard.elapsed() > self.limit() {
                        let ranks = (0..size).filter(|&r| r != me && scenes[r].is_none()).collect();
                        return Err(Fault::Silent {
                            ranks,
                            waited: last_heard.elapsed(),
                            frame,
                            waiting_for: "its scene",
                        });
                    }
                    std::thread::sleep(IDLE);
                }
            }
        }
        let waited = begun.elapsed();
        for m in early.into_iter().rev() {
            self.ahead.push_front(m);
        }
        let mut frames = Vec::with_capacity(size);
        for (r, scene) in scenes.into_iter().enumerate() {
            if r == me {
                frames.push(mine.clone());
                continue;
            }
            let bytes = scene.expect("every scene is in");
            let f = decode(&bytes, &mut self.held[r])
                .map_err(|e| Fault::Damaged { rank: r, why: format!("a scene glray cannot read: {e}") })?;
            let (meshes, textures) = ids_of(&f);
            self.held[r].retain(&meshes, &textures);
            frames.push(f);
        }
        Ok((glray_scene::merge::merge(frames), waited))
    }

    /// Steps 2 and 3: this rank's share traced on its threads while this thread moves the
    /// messages; rank 0's picture.
    fn trace(
        &mut self,
        shared: &Shared,
        renderer: &mut Renderer,
        pool: Option<&rayon::ThreadPool>,
        report: &mut FrameReport,
    ) -> Result<Option<Rendered>, Fault> {
        let (w, h) = shared.merged.size();
        let grid = TileGrid::new(w, h);
        report.tiles_total = grid.count();
        let (event_tx, event_rx) = channel();
        let (grant_tx, grant_rx) = channel();
        let abort = AtomicBool::new(false);
        let work = ChannelWork { events: Mutex::new(event_tx), grants: Mutex::new(grant_rx), abort: &abort };
        let traced = AtomicBool::new(false);
        let tracing = Mutex::new((Duration::ZERO, 0u64));
        let mut lanes = Lanes { events: event_rx, grants: grant_tx, traced: &traced };
        let owned;
        let pool = match pool {
            Some(p) => p,
            None => {
                owned = rayon::ThreadPoolBuilder::new()
                    .build()
                    .map_err(|e| Fault::Transport(format!("no threads: {e}")))?;
                &owned
            }
        };
        let tracer = &mut *renderer;
        let traces = self.master.traces(self.rank());
        if !traces {
            // A dedicated master: nothing to trace here (the frame counted all the same).
            tracer.pass_frame(shared.merged.triangle_count() as u64);
            traced.store(true, Ordering::Release);
        }
        let served = pool.in_place_scope(|s| {
            let (work, traced, tracing) = (&work, &traced, &tracing);
            s.spawn(move |_| {
                if !traces {
                    return;
                }
                let start = Instant::now();
                let stats = tracer.render_tiles(shared.merged, w, h, shared.pass, shared.linear, work);
                *tracing.lock().unwrap_or_else(|e| e.into_inner()) = (start.elapsed(), stats.rays);
                traced.store(true, Ordering::Release);
            });
            let r = self.serve(shared, grid, &mut lanes, tracing, report);
            abort.store(r.is_err(), Ordering::Release);
            r
        });
        let gathered = served?;
        (report.trace, report.rays) = *tracing.lock().unwrap_or_else(|e| e.into_inner());
        Ok(gathered.map(|(picture, colors, ao)| renderer.add_pass(shared.merged, shared.key, picture, colors, ao)))
    }

    /// The message loop of a frame's tracing, until this rank's part is done: rank 0 hands out
    /// tiles and gathers them (returning the picture and its linear colours), the others ask
    /// for tiles and send them on.
    fn serve(
        &mut self,
        shared: &Shared,
        grid: TileGrid,
        lanes: &mut Lanes,
        tracing: &Mutex<(Duration, u64)>,
        report: &mut FrameReport,
    ) -> Result<Option<Gathered>, Fault> {
        let (me, size, frame) = (self.rank(), self.size(), shared.frame);
        let tiles = grid.count();
        // Rank 0: the picture being gathered, and who has reported.
        let mut gather = (me == 0).then(|| Gather::new(grid, shared.linear, shared.ao));
        let mut reports: Vec<Option<RankReport>> = vec![None; size];
        let mut reserve: VecDeque<Vec<u32>> = VecDeque::new();
        let (mut asked, mut exhausted, mut tracer_waits) = (false, false, false);
        if me == 0 {
            let batches = self.master.begin(tiles);
            // (An empty grant means "no more": a rank without a first batch asks instead.)
            for (r, batch) in batches.into_iter().enumerate().filter(|(_, b)| !b.is_empty()) {
                if r == 0 {
                    reserve.push_back(batch);
                } else {
                    self.send(r, Message::Grant { frame, tiles: batch })?;
                }
            }
        }
        let mut last_heard = Instant::now();
        let mut my_tiles = 0u32;
        let mut traced_at: Option<Instant> = None;
        let mut busy = true;
        loop {
            // What the tracer said: it wants tiles, or has traced some (all of them, once it
            // has finished: `done` comes before `traced`). The wait for it is the loop's idle
            // time, so that a tile or an ask is taken at once.
            let traced = lanes.traced.load(Ordering::Acquire);
            let mut traced_tiles = Vec::new();
            // Waited for only when the last round found nothing to do.
            let wait = if busy { Duration::ZERO } else { POLL };
            busy = false;
            let mut first = lanes.events.recv_timeout(wait).ok();
            while let Some(event) = first.take().or_else(|| lanes.events.try_recv().ok()) {
                match event {
                    TracerEvent::Ask => tracer_waits = true,
                    TracerEvent::Tile(t) => traced_tiles.push(t),
                }
            }
            if tracer_waits {
                let chunk = match reserve.pop_front() {
                    Some(c) => Some(c),
                    None if me == 0 => Some(self.master.next(0)).filter(|c| !c.is_empty()),
                    None if exhausted => None,
                    None => {
                        // Wait for the master's answer.
                        if !asked {
                            self.send(0, Message::Ask { frame })?;
                            asked = true;
                            // The wait for the answer starts now.
                            last_heard = Instant::now();
                        }
                        Some(Vec::new())
                    }
                };
                match chunk {
                    Some(c) if c.is_empty() => {}
                    Some(c) => {
                        my_tiles += c.len() as u32;
                        let _ = lanes.grants.send(Some(c));
                        tracer_waits = false;
                        busy = true;
                    }
                    None => {
                        let _ = lanes.grants.send(None);
                        tracer_waits = false;
                    }
                }
            }
            // No chunk is asked for ahead of need: one held in reserve at the end of a frame is
            // work another rank could have taken (2 ranks: 1.54x over one with it, see
            // docs/distributed.md); an ask costs a round trip of at most `POLL`.
            // Tiles this rank traced.
            for t in traced_tiles {
                busy = true;
                match gather.as_mut() {
                    Some(g) => {
                        g.paste(&t);
                    }
                    None => {
                        let m = tile_message(frame, &t);
                        self.send(0, m)?;
                    }
                }
            }
            // Messages from the other ranks.
            while let Some((from, message)) = self.receive(frame)? {
                busy = true;
                last_heard = Instant::now();
                match message {
                    Message::Ask { .. } if me == 0 => {
                        let chunk = self.master.next(from);
                        self.send(from, Message::Grant { frame, tiles: chunk })?;
                    }
                    Message::Grant { tiles, .. } if me != 0 => {
                        asked = false;
                        if tiles.is_empty() {
                            exhausted = true;
                        } else {
                            reserve.push_back(tiles);
                        }
                    }
                    Message::Tile { tile, rgba, depth, colors, ao, .. } if me == 0 => {
                        let pasted = tile_pixels(tile, rgba, &depth, &colors, &ao)
                            .is_some_and(|t| gather.as_mut().is_some_and(|g| g.paste(&t)));
                        if !pasted {
                            return Err(Fault::Damaged { rank: from, why: format!("tile {tile} of another size") });
                        }
                    }
                    Message::Done { report, .. } if me == 0 => reports[from] = Some(report),
                    other => {
                        return Err(Fault::Damaged { rank: from, why: format!("{other:?} out of turn") });
                    }
                }
            }
            if traced && traced_at.is_none() {
                traced_at = Some(Instant::now());
            }
            if traced {
                match gather.as_ref() {
                    None => {
                        let (seconds, rays) = *tracing.lock().unwrap_or_else(|e| e.into_inner());
                        let r = RankReport { tiles: my_tiles, rays, trace: seconds.as_secs_f64() };
                        self.send(0, Message::Done { frame, report: r })?;
                        self.flush(frame)?;
                        report.tiles = my_tiles;
                        report.wait += traced_at.map_or(Duration::ZERO, |t| t.elapsed());
                        return Ok(None);
                    }
                    Some(g) if g.count == tiles && (1..size).all(|r| reports[r].is_some()) => {
                        let (seconds, _) = *tracing.lock().unwrap_or_else(|e| e.into_inner());
                        let mut times = vec![seconds.as_secs_f64()];
                        times.extend(reports[1..].iter().flatten().map(|r| r.trace));
                        let known: Vec<Option<f64>> = times.iter().map(|&t| Some(t)).collect();
                        if !self.master.traces(0) {
                            times.remove(0);
                        }
                        report.imbalance = Some(imbalance(&times));
                        report.tiles = my_tiles;
                        report.wait += traced_at.map_or(Duration::ZERO, |t| t.elapsed());
                        self.master.end(&known);
                        let g = gather.take().expect("rank 0 gathers");
                        return Ok(Some(g.finish()));
                    }
                    Some(_) => {}
                }
            }
            if !busy {
                // Silent past the limit: on rank 0, ranks that have not finished; on another
                // rank, the master, while this rank's tracer waits for tiles.
                let silent = last_heard.elapsed() > self.limit();
                let unfinished: Vec<usize> = (1..size).filter(|&r| reports[r].is_none()).collect();
                if silent && me == 0 && !unfinished.is_empty() {
                    let waited = last_heard.elapsed();
                    return Err(Fault::Silent { ranks: unfinished, waited, frame, waiting_for: "tiles" });
                }
                if silent && me != 0 && tracer_waits {
                    let waited = last_heard.elapsed();
                    return Err(Fault::Silent { ranks: vec![0], waited, frame, waiting_for: "tiles to trace" });
                }
            }
        }
    }

    /// A rank other than 0: the display rank's picture of `frame`, and the time waited for it
    /// (bounded).
    fn await_picture(&mut self, frame: u64) -> Result<(Rendered, Duration), Fault> {
        let start = Instant::now();
        loop {
            match self.receive(frame)? {
                Some((from, Message::Picture { width, height, rgba, depth, .. })) => {
                    let p = picture(width, height, rgba, &depth)
                        .ok_or_else(|| Fault::Damaged { rank: from, why: "a picture of another size".into() })?;
                    return Ok((p, start.elapsed()));
                }
                Some((from, other)) => {
                    return Err(Fault::Damaged { rank: from, why: format!("{other:?} out of turn") });
                }
                None if start.elapsed() > self.limit() => {
                    let waited = start.elapsed();
                    return Err(Fault::Silent { ranks: vec![0], waited, frame, waiting_for: "the picture" });
                }
                None => std::thread::sleep(IDLE),
            }
        }
    }

    /// Waits until every send has left (bounded).
    fn flush(&mut self, frame: u64) -> Result<(), Fault> {
        let start = Instant::now();
        while !self.transport.flushed().map_err(Fault::Transport)? {
            if start.elapsed() > self.limit() {
                return Err(Fault::Silent {
                    ranks: vec![0],
                    waited: start.elapsed(),
                    frame,
                    waiting_for: "its tiles to be taken",
                });
            }
            std::thread::sleep(IDLE);
        }
        Ok(())
    }
}

/// Rank 0's picture of a pass, its colours before rounding when kept, and its AO apart when
/// denoised.
type Gathered = (Rendered, Option<Vec<glam::Vec4>>, Option<Vec<AoPixel>>);

/// What every rank traces this frame.
struct Shared<'a> {
    frame: u64,
    merged: &'a Frame,
    /// Its accumulation key (`Renderer::accumulation_key`), and which pass this is under it.
    key: Option<u64>,
    pass: u32,
    /// Tiles carry colours before rounding (`Renderer::linear`), and AO apart (`denoises`).
    linear: bool,
    ao: bool,
}

/// The message loop's ends of the channels to the tracer.
struct Lanes<'a> {
    events: Receiver<TracerEvent>,
    grants: Sender<Option<Vec<u32>>>,
    traced: &'a AtomicBool,
}

/// What the tracer tells the message loop.
enum TracerEvent {
    Ask,
    Tile(TilePixels),
}

/// The tracer's ends: it asks for tiles and hands them back through the message loop.
struct ChannelWork<'a> {
    events: Mutex<Sender<TracerEvent>>,
    grants: Mutex<Receiver<Option<Vec<u32>>>>,
    abort: &'a AtomicBool,
}

impl TileWork for ChannelWork<'_> {
    fn next(&self) -> Option<Vec<u32>> {
        let grants = self.grants.lock().unwrap_or_else(|e| e.into_inner());
        self.events.lock().unwrap_or_else(|e| e.into_inner()).send(TracerEvent::Ask).ok()?;
        loop {
            match grants.recv_timeout(Duration::from_millis(20)) {
                Ok(g) => return g,
                Err(RecvTimeoutError::Timeout) if !self.abort.load(Ordering::Acquire) => {}
                Err(_) => return None,
            }
        }
    }

    fn done(&self, pixels: TilePixels) {
        let _ = self.events.lock().unwrap_or_else(|e| e.into_inner()).send(TracerEvent::Tile(pixels));
    }
}

/// Rank 0's picture, tile by tile.
struct Gather {
    grid: TileGrid,
    rgba: Vec<u8>,
    depth: Vec<f32>,
    colors: Option<Vec<glam::Vec4>>,
    ao: Option<Vec<AoPixel>>,
    have: Vec<bool>,
    count: u32,
}

impl Gather {
    fn new(grid: TileGrid, linear: bool, ao: bool) -> Gather {
        let n = grid.width as usize * grid.height as usize;
        Gather {
            grid,
            rgba: vec![0; 4 * n],
            depth: vec![1.0; n],
            colors: linear.then(|| vec![glam::Vec4::ZERO; n]),
            ao: ao.then(|| vec![AoPixel::NONE; n]),
            have: vec![false; grid.count() as usize],
            count: 0,
        }
    }

    fn paste(&mut self, t: &TilePixels) -> bool {
        let image = LayersMut {
            rgba: &mut self.rgba,
            depth: &mut self.depth,
            colors: self.colors.as_deref_mut(),
            ao: self.ao.as_deref_mut(),
        };
        if !self.grid.paste(t, image) {
            return false;
        }
        if !std::mem::replace(&mut self.have[t.tile as usize], true) {
            self.count += 1;
        }
        true
    }

    fn finish(self) -> Gathered {
        let (width, height) = (self.grid.width, self.grid.height);
        (Rendered { width, height, rgba: self.rgba, depth: self.depth }, self.colors, self.ao)
    }
}

/// The meshes and textures a frame draws with.
fn ids_of(frame: &Frame) -> (std::collections::HashSet<u64>, std::collections::HashSet<u64>) {
    let meshes = frame.instances.iter().map(|i| i.mesh.id).collect();
    let textures = frame.surfaces.iter().filter_map(|s| s.texturing.as_ref()).map(|t| t.texture.version).collect();
    (meshes, textures)
}
