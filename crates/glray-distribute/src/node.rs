//! One rank's part in a frame (`Node::frame`), image-parallel over a replicated scene:
//!
//! 1. every rank sends the frame it captured to every other (meshes and textures the others
//!    lack go with it, once: `glray_scene::encode`), with the part of the window its own data
//!    covers, and merges all of them in rank order (`glray_scene::merge`): every rank holds the
//!    same whole scene;
//! 2. the window is cut into a band of rows per rank that traces (`bands`); rank 0's master
//!    hands out tiles, each rank's own band's first (`Master`, on rank 0's link); each rank
//!    traces what it is given on its threads and sends the rows of each finished tile to the
//!    ranks whose bands hold them or whose denoising reads them;
//! 3. each rank adds its band's pass to the ones before and denoises its AO (the rows of the
//!    last frame its pixels follow back into fetched from the ranks that held them: bit for
//!    bit what one process does with the whole frame), then sends every rank the part of its
//!    band that rank's data covers (rank 0, the display, gets all of it): a sort-last
//!    compositor (IceT) takes a rank's pixels only where its own data projects.
//!
//! Nothing of a frame is finished on one rank alone. Messages move on the rank's link
//! (`link`: a thread of its own, or the host's thread where MPI allows no other), the tracing
//! on the tracer's threads, and every wait on another rank has a time limit: a rank that
//! stops answering ends the frame with a `Fault` naming it, never a hang.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use glray_render::denoise::{AoPixel, Past};
use glray_render::tiles::{TileGrid, TilePixels};
use glray_render::{Rendered, Renderer};
use glray_scene::encode::{decode, encode, ObjectStore};
use glray_scene::frame::Frame;

use crate::assembly::{cut, BandRows, Canvas, Piece};
use crate::bands::Bands;
use crate::link::{Event, Link};
use crate::master::{imbalance, Master};
use crate::pack::{Compression, Packed};
use crate::paging::{Missing, Paging, PagingReport, PagingSetup, Resident};
use crate::protocol::{packed, unpacked, Message, RankReport, Rect};
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
                     died, skipped the frame or lost its link",
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
    /// Bytes sent and received on the wire, and what they came to before compression.
    pub bytes_sent: u64,
    pub bytes_received: u64,
    pub raw_sent: u64,
    pub raw_received: u64,
    /// Pixels other ranks traced of this frame (for bytes per pixel).
    pub pixels_elsewhere: u64,
    /// Time spent waiting for other ranks: for their scenes, for tiles, at the end.
    pub wait: Duration,
    /// Step 1: this rank's scene sent, every other rank's received, decoded and merged (on the
    /// first frame, the replication of every mesh).
    pub exchange: Duration,
    /// This rank's tracing of its tiles.
    pub trace: Duration,
    /// Its band: waiting for the rows of it traced elsewhere, then adding the pass up and
    /// denoising it.
    pub band_wait: Duration,
    pub band: Duration,
    /// Compressing and decompressing messages (`mpi_compression`), on any of its threads.
    pub pack: Duration,
    pub unpack: Duration,
    /// Pixels of the picture other ranks sent this rank (its part: `mpi_picture`).
    pub picture_pixels: u64,
    /// Slowest rank's tracing time over the mean (rank 0 only).
    pub imbalance: Option<f64>,
    /// The picture was the last one's again (converged), or traced by rank 0 alone.
    pub untraced: bool,
    /// What paging did (`distribute = paged`).
    pub paging: Option<PagingReport>,
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
            raw_sent: self.raw_sent + later.raw_sent,
            raw_received: self.raw_received + later.raw_received,
            pixels_elsewhere: self.pixels_elsewhere + later.pixels_elsewhere,
            wait: self.wait + later.wait,
            exchange: self.exchange + later.exchange,
            trace: self.trace + later.trace,
            band_wait: self.band_wait + later.band_wait,
            band: self.band + later.band,
            pack: self.pack + later.pack,
            picture_pixels: self.picture_pixels + later.picture_pixels,
            unpack: self.unpack + later.unpack,
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

/// Whether rank 0 traces too (`Shared`, the default) or only hands out tiles and shows the
/// picture (`Dedicated`); or, as the paper ran it, rank 0 the display and rank 1 the master,
/// neither tracing (`Paper`: the other ranks trace).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Roles {
    #[default]
    Shared,
    Dedicated,
    Paper,
}

/// How long a rank waits for another: `fixed` (the setting `mpi_timeout`) or, when not set,
/// `FIRST_FRAME_LIMIT`, then the last frame's time plus `SLACK`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Limits {
    pub fixed: Option<Duration>,
}

/// Which part of the shared picture a rank other than 0 is sent: what its own data covers
/// (`Own`: what a sort-last compositor takes from it) or the whole window.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum PictureParts {
    #[default]
    Own,
    Whole,
}

/// How a rank's node is set up (the `mpi_*` settings).
#[derive(Debug, Clone, Copy)]
pub struct Setup {
    pub limits: Limits,
    pub roles: Roles,
    /// Its messages move on a thread of their own (MPI_THREAD_MULTIPLE), else on the host's.
    pub threaded: bool,
    /// How long the link waits between polls of MPI when it has nothing to do (0: it spins).
    pub poll: Duration,
    pub compression: Compression,
    pub parts: PictureParts,
    /// Paged meshes (`distribute = paged`), else every rank holds every mesh.
    pub paging: Option<PagingSetup>,
    /// The memory a rank may use (`memory_mb`, or its cgroup's limit): replicated, a scene that
    /// would not fit stops the sharing with a message naming paging.
    pub memory_limit: Option<u64>,
    /// Where tiles go first (`mpi_tiles`; read where tiles are handed out).
    pub tiles: TileHomes,
}

/// Which rank each tile goes to first (`mpi_tiles`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TileHomes {
    /// The rank whose band of rows holds it: every frame the same tiles on the same rank, so
    /// that what it holds for them (paging's cache) stays warm and its rows cross no link.
    Bands,
    /// A rank drawn at random for each tile and frame: the comparison coherence is measured
    /// against.
    Random,
}

/// Tile `tile`'s rank of `tracing` in frame `frame`, drawn at random (`TileHomes::Random`),
/// the same on any machine (the tracer's own hash of the frame and tile).
fn random_home(frame: u64, tile: usize, tracing: &[usize]) -> usize {
    let h = glray_render::sampling::hash(&[frame as u32, (frame >> 32) as u32, tile as u32]);
    tracing[h as usize % tracing.len().max(1)]
}

impl Default for Setup {
    fn default() -> Setup {
        Setup {
            limits: Limits::default(),
            roles: Roles::Shared,
            threaded: true,
            poll: DEFAULT_POLL,
            compression: Compression::default(),
            parts: PictureParts::Own,
            paging: None,
            memory_limit: None,
            tiles: TileHomes::Bands,
        }
    }
}

/// The link's wait between polls of MPI when it has nothing to do (docs/distributed.md
/// measures it against a spin, which is what a blocking probe costs).
pub const DEFAULT_POLL: Duration = Duration::from_micros(1000);

/// A rank of the job: its link, what it has sent and been sent, the pictures it returned.
pub struct Node {
    link: Link,
    frame: u64,
    agreement: Agreement,
    setup: Setup,
    /// The ranks that trace.
    tracing: Vec<usize>,
    /// What every other rank holds of this rank's meshes and textures.
    sent: ObjectStore,
    /// What this rank holds of each rank's.
    held: Vec<ObjectStore>,
    /// The meshes joined from the ranks' pieces of one mesh.
    joined: glray_scene::join::Joined,
    /// Pixels of the picture other ranks have sent this rank, all told (`FrameReport::picture_pixels`).
    picture_pixels: u64,
    /// Messages of frames this rank has not reached yet.
    ahead: VecDeque<(usize, Message)>,
    /// The accumulation key of the last frame and the passes traced under it.
    run: Option<(u64, u32)>,
    last_frame: Option<Duration>,
    /// Rank 0: settings changes to hand on with the next frame (`announce`).
    announced: Announced,
    /// Other ranks: how to make rank 0's changes (`on_settings`).
    hook: Option<SettingsHook>,
    /// The picture this rank returned last, shown again while it has converged.
    last_picture: Option<Rendered>,
    /// Whether the last frame that changed a renderer was traced by all (bands) or by rank 0
    /// alone: the passes and AO history of the one do not carry over to the other.
    last_kind: Option<Kind>,
    /// Its pager, paging (`Setup::paging`).
    paging: Option<Arc<Paging>>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Shared,
    Alone,
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

/// What a byte of a scene message takes on a replicated rank: the decoded meshes, the meshes
/// the ranks' pieces join into, and their tree (the 1M isosurface: ~6, less the rank's memory
/// before it).
const REPLICATED_BYTES_A_SCENE_BYTE: u64 = 4;

/// How long a wait for the next message lasts before the limits are looked at again.
const WAKE: Duration = Duration::from_millis(2);
/// The same while this rank's tracer runs (its tiles and its end wake the wait).
const TRACER_WAKE: Duration = Duration::from_millis(50);

/// What the frame's thread is given: a message of this frame, a tile this rank's tracer
/// traced, or the tracer done.
enum Incoming {
    Message(usize, Message),
    Tile(TilePixels),
    Traced,
}

impl Node {
    pub fn new<T: Transport + Send + 'static>(transport: T, agreement: Agreement, setup: Setup) -> Node {
        let size = transport.size();
        let mut master = Master::new(size);
        match setup.roles {
            Roles::Shared => {}
            Roles::Dedicated => master.leave_out(0),
            Roles::Paper => {
                master.leave_out(0);
                if size > 2 {
                    master.leave_out(1);
                }
            }
        }
        let tracing = master.tracing();
        // The master's queue lives on the rank that hands out tiles: rank 1 in the paper's
        // roles (with three ranks or more), else rank 0.
        let master_rank = if setup.roles == Roles::Paper && size > 2 { 1 } else { 0 };
        let own_master = (transport.rank() == master_rank).then_some(master);
        let rank = transport.rank();
        let mut link =
            Link::start(Box::new(transport), own_master, master_rank, setup.threaded, setup.poll, setup.compression);
        let paging = setup.paging.map(|p| Arc::new(Paging::new(rank, p)));
        if let Some(p) = &paging {
            // (A link that has ended fails the first frame's sends as well.)
            let _ = link.page(p.clone());
        }
        Node {
            link,
            frame: 0,
            agreement,
            setup,
            tracing,
            sent: ObjectStore::default(),
            held: (0..size).map(|_| ObjectStore::default()).collect(),
            joined: Default::default(),
            picture_pixels: 0,
            ahead: VecDeque::new(),
            run: None,
            last_frame: None,
            announced: Announced::default(),
            hook: None,
            last_picture: None,
            last_kind: None,
            paging,
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
        self.link.rank()
    }

    pub fn size(&self) -> usize {
        self.link.size()
    }

    /// The rank whose master hands out tiles.
    fn master_rank(&self) -> usize {
        if self.setup.roles == Roles::Paper && self.size() > 2 {
            1
        } else {
            0
        }
    }

    /// The time limit of any wait on another rank this frame.
    pub fn limit(&self) -> Duration {
        self.setup.limits.fixed.unwrap_or_else(|| self.last_frame.map_or(FIRST_FRAME_LIMIT, |t| t + SLACK))
    }

    fn send(&mut self, to: usize, message: Message) -> Result<(), Fault> {
        self.link.send(to, message).map_err(Fault::Transport)
    }

    /// The next message of frame `frame`, or tile or end of this rank's tracer, waiting at most
    /// `wait` for it: messages of earlier frames (a frame this rank gave up on) are dropped,
    /// those of later ones kept for then.
    fn receive(&mut self, frame: u64, wait: Duration) -> Result<Option<Incoming>, Fault> {
        if let Some(k) = self.ahead.iter().position(|(_, m)| m.frame() == frame) {
            return Ok(self.ahead.remove(k).map(|(from, m)| Incoming::Message(from, m)));
        }
        let start = Instant::now();
        loop {
            let left = wait.saturating_sub(start.elapsed());
            match self.link.receive(left) {
                Some(Event::Message(from, message)) => match message.frame() {
                    f if f == frame => return Ok(Some(Incoming::Message(from, message))),
                    f if f > frame => self.ahead.push_back((from, message)),
                    _ => {}
                },
                Some(Event::Tile(t)) => return Ok(Some(Incoming::Tile(t))),
                Some(Event::Traced) => return Ok(Some(Incoming::Traced)),
                Some(Event::Failed(why)) => return Err(Fault::Transport(why)),
                None => return Ok(None),
            }
            if start.elapsed() >= wait {
                return Ok(None);
            }
        }
    }

    /// The next message of frame `frame` (waiting at most `wait`); anything else is out of turn.
    fn message(&mut self, frame: u64, wait: Duration) -> Result<Option<(usize, Message)>, Fault> {
        match self.receive(frame, wait)? {
            Some(Incoming::Message(from, m)) => Ok(Some((from, m))),
            Some(_) => Err(Fault::Damaged { rank: self.rank(), why: "a tile after its tracer was done".into() }),
            None => Ok(None),
        }
    }

    /// Traces `mine` (this rank's captured frame) with every other rank's, and returns this
    /// rank's picture: the part of the frame its data covers (rank 0: all of it), over its
    /// own background; None when `present` is false (a pass of a batch frame before its
    /// last: only the last is shown). `previous` is the picture under a frame that does not
    /// clear.
    pub fn frame(
        &mut self,
        mine: &Frame,
        previous: Option<&Rendered>,
        renderer: &mut Renderer,
        pool: Option<&rayon::ThreadPool>,
        present: bool,
    ) -> Result<(Option<Rendered>, FrameReport), Fault> {
        let frame = self.frame;
        self.frame += 1;
        let started = Instant::now();
        let counted = self.link.counters();
        let packing = crate::pack::spent();
        let pictured = self.picture_pixels;
        let mut report = FrameReport { frame, ..FrameReport::default() };
        if let Some(p) = &self.paging {
            let pager: Arc<dyn glray_render::paged::Pager> = p.clone();
            renderer.set_pager(Some(pager));
            p.set_limit(self.limit());
        }
        let want = if self.rank() == 0 || self.setup.parts == PictureParts::Whole {
            let (w, h) = mine.size();
            (w > 0 && h > 0).then_some(Rect { x: 0, y: 0, width: w, height: h })
        } else {
            glray_scene::covered::covered(mine).map(|(x, y, width, height)| Rect { x, y, width, height })
        };
        let (merged, wants, waited) = self.exchange(frame, mine, want, renderer)?;
        report.wait += waited;
        report.exchange = started.elapsed();
        let (w, h) = merged.size();
        let key = renderer.accumulation_key(&merged, w, h);
        let pass = match (key, self.run) {
            (Some(k), Some((run, n))) if k == run => n,
            _ => 0,
        };
        let me = self.rank();
        let picture = if w > 0 && h > 0 && pass >= renderer.converged_passes() && self.last_picture.is_some() {
            // Converged: every rank shows the picture it showed last.
            report.untraced = true;
            renderer.shown_again(merged.triangle_count() as u64);
            self.last_picture.clone()
        } else if w == 0 || h == 0 || merged.is_empty() || !Renderer::shares(&merged) {
            // Nothing to trace (rank 0 shows what the frame cleared to), or a frame drawn over
            // the last or in several viewports: rank 0 renders it alone, as one process would,
            // and sends each rank its part.
            report.untraced = true;
            self.kind(Kind::Alone, renderer);
            self.run = None;
            let mut canvas = Canvas::new(background(mine, &renderer.options), wants[me]);
            if me == 0 {
                let whole = renderer.render(&merged, w, h, previous);
                if present {
                    for (r, want) in wants.iter().enumerate().skip(1) {
                        if let Some(part) = want.filter(|_| whole.width == w && whole.height == h) {
                            let (rgba, depth) = cut(&whole, 0, part);
                            let how = self.link.compression();
                            let m = Message::Part {
                                frame,
                                rect: part,
                                rgba: packed(&rgba, how),
                                depth: packed(&depth, how),
                            };
                            self.send(r, m)?;
                        }
                    }
                }
                canvas.picture = whole;
            } else {
                // Counted all the same: every rank's AO rays stay rank 0's.
                renderer.pass_frame(merged.triangle_count() as u64);
                if present {
                    let waited = self.await_parts(frame, &mut canvas)?;
                    report.wait += waited;
                }
            }
            Some(canvas.picture)
        } else {
            self.kind(Kind::Shared, renderer);
            self.run = key.map(|k| (k, pass + 1));
            let (linear, ao) = (renderer.linear(key), renderer.denoises());
            let shared = Shared { frame, merged: &merged, key, pass, linear, ao, present };
            let canvas = Canvas::new(background(mine, &renderer.options), wants[me]);
            Some(self.trace(&shared, &wants, canvas, renderer, pool, &mut report)?)
        };
        if let Some(p) = &self.paging {
            report.paging = Some(p.take_report());
            match p.take_failure() {
                Some(Missing::Late { owner }) => {
                    let waited = self.limit();
                    return Err(Fault::Silent {
                        ranks: vec![owner],
                        waited,
                        frame,
                        waiting_for: "a block of its data",
                    });
                }
                Some(Missing::Refused { owner, why }) => return Err(Fault::Damaged { rank: owner, why }),
                None => {}
            }
        }
        if !report.untraced {
            self.last_frame = Some(started.elapsed());
        }
        let now = self.link.counters();
        (report.bytes_sent, report.bytes_received) = (now[0] - counted[0], now[1] - counted[1]);
        (report.raw_sent, report.raw_received) = (now[2] - counted[2], now[3] - counted[3]);
        let packed = crate::pack::spent();
        (report.pack, report.unpack) = (packed.0 - packing.0, packed.1 - packing.1);
        report.picture_pixels = self.picture_pixels - pictured;
        if present {
            self.last_picture = picture.clone();
            Ok((picture, report))
        } else {
            Ok((None, report))
        }
    }

    /// A frame of kind `kind` on the ranks: a switch between frames all ranks trace in bands and
    /// frames rank 0 renders alone starts the passes and AO history afresh on every rank (each
    /// kind keeps them in its own shape).
    fn kind(&mut self, kind: Kind, renderer: &mut Renderer) {
        if self.size() > 1 && self.last_kind.is_some_and(|k| k != kind) {
            renderer.restart();
        }
        self.last_kind = Some(kind);
    }

    /// Step 1: every rank's frame to every rank, merged in rank order; what part of the picture
    /// each rank wants; and the time waited.
    fn exchange(
        &mut self,
        frame: u64,
        mine: &Frame,
        want: Option<Rect>,
        renderer: &mut Renderer,
    ) -> Result<(Frame, Vec<Option<Rect>>, Duration), Fault> {
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
        let mut wants = vec![None; size];
        wants[me] = want;
        // Paging: the meshes it pages go as stand-ins, their layouts first.
        let paged_mine;
        let mine = match &self.paging {
            Some(p) => {
                let (f, layouts) = p.own_frame(mine, frame);
                if !layouts.is_empty() {
                    let m = Message::Layouts { frame, layouts };
                    for r in (0..size).filter(|&r| r != me) {
                        self.send(r, m.clone())?;
                    }
                }
                paged_mine = f;
                &paged_mine
            }
            None => mine,
        };
        let mut own_raw = 0;
        if size > 1 {
            let scene = encode(mine, &mut self.sent);
            own_raw = scene.len() as u64;
            // Packed once for every rank (the first frame's may be hundreds of megabytes).
            let scene = Packed::new(&scene, 4, self.link.compression());
            let m = Message::Scene { frame, settings: self.agreement.settings, want, scene };
            for r in (0..size).filter(|&r| r != me) {
                self.send(r, m.clone())?;
            }
        }
        // What the others hold of ours is what this frame draws (the rest they forget, below).
        let (meshes, textures) = ids_of(mine);
        self.sent.retain(&meshes, &textures);
        let mut scenes: Vec<Option<Packed>> = vec![None; size];
        // The master's first tiles and other ranks' rows may come before the last scene: kept
        // for the tracing.
        let mut early = Vec::new();
        let begun = Instant::now();
        let mut last_heard = Instant::now();
        while scenes.iter().enumerate().any(|(r, s)| r != me && s.is_none()) {
            match self.message(frame, WAKE)? {
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
                Some((from, Message::Scene { settings, want, scene, .. })) => {
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
                    wants[from] = want;
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
                }
            }
        }
        let waited = begun.elapsed();
        if let (None, Some(limit)) = (&self.paging, self.setup.memory_limit) {
            // Every rank weighs the same scenes: all stop together, rather than one be killed.
            let raw: u64 = scenes.iter().flatten().map(|p| p.sizes().0).sum::<u64>() + own_raw;
            let need = glray_core::memory::resident() + REPLICATED_BYTES_A_SCENE_BYTE * raw;
            if need > limit {
                let mb = |b: u64| b >> 20;
                return Err(Fault::Refused {
                    rank: me,
                    why: format!(
                        "every rank's scene on every rank (distribute = replicated) would take about {} MB, over \
                         this rank's memory limit of {} MB (memory_mb, or its share of its cgroup's): with distribute = paged \
                         each rank keeps its own meshes and a cache of a share of the others' (cache_fraction)",
                        mb(need),
                        mb(limit)
                    ),
                });
            }
        }
        for m in early.into_iter().rev() {
            self.ahead.push_front(m);
        }
        let mut frames = Vec::with_capacity(size);
        for (r, scene) in scenes.into_iter().enumerate() {
            if r == me {
                frames.push(mine.clone());
                continue;
            }
            let damaged = |why: String| Fault::Damaged { rank: r, why: format!("a scene glray cannot read: {why}") };
            let bytes = scene.expect("every scene is in").unpack().map_err(damaged)?;
            let f = decode(&bytes, &mut self.held[r]).map_err(|e| damaged(e.to_string()))?;
            let (meshes, textures) = ids_of(&f);
            self.held[r].retain(&meshes, &textures);
            frames.push(f);
        }
        // Pieces of one mesh the ranks drew under one transform: one mesh again, one tree.
        let ranks: Vec<usize> =
            frames.iter().enumerate().flat_map(|(r, f)| std::iter::repeat_n(r, f.instances.len())).collect();
        let mut merged = glray_scene::merge::merge(frames);
        match &self.paging {
            Some(p) => {
                self.joined.join_with(&mut merged.instances, &ranks, |pieces| p.join(pieces, frame));
                p.retain(&merged, frame);
                match p.setup().resident {
                    Resident::All => p.fetch_all(&merged),
                    Resident::Fetch => p.prefetch(),
                }
            }
            None => self.joined.join(&mut merged.instances, &ranks),
        }
        Ok((merged, wants, waited))
    }

    /// Steps 2 and 3: this rank's share traced on its threads while this thread routes the
    /// tiles; its band added up and denoised; its picture.
    fn trace(
        &mut self,
        shared: &Shared,
        wants: &[Option<Rect>],
        canvas: Canvas,
        renderer: &mut Renderer,
        pool: Option<&rayon::ThreadPool>,
        report: &mut FrameReport,
    ) -> Result<Rendered, Fault> {
        let (w, h) = shared.merged.size();
        // Tiles small enough for every tracing rank to get its share in several chunks.
        let grid = TileGrid::for_ranks(w, h, self.tracing.len());
        let bands = Bands::new(w as usize, h as usize, &self.tracing);
        report.tiles_total = grid.count();
        let me = self.rank();
        let mine = bands.of(me).map(|b| BandRows::new(b, shared.linear, shared.ao));
        // The tracer's threads: its tiles, then its band's adding up and denoising (on the
        // threads `threads` gives the rank, not rayon's pool of every core).
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
        let mut state = FrameState {
            shared,
            pool,
            grid,
            bands,
            band: mine,
            history: HistoryState::default(),
            canvas,
            wants,
            reports: vec![None; self.size()],
            finished: vec![false; self.size()],
            tiles_here: 0,
            pixels_here: 0,
            pending_rows: Vec::new(),
        };
        if me == self.master_rank() {
            let mut homes = state.bands.homes(&grid);
            if self.setup.tiles == TileHomes::Random && !self.tracing.is_empty() {
                for (t, h) in homes.iter_mut().enumerate() {
                    *h = random_home(shared.frame, t, &self.tracing);
                }
            }
            self.link.begin(shared.frame, homes).map_err(Fault::Transport)?;
        }
        // Phase 1: the tracer's tiles routed as they come, other ranks' rows taken in.
        let traces = self.tracing.contains(&me);
        let abort = AtomicBool::new(false);
        let tracing = Mutex::new((Duration::ZERO, 0u64));
        let done = Mutex::new(self.link.tracer_events());
        if !traces {
            // Rank 0 of the dedicated roles: nothing to trace (the frame counted all the same).
            renderer.pass_frame(shared.merged.triangle_count() as u64);
            let _ = done.lock().unwrap_or_else(|e| e.into_inner()).send(Event::Traced);
        }
        let limit = self.limit();
        let work = self.link.work(shared.frame, grid, &abort, limit);
        let starved = work.starved();
        let served = pool.in_place_scope(|s| {
            let tracer = &mut *renderer;
            let (work, tracing, done) = (&work, &tracing, &done);
            if traces {
                s.spawn(move |_| {
                    let start = Instant::now();
                    let stats = tracer.render_tiles(shared.merged, w, h, shared.pass, shared.linear, work);
                    *tracing.lock().unwrap_or_else(|e| e.into_inner()) = (start.elapsed(), stats.rays);
                    let _ = done.lock().unwrap_or_else(|e| e.into_inner()).send(Event::Traced);
                });
            }
            let r = self.route_while_tracing(&mut state, &starved);
            abort.store(r.is_err(), Ordering::Release);
            r
        });
        drop(work);
        served?;
        let (seconds, rays) = *tracing.lock().unwrap_or_else(|e| e.into_inner());
        let tiles = state.tiles_here;
        (report.trace, report.rays, report.tiles) = (seconds, rays, tiles);
        report.pixels_elsewhere = u64::from(w) * u64::from(h) - state.pixels_here;
        let mine_report = RankReport { tiles, rays, trace: seconds.as_secs_f64() };
        if me == self.master_rank() {
            state.reports[me] = Some(mine_report);
        } else {
            self.send(self.master_rank(), Message::Done { frame: shared.frame, report: mine_report })?;
        }
        // Phase 2: the band finished here, the picture's parts gathered.
        let band_start = Instant::now();
        self.finish(&mut state, renderer, report)?;
        report.band = band_start.elapsed().saturating_sub(report.band_wait);
        if me == self.master_rank() {
            let mut times: Vec<Option<f64>> = state.reports.iter().map(|r| r.map(|r| r.trace)).collect();
            let known: Vec<f64> = self.tracing.iter().filter_map(|&r| times[r]).collect();
            report.imbalance = Some(imbalance(&known));
            for (r, t) in times.iter_mut().enumerate() {
                if !self.tracing.contains(&r) {
                    *t = None;
                }
            }
            self.link.end(times).map_err(Fault::Transport)?;
        }
        Ok(state.canvas.picture)
    }
}

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
    /// The picture is shown (its parts sent): not a batch frame's pass before its last.
    present: bool,
}

/// A shared frame as it goes on this rank.
struct FrameState<'a> {
    shared: &'a Shared<'a>,
    pool: &'a rayon::ThreadPool,
    grid: TileGrid,
    bands: Bands,
    /// This rank's band, as its rows arrive (None: it has none).
    band: Option<BandRows>,
    history: HistoryState,
    canvas: Canvas,
    wants: &'a [Option<Rect>],
    /// The master's rank: every rank's report.
    reports: Vec<Option<RankReport>>,
    /// Where the link is inline: which ranks have done their part.
    finished: Vec<bool>,
    /// Tiles and pixels this rank traced.
    tiles_here: u32,
    pixels_here: u64,
    /// History rows fetched for the band, for the renderer once the tracer has let go of it.
    pending_rows: Vec<(usize, Vec<Past>)>,
}

/// The rows of the last frame this rank's band follows back into and does not hold: asked of
/// the ranks that held them, and their answers.
#[derive(Default)]
struct HistoryState {
    asked: bool,
    /// Answers awaited, per rank asked.
    awaited: Vec<(usize, u32)>,
}

impl Node {
    /// Phase 1 of a shared frame, until this rank's tracer has traced its last tile: each tile
    /// it traces sent in rows where they are needed (its own band's kept), and what other
    /// ranks send taken in.
    fn route_while_tracing(&mut self, state: &mut FrameState, starved: &AtomicBool) -> Result<(), Fault> {
        let frame = state.shared.frame;
        loop {
            // (Nothing here waits on another rank for long: the tracer's wait for tiles is
            // bounded, and so is every wait after it.)
            if starved.load(Ordering::Acquire) {
                let master = self.master_rank();
                return Err(Fault::Silent {
                    ranks: vec![master],
                    waited: self.limit(),
                    frame,
                    waiting_for: "tiles to trace",
                });
            }
            match self.receive(frame, TRACER_WAKE)? {
                Some(Incoming::Tile(t)) => self.route(state, t)?,
                Some(Incoming::Message(from, m)) => self.take(state, from, m)?,
                // (After its last tile, on the same channel.)
                Some(Incoming::Traced) => return Ok(()),
                None => {}
            }
        }
    }

    /// A tile this rank traced: its rows to the ranks whose bands hold them or read them.
    fn route(&mut self, state: &mut FrameState, t: TilePixels) -> Result<(), Fault> {
        let (x0, y0, tw, th) = state.grid.rect(t.tile);
        state.tiles_here += 1;
        state.pixels_here += (tw * th) as u64;
        let me = self.rank();
        let how = self.link.compression();
        let shared = state.shared;
        for (to, rows, whole) in state.bands.destinations(y0..y0 + th, shared.ao) {
            let at = (rows.start - y0) * tw..(rows.end - y0) * tw;
            let ao_of = |lit: bool| -> Vec<AoPixel> {
                t.ao.get(at.clone()).map_or_else(Vec::new, |a| {
                    if lit {
                        a.to_vec()
                    } else {
                        // The rows around a band: what guides its denoising, not what AO darkens.
                        a.iter().map(|p| AoPixel { lit: glam::Vec3::ZERO, ..*p }).collect()
                    }
                })
            };
            if to == me {
                let ao = if shared.ao { &t.ao[at.clone()] } else { &[][..] };
                let piece = Piece {
                    x: x0,
                    width: tw,
                    first: rows.start,
                    rows: rows.len(),
                    whole,
                    rgba: &t.rgba[4 * at.start..4 * at.end],
                    depth: &t.depth[at.clone()],
                    colors: if shared.linear { &t.colors[at.clone()] } else { &[] },
                    ao,
                };
                let band = state.band.as_mut().expect("rows for this rank: it has a band");
                if !band.paste(&piece) {
                    return Err(Fault::Damaged { rank: me, why: format!("tile {} of another size", t.tile) });
                }
                continue;
            }
            let m = Message::Rows {
                frame: shared.frame,
                tile: t.tile,
                first_row: rows.start as u32,
                rows: rows.len() as u32,
                full: whole,
                rgba: packed(if whole && !shared.linear { &t.rgba[4 * at.start..4 * at.end] } else { &[] }, how),
                depth: packed(if whole { &t.depth[at.clone()] } else { &[] }, how),
                colors: packed(if whole && shared.linear { &t.colors[at.clone()] } else { &[] }, how),
                ao: packed(&if shared.ao { ao_of(whole) } else { Vec::new() }, how),
            };
            self.send(to, m)?;
        }
        Ok(())
    }

    /// A message of this frame from rank `from`.
    fn take(&mut self, state: &mut FrameState, from: usize, m: Message) -> Result<(), Fault> {
        let damaged = |why: String| Fault::Damaged { rank: from, why };
        match m {
            Message::Rows { tile, first_row, rows, full, rgba, depth, colors, ao, .. } => {
                let (x, _, width, _) = state.grid.rect(tile.min(state.grid.count().saturating_sub(1)));
                let (rgba, depth, colors, ao) = (
                    rgba.unpack().map_err(damaged)?,
                    unpacked::<f32>(depth).ok_or_else(|| damaged("damaged depths".into()))?,
                    unpacked::<glam::Vec4>(colors).ok_or_else(|| damaged("damaged colours".into()))?,
                    unpacked::<AoPixel>(ao).ok_or_else(|| damaged("a damaged AO layer".into()))?,
                );
                let piece = Piece {
                    x,
                    width,
                    first: first_row as usize,
                    rows: rows as usize,
                    whole: full,
                    rgba: &rgba,
                    depth: &depth,
                    colors: &colors,
                    ao: &ao,
                };
                let pasted = tile < state.grid.count() && state.band.as_mut().is_some_and(|b| b.paste(&piece));
                if !pasted {
                    return Err(damaged(format!("rows {first_row}.. of tile {tile}, not for this rank's band")));
                }
            }
            Message::Part { rect, rgba, depth, .. } => self.paste_part(&mut state.canvas, from, rect, rgba, depth)?,
            Message::History { first, rows, held, past, .. } => {
                let past: Vec<Past> = unpacked(past).ok_or_else(|| damaged("damaged history rows".into()))?;
                if !held {
                    return Err(damaged(format!(
                        "no history of rows {first}..{} (it does not hold them)",
                        first + rows
                    )));
                }
                let Some(k) = state.history.awaited.iter().position(|(r, _)| *r == from) else {
                    return Err(damaged("history rows this rank did not ask for".into()));
                };
                state.history.awaited[k].1 -= 1;
                if state.history.awaited[k].1 == 0 {
                    state.history.awaited.remove(k);
                }
                state.pending_rows.push((first as usize, past));
            }
            Message::Done { report, .. } if from < state.reports.len() => state.reports[from] = Some(report),
            Message::Finished { .. } if from < state.finished.len() => state.finished[from] = true,
            other => return Err(damaged(format!("{other:?} out of turn"))),
        }
        Ok(())
    }
}

impl Node {
    /// Phase 2 of a shared frame: this rank's band added up and denoised once its rows are in
    /// (the last frame's rows it follows back into fetched first), its parts sent to the ranks
    /// that want them; until this rank's picture is whole (and, on the master's rank, every
    /// rank has reported).
    fn finish(
        &mut self,
        state: &mut FrameState,
        renderer: &mut Renderer,
        report: &mut FrameReport,
    ) -> Result<(), Fault> {
        let shared = state.shared;
        let (frame, me) = (shared.frame, self.rank());
        let start = Instant::now();
        let mut last_heard = Instant::now();
        let mut said_finished = false;
        loop {
            if state.band.as_ref().is_some_and(BandRows::complete) {
                if !state.history.asked {
                    report.band_wait = start.elapsed();
                    state.history.asked = true;
                    self.ask_history(state, renderer)?;
                }
                if state.history.awaited.is_empty() {
                    self.band_done(state, renderer)?;
                    last_heard = Instant::now();
                }
            }
            let band_done = state.band.is_none();
            let reports_due = me == self.master_rank() && self.tracing.iter().any(|&r| state.reports[r].is_none());
            let parts_due = shared.present && !state.canvas.complete();
            if band_done && !reports_due && !parts_due {
                if !self.link.is_inline() && self.paging.is_none() {
                    return Ok(());
                }
                // Glray's messages move only inside the host's GL calls here, or ranks fetch
                // each other's blocks: every rank stays until every other has done its part, so
                // that each is there to answer.
                if !said_finished {
                    said_finished = true;
                    state.finished[me] = true;
                    for r in (0..self.size()).filter(|&r| r != me) {
                        self.send(r, Message::Finished { frame })?;
                    }
                }
                if state.finished.iter().all(|&f| f) {
                    return Ok(());
                }
            }
            match self.message(frame, WAKE)? {
                Some((from, m)) => {
                    self.take(state, from, m)?;
                    last_heard = Instant::now();
                }
                None if last_heard.elapsed() > self.limit() => {
                    let waited = last_heard.elapsed();
                    let others: Vec<usize> = (0..self.size()).filter(|&r| r != me).collect();
                    let (ranks, waiting_for) = if !state.history.awaited.is_empty() {
                        (state.history.awaited.iter().map(|(r, _)| *r).collect(), "the last frame's denoising rows")
                    } else if !band_done {
                        (others, "the rows of its band traced elsewhere")
                    } else if parts_due {
                        (self.tracing.iter().copied().filter(|&r| r != me).collect(), "its part of the picture")
                    } else if reports_due {
                        (self.tracing.iter().copied().filter(|&r| state.reports[r].is_none()).collect(), "tiles")
                    } else {
                        ((0..self.size()).filter(|&r| !state.finished[r]).collect(), "the others to finish the frame")
                    };
                    return Err(Fault::Silent { ranks, waited, frame, waiting_for });
                }
                None => {}
            }
        }
    }

    /// The last frame's rows the band follows back into and does not hold, asked of the ranks
    /// whose bands held them (their bands were these bands: the window and ranks are the same,
    /// or nothing is followed).
    fn ask_history(&mut self, state: &mut FrameState, renderer: &Renderer) -> Result<(), Fault> {
        let band = state.band.as_ref().expect("a band");
        let Some(layer) = band.layer().filter(|_| state.shared.ao) else { return Ok(()) };
        let missing = renderer.history_missing(state.shared.merged, &band.band, layer);
        let mut asks: Vec<(usize, Vec<(u32, u32)>)> = Vec::new();
        for run in missing {
            // A run may lie across two bands: cut it where their owners change.
            let mut y = run.start;
            while y < run.end {
                let owner = state.bands.owner(y).unwrap_or(0);
                let mut end = y + 1;
                while end < run.end && state.bands.owner(end) == Some(owner) {
                    end += 1;
                }
                match asks.iter_mut().find(|(r, _)| *r == owner) {
                    Some((_, rows)) => rows.push((y as u32, end as u32)),
                    None => asks.push((owner, vec![(y as u32, end as u32)])),
                }
                y = end;
            }
        }
        for (owner, rows) in asks {
            state.history.awaited.push((owner, rows.len() as u32));
            self.send(owner, Message::HistoryAsk { frame: state.shared.frame, rows })?;
        }
        Ok(())
    }

    /// The band's rows are all here, and the rows of history it needs: its pass added up and
    /// denoised, its history kept for the other ranks to fetch, its parts sent.
    fn band_done(&mut self, state: &mut FrameState, renderer: &mut Renderer) -> Result<(), Fault> {
        let shared = state.shared;
        for (first, past) in state.pending_rows.drain(..) {
            renderer.take_history_rows(first, &past);
        }
        let (band, picture, colors, ao) = state.band.take().expect("a band").into_pass();
        let picture =
            state.pool.install(|| renderer.add_band_pass(shared.merged, shared.key, &band, picture, colors, ao));
        if shared.ao {
            self.link.publish(shared.frame, renderer.held_history()).map_err(Fault::Transport)?;
        }
        if !shared.present {
            return Ok(());
        }
        let me = self.rank();
        let how = self.link.compression();
        let rows = band.rows.start as u32..band.rows.end as u32;
        for (r, want) in state.wants.iter().enumerate() {
            let Some(part) = want.and_then(|w| w.rows(rows.clone())) else { continue };
            let (rgba, depth) = cut(&picture, band.rows.start, part);
            if r == me {
                if !state.canvas.paste(part, &rgba, &depth) {
                    return Err(Fault::Damaged { rank: me, why: format!("a part {part:?} outside its own") });
                }
            } else {
                let m = Message::Part {
                    frame: shared.frame,
                    rect: part,
                    rgba: packed(&rgba, how),
                    depth: packed(&depth, how),
                };
                self.send(r, m)?;
            }
        }
        Ok(())
    }

    /// A rank other than 0, in a frame rank 0 renders alone: its part of the picture, and the
    /// time waited for it (bounded).
    /// A part of the picture rank `from` sent, put in place (and counted).
    fn paste_part(
        &mut self,
        canvas: &mut Canvas,
        from: usize,
        rect: Rect,
        rgba: Packed,
        depth: Packed,
    ) -> Result<(), Fault> {
        self.picture_pixels += u64::from(rect.width) * u64::from(rect.height);
        let damaged = |why: String| Fault::Damaged { rank: from, why };
        let rgba = rgba.unpack().map_err(damaged)?;
        let depth = unpacked::<f32>(depth).ok_or_else(|| damaged("damaged depths".into()))?;
        if !canvas.paste(rect, &rgba, &depth) {
            return Err(damaged(format!("a part {rect:?} of the picture this rank did not ask for")));
        }
        Ok(())
    }

    fn await_parts(&mut self, frame: u64, canvas: &mut Canvas) -> Result<Duration, Fault> {
        let start = Instant::now();
        while !canvas.complete() {
            match self.message(frame, WAKE)? {
                Some((from, Message::Part { rect, rgba, depth, .. })) => {
                    self.paste_part(canvas, from, rect, rgba, depth)?;
                }
                Some((from, other)) => {
                    return Err(Fault::Damaged { rank: from, why: format!("{other:?} out of turn") });
                }
                None if start.elapsed() > self.limit() => {
                    return Err(Fault::Silent {
                        ranks: vec![0],
                        waited: start.elapsed(),
                        frame,
                        waiting_for: "the picture",
                    });
                }
                None => {}
            }
        }
        Ok(start.elapsed())
    }
}

/// What a rank shows where the shared picture is not sent to it: what its frame cleared to, at
/// the depth it cleared to (far), which a sort-last compositor passes over.
fn background(mine: &Frame, options: &glray_render::Options) -> Rendered {
    let (w, h) = mine.size();
    let clear = Frame {
        clear_color: mine.clear_color,
        cleared: true,
        depth_cleared: mine.depth_cleared,
        width: w,
        height: h,
        ..Frame::default()
    };
    glray_render::render(&clear, w, h, None, options)
}

/// The meshes and textures a frame draws with.
fn ids_of(frame: &Frame) -> (std::collections::HashSet<u64>, std::collections::HashSet<u64>) {
    let meshes = frame.instances.iter().map(|i| i.mesh.id).collect();
    let textures = frame.surfaces.iter().filter_map(|s| s.texturing.as_ref()).map(|t| t.texture.version).collect();
    (meshes, textures)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_at_random_reach_every_tracing_rank_and_change_with_the_frame() {
        let tracing = [0, 2, 3];
        let deal = |frame| (0..300).map(|t| random_home(frame, t, &tracing)).collect::<Vec<_>>();
        let first = deal(1);
        assert_eq!(first, deal(1), "the same deal for the same frame");
        assert_ne!(first, deal(2), "another frame, another deal");
        for r in tracing {
            let n = first.iter().filter(|&&h| h == r).count();
            assert!((60..140).contains(&n), "rank {r}: {n} of 300 tiles");
        }
        assert!(first.iter().all(|h| tracing.contains(h)), "only ranks that trace");
    }
}
