//! A process that is an MPI rank shares each frame with the others (docs/distributed.md):
//! with `distribute = replicated` (the default in an MPI rank) every rank traces tiles of the
//! whole image against every rank's scene, and rank 0's framebuffer gets the picture while the
//! others get the background at the far depth, so that a host's sort-last compositing (IceT)
//! keeps rank 0's picture. `data-parallel` and `local` trace each rank's own frame, as a lone
//! process does.
//!
//! - `edge`: libglray_mpi.so (the only part of glray that links MPI), loaded on demand;
//! - `mpi_entry`: MPI_Init, MPI_Init_thread, MPI_Finalize, interposed.
//!
//! The protocol itself is glray-distribute's; a fault (a rank silent past the time limit, set
//! differently, gone) is said once, naming the rank, and this process traces alone from then
//! on: the host goes on.

mod edge;
pub mod mpi_entry;

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use glray_core::config::Config;
use glray_distribute::node::{Announced, PictureParts, Roles, Setup, TileHomes};
use glray_distribute::pack::Compression;
use glray_distribute::paging::{Budget, PagingSetup, Resident};
use glray_distribute::{Agreement, FrameReport, Limits, Node, Transport};
use glray_render::{Rendered, Renderer};
use glray_scene::frame::Frame;

/// The host's MPI_Finalize came: no more MPI.
static ENDED: AtomicBool = AtomicBool::new(false);

/// MPI's threading levels (the standard's order; OpenMPI's numbers).
const THREAD_MULTIPLE: i32 = 3;

/// This process's rank as the launcher's environment gives it (Open MPI, MPICH/PMI, PMIx).
pub fn env_rank() -> Option<u32> {
    ["OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"].iter().find_map(|v| std::env::var(v).ok()?.parse().ok())
}

/// How many ranks of the job run on this node (1 when not known).
pub fn ranks_on_node() -> usize {
    ["OMPI_COMM_WORLD_LOCAL_SIZE", "MPI_LOCALNRANKS"]
        .iter()
        .find_map(|v| std::env::var(v).ok()?.parse().ok())
        .unwrap_or(1)
        .max(1)
}

/// Whether this process is an MPI rank: started by a launcher, or its host called MPI_Init.
pub fn in_mpi() -> bool {
    env_rank().is_some() || mpi_entry::HOST_STARTED_MPI.load(Ordering::Relaxed)
}

/// Called as the library loads: objects made from here on have ids of this rank's own (ranks
/// send their meshes to each other).
pub fn at_load() {
    if let Some(rank) = env_rank() {
        glray_scene::ids::set_space(rank + 1);
    }
}

/// The host's MPI_Finalize: glray's MPI work stops (its thread's last sends made, within
/// two seconds).
fn end() {
    ENDED.store(true, Ordering::Relaxed);
    glray_distribute::link::stop_all(Duration::from_secs(3));
}

/// At the exit of a program that does not use MPI, where glray started it: MPI ends (mpirun
/// counts a rank that exits without MPI_Finalize as failed).
extern "C" fn end_at_exit() {
    let _ = std::panic::catch_unwind(|| {
        end();
        if let Ok(edge) = edge::get() {
            (edge.finalize)(0);
        }
    });
}

/// How frames are shared in this process.
pub struct Distribution {
    replicated: bool,
    settings: u64,
    setup: Setup,
    node: Option<Node>,
    /// Image-parallel tracing stopped (a fault, or MPI could not be joined).
    stopped: bool,
    /// The settings at start, which rank 0's changes (the live control panel) are made to on
    /// the other ranks; and the last settings such a change left here, for the caller
    /// (`take_changed`).
    config: Config,
    changed: std::sync::Arc<std::sync::Mutex<Option<Config>>>,
    /// Rank 0: changes to hand on with the next frame (before the node exists).
    announced: Announced,
}

/// What a shared frame gave this rank: the picture for its framebuffer (None for a pass that is
/// not shown), and the report.
pub struct Shared {
    pub picture: Option<Rendered>,
    pub report: FrameReport,
    pub rank: usize,
    pub ranks: usize,
}

impl Distribution {
    pub fn configure(config: &Config) -> Distribution {
        Distribution {
            replicated: matches!(config.distribute(in_mpi()), "replicated" | "paged"),
            settings: config.picture_settings(),
            setup: Setup {
                limits: Limits { fixed: config.mpi_timeout().map(Duration::from_secs_f64) },
                roles: match config.mpi_roles() {
                    "dedicated" => Roles::Dedicated,
                    "paper" => Roles::Paper,
                    _ => Roles::Shared,
                },
                threaded: true,
                poll: Duration::from_micros(config.mpi_poll()),
                compression: Compression::from_setting(config.mpi_compression()).unwrap_or_default(),
                parts: if config.mpi_whole_picture() { PictureParts::Whole } else { PictureParts::Own },
                paging: (config.distribute(in_mpi()) == "paged").then(|| PagingSetup {
                    resident: if config.all_resident() { Resident::All } else { Resident::Fetch },
                    budget: match config.cache_mb() {
                        Some(mb) => Budget::Bytes(mb << 20),
                        None => Budget::Fraction(config.cache_fraction()),
                    },
                    block_bytes: config.block_bytes(),
                    park: config.paging_parks(),
                    prefetch: config.paging_prefetches(),
                }),
                // (A cgroup's limit is for every process in it: the job's ranks on this node share it.)
                memory_limit: config
                    .memory_limit()
                    .or_else(|| glray_core::memory::cgroup_limit().map(|l| l / ranks_on_node() as u64)),
                tiles: if config.mpi_random_tiles() { TileHomes::Random } else { TileHomes::Bands },
            },
            node: None,
            stopped: false,
            config: config.clone(),
            changed: Default::default(),
            announced: Announced::default(),
        }
    }

    /// Rank 0: settings changed from the live control panel (`config` the result, already in
    /// force here); every other rank makes `changes` before it traces the next frame.
    pub fn announce(&mut self, config: &Config, changes: Vec<(String, String)>) {
        // (`self.settings` stays the agreement to start a node from: the one before the change.)
        let settings = config.picture_settings();
        match self.node.as_mut() {
            Some(node) => node.announce(settings, changes),
            None => self.announced.add(settings, changes),
        }
    }

    /// A rank other than 0: the settings rank 0's last change left here, once (the frame's
    /// trigger is the caller's).
    pub fn take_changed(&mut self) -> Option<Config> {
        self.changed.lock().unwrap_or_else(|e| e.into_inner()).take()
    }

    /// Whether frames are to be shared (`frame`) rather than traced alone.
    pub fn active(&self) -> bool {
        self.replicated && !self.stopped && !ENDED.load(Ordering::Relaxed)
    }

    fn stop(&mut self, why: &str) {
        self.stopped = true;
        self.node = None;
        glray_core::error!("image-parallel tracing stopped: {why}; this rank traces its own data from here on");
    }

    /// Shares `mine` with the other ranks (see the module); None when this rank is to trace it
    /// alone (not shared, or just stopped). `present`: the picture is shown (false for the
    /// passes of a batch frame before its last, whose pictures are not sent).
    pub fn frame(
        &mut self,
        mine: &Frame,
        previous: Option<&Rendered>,
        renderer: &mut Renderer,
        pool: Option<&rayon::ThreadPool>,
        present: bool,
    ) -> Option<Shared> {
        if !self.active() {
            return None;
        }
        if self.node.is_none() {
            let limit = self.setup.limits.fixed.unwrap_or(glray_distribute::node::FIRST_FRAME_LIMIT);
            let joined = edge::get().map_err(str::to_string).and_then(|e| e.join(limit).map(|t| (e, t)));
            match joined {
                Ok((edge, transport)) => {
                    if !mpi_entry::HOST_STARTED_MPI.load(Ordering::Relaxed) {
                        // glray started MPI (the program does not use it): glray ends it.
                        // SAFETY: registering a plain function.
                        unsafe { libc::atexit(end_at_exit) };
                    }
                    let threading = (edge.threading)();
                    if threading < THREAD_MULTIPLE {
                        glray_core::warn!(
                            "MPI gives threading level {threading}, not MPI_THREAD_MULTIPLE: glray's messages move \
                             only inside the host's GL calls, on its thread"
                        );
                    }
                    glray_core::info!("rank {} of {}: image-parallel tracing", transport.rank(), transport.size());
                    // Settings changed before the first frame count from it (rank 0 hands them on).
                    let agreement = Agreement { settings: self.settings };
                    let mut setup = Setup { threaded: threading >= THREAD_MULTIPLE, ..self.setup };
                    if !setup.threaded && setup.paging.is_some() {
                        // (A rank tracing alone could not serve, nor be served, its blocks.)
                        glray_core::warn!(
                            "distribute = paged needs MPI_THREAD_MULTIPLE (glray's MPI thread serves a rank's blocks \
                             while it traces): every rank holds every mesh (replicated) instead"
                        );
                        setup.paging = None;
                    }
                    let mut node = Node::new(transport, agreement, setup);
                    if let Some((settings, changes)) = self.announced.take() {
                        node.announce(settings, changes);
                    }
                    // This rank's settings, as the changes so far made them (the hook's own).
                    let (mut config, changed) = (self.config.clone(), self.changed.clone());
                    node.on_settings(Box::new(move |changes, renderer| {
                        let (made, options) = crate::panel::changes::change(&config, changes)?;
                        renderer.set_options(options);
                        config = made.clone();
                        let settings = made.picture_settings();
                        *changed.lock().unwrap_or_else(|e| e.into_inner()) = Some(made);
                        Ok(settings)
                    }));
                    self.node = Some(node);
                }
                Err(e) => {
                    self.stop(&e);
                    return None;
                }
            }
        }
        let node = self.node.as_mut()?;
        let (rank, ranks) = (node.rank(), node.size());
        match node.frame(mine, previous, renderer, pool, present) {
            Ok((picture, report)) => Some(Shared { picture, report, rank, ranks }),
            Err(fault) => {
                self.stop(&fault.to_string());
                None
            }
        }
    }
}

/// Tracer threads for this process: the setting `threads`, else the cores shared among the
/// ranks on this node.
pub fn tracer_threads(config: &Config) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    config.threads().unwrap_or_else(|| if in_mpi() { (cores / ranks_on_node()).max(1) } else { cores })
}
