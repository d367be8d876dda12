//! The live control panel (setting `panel`, `glray run --panel`): a small HTTP server inside
//! the program's process (rank 0's under MPI) on 127.0.0.1 only, serving a web page and a JSON
//! API (docs/panel.md) to steer the picture settings while the program runs and to watch its
//! frames and statistics.
//!
//! It never delays a frame: the server runs on threads of its own, and the render thread only
//! takes the changes made since its last frame (`take_changes`) and leaves a copy of the frame,
//! scaled down, and its statistics (`publish`), each under a lock held for a copy. Every request
//! must carry the access token printed at start; the changes are checked as any setting is
//! (`changes`), and made by every rank from the next frame (`Distribution::announce`).

pub mod changes;
mod server;

use std::collections::VecDeque;
use std::sync::{Arc, Mutex, MutexGuard};

use glray_core::config::Config;

/// The widest frame the panel keeps (a picture to watch, not to use).
const THUMBNAIL: u32 = 480;
/// The frames whose statistics the panel keeps, for its plots.
const KEPT_FRAMES: usize = 120;

/// The panel's handle, kept by the live tracer.
pub struct Panel {
    shared: Arc<Shared>,
}

/// What the server's threads and the render thread share.
struct Shared {
    token: String,
    state: Mutex<State>,
}

struct State {
    /// The settings in force (or from the next frame: changes not taken yet).
    config: Config,
    /// Changes made since the render thread last took them, in order.
    pending: Vec<(String, String)>,
    /// The last frame presented, scaled down: its number, size and RGBA rows (bottom first).
    frame: Option<(u64, u32, u32, Vec<u8>)>,
    /// The last frames' statistics, as JSON objects (`GLRAY_STATS`'s lines).
    stats: VecDeque<String>,
}

impl Shared {
    fn state(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl Panel {
    /// Starts the panel when `config` asks for one (None otherwise, or when it cannot listen:
    /// said, and the program runs on without it).
    pub fn start(config: &Config) -> Option<Panel> {
        let port = config.panel()?;
        let token = match token() {
            Ok(t) => t,
            Err(e) => {
                glray_core::error!("panel: no random access token ({e}); the panel is off");
                return None;
            }
        };
        let server = match tiny_http::Server::http(("127.0.0.1", port)) {
            Ok(s) => s,
            Err(e) => {
                glray_core::error!("panel: cannot listen on 127.0.0.1:{port} ({e}); the panel is off");
                return None;
            }
        };
        let Some(address) = server.server_addr().to_ip() else {
            glray_core::error!("panel: not listening on an IP address; the panel is off");
            return None;
        };
        let state = State { config: config.clone(), pending: Vec::new(), frame: None, stats: VecDeque::new() };
        let shared = Arc::new(Shared { token, state: Mutex::new(state) });
        let serving = shared.clone();
        let started =
            std::thread::Builder::new().name("glray-panel".into()).spawn(move || server::serve(server, serving));
        if let Err(e) = started {
            glray_core::error!("panel: no thread to serve it ({e}); the panel is off");
            return None;
        }
        // Printed whatever the log level: the one way to reach the panel.
        eprintln!("glray: panel http://{address}/?token={}", shared.token);
        Some(Panel { shared })
    }

    /// The settings as the changes since the last call leave them, and those changes; None
    /// when nothing changed.
    pub fn take_changes(&self) -> Option<(Config, Vec<(String, String)>)> {
        let mut s = self.shared.state();
        if s.pending.is_empty() {
            return None;
        }
        let changes = std::mem::take(&mut s.pending);
        Some((s.config.clone(), changes))
    }

    /// Keeps frame `number` (scaled down) and its statistics (a JSON object) for the page.
    pub fn publish(&self, number: u64, picture: &glray_render::Rendered, stats: Option<String>) {
        let small = thumbnail(picture);
        let mut s = self.shared.state();
        s.frame = Some((number, small.0, small.1, small.2));
        if let Some(line) = stats {
            if s.stats.len() == KEPT_FRAMES {
                s.stats.pop_front();
            }
            s.stats.push_back(line);
        }
    }
}

/// `picture` scaled down to at most `THUMBNAIL` pixels wide (nearest pixels: cheap, on the
/// render thread).
fn thumbnail(picture: &glray_render::Rendered) -> (u32, u32, Vec<u8>) {
    let (w, h) = (picture.width.max(1), picture.height.max(1));
    let step = w.div_ceil(THUMBNAIL).max(1);
    let (tw, th) = (w.div_ceil(step), h.div_ceil(step));
    let mut out = Vec::with_capacity(4 * (tw * th) as usize);
    for y in (0..th).map(|y| y * step) {
        for x in (0..tw).map(|x| x * step) {
            let at = 4 * (y * w + x) as usize;
            // Opaque: a frame cleared to alpha 0 is still a picture to look at.
            let p = picture.rgba.get(at..at + 3).unwrap_or(&[0, 0, 0]);
            out.extend_from_slice(&[p[0], p[1], p[2], 255]);
        }
    }
    (tw, th, out)
}

/// A random access token: 128 bits from the kernel, as hex.
fn token() -> std::io::Result<String> {
    use std::io::Read;
    let mut bytes = [0u8; 16];
    std::fs::File::open("/dev/urandom")?.read_exact(&mut bytes)?;
    Ok(bytes.iter().map(|b| format!("{b:02x}")).collect())
}
