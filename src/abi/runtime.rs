//! What the library reads once: its settings, its own file (so that a lookup never takes glray
//! for the real GL), and the real libraries, each opened on first need.

use std::ffi::{c_void, CString};
use std::path::Path;
use std::sync::OnceLock;

use glray_core::config::Config;
use glray_core::reallib::{self, FileId, RealKind, RealLib};

pub struct Runtime {
    pub config: Config,
    /// What was wrong with the settings (glray then passes everything through), told at the
    /// process's first GL call (`real`), not as the library loads: under a plain LD_PRELOAD
    /// every process of a command loads glray (`timeout`, a shell, a launcher script), and the
    /// user should read it once, from the program that draws.
    bad_settings: Option<String>,
    /// glray's own file, as the loader found it (the preload path or the drop-in name).
    pub own_path: Option<CString>,
    pub own_file: Option<FileId>,
    /// The address glray's code is loaded at, to recognise its own symbols.
    pub own_base: *const c_void,
}

// SAFETY: `own_base` is only compared, never dereferenced.
unsafe impl Sync for Runtime {}
unsafe impl Send for Runtime {}

static RUNTIME: OnceLock<Runtime> = OnceLock::new();

pub fn get() -> &'static Runtime {
    RUNTIME.get_or_init(init)
}

fn init() -> Runtime {
    let (config, bad_settings) = match Config::from_process_env() {
        Ok(c) => (c, None),
        Err(e) => {
            // Never stop the host: change nothing it draws, and say what is wrong (`real`).
            let off = Config::resolve(&[], &[("enable".into(), "false".into())]).expect("defaults are valid");
            (off, Some(e.to_string()))
        }
    };
    glray_core::log::set_level(if bad_settings.is_some() { glray_core::log::Level::Error } else { config.log_level() });

    let mut info: libc::Dl_info = unsafe { std::mem::zeroed() };
    // SAFETY: dladdr on the address of one of our own functions.
    let found = unsafe { libc::dladdr(get as *const c_void, &mut info) } != 0;
    let own_path =
        (found && !info.dli_fname.is_null()).then(|| unsafe { std::ffi::CStr::from_ptr(info.dli_fname) }.to_owned());
    let own_file = own_path.as_ref().and_then(|p| FileId::of(Path::new(&*p.to_string_lossy())));
    glray_core::info!(
        "glray {} loaded from {}{}",
        glray_core::VERSION,
        own_path.as_ref().map_or("?".into(), |p| p.to_string_lossy()),
        if config.enable() { "" } else { " (pass-through: enable = false)" }
    );
    Runtime { config, bad_settings, own_path, own_file, own_base: info.dli_fbase }
}

/// The real library of `kind`, opened on first use; None (logged once) if it cannot be found.
pub fn real(kind: RealKind) -> Option<&'static RealLib> {
    static LIBS: [OnceLock<Option<RealLib>>; 4] = [const { OnceLock::new() }; 4];
    let slot = &LIBS[RealKind::ALL.iter().position(|k| *k == kind).unwrap()];
    slot.get_or_init(|| {
        let rt = get();
        tell_bad_settings(rt);
        match reallib::open(kind, rt.config.real_path(kind.setting()), rt.own_file) {
            Ok(lib) => {
                glray_core::debug!("real {} is {}", kind.soname(), lib.path);
                Some(lib)
            }
            Err(e) => {
                glray_core::error!("{e}");
                None
            }
        }
    })
    .as_ref()
}

/// Says, once, what is wrong with the settings: at the first GL, GLX, EGL or OSMesa call that
/// needs a real library, so in the process that draws and not in every process the command
/// started.
fn tell_bad_settings(rt: &Runtime) {
    static TOLD: std::sync::Once = std::sync::Once::new();
    if let Some(e) = &rt.bad_settings {
        TOLD.call_once(|| glray_core::error!("{e}; glray runs as a pure pass-through until this is fixed"));
    }
}
