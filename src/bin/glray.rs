//! The `glray` command: runs a program under glray (`glray run`), and tells what glray would do
//! (`glray info`). Settings given as flags win over the environment and the config file; they
//! reach the library as GLRAY_* environment variables of the program.

use std::ffi::OsString;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use glray_core::config::{env_name, Config, Kind, SETTINGS};
use glray_core::reallib::{self, FileId, RealKind};

#[derive(Parser)]
#[command(name = "glray", version, about = "Ray-traced frames for unmodified OpenGL programs")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run PROGRAM under glray (LD_PRELOAD by default, like vglrun).
    Run {
        /// Drop-in instead of preload: put a directory whose libGL.so.1, libEGL.so.1 and
        /// libOSMesa.so.8 are glray first on LD_LIBRARY_PATH. Needed for programs that dlopen
        /// libGL.so.1 without linking it (apitrace's glretrace) when preloading is not wanted.
        #[arg(long)]
        dropin: bool,
        /// A setting for this run, KEY=VALUE (see `glray info`); may be repeated.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// libglray.so to use (default: the one installed beside this command).
        #[arg(long, value_name = "PATH")]
        library: Option<PathBuf>,
        /// The program and its arguments.
        #[arg(required = true, last = true, value_name = "PROGRAM ARGS")]
        program: Vec<OsString>,
    },
    /// Print the version, the library, the real GL libraries found and every setting in force
    /// with where it came from.
    Info {
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        #[arg(long, value_name = "PATH")]
        library: Option<PathBuf>,
    },
    /// Print (creating it if needed) the drop-in directory: LD_LIBRARY_PATH=$(glray dropin-dir) app
    DropinDir {
        #[arg(long, value_name = "PATH")]
        library: Option<PathBuf>,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run { dropin, set, library, program } => run(dropin, &set, library, &program),
        Command::Info { set, library } => info(&set, library),
        Command::DropinDir { library } => find_library(library)
            .and_then(|lib| dropin_dir(&lib))
            .map(|d| println!("{}", d.display())),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("glray: error: {e}");
            ExitCode::from(2)
        }
    }
}

fn parse_flags(set: &[String]) -> Result<Vec<(String, String)>, String> {
    set.iter()
        .map(|kv| {
            kv.split_once('=')
                .map(|(k, v)| (k.trim().to_string(), v.to_string()))
                .ok_or_else(|| format!("--set {kv:?}: expected KEY=VALUE"))
        })
        .collect()
}

fn process_env() -> Vec<(String, String)> {
    std::env::vars_os()
        .filter_map(|(k, v)| Some((k.into_string().ok()?, v.into_string().ok()?)))
        .collect()
}

/// libglray.so: --library, else beside this executable, else in ../lib/glray or ../lib.
fn find_library(explicit: Option<PathBuf>) -> Result<PathBuf, String> {
    if let Some(p) = explicit {
        return p.canonicalize().map_err(|e| format!("--library {}: {e}", p.display()));
    }
    let exe = std::env::current_exe().map_err(|e| format!("cannot locate the glray command: {e}"))?;
    let dir = exe.parent().unwrap_or(Path::new("/"));
    let candidates = [
        dir.join("libglray.so"),
        dir.join("../lib/glray/libglray.so"),
        dir.join("../lib/libglray.so"),
    ];
    candidates
        .iter()
        .find(|p| p.exists())
        .and_then(|p| p.canonicalize().ok())
        .ok_or_else(|| {
            format!(
                "cannot find libglray.so beside {} (looked in {}); build it with `cargo build --release` \
                 or pass --library PATH",
                exe.display(),
                candidates.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
            )
        })
}

/// The drop-in directory: libGL.so.1, libEGL.so.1 and libOSMesa.so.8 linked to libglray.so.
/// Beside the library if writable, else in the user's cache directory.
fn dropin_dir(lib: &Path) -> Result<PathBuf, String> {
    // libOpenGL.so.0 and libGLX.so.0 are not here: they are glray's own dependencies (the real
    // ones must load under those names); preloading covers programs that dlopen them.
    const NAMES: [&str; 6] = ["libGL.so.1", "libGL.so", "libEGL.so.1", "libEGL.so", "libOSMesa.so.8", "libOSMesa.so"];
    let beside = lib.parent().unwrap_or(Path::new(".")).join("glray-dropin");
    let cache = std::env::var_os("XDG_CACHE_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cache")))
        .unwrap_or_else(std::env::temp_dir)
        .join("glray/dropin");
    let mut errors = Vec::new();
    for dir in [beside, cache] {
        let made = (|| -> std::io::Result<()> {
            std::fs::create_dir_all(&dir)?;
            for name in NAMES {
                let link = dir.join(name);
                if std::fs::read_link(&link).ok().as_deref() != Some(lib) {
                    let _ = std::fs::remove_file(&link);
                    std::os::unix::fs::symlink(lib, &link)?;
                }
            }
            Ok(())
        })();
        match made {
            Ok(()) => return Ok(dir),
            Err(e) => errors.push(format!("{}: {e}", dir.display())),
        }
    }
    Err(format!("cannot create the drop-in directory: {}", errors.join("; ")))
}

/// `value` first in a search path (LD_LIBRARY_PATH: the drop-in directory wins).
fn prepend(var: &str, value: &Path, sep: char) -> OsString {
    let mut out = OsString::from(value);
    if let Some(old) = std::env::var_os(var).filter(|o| !o.is_empty()) {
        out.push(sep.to_string());
        out.push(old);
    }
    out
}

/// `value` last in LD_PRELOAD: interposers the user already preloads (overlays, frame grabbers,
/// tracers) see each call first and reach glray through RTLD_NEXT, as they would reach libGL.
fn append(var: &str, value: &Path, sep: char) -> OsString {
    match std::env::var_os(var).filter(|o| !o.is_empty()) {
        Some(mut old) => {
            old.push(sep.to_string());
            old.push(value);
            old
        }
        None => OsString::from(value),
    }
}

fn run(dropin: bool, set: &[String], library: Option<PathBuf>, program: &[OsString]) -> Result<(), String> {
    let flags = parse_flags(set)?;
    // Refuse to start with a bad setting: the library would only fall back to pass-through.
    Config::resolve(&process_env(), &flags)?;
    let lib = find_library(library)?;
    let mut cmd = std::process::Command::new(&program[0]);
    cmd.args(&program[1..]);
    for (k, v) in &flags {
        cmd.env(env_name(k), v);
    }
    if dropin {
        let dir = dropin_dir(&lib)?;
        cmd.env("LD_LIBRARY_PATH", prepend("LD_LIBRARY_PATH", &dir, ':'));
    } else {
        cmd.env("LD_PRELOAD", append("LD_PRELOAD", &lib, ':'));
    }
    let err = cmd.exec();
    Err(format!("cannot run {}: {err}", Path::new(&program[0]).display()))
}

fn info(set: &[String], library: Option<PathBuf>) -> Result<(), String> {
    let flags = parse_flags(set)?;
    let config = Config::resolve(&process_env(), &flags)?;
    println!("glray {}", glray_core::VERSION);
    let lib = find_library(library);
    match &lib {
        Ok(p) => println!("library: {}", p.display()),
        Err(e) => println!("library: not found ({e})"),
    }
    let own = lib.as_ref().ok().and_then(|p| FileId::of(p));
    println!("real libraries:");
    for kind in RealKind::ALL {
        match reallib::open(kind, config.real_path(kind.setting()), own) {
            Ok(l) => println!("  {:<15} {}", kind.soname(), l.path),
            Err(e) => println!("  {:<15} not found: {e}", kind.soname()),
        }
    }
    match &config.file {
        Some(f) => println!("config file: {}", f.display()),
        None => println!("config file: none (set GLRAY_CONFIG, or create ~/.config/glray/config.toml)"),
    }
    println!("settings (KEY = VALUE  [source]  environment variable):");
    for (s, value, source) in config.entries() {
        let shown = if s.kind == Kind::Path && value.is_empty() { "(auto)" } else { value };
        println!("  {:<17} = {:<8} [{source}]  {}", s.key, shown, env_name(s.key));
    }
    debug_assert_eq!(config.entries().len(), SETTINGS.len());
    Ok(())
}
