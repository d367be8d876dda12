//! A rank's pager (`glray_render::paged::Pager`): its own blocks, resident; the layouts of
//! every paged mesh, its own and the others' (`Message::Layouts`); other ranks' blocks fetched
//! when a ray reaches them, into the cache.
//!
//! A fetch is a request and a reply through the rank's MPI thread (`Asks`, then `arrived`):
//! one request a block at a time however many threads miss it (they wait on the same
//! `Pending`), requests to one owner sent together each round of the thread. The tracer's
//! thread that misses waits for its block (the blocking way, as GLuRay's render threads wait
//! on their one-sided reads), at most the frame's limit; a block that does not come fails the
//! frame with its owner named (`take_failure`).
//!
//! Parking (`PagingSetup::park`, `paging = park`): while the tracer traces a piece of the picture
//! in parking mode (`Pager::park`), a block not here is asked for and the piece goes on without
//! it, to be traced again later (`glray_render`'s parking), so that a thread's misses travel
//! together instead of one round trip after another. At most as many blocks as the cache holds
//! are on their way (their bytes wait outside the cache until a piece takes them); beyond, the
//! piece's retry waits for them as the blocking way does.
//!
//! Prefetching (`PagingSetup::prefetch`, `prefetch = true`): at the start of a frame the blocks
//! last frame's rays used that the cache no longer holds are asked for at once (`prefetch`),
//! so that they travel together while the frame starts; a ray that reaches one waits only if it
//! has not come yet. With the same tiles on the same rank frame after frame (`mpi_tiles =
//! bands`), those are the blocks the rank's rays are likeliest to need again.

use std::cell::RefCell;
use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, RwLock, Weak};
use std::time::{Duration, Instant};

use glam::Vec3;
use glray_render::paged::{Block, BlockRef, Layout, Pager};
use glray_scene::frame::Frame;
use glray_scene::instance::Instance;
use glray_scene::mesh::Mesh;
use rayon::prelude::*;

use super::blocks;
use super::cache::Cache;
use crate::protocol::{BlockEntry, LayoutEntry};

/// Whether other ranks' blocks are fetched as rays reach them (`Fetch`), or every block of the
/// frame is fetched before it is traced and kept (`All`, the debug mode `all-resident`: the
/// same blocks and trees, nothing remote while tracing: the reference paging is checked by).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Resident {
    Fetch,
    All,
}

/// The cache's budget: a share of every rank's blocks together (the paper's 1/F), or bytes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Budget {
    Fraction(f64),
    Bytes(u64),
}

/// How a rank pages (`distribute = paged` and its settings).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PagingSetup {
    pub resident: Resident,
    pub budget: Budget,
    /// About how many bytes a block holds (`block_kb`).
    pub block_bytes: usize,
    /// Whether rays that miss a block are parked (`paging = park`) or wait (`wait`).
    pub park: bool,
    /// Whether last frame's blocks are asked for as a frame starts (`prefetch`).
    pub prefetch: bool,
}

impl Default for PagingSetup {
    fn default() -> PagingSetup {
        PagingSetup {
            resident: Resident::Fetch,
            budget: Budget::Fraction(0.125),
            block_bytes: 128 * 1024,
            park: false,
            prefetch: false,
        }
    }
}

/// Sends a request for a block to its owner (the rank's link).
pub trait Asks: Send {
    fn ask(&self, owner: usize, key: u64) -> bool;
}

/// What paging did in a frame, on one rank (`Paging::take_report`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PagingReport {
    /// Blocks the tracer asked for (a ray reaching a block's box, a hit shaded), and of them
    /// its own, those in the cache, and those fetched (misses: one request each; `waits`
    /// more asked for a block already on its way).
    pub accesses: u64,
    pub resident: u64,
    pub cached: u64,
    pub misses: u64,
    pub waits: u64,
    pub evictions: u64,
    /// Bytes of blocks received, and the fetches' times from request to reply (ms).
    pub bytes_fetched: u64,
    pub fetch_mean_ms: f64,
    pub fetch_p99_ms: f64,
    pub fetch_max_ms: f64,
    /// Time the tracer's threads waited for blocks, all threads together.
    pub stall: Duration,
    /// Pieces of the picture set aside for a missing block and traced again (parking).
    pub parked: u64,
    /// Blocks asked for as the frame started (`prefetch`; not counted in `misses`), and of
    /// those that came, how many a ray then used.
    pub prefetched: u64,
    pub prefetch_used: u64,
    /// Blocks of this rank's sent to others, their bytes, and how many went compressed (the
    /// network behind: `mpi_compression` applies to blocks only then).
    pub served: u64,
    pub served_bytes: u64,
    pub served_packed: u64,
    /// Bytes the cache holds and may hold; blocks it took over its budget (all pinned).
    pub cache_bytes: u64,
    pub cache_capacity: u64,
    pub over: u64,
    /// Bytes of this rank's own blocks, and of every rank's.
    pub own_bytes: u64,
    pub scene_bytes: u64,
    /// This process's peak resident memory so far (VmHWM), bytes.
    pub peak_memory: u64,
}

impl PagingReport {
    /// Misses as a share of accesses (the paper's measure), in percent.
    pub fn miss_percent(&self) -> f64 {
        100.0 * self.misses as f64 / self.accesses.max(1) as f64
    }
}

/// Why a block could not be had (`Paging::take_failure`).
#[derive(Debug, Clone, PartialEq)]
pub enum Missing {
    /// Its owner did not answer within the limit.
    Late { owner: usize },
    /// It could not be asked for, or what its owner sent is no block.
    Refused { owner: usize, why: String },
}

/// A block on its way, asked for at `asked`.
struct Pending {
    state: Mutex<State>,
    changed: Condvar,
    asked: Instant,
    /// Asked for by `prefetch`, not by a ray.
    prefetched: bool,
}

#[derive(Default)]
enum State {
    #[default]
    Asked,
    /// Its bytes came (None: its owner does not hold it), at this time.
    Arrived(Option<Vec<u8>>, Instant),
    /// A thread is building its tree.
    Building,
    Ready(Arc<Block>),
    Failed,
}

/// An own mesh cut into blocks: the mesh (while the host holds it) and its stand-in.
struct OwnMesh {
    mesh: Weak<Mesh>,
    stand_in: Arc<Mesh>,
    keys: Vec<u64>,
}

/// A layout and the frame it was made for (layouts no frame names after it go).
struct Known {
    layout: Arc<Layout>,
    since: u64,
}

#[derive(Default)]
struct Counts {
    accesses: AtomicU64,
    resident: AtomicU64,
    cached: AtomicU64,
    misses: AtomicU64,
    waits: AtomicU64,
    evictions: AtomicU64,
    bytes_fetched: AtomicU64,
    stall_ns: AtomicU64,
    served: AtomicU64,
    served_bytes: AtomicU64,
    served_packed: AtomicU64,
    parked: AtomicU64,
    prefetched: AtomicU64,
    prefetch_used: AtomicU64,
}

/// What a piece traced in parking mode has met so far, on this thread (`Pager::park`): its
/// accesses, counted only if the piece need not be traced again (the retry counts them), and
/// whether a block was missing.
#[derive(Default)]
struct Attempt {
    accesses: u64,
    resident: u64,
    cached: u64,
    missed: bool,
}

thread_local! {
    /// The pieces this thread is tracing in parking mode, innermost last (a thread waiting
    /// inside one may be lent to another's work by rayon).
    static ATTEMPTS: RefCell<Vec<Attempt>> = const { RefCell::new(Vec::new()) };
}

/// Counts an access of the kind `kind` picks: on the piece in parking mode, or at once.
fn count(global: &AtomicU64, kind: fn(&mut Attempt) -> &mut u64) {
    let counted = ATTEMPTS.with(|a| a.borrow_mut().last_mut().map(|a| *kind(a) += 1).is_some());
    if !counted {
        global.fetch_add(1, Ordering::Relaxed);
    }
}

/// Whether this thread is tracing a piece in parking mode.
fn parking() -> bool {
    ATTEMPTS.with(|a| !a.borrow().is_empty())
}

/// A rank's paging: see the module.
pub struct Paging {
    setup: PagingSetup,
    rank: usize,
    /// How long a thread waits for a block.
    limit: Mutex<Duration>,
    own: RwLock<HashMap<u64, Arc<Block>>>,
    own_meshes: Mutex<HashMap<u64, OwnMesh>>,
    layouts: RwLock<HashMap<u64, Known>>,
    /// Every block a layout names: its owner and bytes.
    blocks: RwLock<HashMap<u64, (usize, u64)>>,
    cache: Mutex<Cache>,
    pending: Mutex<HashMap<u64, Arc<Pending>>>,
    asks: Mutex<Option<Box<dyn Asks>>>,
    counts: Counts,
    latencies: Mutex<Vec<f32>>,
    /// The other ranks' blocks last frame's rays used, first used first (for `prefetch`).
    last_frame: Mutex<Vec<u64>>,
    /// The first block that did not come this frame: its owner, and why.
    failure: Mutex<Option<Missing>>,
}

impl Paging {
    pub fn new(rank: usize, setup: PagingSetup) -> Paging {
        let capacity = match (setup.resident, setup.budget) {
            (Resident::All, _) => u64::MAX,
            (_, Budget::Bytes(b)) => b,
            (_, Budget::Fraction(_)) => 0,
        };
        Paging {
            setup,
            rank,
            limit: Mutex::new(Duration::from_secs(30)),
            own: RwLock::default(),
            own_meshes: Mutex::default(),
            layouts: RwLock::default(),
            blocks: RwLock::default(),
            cache: Mutex::new(Cache::new(capacity)),
            pending: Mutex::default(),
            asks: Mutex::new(None),
            counts: Counts::default(),
            latencies: Mutex::default(),
            last_frame: Mutex::default(),
            failure: Mutex::default(),
        }
    }

    pub fn setup(&self) -> PagingSetup {
        self.setup
    }

    /// Where requests for blocks go.
    pub fn connect(&self, asks: Box<dyn Asks>) {
        *lock(&self.asks) = Some(asks);
    }

    /// How long a thread waits for a block from now on (the frame's limit).
    pub fn set_limit(&self, limit: Duration) {
        *lock(&self.limit) = limit;
    }

    /// `mine` (this rank's frame `frame`) as the other ranks are sent it: each mesh it pages
    /// replaced by its stand-in, the mesh cut into blocks the first time it is drawn (their
    /// trees built on the rank's threads); and the layouts of those new meshes, for the other
    /// ranks. Own meshes this frame does not draw are forgotten, with their blocks.
    pub fn own_frame(&self, mine: &Frame, frame: u64) -> (Frame, Vec<LayoutEntry>) {
        let mut out = mine.clone();
        let mut meshes = lock(&self.own_meshes);
        let mut new: Vec<Arc<Mesh>> = Vec::new();
        for i in &mine.instances {
            let fresh = !meshes.contains_key(&i.mesh.id) && !new.iter().any(|m| m.id == i.mesh.id);
            if fresh && blocks::pages(&i.mesh, self.setup.block_bytes) {
                new.push(i.mesh.clone());
            }
        }
        let block_bytes = self.setup.block_bytes;
        let cut: Vec<(Arc<Mesh>, Vec<Block>)> = new
            .into_par_iter()
            .map(|m| {
                let parts = blocks::cut(&m, block_bytes);
                (m, parts.into_par_iter().map(Block::new).collect())
            })
            .collect();
        let mut entries = Vec::new();
        for (mesh, made) in cut {
            let refs: Vec<BlockRef> = made.iter().map(block_ref).collect();
            let stand_in = Arc::new(Mesh::stand_in(glray_scene::ids::next(), mesh.min, mesh.max));
            entries.push(LayoutEntry { mesh: stand_in.id, blocks: refs.iter().map(BlockEntry::from).collect() });
            {
                let mut own = write(&self.own);
                let mut known = write(&self.blocks);
                for (r, b) in refs.iter().zip(made) {
                    own.insert(r.key, Arc::new(b));
                    known.insert(r.key, (self.rank, r.bytes));
                }
            }
            write(&self.layouts)
                .insert(stand_in.id, Known { layout: Arc::new(Layout::new(refs.clone())), since: frame });
            let keys = refs.iter().map(|r| r.key).collect();
            meshes.insert(mesh.id, OwnMesh { mesh: Arc::downgrade(&mesh), stand_in, keys });
        }
        let drawn: HashSet<u64> = mine.instances.iter().map(|i| i.mesh.id).collect();
        let gone: Vec<u64> = meshes
            .iter()
            .filter(|(id, m)| !drawn.contains(id) || m.mesh.strong_count() == 0)
            .map(|(&id, _)| id)
            .collect();
        for id in gone {
            let m = meshes.remove(&id).expect("listed");
            let mut own = write(&self.own);
            for k in &m.keys {
                own.remove(k);
            }
        }
        for i in &mut out.instances {
            if let Some(m) = meshes.get(&i.mesh.id) {
                i.mesh = m.stand_in.clone();
            }
        }
        self.update_capacity();
        (out, entries)
    }

    /// The layouts rank `from` sent (its new meshes of frame `frame`).
    pub fn add_layouts(&self, from: usize, frame: u64, entries: Vec<LayoutEntry>) {
        {
            let mut known = write(&self.blocks);
            let mut layouts = write(&self.layouts);
            for e in entries {
                let refs: Vec<BlockRef> = e.blocks.iter().map(BlockEntry::to_ref).collect();
                for r in &refs {
                    known.insert(r.key, (from, r.bytes));
                }
                layouts.insert(e.mesh, Known { layout: Arc::new(Layout::new(refs)), since: frame });
            }
        }
        self.update_capacity();
    }

    /// The mesh standing in for pieces of one paged mesh drawn by several ranks (`Joined`):
    /// its layout the pieces' blocks one after the other; None when not every piece is paged
    /// (those are traced as pieces).
    pub fn join(&self, pieces: &[&Instance], frame: u64) -> Option<Mesh> {
        let mut layouts = write(&self.layouts);
        let parts: Vec<Arc<Layout>> =
            pieces.iter().map(|p| layouts.get(&p.mesh.id).map(|k| k.layout.clone())).collect::<Option<_>>()?;
        let (mut min, mut max) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for p in pieces {
            (min, max) = (min.min(p.mesh.min), max.max(p.mesh.max));
        }
        let stand_in = Mesh::stand_in(glray_scene::ids::next(), min, max);
        layouts.insert(stand_in.id, Known { layout: Arc::new(Layout::joined(&parts)), since: frame });
        Some(stand_in)
    }

    /// Keeps the layouts `merged` (frame `frame`, as traced) names and those made for later
    /// frames; the blocks no layout names any more leave the cache.
    pub fn retain(&self, merged: &Frame, frame: u64) {
        let named: HashSet<u64> = merged.instances.iter().map(|i| i.mesh.id).collect();
        let mut layouts = write(&self.layouts);
        layouts.retain(|id, k| named.contains(id) || k.since > frame);
        let live: HashSet<u64> = layouts.values().flat_map(|k| k.layout.blocks.iter().map(|b| b.key)).collect();
        drop(layouts);
        write(&self.blocks).retain(|k, _| live.contains(k));
        let mut cache = lock(&self.cache);
        for k in cache.keys() {
            if !live.contains(&k) {
                cache.remove(k);
            }
        }
        *lock(&self.last_frame) = cache.take_touched();
        drop(cache);
        // Blocks that came for parked pieces whose retries did not need them after all (the
        // first try's rays went where the missing blocks would have stopped them).
        lock(&self.pending).retain(|_, p| !matches!(*lock(&p.state), State::Arrived(..)));
        self.update_capacity();
    }

    /// The cache's budget from the blocks known now (a share of all of them).
    fn update_capacity(&self) {
        if let (Resident::Fetch, Budget::Fraction(f)) = (self.setup.resident, self.setup.budget) {
            let total: u64 = read(&self.blocks).values().map(|b| b.1).sum();
            lock(&self.cache).set_capacity((total as f64 * f) as u64);
        }
    }

    /// `all-resident`: every block of the frame's paged meshes not here fetched now, before
    /// the frame is traced (all asked at once, then waited for).
    pub fn fetch_all(&self, merged: &Frame) {
        let keys: Vec<u64> = {
            let layouts = read(&self.layouts);
            let own = read(&self.own);
            let mut keys: Vec<u64> = merged
                .instances
                .iter()
                .filter_map(|i| layouts.get(&i.mesh.id))
                .flat_map(|k| k.layout.blocks.iter().map(|b| b.key))
                .filter(|k| !own.contains_key(k))
                .collect();
            keys.sort_unstable();
            keys.dedup();
            keys
        };
        let waiting: Vec<(u64, Arc<Pending>)> = {
            let mut cache = lock(&self.cache);
            keys.into_iter().filter(|&k| cache.get(k).is_none()).map(|k| (k, self.ask(k, false).0)).collect()
        };
        for (key, p) in waiting {
            let _ = self.wait(key, &p, Instant::now());
        }
    }

    /// `prefetch`: the blocks last frame's rays used that the cache no longer holds (and that
    /// a layout still names, not on their way already), asked for now, first used first, at
    /// most as many as the cache holds. The tracer takes them as its rays reach them.
    pub fn prefetch(&self) {
        let last = std::mem::take(&mut *lock(&self.last_frame));
        if !self.setup.prefetch || self.setup.resident == Resident::All {
            return;
        }
        let room = self.in_flight_limit();
        let wanted: Vec<u64> = {
            let cache = lock(&self.cache);
            let known = read(&self.blocks);
            let pending = lock(&self.pending);
            let room = room.saturating_sub(pending.len());
            last.into_iter()
                .filter(|k| !cache.holds(*k) && known.contains_key(k) && !pending.contains_key(k))
                .take(room)
                .collect()
        };
        for k in wanted {
            self.ask(k, true);
        }
    }

    /// Asks for block `key` unless it is on its way already (for a ray, or `prefetch`ed): its
    /// pending entry, and whether this call asked.
    fn ask(&self, key: u64, prefetched: bool) -> (Arc<Pending>, bool) {
        let mut pending = lock(&self.pending);
        if let Some(p) = pending.get(&key) {
            return (p.clone(), false);
        }
        let p =
            Arc::new(Pending { state: Mutex::default(), changed: Condvar::new(), asked: Instant::now(), prefetched });
        pending.insert(key, p.clone());
        drop(pending);
        let kind = if prefetched { &self.counts.prefetched } else { &self.counts.misses };
        kind.fetch_add(1, Ordering::Relaxed);
        let owner = read(&self.blocks).get(&key).map(|b| b.0);
        let asked = match (owner, lock(&self.asks).as_ref()) {
            (Some(owner), Some(asks)) => asks.ask(owner, key),
            _ => false,
        };
        if !asked {
            let why = match owner {
                Some(_) => "glray's MPI thread has ended".to_string(),
                None => format!("block {key} is in no layout this rank was sent"),
            };
            self.fail(key, &p, Missing::Refused { owner: owner.unwrap_or(self.rank), why });
        }
        (p, true)
    }

    /// Block `key`, not here, for a piece traced in parking mode: built now if its bytes have
    /// come; else asked for (unless as many blocks as the cache holds are on their way
    /// already: the piece's retry waits for it) and the piece marked to be traced again.
    fn parked(&self, key: u64, since: Instant) -> Option<Arc<Block>> {
        let (on_way, in_flight) = {
            let pending = lock(&self.pending);
            (pending.get(&key).cloned(), pending.len())
        };
        let here = on_way.filter(|p| matches!(*lock(&p.state), State::Arrived(..) | State::Ready(_)));
        if let Some(p) = here {
            return self.wait(key, &p, since);
        }
        let room = in_flight < self.in_flight_limit();
        if room {
            self.ask(key, false);
        }
        ATTEMPTS.with(|a| a.borrow_mut().last_mut().map(|a| a.missed = true));
        None
    }

    /// How many blocks may be on their way at once for parked pieces or a prefetch: as many as
    /// the cache holds (at least 16).
    fn in_flight_limit(&self) -> usize {
        let capacity = lock(&self.cache).capacity();
        ((capacity / self.setup.block_bytes.max(1) as u64) as usize).max(16)
    }

    fn fail(&self, key: u64, p: &Pending, missing: Missing) {
        let mut first = lock(&self.failure);
        if first.is_none() {
            *first = Some(missing);
        }
        drop(first);
        *lock(&p.state) = State::Failed;
        p.changed.notify_all();
        lock(&self.pending).remove(&key);
    }

    /// Waits for block `key` (asked for at `since`), building its tree if this thread is the
    /// first to see its bytes; None if it did not come within the limit.
    fn wait(&self, key: u64, p: &Pending, since: Instant) -> Option<Arc<Block>> {
        let limit = *lock(&self.limit);
        let mut state = lock(&p.state);
        let out = loop {
            match std::mem::take(&mut *state) {
                State::Ready(b) => {
                    *state = State::Ready(b.clone());
                    break Some(b);
                }
                State::Failed => {
                    *state = State::Failed;
                    break None;
                }
                State::Arrived(bytes, at) => {
                    *state = State::Building;
                    drop(state);
                    let owner = read(&self.blocks).get(&key).map_or(self.rank, |b| b.0);
                    let built = match bytes {
                        Some(bytes) => blocks::decode(&bytes),
                        None => Err(format!("it does not hold block {key}")),
                    };
                    let block = match built {
                        Ok(b) => Arc::new(b),
                        Err(why) => {
                            self.fail(key, p, Missing::Refused { owner, why });
                            break None;
                        }
                    };
                    lock(&self.latencies).push(at.saturating_duration_since(p.asked).as_secs_f32() * 1000.0);
                    if p.prefetched {
                        self.counts.prefetch_used.fetch_add(1, Ordering::Relaxed);
                    }
                    let bytes = block.bytes() as u64;
                    let evicted = lock(&self.cache).insert(key, block.clone(), bytes);
                    self.counts.evictions.fetch_add(u64::from(evicted), Ordering::Relaxed);
                    *lock(&p.state) = State::Ready(block.clone());
                    p.changed.notify_all();
                    lock(&self.pending).remove(&key);
                    break Some(block);
                }
                s @ (State::Asked | State::Building) => {
                    *state = s;
                    if since.elapsed() > limit {
                        drop(state);
                        let owner = read(&self.blocks).get(&key).map_or(self.rank, |b| b.0);
                        self.fail(key, p, Missing::Late { owner });
                        break None;
                    }
                    state =
                        p.changed.wait_timeout(state, Duration::from_millis(20)).unwrap_or_else(|e| e.into_inner()).0;
                }
            }
        };
        self.counts.stall_ns.fetch_add(since.elapsed().as_nanos() as u64, Ordering::Relaxed);
        out
    }

    /// The link: block `key`'s bytes came from its owner (None: it does not hold it).
    pub fn arrived(&self, key: u64, bytes: Option<Vec<u8>>) {
        self.counts.bytes_fetched.fetch_add(bytes.as_ref().map_or(0, |b| b.len() as u64), Ordering::Relaxed);
        let Some(p) = lock(&self.pending).get(&key).cloned() else { return };
        *lock(&p.state) = State::Arrived(bytes, Instant::now());
        p.changed.notify_all();
    }

    /// The link: another rank asks for these blocks of this rank's; their bytes (None for one
    /// it does not hold).
    pub fn serve(&self, keys: &[u64]) -> Vec<(u64, Option<Vec<u8>>)> {
        let own = read(&self.own);
        let out: Vec<(u64, Option<Vec<u8>>)> =
            keys.iter().map(|&k| (k, own.get(&k).map(|b| blocks::encode(b)))).collect();
        let bytes: u64 = out.iter().filter_map(|(_, b)| b.as_ref()).map(|b| b.len() as u64).sum();
        self.counts.served.fetch_add(out.len() as u64, Ordering::Relaxed);
        self.counts.served_bytes.fetch_add(bytes, Ordering::Relaxed);
        out
    }

    /// The link: `count` blocks it served went compressed.
    pub fn served_packed(&self, count: u64) {
        self.counts.served_packed.fetch_add(count, Ordering::Relaxed);
    }

    /// Why the first block that could not be had since this was last asked was not.
    pub fn take_failure(&self) -> Option<Missing> {
        lock(&self.failure).take()
    }

    /// What paging did since this was last asked.
    pub fn take_report(&self) -> PagingReport {
        let c = &self.counts;
        let take = |a: &AtomicU64| a.swap(0, Ordering::Relaxed);
        let mut latencies = std::mem::take(&mut *lock(&self.latencies));
        latencies.sort_by(f32::total_cmp);
        let at = |q: f64| latencies.get(((latencies.len() as f64 * q) as usize).min(latencies.len().max(1) - 1));
        let cache = lock(&self.cache);
        let blocks = read(&self.blocks);
        PagingReport {
            accesses: take(&c.accesses),
            resident: take(&c.resident),
            cached: take(&c.cached),
            misses: take(&c.misses),
            waits: take(&c.waits),
            evictions: take(&c.evictions),
            bytes_fetched: take(&c.bytes_fetched),
            fetch_mean_ms: latencies.iter().map(|&l| f64::from(l)).sum::<f64>() / latencies.len().max(1) as f64,
            fetch_p99_ms: at(0.99).map_or(0.0, |&l| f64::from(l)),
            fetch_max_ms: latencies.last().map_or(0.0, |&l| f64::from(l)),
            stall: Duration::from_nanos(take(&c.stall_ns)),
            parked: take(&c.parked),
            prefetched: take(&c.prefetched),
            prefetch_used: take(&c.prefetch_used),
            served: take(&c.served),
            served_bytes: take(&c.served_bytes),
            served_packed: take(&c.served_packed),
            cache_bytes: cache.used(),
            cache_capacity: cache.capacity(),
            over: cache.over,
            own_bytes: blocks.values().filter(|b| b.0 == self.rank).map(|b| b.1).sum(),
            scene_bytes: blocks.values().map(|b| b.1).sum(),
            peak_memory: glray_core::memory::peak(),
        }
    }
}

impl Pager for Paging {
    fn layout(&self, mesh: u64) -> Option<Arc<Layout>> {
        read(&self.layouts).get(&mesh).map(|k| k.layout.clone())
    }

    fn block(&self, key: u64) -> Option<Arc<Block>> {
        let c = &self.counts;
        count(&c.accesses, |a| &mut a.accesses);
        if let Some(b) = read(&self.own).get(&key) {
            count(&c.resident, |a| &mut a.resident);
            return Some(b.clone());
        }
        if let Some(b) = lock(&self.cache).get(key) {
            count(&c.cached, |a| &mut a.cached);
            return Some(b);
        }
        let since = Instant::now();
        if parking() {
            return self.parked(key, since);
        }
        let (p, asked) = self.ask(key, false);
        if !asked {
            c.waits.fetch_add(1, Ordering::Relaxed);
        }
        self.wait(key, &p, since)
    }

    fn parks(&self) -> bool {
        self.setup.park && self.setup.resident == Resident::Fetch
    }

    fn park(&self) {
        ATTEMPTS.with(|a| a.borrow_mut().push(Attempt::default()));
    }

    fn unpark(&self) -> bool {
        let Some(a) = ATTEMPTS.with(|a| a.borrow_mut().pop()) else { return false };
        let c = &self.counts;
        if a.missed {
            c.parked.fetch_add(1, Ordering::Relaxed);
        } else {
            c.accesses.fetch_add(a.accesses, Ordering::Relaxed);
            c.resident.fetch_add(a.resident, Ordering::Relaxed);
            c.cached.fetch_add(a.cached, Ordering::Relaxed);
        }
        a.missed
    }
}

fn block_ref(b: &Block) -> BlockRef {
    BlockRef {
        key: b.mesh.id,
        min: b.mesh.min,
        max: b.mesh.max,
        triangles: b.mesh.triangles.len() as u32,
        bytes: b.bytes() as u64,
    }
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

fn read<T>(m: &RwLock<T>) -> std::sync::RwLockReadGuard<'_, T> {
    m.read().unwrap_or_else(|e| e.into_inner())
}

fn write<T>(m: &RwLock<T>) -> std::sync::RwLockWriteGuard<'_, T> {
    m.write().unwrap_or_else(|e| e.into_inner())
}
