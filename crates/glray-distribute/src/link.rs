//! The one thread that moves a rank's glray messages (the paper's display process has one;
//! OSPRay's MPI module too): every send and receive of glray's goes through it, so the host's
//! thread and the tracer's threads never wait on MPI, and it answers at once what needs no
//! frame of the rank's: the master's tiles (rank 0: a rank that asks for tiles is answered
//! when its ask arrives, not when rank 0's frame next looks), tiles for this rank's tracer, and
//! rows of the last frame's denoising history (while the rank's own frame is elsewhere, or
//! over). Everything else is handed to the rank's frame (`Link::receive`).
//!
//! Where MPI gives less than MPI_THREAD_MULTIPLE the same loop runs on the host's thread,
//! inside its GL calls (`Link::inline`): it steps whenever the frame waits.
//!
//! The loop polls MPI (a matched probe, never a blocking call, so it can always stop); between
//! polls it waits `poll` for work from the rank's own threads. A spin (`poll` 0) is what a
//! blocking MPI_Probe costs with Open MPI over TCP: a core (docs/distributed.md measures it).

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use glray_render::denoise::HeldRows;
use glray_render::tiles::{TileGrid, TilePixels, TileWork};

use crate::master::Master;
use crate::pack::{Compression, Packed};
use crate::paging::{Asks, Paging};
use crate::protocol::{packed, Message};
use crate::transport::Transport;

/// Link threads still running, and the request that they all stop (`stop_all`).
static RUNNING: AtomicUsize = AtomicUsize::new(0);
static STOP_ALL: AtomicBool = AtomicBool::new(false);

/// Stops every link thread of the process and waits for them (at most `limit`): before the
/// host's MPI_Finalize, after which no glray message may move.
pub fn stop_all(limit: Duration) {
    STOP_ALL.store(true, Ordering::Release);
    let start = Instant::now();
    while RUNNING.load(Ordering::Acquire) > 0 && start.elapsed() < limit {
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// What the rank's own threads ask of its link.
enum Command {
    Send(usize, Message),
    /// Rank 0: frame `frame` begins, its tile `t` at home on rank `homes[t]`.
    Begin {
        frame: u64,
        homes: Vec<usize>,
    },
    /// Rank 0: the frame's ranks traced their tiles in these times (the next frame's shares).
    End {
        seconds: Vec<Option<f64>>,
    },
    /// The tracer wants tiles of `frame`.
    Want {
        frame: u64,
    },
    /// The history rows a frame's denoising kept (`generation`: that frame's number), to
    /// answer other ranks' asks with while the next frame is denoised.
    Held {
        generation: u64,
        rows: HeldRows,
    },
    /// Paging: the rank's pager, whose blocks the loop serves and whose fetches it delivers.
    Paging(Arc<Paging>),
    /// Paging: the tracer asks for block `key` of rank `owner`'s.
    Fetch {
        owner: usize,
        key: u64,
    },
}

/// The pager's way to its link (`Asks`).
struct LinkAsks(Mutex<Sender<Command>>);

impl Asks for LinkAsks {
    fn ask(&self, owner: usize, key: u64) -> bool {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).send(Command::Fetch { owner, key }).is_ok()
    }
}

/// What reaches the rank's frame: a message from another rank (or the link's fault), a tile
/// its tracer traced, its tracer done. One channel for all, so the frame's thread sleeps until
/// there is something to do (it woke every half millisecond to look at two, and the tracer
/// beside it was the slower for it).
#[derive(Debug)]
pub enum Event {
    Message(usize, Message),
    Failed(String),
    Tile(TilePixels),
    Traced,
}

/// Tiles for a rank's tracer: the frame, and the tiles (None: no more this frame).
type Grant = (u64, Option<Vec<u32>>);

/// Bytes moved, on the wire and before compression.
#[derive(Debug, Default)]
pub struct Counters {
    pub sent: AtomicU64,
    pub received: AtomicU64,
    pub sent_raw: AtomicU64,
    pub received_raw: AtomicU64,
}

impl Counters {
    pub fn get(&self) -> [u64; 4] {
        [&self.sent, &self.received, &self.sent_raw, &self.received_raw].map(|c| c.load(Ordering::Relaxed))
    }
}

/// A rank's side of its link: what its frame and tracer hand to the loop, and what comes back.
pub struct Link {
    rank: usize,
    size: usize,
    commands: Sender<Command>,
    inbox: Receiver<Event>,
    /// For the tracer's tiles (`work`) and its end (`traced`).
    events: Sender<Event>,
    /// Tiles for this rank's tracer: (frame, tiles; None when there are no more).
    grants: Arc<Mutex<Receiver<Grant>>>,
    counters: Arc<Counters>,
    /// Inline (no thread): the loop, stepped by `pump`.
    inline: Option<Core>,
    /// Threaded: tells the thread to end, and whether it has.
    stop: Arc<AtomicBool>,
    ended: Arc<AtomicBool>,
    compression: Compression,
}

impl Link {
    /// A link over `transport`, in a thread of its own (`threaded`) or stepped by the caller;
    /// `master` is the tile queue on the rank that hands out tiles (`master_rank`; None on the
    /// others); between polls the loop waits `poll` for its own threads' work.
    pub fn start(
        transport: Box<dyn Transport + Send>,
        master: Option<Master>,
        master_rank: usize,
        threaded: bool,
        poll: Duration,
        compression: Compression,
    ) -> Link {
        let (rank, size) = (transport.rank(), transport.size());
        let (command_tx, command_rx) = channel();
        let (inbox_tx, inbox_rx) = channel();
        let (grant_tx, grant_rx) = channel();
        let counters = Arc::new(Counters::default());
        let (stop, ended) = (Arc::new(AtomicBool::new(false)), Arc::new(AtomicBool::new(false)));
        let core = Core {
            transport,
            master,
            master_rank,
            commands: command_rx,
            inbox: inbox_tx.clone(),
            grants: grant_tx,
            counters: counters.clone(),
            tiles: TileState::default(),
            history: VecDeque::new(),
            pending_asks: Vec::new(),
            frame_begun: None,
            compression,
            failed: false,
            paging: None,
            fetches: std::collections::BTreeMap::new(),
            hurry_until: None,
        };
        let mut link = Link {
            rank,
            size,
            commands: command_tx,
            inbox: inbox_rx,
            events: inbox_tx,
            grants: Arc::new(Mutex::new(grant_rx)),
            counters,
            inline: None,
            stop: stop.clone(),
            ended: ended.clone(),
            compression,
        };
        if threaded {
            RUNNING.fetch_add(1, Ordering::AcqRel);
            let spawned = std::thread::Builder::new().name("glray-mpi".into()).spawn(move || {
                let mut core = core;
                while !stop.load(Ordering::Acquire) && !STOP_ALL.load(Ordering::Acquire) {
                    if !core.step() {
                        core.idle(poll);
                    }
                }
                core.drain(DRAIN);
                ended.store(true, Ordering::Release);
                RUNNING.fetch_sub(1, Ordering::AcqRel);
            });
            if spawned.is_err() {
                RUNNING.fetch_sub(1, Ordering::AcqRel);
                link.ended.store(true, Ordering::Release);
            }
        } else {
            link.inline = Some(core);
        }
        link
    }

    pub fn rank(&self) -> usize {
        self.rank
    }

    pub fn size(&self) -> usize {
        self.size
    }

    pub fn compression(&self) -> Compression {
        self.compression
    }

    /// Whether the loop runs on the caller's thread.
    pub fn is_inline(&self) -> bool {
        self.inline.is_some()
    }

    /// Steps an inline loop (a no-op for a threaded one).
    pub fn pump(&mut self) {
        if let Some(core) = self.inline.as_mut() {
            while core.step() {}
        }
    }

    fn command(&mut self, c: Command) -> Result<(), String> {
        if self.ended.load(Ordering::Acquire) || STOP_ALL.load(Ordering::Acquire) {
            return Err("glray's MPI thread has ended (MPI_Finalize)".into());
        }
        self.commands.send(c).map_err(|_| "glray's MPI thread has ended".to_string())?;
        self.pump();
        Ok(())
    }

    pub fn send(&mut self, to: usize, m: Message) -> Result<(), String> {
        self.command(Command::Send(to, m))
    }

    pub fn begin(&mut self, frame: u64, homes: Vec<usize>) -> Result<(), String> {
        self.command(Command::Begin { frame, homes })
    }

    pub fn end(&mut self, seconds: Vec<Option<f64>>) -> Result<(), String> {
        self.command(Command::End { seconds })
    }

    pub fn publish(&mut self, generation: u64, rows: HeldRows) -> Result<(), String> {
        self.command(Command::Held { generation, rows })
    }

    /// Serves `paging`'s blocks to the other ranks and carries its requests from now on.
    pub fn page(&mut self, paging: Arc<Paging>) -> Result<(), String> {
        paging.connect(Box::new(LinkAsks(Mutex::new(self.commands.clone()))));
        self.command(Command::Paging(paging))
    }

    /// The next event, waiting at most `wait` for it.
    pub fn receive(&mut self, wait: Duration) -> Option<Event> {
        self.pump();
        match self.inbox.try_recv() {
            Ok(d) => return Some(d),
            Err(_) if wait.is_zero() => return None,
            Err(_) => {}
        }
        if self.inline.is_some() {
            // Stepped here: poll until something comes or the wait is over.
            let start = Instant::now();
            loop {
                self.pump();
                if let Ok(d) = self.inbox.try_recv() {
                    return Some(d);
                }
                if start.elapsed() >= wait {
                    return None;
                }
                std::thread::sleep(Duration::from_micros(20));
            }
        }
        match self.inbox.recv_timeout(wait) {
            Ok(d) => Some(d),
            Err(RecvTimeoutError::Timeout) => None,
            Err(RecvTimeoutError::Disconnected) => Some(Event::Failed("glray's MPI thread has ended".into())),
        }
    }

    /// Where the tracer says it is done (`Event::Traced`), after its last tile.
    pub fn tracer_events(&self) -> Sender<Event> {
        self.events.clone()
    }

    /// Bytes moved so far (sent and received, on the wire and before compression).
    pub fn counters(&self) -> [u64; 4] {
        self.counters.get()
    }

    /// The tracer's side for frame `frame`: it asks for tiles through this link (answered at
    /// once by the master's rank, or by it over MPI), waiting at most `limit` for them, and
    /// hands each traced tile of `grid` to the rank's frame (`Event::Tile`). (An inline link
    /// is stepped meanwhile by the thread that waits for the tracer.)
    pub fn work<'a>(&self, frame: u64, grid: TileGrid, abort: &'a AtomicBool, limit: Duration) -> LinkWork<'a> {
        LinkWork {
            frame,
            grid,
            commands: Mutex::new(self.commands.clone()),
            grants: self.grants.clone(),
            done: Mutex::new(self.events.clone()),
            abort,
            limit,
            starved: Arc::new(AtomicBool::new(false)),
        }
    }
}

impl Drop for Link {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(core) = self.inline.as_mut() {
            core.drain(DRAIN);
            return;
        }
        // The thread sends what it was given, and ends; not waited for beyond the drain.
        let start = Instant::now();
        while !self.ended.load(Ordering::Acquire) && start.elapsed() < DRAIN + Duration::from_millis(100) {
            std::thread::sleep(Duration::from_micros(100));
        }
    }
}

/// How long an ending link keeps sending what it was given (the last frame's messages to the
/// others: a rank done with its frames still owes them its parts of their pictures).
const DRAIN: Duration = Duration::from_secs(2);

/// The tracer's `TileWork` over a link.
pub struct LinkWork<'a> {
    frame: u64,
    grid: TileGrid,
    commands: Mutex<Sender<Command>>,
    grants: Arc<Mutex<Receiver<Grant>>>,
    done: Mutex<Sender<Event>>,
    abort: &'a AtomicBool,
    limit: Duration,
    /// No tiles came within the limit: the master's rank is silent.
    starved: Arc<AtomicBool>,
}

impl LinkWork<'_> {
    /// Set when the tracer gave up waiting for tiles.
    pub fn starved(&self) -> Arc<AtomicBool> {
        self.starved.clone()
    }
}

impl TileWork for LinkWork<'_> {
    fn grid(&self, _: u32, _: u32) -> TileGrid {
        self.grid
    }

    fn next(&self) -> Option<Vec<u32>> {
        let grants = self.grants.lock().unwrap_or_else(|e| e.into_inner());
        self.commands.lock().unwrap_or_else(|e| e.into_inner()).send(Command::Want { frame: self.frame }).ok()?;
        let start = Instant::now();
        loop {
            match grants.recv_timeout(Duration::from_millis(20)) {
                // (A grant of a frame given up on is dropped.)
                Ok((frame, _)) if frame != self.frame => {}
                Ok((_, g)) => return g,
                Err(RecvTimeoutError::Timeout) if start.elapsed() > self.limit => {
                    self.starved.store(true, Ordering::Release);
                    return None;
                }
                Err(RecvTimeoutError::Timeout) if !self.abort.load(Ordering::Acquire) => {}
                Err(_) => return None,
            }
        }
    }

    fn done(&self, pixels: TilePixels) {
        let _ = self.done.lock().unwrap_or_else(|e| e.into_inner()).send(Event::Tile(pixels));
    }
}

/// The tiles of this rank's tracer: chunks granted and not yet asked for, an ask of rank 0's
/// under way, no more to come, the tracer waiting.
#[derive(Default)]
struct TileState {
    frame: u64,
    reserve: VecDeque<Vec<u32>>,
    asked: bool,
    exhausted: bool,
    waiting: bool,
}

/// The loop's state.
struct Core {
    transport: Box<dyn Transport + Send>,
    master: Option<Master>,
    /// The rank that hands out tiles (where this rank's tracer asks).
    master_rank: usize,
    commands: Receiver<Command>,
    inbox: Sender<Event>,
    grants: Sender<Grant>,
    counters: Arc<Counters>,
    tiles: TileState,
    /// The last two generations of history rows this rank holds (newest last).
    history: VecDeque<(u64, HeldRows)>,
    /// Rank 0: asks for tiles of a frame it has not begun yet (a rank ahead of it).
    pending_asks: Vec<(usize, u64)>,
    /// Rank 0: the frame whose tiles the master hands out.
    frame_begun: Option<u64>,
    compression: Compression,
    /// The transport failed: the frame was told, nothing more moves.
    failed: bool,
    /// Paging: the rank's pager, and the blocks its tracer asked for this round, by owner.
    paging: Option<Arc<Paging>>,
    fetches: std::collections::BTreeMap<usize, Vec<u64>>,
    /// Until when the loop polls every `BLOCK_POLL` (blocks moved lately).
    hurry_until: Option<Instant>,
}

/// Bytes of sends under way past which the network is behind (`block_packing`).
const SATURATED: u64 = 2 << 20;

/// How a reply of blocks is packed, `unsent` bytes still under way: compressed (`how`) only
/// while the network is behind; on a link that keeps up (loopback, a fast fabric),
/// compressing costs both ends more time than the bytes it saves (LZ4 packs a 94 KB block in
/// 0.29 ms and unpacks it in 0.16 ms, more than the block's encoding and decoding together).
fn block_packing(unsent: u64, how: Compression) -> Compression {
    if unsent >= SATURATED {
        how
    } else {
        Compression::None
    }
}

/// The wait between polls while blocks are moving (`Core::hurry_until`), and for how long
/// after the last one moved.
const BLOCK_POLL: Duration = Duration::from_micros(20);
const BLOCK_HURRY: Duration = Duration::from_millis(50);

impl Core {
    /// One round: the rank's own work, then every message that has arrived. Whether there
    /// was anything to do.
    fn step(&mut self) -> bool {
        if self.failed {
            return false;
        }
        let mut busy = false;
        while let Ok(c) = self.commands.try_recv() {
            busy = true;
            self.command(c);
        }
        self.ask_blocks();
        loop {
            match self.transport.poll() {
                Ok(Some((from, bytes))) => {
                    busy = true;
                    self.arrived(from, bytes);
                }
                Ok(None) => break,
                Err(e) => {
                    self.fail(e);
                    return false;
                }
            }
        }
        if let Err(e) = self.transport.flushed() {
            self.fail(e);
        }
        busy
    }

    /// The end: what the rank's threads handed over is sent, and the sends under way are
    /// waited for, at most `limit` (messages that arrive meanwhile are answered too).
    fn drain(&mut self, limit: Duration) {
        let start = Instant::now();
        while !self.failed && start.elapsed() < limit {
            let busy = self.step();
            if !busy && matches!(self.transport.flushed(), Ok(true)) {
                return;
            }
            if !busy {
                std::thread::sleep(Duration::from_micros(50));
            }
        }
    }

    /// Nothing to do: waits up to `poll` for the rank's own work (a spin when 0).
    fn idle(&mut self, poll: Duration) {
        // Blocks are asked for and answered one after another while a frame is traced: each
        // poll's wait would add to every fetch.
        let poll = match self.hurry_until {
            Some(until) if Instant::now() < until => poll.min(BLOCK_POLL),
            _ => poll,
        };
        if poll.is_zero() {
            std::hint::spin_loop();
            return;
        }
        if let Ok(c) = self.commands.recv_timeout(poll) {
            self.command(c);
            self.ask_blocks();
        }
    }

    /// The blocks asked for since the last round, one request to each owner.
    fn ask_blocks(&mut self) {
        let frame = self.tiles.frame;
        if !self.fetches.is_empty() {
            self.hurry_until = Some(Instant::now() + BLOCK_HURRY);
        }
        for (owner, keys) in std::mem::take(&mut self.fetches) {
            self.send(owner, Message::BlockAsk { frame, keys });
        }
    }

    fn fail(&mut self, why: String) {
        self.failed = true;
        let _ = self.inbox.send(Event::Failed(format!("MPI failed: {why}")));
    }

    fn send(&mut self, to: usize, m: Message) {
        let (raw, packed) = m.packed_sizes();
        let bytes = m.encode();
        let c = &self.counters;
        c.sent.fetch_add(bytes.len() as u64, Ordering::Relaxed);
        c.sent_raw.fetch_add(bytes.len() as u64 + raw - packed, Ordering::Relaxed);
        if to == self.transport.rank() {
            // (To itself: handed to the frame as it would arrive.)
            self.arrived(to, bytes);
            return;
        }
        if let Err(e) = self.transport.send(to, bytes) {
            self.fail(e);
        }
    }

    fn command(&mut self, c: Command) {
        match c {
            Command::Send(to, m) => self.send(to, m),
            Command::Begin { frame, homes } => {
                let Some(master) = self.master.as_mut() else { return };
                let batches = master.begin(&homes);
                self.frame_begun = Some(frame);
                let me = self.transport.rank();
                // (An empty grant means "no more": a rank without a first batch asks instead.)
                for (r, batch) in batches.into_iter().enumerate().filter(|(_, b)| !b.is_empty()) {
                    if r == me {
                        self.granted(frame, batch);
                    } else {
                        self.send(r, Message::Grant { frame, tiles: batch });
                    }
                }
                for (from, f) in std::mem::take(&mut self.pending_asks) {
                    self.ask(from, f);
                }
            }
            Command::End { seconds } => {
                if let Some(master) = self.master.as_mut() {
                    master.end(&seconds);
                }
            }
            Command::Want { frame } => {
                if self.tiles.frame != frame {
                    self.tiles = TileState { frame, ..TileState::default() };
                }
                self.tiles.waiting = true;
                self.serve_tracer();
            }
            Command::Held { generation, rows } => {
                self.history.push_back((generation, rows));
                while self.history.len() > 2 {
                    self.history.pop_front();
                }
            }
            Command::Paging(p) => self.paging = Some(p),
            Command::Fetch { owner, key } => self.fetches.entry(owner).or_default().push(key),
        }
    }

    /// Tiles for this rank's tracer (a first batch, or an answer to its ask).
    fn granted(&mut self, frame: u64, tiles: Vec<u32>) {
        if self.tiles.frame != frame {
            if frame < self.tiles.frame {
                return;
            }
            self.tiles = TileState { frame, ..TileState::default() };
        }
        self.tiles.asked = false;
        if tiles.is_empty() {
            self.tiles.exhausted = true;
        } else {
            self.tiles.reserve.push_back(tiles);
        }
        self.serve_tracer();
    }

    /// Gives the waiting tracer a chunk: one in reserve, or rank 0's master's next, or none
    /// when all are out; else asks rank 0.
    fn serve_tracer(&mut self) {
        if !self.tiles.waiting {
            return;
        }
        let frame = self.tiles.frame;
        let me = self.transport.rank();
        let chunk = match self.tiles.reserve.pop_front() {
            Some(c) => Some(c),
            None if self.master.is_some() => {
                if self.frame_begun != Some(frame) {
                    // Not begun here yet: the tracer waits for `Begin`.
                    return;
                }
                let c = self.master.as_mut().map(|m| m.next(me)).unwrap_or_default();
                (!c.is_empty()).then_some(c)
            }
            None if self.tiles.exhausted => None,
            None => {
                if !self.tiles.asked {
                    self.tiles.asked = true;
                    self.send(self.master_rank, Message::Ask { frame });
                }
                return;
            }
        };
        self.tiles.waiting = false;
        let _ = self.grants.send((frame, chunk));
    }

    /// Rank 0: a rank asks for tiles of `frame`.
    fn ask(&mut self, from: usize, frame: u64) {
        match self.frame_begun {
            Some(f) if f == frame => {
                let chunk = self.master.as_mut().map(|m| m.next(from)).unwrap_or_default();
                self.send(from, Message::Grant { frame, tiles: chunk });
            }
            // Ahead of this rank: answered when the frame begins here.
            Some(f) if f > frame => {}
            _ => self.pending_asks.push((from, frame)),
        }
    }

    /// A message from rank `from`: answered here when it can be, else handed to the frame.
    fn arrived(&mut self, from: usize, bytes: Vec<u8>) {
        let size = bytes.len() as u64;
        let message = match Message::decode(bytes) {
            Ok(m) => m,
            Err(why) => {
                let _ = self.inbox.send(Event::Failed(format!("rank {from} sent {why}")));
                return;
            }
        };
        let (raw, travelled) = message.packed_sizes();
        if from != self.transport.rank() {
            let c = &self.counters;
            c.received.fetch_add(size, Ordering::Relaxed);
            c.received_raw.fetch_add(size + raw - travelled, Ordering::Relaxed);
        }
        match message {
            Message::Ask { frame } if self.master.is_some() => self.ask(from, frame),
            Message::Grant { frame, tiles } if self.master.is_none() => self.granted(frame, tiles),
            Message::HistoryAsk { frame, rows } => {
                // The newest rows kept by a frame before `frame`.
                let held = self.history.iter().rev().find(|(g, _)| *g < frame).map(|(_, h)| h.clone());
                for (first, end) in rows {
                    let past = held.as_ref().and_then(|h| h.rows(first as usize..end as usize));
                    let reply = Message::History {
                        frame,
                        first,
                        rows: end - first,
                        held: past.is_some(),
                        past: packed(past.as_deref().unwrap_or(&[]), self.compression),
                    };
                    self.send(from, reply);
                }
            }
            Message::Layouts { frame, layouts } if self.paging.is_some() => {
                if let Some(p) = &self.paging {
                    p.add_layouts(from, frame, layouts);
                }
            }
            Message::BlockAsk { frame, keys } if self.paging.is_some() => {
                self.hurry_until = Some(Instant::now() + BLOCK_HURRY);
                let served = self.paging.as_ref().map(|p| p.serve(&keys)).unwrap_or_default();
                let how = block_packing(self.transport.unsent().unwrap_or(0), self.compression);
                if let (Some(p), true) = (&self.paging, how != Compression::None) {
                    p.served_packed(served.len() as u64);
                }
                let blocks = served.into_iter().map(|(k, b)| (k, b.map(|b| Packed::new(&b, 1, how)))).collect();
                self.send(from, Message::BlockData { frame, blocks });
            }
            Message::BlockData { blocks, .. } if self.paging.is_some() => {
                let paging = self.paging.clone().expect("paging");
                for (key, b) in blocks {
                    match b.map(Packed::unpack).transpose() {
                        Ok(bytes) => paging.arrived(key, bytes),
                        Err(why) => {
                            let _ = self.inbox.send(Event::Failed(format!("rank {from} sent a damaged block: {why}")));
                        }
                    }
                }
            }
            other => {
                let _ = self.inbox.send(Event::Message(from, other));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_are_compressed_only_while_the_network_is_behind() {
        assert_eq!(block_packing(0, Compression::Lz4), Compression::None);
        assert_eq!(block_packing(SATURATED - 1, Compression::Zstd(1)), Compression::None);
        assert_eq!(block_packing(SATURATED, Compression::Lz4), Compression::Lz4);
        assert_eq!(block_packing(50 << 20, Compression::Zstd(1)), Compression::Zstd(1));
        assert_eq!(block_packing(50 << 20, Compression::None), Compression::None, "`none` never compresses");
    }
}
