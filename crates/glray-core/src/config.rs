//! glray's settings: one table of every setting, and their resolution from
//! defaults < config file < environment < `glray run` flags, remembering where each value came
//! from (`glray info` prints it).
//!
//! An unknown key or a bad value is an error that names the key, where it was found and the
//! allowed values. The library turns such an error into a loud message and a pure pass-through
//! (it never stops the host); the `glray` command refuses to start the program.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

/// What values a setting accepts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    Bool,
    /// One of the listed words.
    Choice(&'static [&'static str]),
    /// A file system path; empty means "not set".
    Path,
    /// A whole number in [min, max]; empty means "the preset's".
    Int(i64, i64),
    /// A number in [min, max]; empty means "the preset's".
    Float(f64, f64),
    /// true or false; empty means "the preset's".
    OptionalBool,
    /// A share in (0, 1], as a fraction (1/8) or a number (0.125).
    Fraction,
}

/// One setting: its key in the TOML file; its environment variable is GLRAY_ + KEY uppercased.
#[derive(Debug)]
pub struct Setting {
    pub key: &'static str,
    pub kind: Kind,
    pub default: &'static str,
    pub doc: &'static str,
}

pub const LOG_LEVELS: &[&str] = &["off", "error", "warn", "info", "debug"];
pub const PRESETS: &[&str] = &["off", "gl", "ao", "full"];
pub const TRIGGERS: &[&str] = &["auto", "swap", "finish", "flush", "readpixels"];
pub const LIGHTING: &[&str] = &["vertex", "pixel"];
pub const PRESENTS: &[&str] = &["auto", "pixels", "shader"];
pub const DISTRIBUTIONS: &[&str] = &["auto", "local", "replicated", "paged", "data-parallel"];
pub const PAGING: &[&str] = &["wait", "park", "all-resident"];
pub const MPI_ROLES: &[&str] = &["shared", "dedicated", "paper"];
pub const MPI_COMPRESSIONS: &[&str] = &["lz4", "zstd", "none"];
pub const MPI_PICTURES: &[&str] = &["own", "whole"];
/// The values of `mpi_tiles` (glray-distribute's `TileHomes`).
pub const MPI_TILES: &[&str] = &["bands", "random"];
/// The values of `bvh` (glray-render's `bvh_choice::BvhBuild`).
pub const BVH_BUILDS: &[&str] = &["auto", "sah", "fast"];

/// Every setting glray has. docs/settings.md is checked against this table by a test.
pub const SETTINGS: &[Setting] = &[
    Setting {
        key: "enable",
        kind: Kind::Bool,
        default: "true",
        doc: "false makes glray a pure pass-through: every call goes to the real GL unchanged.",
    },
    Setting {
        key: "log",
        kind: Kind::Choice(LOG_LEVELS),
        default: "warn",
        doc: "How much glray writes to standard error (each line starts with `glray:`).",
    },
    Setting {
        key: "intercept_dlopen",
        kind: Kind::Bool,
        default: "true",
        doc: "Redirect the program's dlopen of libGL, libGLX, libOpenGL, libEGL and libOSMesa \
              (exact library names only) to glray, so that programs that load GL themselves \
              still reach it.",
    },
    Setting {
        key: "record",
        kind: Kind::Path,
        default: "",
        doc: "Record every GL/GLX/EGL/OSMesa call of the program into this trace file (docs/trace-format.md); \
              `%p` becomes the process id. Empty: no recording.",
    },
    Setting {
        key: "preset",
        kind: Kind::Choice(PRESETS),
        default: "ao",
        doc: "What the program's frames become: `gl`, ray traced in the look of GL's fixed-function pipeline \
              (matching what Mesa draws); `ao`, that look times ambient occlusion (16 rays); `full`, the \
              advanced look (36 AO rays, shadows from the GL lights, one reflection, 4 samples per pixel); \
              `off`, the real GL's own frames (glray only passes calls through, and records if asked). The \
              effect settings below override a preset's choice one by one.",
    },
    Setting {
        key: "ao_samples",
        kind: Kind::Int(0, 1024),
        default: "",
        doc: "Ambient-occlusion rays per visible point (0: none). Empty: the preset's (gl 0, ao 16, full 36).",
    },
    Setting {
        key: "ao_distance",
        kind: Kind::Float(0.0, 10.0),
        default: "",
        doc: "How far an occluder darkens a point, as a fraction of the scene's diagonal (default 0.1).",
    },
    Setting {
        key: "ao_intensity",
        kind: Kind::Float(0.0, 1.0),
        default: "",
        doc: "How dark a fully occluded point becomes: its colour times 1 - intensity (default 1).",
    },
    Setting {
        key: "shadows",
        kind: Kind::OptionalBool,
        default: "",
        doc: "Hard shadows from every enabled GL light (lit surfaces are then lit per pixel). Empty: the \
              preset's (on in full).",
    },
    Setting {
        key: "reflections",
        kind: Kind::Int(0, 16),
        default: "",
        doc: "Reflection bounces (0: none). Empty: the preset's (1 in full).",
    },
    Setting {
        key: "reflectivity",
        kind: Kind::Float(0.0, 1.0),
        default: "",
        doc: "How much of every surface is mirror, seen head-on, when reflections are on (default 0.04, \
              as glass or plastic); more at grazing angles, all at the most (Fresnel, as Schlick has it).",
    },
    Setting {
        key: "samples",
        kind: Kind::Int(1, 1024),
        default: "",
        doc: "Samples per pixel: the first at the pixel centre, the others jittered over it (antialiasing). \
              Empty: the preset's (4 in full, else 1).",
    },
    Setting {
        key: "progressive",
        kind: Kind::Bool,
        default: "true",
        doc: "While the scene and camera stay the same from frame to frame, each frame adds its samples to \
              the ones before (up to 64 frames), so a still picture converges to full quality; a converged \
              picture (the GL look: after one frame) is shown again without tracing. false: every frame is \
              traced anew.",
    },
    Setting {
        key: "denoise",
        kind: Kind::Bool,
        default: "true",
        doc: "Denoise ambient occlusion: each frame's AO is averaged with the last frames' where the same \
              surface points were (followed through the objects' and the camera's motion) and filtered \
              along surfaces (edge-aware, guided by depth, normals and objects), so that one pass's few \
              rays give a clean picture on a moving scene. The GL look under it is not filtered. false: \
              the raw samples (progressive refinement still averages a still scene).",
    },
    Setting {
        key: "batch_passes",
        kind: Kind::Int(0, 64),
        default: "16",
        doc: "An offscreen program's frames (drawn into a framebuffer object by a process that has \
              swapped a window at most once: pvbatch, `openscad -o`), whose one read-back \
              frame is the picture, are traced with this many passes at once with effects on, so that \
              its ambient occlusion and antialiasing have converged in that frame (as `progressive` \
              converges a still interactive view over frames). 0 or 1: one pass per frame. Under MPI \
              each pass is a frame shared by every rank.",
    },
    Setting {
        key: "panel",
        kind: Kind::Int(0, 65535),
        default: "",
        doc: "The live control panel: a web page and JSON API on 127.0.0.1 at this port (0: a free one), \
              to steer the picture settings of the running program and watch its frames and statistics \
              (docs/panel.md). Its address and access token are printed at start. Empty: off.",
    },
    Setting {
        key: "stats",
        kind: Kind::Path,
        default: "",
        doc: "Per-frame statistics: `stderr`, or a file to append JSON lines to (capture, BVH build, trace \
              and present times, rays, rays per second, triangles, samples). Empty: none.",
    },
    Setting {
        key: "trigger",
        kind: Kind::Choice(TRIGGERS),
        default: "auto",
        doc: "When a frame is ray traced and put in place: `auto`, at the first of a buffer swap (GLX, EGL), \
              glFinish/glFlush of an OSMesa context, or a glReadPixels of a frame not yet presented; `swap`, \
              `finish`, `flush` or `readpixels`, only there.",
    },
    Setting {
        key: "lighting",
        kind: Kind::Choice(LIGHTING),
        default: "vertex",
        doc: "Where the GL look evaluates the lighting equation: `vertex`, at the vertices, colours interpolated \
              across triangles (Gouraud, as GL does); `pixel`, at every pixel with the interpolated normal \
              (smoother highlights on coarse meshes; no longer identical to GL).",
    },
    Setting {
        key: "bvh",
        kind: Kind::Choice(BVH_BUILDS),
        default: "auto",
        doc: "How BVHs are built: `sah`, by the surface area heuristic (the tree the rays walk fastest); \
              `fast`, a linear BVH (Morton order: the build in about half the time, rays 13-20% slower); \
              `auto`, fast only for a tree the next frame builds again (the frame's loose triangles, or a mesh \
              the program replaces every frame, such as simulation time steps) when its build outweighs the \
              frame's rays (a mesh built so that then stays is built by SAH in its second frame), otherwise \
              by SAH.",
    },
    Setting {
        key: "present",
        kind: Kind::Choice(PRESENTS),
        default: "auto",
        doc: "How a ray-traced frame is put into the real framebuffer: `auto`, with glDrawPixels in \
              compatibility contexts and with a textured triangle drawn by a small shader program in core \
              profiles (which have no glDrawPixels); `pixels` or `shader` to force one (`shader` needs \
              GL 3.1; `pixels` falls back to it in a core profile).",
    },
    Setting {
        key: "dump_scene",
        kind: Kind::Path,
        default: "",
        doc: "Write each ray-traced frame's captured scene into this directory: scene-NNNN.obj + .mtl (eye \
              coordinates) and scene-NNNN.json (triangles, draws, camera). Empty: no dump.",
    },
    Setting {
        key: "dump_frames",
        kind: Kind::Int(0, 1 << 30),
        default: "10",
        doc: "How many frames `dump_scene` writes: the first N ray-traced ones (a program drawing 60 \
              frames a second would fill a disk). 0: every frame.",
    },
    Setting {
        key: "distribute",
        kind: Kind::Choice(DISTRIBUTIONS),
        default: "auto",
        doc: "How the ranks of an MPI job share frames (docs/distributed.md): `replicated`, every rank traces \
              tiles of the whole image against every rank's scene (image-parallel: shadows, AO and reflections \
              see all the data); `paged`, the same pictures, but each rank keeps only the big meshes its host \
              drew (in blocks) and fetches the blocks of other ranks' its rays reach into a cache \
              (`cache_fraction`); `data-parallel`, each rank traces only what it drew, for the host's \
              compositor; `local`, no MPI at all. `auto`: `replicated` in an MPI rank, `local` otherwise.",
    },
    Setting {
        key: "cache_fraction",
        kind: Kind::Fraction,
        default: "1/8",
        doc: "With `distribute = paged`: each rank's cache of other ranks' blocks, as a share of all the \
              ranks' paged meshes together (the paper's 1/F: 1/2, 1/4, 1/8), e.g. `1/8` or `0.125`.",
    },
    Setting {
        key: "cache_mb",
        kind: Kind::Int(0, 1 << 30),
        default: "0",
        doc: "With `distribute = paged`: each rank's cache of other ranks' blocks in megabytes, in place of \
              `cache_fraction`. 0: `cache_fraction` decides.",
    },
    Setting {
        key: "paging",
        kind: Kind::Choice(PAGING),
        default: "wait",
        doc: "With `distribute = paged`, how other ranks' blocks come: `wait`, fetched as rays reach them, \
              the thread waiting for each (the blocking way, GLuRay's; faster on this 2-core machine); `park`, \
              fetched as rays reach them, a piece of the picture whose rays miss one set aside while the \
              thread traces others, and traced again when its blocks have come; `all-resident` (for checking), every block of the \
              frame fetched before it is traced and kept: the same blocks and trees with nothing remote \
              while tracing, the reference paging's pictures equal.",
    },
    Setting {
        key: "prefetch",
        kind: Kind::Bool,
        default: "false",
        doc: "With `distribute = paged`: at the start of each frame, ask at once for the other ranks' blocks \
              this rank's rays used last frame that its cache no longer holds (at most as many as the cache \
              holds), so that they travel together while the frame starts instead of one round trip at a \
              time as rays reach them.",
    },
    Setting {
        key: "memory_mb",
        kind: Kind::Int(0, 1 << 30),
        default: "0",
        doc: "The memory a rank may use, in megabytes (0: its share of its cgroup's limit, if it has one: the \
              limit over the job's ranks on the node). Replicated, \
              a rank whose scene would not fit stops sharing frames with a message naming `distribute = \
              paged` (each rank then traces its own data) rather than be killed for its memory.",
    },
    Setting {
        key: "block_kb",
        kind: Kind::Int(1, 1 << 20),
        default: "128",
        doc: "With `distribute = paged`: about how many kilobytes of triangles and tree a block holds (meshes \
              of more than 8,192 triangles are paged, in blocks of their triangles close in space).",
    },
    Setting {
        key: "mpi_roles",
        kind: Kind::Choice(MPI_ROLES),
        default: "shared",
        doc: "With `distribute = replicated`: `shared`, every rank traces, rank 0 hands out the tiles beside \
              its share; `dedicated`, rank 0 only hands out tiles and shows the picture, the other ranks \
              trace; `paper`, as the paper ran it: rank 0 the display, rank 1 the master (with three ranks or \
              more), the other ranks trace.",
    },
    Setting {
        key: "mpi_compression",
        kind: Kind::Choice(MPI_COMPRESSIONS),
        default: "lz4",
        doc: "How glray's messages between ranks are compressed (losslessly: the pictures are the same): \
              `lz4` (fast, about half the bytes of a frame's pixels), `zstd` (fewer bytes for a few times the \
              time: slow links), `none`. A paged scene's blocks go compressed only while the network is behind.",
    },
    Setting {
        key: "mpi_poll",
        kind: Kind::Int(0, 100_000),
        default: "1000",
        doc: "Microseconds glray's MPI thread waits between looks at MPI when it has nothing to do: an ask \
              from another rank waits at most this long. 0: it never waits (a core kept busy, as a blocking \
              MPI_Probe keeps one with Open MPI over TCP).",
    },
    Setting {
        key: "mpi_picture",
        kind: Kind::Choice(MPI_PICTURES),
        default: "own",
        doc: "Which part of the ray-traced picture each rank other than 0 gets back for its framebuffer: \
              `own`, the part its own data covers (what a sort-last compositor such as IceT takes from it; \
              the rest is its background); `whole`, all of it (a host that reads the whole frame on every \
              rank). Rank 0 always gets all of it.",
    },
    Setting {
        key: "mpi_tiles",
        kind: Kind::Choice(MPI_TILES),
        default: "bands",
        doc: "Where each tile of a shared frame goes first: `bands`, to the rank whose band of rows holds it \
              (the same tiles on the same rank frame after frame: what it holds for them, paging's cache, \
              stays warm); `random`, to a rank drawn at random for each tile and frame (the comparison). Read \
              on the rank that hands out tiles.",
    },
    Setting {
        key: "threads",
        kind: Kind::Int(0, 4096),
        default: "0",
        doc: "Tracer threads in each process. 0: every core, shared among the ranks of an MPI job that run \
              on the same node.",
    },
    Setting {
        key: "mpi_timeout",
        kind: Kind::Float(0.0, 86400.0),
        default: "",
        doc: "Seconds a rank waits for another before it stops image-parallel tracing with a message naming \
              that rank (each rank then traces its own data). Empty: 120 s on the first frame, then the last \
              frame's time plus 10 s.",
    },
    Setting {
        key: "mpi_library",
        kind: Kind::Path,
        default: "",
        doc: "glray's MPI edge, libglray_mpi.so, loaded only in an MPI rank (default: the one beside \
              libglray.so).",
    },
    Setting {
        key: "real_opengl",
        kind: Kind::Path,
        default: "",
        doc: "The real GL library (default: glvnd's libOpenGL.so.0).",
    },
    Setting {
        key: "real_glx",
        kind: Kind::Path,
        default: "",
        doc: "The real GLX library (default: glvnd's libGLX.so.0).",
    },
    Setting {
        key: "real_egl",
        kind: Kind::Path,
        default: "",
        doc: "The real EGL library (default: glvnd's libEGL.so.1).",
    },
    Setting {
        key: "real_osmesa",
        kind: Kind::Path,
        default: "",
        doc: "The real OSMesa library (default: libOSMesa.so.8).",
    },
];

/// The environment variable that names the config file; it is not a setting of the file itself.
pub const CONFIG_ENV: &str = "GLRAY_CONFIG";

pub fn env_name(key: &str) -> String {
    format!("GLRAY_{}", key.to_ascii_uppercase())
}

/// Where a value came from, lowest precedence first.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Source {
    Default,
    File(PathBuf),
    Env(String),
    Flag,
    /// Changed while the program runs, from the live control panel.
    Panel,
}

impl fmt::Display for Source {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            Source::Default => write!(f, "default"),
            Source::File(p) => write!(f, "file {}", p.display()),
            Source::Env(v) => write!(f, "environment {v}"),
            Source::Flag => write!(f, "glray run flag"),
            Source::Panel => write!(f, "the live control panel"),
        }
    }
}

/// A bad setting, with enough words to fix it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConfigError(pub String);

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ConfigError {}

impl From<ConfigError> for String {
    fn from(e: ConfigError) -> String {
        e.0
    }
}

/// The settings in force, each with its source.
#[derive(Debug, Clone)]
pub struct Config {
    values: BTreeMap<&'static str, (String, Source)>,
    pub file: Option<PathBuf>,
}

fn setting(key: &str) -> Option<&'static Setting> {
    SETTINGS.iter().find(|s| s.key == key)
}

fn allowed(kind: Kind) -> String {
    match kind {
        Kind::Bool => "true, false (also 1, 0, yes, no, on, off)".into(),
        Kind::Choice(words) => words.join(", "),
        Kind::Path => "a file path".into(),
        Kind::Int(lo, hi) => format!("a whole number from {lo} to {hi}, or empty for the preset's"),
        Kind::Float(lo, hi) => format!("a number from {lo} to {hi}, or empty for the preset's"),
        Kind::OptionalBool => "true, false (also 1, 0, yes, no, on, off), or empty for the preset's".into(),
        Kind::Fraction => "a share from 0 (not included) to 1, as a fraction (1/8) or a number (0.125)".into(),
    }
}

fn parse_bool(v: &str) -> Option<bool> {
    match v.trim().to_ascii_lowercase().as_str() {
        "1" | "true" | "yes" | "on" => Some(true),
        "0" | "false" | "no" | "off" => Some(false),
        _ => None,
    }
}

/// A share written `a/b` or as a number, if it is in (0, 1].
pub fn fraction(value: &str) -> Option<f64> {
    let v = value.trim();
    let share = match v.split_once('/') {
        Some((a, b)) => a.trim().parse::<f64>().ok()? / b.trim().parse::<f64>().ok()?,
        None => v.parse::<f64>().ok()?,
    };
    (share.is_finite() && share > 0.0 && share <= 1.0).then_some(share)
}

/// Checks `value` for `s` and returns its canonical spelling.
fn validate(s: &Setting, value: &str, place: &dyn Fn() -> String) -> Result<String, ConfigError> {
    let ok = match s.kind {
        Kind::Bool => parse_bool(value).map(|b| b.to_string()),
        Kind::Choice(words) => {
            let v = value.trim().to_ascii_lowercase();
            words.contains(&v.as_str()).then_some(v)
        }
        Kind::Path => Some(value.to_string()),
        _ if value.trim().is_empty() => Some(String::new()),
        Kind::OptionalBool => parse_bool(value).map(|b| b.to_string()),
        Kind::Int(lo, hi) => value.trim().parse::<i64>().ok().filter(|v| (lo..=hi).contains(v)).map(|v| v.to_string()),
        Kind::Float(lo, hi) => {
            value.trim().parse::<f64>().ok().filter(|v| v.is_finite() && (lo..=hi).contains(v)).map(|v| v.to_string())
        }
        Kind::Fraction => fraction(value).map(|_| value.trim().to_string()),
    };
    ok.ok_or_else(|| {
        ConfigError(format!("bad value {value:?} for setting `{}` ({}); allowed: {}", s.key, place(), allowed(s.kind)))
    })
}

fn unknown_key(key: &str, place: &str) -> ConfigError {
    let keys: Vec<&str> = SETTINGS.iter().map(|s| s.key).collect();
    let guess = nearest(key, keys.iter().copied()).map(|k| format!("did you mean `{k}`? ")).unwrap_or_default();
    ConfigError(format!("unknown setting `{key}` ({place}); {guess}known settings: {}", keys.join(", ")))
}

/// The candidate a misspelt `word` most likely meant: the closest by edit distance (letters
/// added, dropped or changed, case aside), if it is close (a third of the word's letters at most).
fn nearest<'a>(word: &str, candidates: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    let word = word.to_ascii_lowercase();
    let best = candidates.map(|c| (edit_distance(&word, &c.to_ascii_lowercase()), c)).min_by_key(|(d, _)| *d)?;
    (best.0 > 0 && best.0 <= word.len().div_ceil(3)).then_some(best.1)
}

/// Levenshtein distance over bytes (setting names are ASCII).
fn edit_distance(a: &str, b: &str) -> usize {
    let b = b.as_bytes();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.bytes().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let next = (diagonal + usize::from(ca != *cb)).min(row[j] + 1).min(row[j + 1] + 1);
            diagonal = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

/// The config file in effect: $GLRAY_CONFIG if set, else $XDG_CONFIG_HOME/glray/config.toml or
/// ~/.config/glray/config.toml if it exists.
pub fn config_file(env: &dyn Fn(&str) -> Option<String>) -> Option<PathBuf> {
    if let Some(p) = env(CONFIG_ENV).filter(|p| !p.is_empty()) {
        return Some(PathBuf::from(p));
    }
    let dir = env("XDG_CONFIG_HOME")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .or_else(|| env("HOME").map(|h| Path::new(&h).join(".config")))?;
    let p = dir.join("glray").join("config.toml");
    p.exists().then_some(p)
}

impl Config {
    /// Resolves every setting from the file, the environment (`env_vars`: all variables, of which
    /// those starting with GLRAY_ are read) and the flags, in that order of precedence.
    pub fn resolve(env_vars: &[(String, String)], flags: &[(String, String)]) -> Result<Config, ConfigError> {
        let env = |k: &str| env_vars.iter().rev().find(|(n, _)| n == k).map(|(_, v)| v.clone());
        let mut values: BTreeMap<&'static str, (String, Source)> =
            SETTINGS.iter().map(|s| (s.key, (s.default.to_string(), Source::Default))).collect();

        let file = config_file(&env);
        if let Some(path) = &file {
            let text = std::fs::read_to_string(path)
                .map_err(|e| ConfigError(format!("cannot read config file {} ({CONFIG_ENV}): {e}", path.display())))?;
            let table: toml::Table =
                text.parse().map_err(|e| ConfigError(format!("config file {}: {e}", path.display())))?;
            for (key, value) in table {
                let place = format!("in {}", path.display());
                let s = setting(&key).ok_or_else(|| unknown_key(&key, &place))?;
                let raw = match (&value, s.kind) {
                    (toml::Value::Boolean(b), Kind::Bool) => b.to_string(),
                    (toml::Value::Integer(i), Kind::Bool) => i.to_string(),
                    (toml::Value::String(v), _) => v.clone(),
                    (other, _) => other.to_string(),
                };
                let v = validate(s, &raw, &|| place.clone())?;
                values.insert(s.key, (v, Source::File(path.clone())));
            }
        }

        for (name, value) in env_vars {
            let Some(rest) = name.strip_prefix("GLRAY_") else { continue };
            if name == CONFIG_ENV {
                continue;
            }
            let key = rest.to_ascii_lowercase();
            let place = format!("environment variable {name}");
            let s = setting(&key).ok_or_else(|| {
                let keys: Vec<String> = SETTINGS.iter().map(|s| env_name(s.key)).collect();
                let guess = nearest(name, keys.iter().map(String::as_str).chain([CONFIG_ENV]))
                    .map(|k| format!("did you mean {k}? "))
                    .unwrap_or_default();
                ConfigError(format!(
                    "unknown setting {name} ({place}); {guess}known: {}, {CONFIG_ENV}",
                    keys.join(", ")
                ))
            })?;
            let v = validate(s, value, &|| place.clone())?;
            values.insert(s.key, (v, Source::Env(name.clone())));
        }

        for (key, value) in flags {
            let place = "a glray run --set flag".to_string();
            let s = setting(key).ok_or_else(|| unknown_key(key, &place))?;
            let v = validate(s, value, &|| place.clone())?;
            values.insert(s.key, (v, Source::Flag));
        }
        Ok(Config { values, file })
    }

    /// Resolves from this process's environment, with no flags.
    pub fn from_process_env() -> Result<Config, ConfigError> {
        let vars: Vec<(String, String)> =
            std::env::vars_os().filter_map(|(k, v)| Some((k.into_string().ok()?, v.into_string().ok()?))).collect();
        Config::resolve(&vars, &[])
    }

    /// Every setting with its value and source, in table order.
    pub fn entries(&self) -> Vec<(&'static Setting, &str, &Source)> {
        SETTINGS
            .iter()
            .map(|s| {
                let (v, src) = &self.values[s.key];
                (s, v.as_str(), src)
            })
            .collect()
    }

    fn get(&self, key: &str) -> &str {
        &self.values[key].0
    }

    /// The value of setting `key` (None: no such setting).
    pub fn value(&self, key: &str) -> Option<&str> {
        self.values.get(key).map(|(v, _)| v.as_str())
    }

    /// These settings with `changes` (key, value) made from the live control panel: each key
    /// one of `allowed`, each value checked as from any other place; the first bad one is the
    /// error, and nothing changes.
    pub fn with_changes(&self, changes: &[(String, String)], allowed: &[&str]) -> Result<Config, ConfigError> {
        let mut out = self.clone();
        for (key, value) in changes {
            let place = "from the live control panel".to_string();
            let s = setting(key).filter(|s| allowed.contains(&s.key)).ok_or_else(|| {
                let guess =
                    nearest(key, allowed.iter().copied()).map(|k| format!("did you mean `{k}`? ")).unwrap_or_default();
                ConfigError(format!(
                    "setting `{key}` cannot be changed from the panel; {guess}it changes: {}",
                    allowed.join(", ")
                ))
            })?;
            let v = validate(s, value, &|| place.clone())?;
            out.values.insert(s.key, (v, Source::Panel));
        }
        Ok(out)
    }

    /// The settings `keys` as a config file (`GLRAY_CONFIG` reads it back): one `key = "value"`
    /// line each, after a comment saying what made it.
    pub fn to_toml(&self, keys: &[&str], made_by: &str) -> String {
        let mut out = format!("# glray settings, {made_by}: GLRAY_CONFIG=this-file reproduces them\n");
        for key in keys {
            if let Some(v) = self.value(key) {
                out.push_str(&format!("{key} = {}\n", toml::Value::String(v.to_string())));
            }
        }
        out
    }

    /// Where setting `key`'s value came from.
    pub fn source(&self, key: &str) -> Option<&Source> {
        self.values.get(key).map(|(_, s)| s)
    }

    /// What setting `key` accepts, in words (None: no such setting).
    pub fn allowed(key: &str) -> Option<String> {
        setting(key).map(|s| allowed(s.kind))
    }

    /// The live control panel's port (None: off).
    pub fn panel(&self) -> Option<u16> {
        self.get("panel").parse().ok()
    }

    pub fn enable(&self) -> bool {
        self.get("enable") == "true"
    }

    pub fn intercept_dlopen(&self) -> bool {
        self.get("intercept_dlopen") == "true"
    }

    pub fn log_level(&self) -> crate::log::Level {
        crate::log::Level::parse(self.get("log")).unwrap_or(crate::log::Level::Warn)
    }

    /// The trace file to record into, if any.
    pub fn record(&self) -> Option<&str> {
        Some(self.get("record")).filter(|p| !p.is_empty())
    }

    /// The preset frames are ray traced with (`off`: pass-through).
    pub fn preset(&self) -> &str {
        self.get("preset")
    }

    /// When frames are ray traced and presented.
    pub fn trigger(&self) -> &str {
        self.get("trigger")
    }

    /// Whether lighting runs per pixel (else per vertex).
    pub fn per_pixel_lighting(&self) -> bool {
        self.get("lighting") == "pixel"
    }

    /// A number setting, if set (empty: the preset decides).
    pub fn number(&self, key: &str) -> Option<f64> {
        self.get(key).parse().ok()
    }

    /// A true/false setting, if set (empty: the preset decides).
    pub fn flag(&self, key: &str) -> Option<bool> {
        parse_bool(self.get(key))
    }

    /// Where per-frame statistics go: "stderr", a file, or nowhere.
    pub fn stats(&self) -> Option<&str> {
        Some(self.get("stats")).filter(|p| !p.is_empty())
    }

    /// How frames are presented: "auto", "pixels" or "shader".
    pub fn present(&self) -> &str {
        self.get("present")
    }

    /// How BVHs are built: "auto", "sah" or "fast".
    pub fn bvh(&self) -> &str {
        self.get("bvh")
    }

    /// Where to dump each frame's scene, if anywhere.
    pub fn dump_scene(&self) -> Option<&str> {
        Some(self.get("dump_scene")).filter(|p| !p.is_empty())
    }

    /// How many frames `dump_scene` writes (None: every one).
    /// Passes traced at once for an offscreen program's frame (at least 1).
    pub fn batch_passes(&self) -> u32 {
        self.get("batch_passes").parse().unwrap_or(16).max(1)
    }

    pub fn dump_frames(&self) -> Option<u64> {
        self.get("dump_frames").parse().ok().filter(|n| *n > 0)
    }

    /// `distribute`, with `auto` decided: `in_mpi` says whether this process is an MPI rank.
    pub fn distribute(&self, in_mpi: bool) -> &str {
        match self.get("distribute") {
            "auto" if in_mpi => "replicated",
            "auto" => "local",
            other => other,
        }
    }

    /// `cache_fraction` as a number.
    pub fn cache_fraction(&self) -> f64 {
        fraction(self.get("cache_fraction")).unwrap_or(0.125)
    }

    /// `cache_mb`, when set (not 0).
    pub fn cache_mb(&self) -> Option<u64> {
        self.get("cache_mb").parse().ok().filter(|&m| m > 0)
    }

    /// Whether `paging` is `all-resident`.
    pub fn all_resident(&self) -> bool {
        self.get("paging") == "all-resident"
    }

    /// Whether `paging` parks rays that miss a block (`park`) rather than wait.
    pub fn paging_parks(&self) -> bool {
        self.get("paging") == "park"
    }

    /// Whether a paged rank asks for last frame's blocks at the start of a frame (`prefetch`).
    pub fn paging_prefetches(&self) -> bool {
        self.get("prefetch") == "true"
    }

    /// `memory_mb` in bytes, when set (not 0).
    pub fn memory_limit(&self) -> Option<u64> {
        self.get("memory_mb").parse::<u64>().ok().filter(|&m| m > 0).map(|m| m << 20)
    }

    /// `block_kb` in bytes.
    pub fn block_bytes(&self) -> usize {
        self.get("block_kb").parse::<usize>().unwrap_or(128).max(1) * 1024
    }

    /// `mpi_roles`: "shared", "dedicated" or "paper".
    pub fn mpi_roles(&self) -> &str {
        self.get("mpi_roles")
    }

    /// `mpi_compression`: "lz4", "zstd" or "none".
    pub fn mpi_compression(&self) -> &str {
        self.get("mpi_compression")
    }

    /// `mpi_poll` in microseconds.
    pub fn mpi_poll(&self) -> u64 {
        self.get("mpi_poll").parse().unwrap_or(1000)
    }

    /// Whether tiles go to ranks at random (`mpi_tiles = random`) rather than to their bands'.
    pub fn mpi_random_tiles(&self) -> bool {
        self.get("mpi_tiles") == "random"
    }

    /// Whether ranks other than 0 get the whole picture back (`mpi_picture = whole`).
    pub fn mpi_whole_picture(&self) -> bool {
        self.get("mpi_picture") == "whole"
    }

    /// Tracer threads asked for (None: decide from the cores and ranks).
    pub fn threads(&self) -> Option<usize> {
        self.get("threads").parse().ok().filter(|n| *n > 0)
    }

    /// `mpi_timeout` in seconds, when set.
    pub fn mpi_timeout(&self) -> Option<f64> {
        self.get("mpi_timeout").parse().ok()
    }

    /// A number that is the same in two processes exactly when the settings that shape a picture
    /// are: what the ranks of an MPI job must agree on (not where logs, traces and statistics go,
    /// nor threads or the MPI library).
    pub fn picture_settings(&self) -> u64 {
        use std::hash::{Hash, Hasher};
        const APART: &[&str] = &[
            "log",
            "panel",
            "record",
            "stats",
            "dump_scene",
            "dump_frames",
            "threads",
            "mpi_timeout",
            "mpi_library",
            "mpi_compression",
            "mpi_poll",
            "mpi_picture",
            "mpi_tiles",
            "real_opengl",
            "real_glx",
            "real_egl",
            "real_osmesa",
            "present",
        ];
        let mut h = std::collections::hash_map::DefaultHasher::new();
        env!("CARGO_PKG_VERSION").hash(&mut h);
        for s in SETTINGS.iter().filter(|s| !APART.contains(&s.key)) {
            (s.key, self.get(s.key)).hash(&mut h);
        }
        h.finish()
    }

    /// The user's path for a real library, if set.
    pub fn real_path(&self, key: &str) -> Option<&str> {
        Some(self.get(key)).filter(|p| !p.is_empty())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vars(v: &[(&str, &str)]) -> Vec<(String, String)> {
        v.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect()
    }

    #[test]
    fn a_misspelt_setting_gets_a_suggestion() {
        let env = |k: &str| vars(&[("HOME", "/nonexistent"), (k, "1")]);
        let e = Config::resolve(&env("GLRAY_AO_SAMPLE"), &[]).unwrap_err().0;
        assert!(e.starts_with("unknown setting GLRAY_AO_SAMPLE (environment variable GLRAY_AO_SAMPLE); did you mean GLRAY_AO_SAMPLES? known:"), "{e}");
        let e = Config::resolve(&vars(&[("HOME", "/nonexistent")]), &[("preest".into(), "gl".into())]).unwrap_err().0;
        assert!(e.contains("did you mean `preset`?"), "{e}");
        // Nothing close: no guess.
        let e = Config::resolve(&env("GLRAY_WHATEVER"), &[]).unwrap_err().0;
        assert!(!e.contains("did you mean"), "{e}");
        assert_eq!(edit_distance("kitten", "sitting"), 3);
    }

    #[test]
    fn paging_settings_take_a_share_a_size_and_a_mode() {
        let env = |k: &str, v: &str| vars(&[("HOME", "/nonexistent"), (k, v)]);
        let defaults = Config::resolve(&vars(&[("HOME", "/nonexistent")]), &[]).unwrap();
        assert_eq!((defaults.cache_fraction(), defaults.cache_mb(), defaults.all_resident()), (0.125, None, false));
        assert!(!defaults.paging_parks(), "rays that miss a block wait unless told to park");
        assert_eq!((defaults.block_bytes(), defaults.memory_limit()), (128 * 1024, None));
        for (value, share) in [("1/4", 0.25), (" 1 / 2 ", 0.5), ("0.0625", 0.0625), ("1", 1.0)] {
            let c = Config::resolve(&env("GLRAY_CACHE_FRACTION", value), &[]).unwrap();
            assert_eq!(c.cache_fraction(), share, "{value}");
        }
        for bad in ["0", "2", "1/0", "-1/8", "an eighth", "1/8/2"] {
            let e = Config::resolve(&env("GLRAY_CACHE_FRACTION", bad), &[]).unwrap_err().0;
            assert!(e.contains("`cache_fraction`") && e.contains("as a fraction (1/8)"), "{bad}: {e}");
        }
        let c = Config::resolve(&env("GLRAY_DISTRIBUTE", "paged"), &[]).unwrap();
        assert_eq!(c.distribute(true), "paged");
        let c = Config::resolve(&env("GLRAY_PAGING", "all-resident"), &[]).unwrap();
        assert!(c.all_resident() && !c.paging_parks());
        let c = Config::resolve(&env("GLRAY_PAGING", "park"), &[]).unwrap();
        assert!(!c.all_resident() && c.paging_parks());
        let e = Config::resolve(&env("GLRAY_PAGING", "fetch"), &[]).unwrap_err().0;
        assert!(e.contains("`paging`") && e.contains("wait, park, all-resident"), "{e}");
        let c = Config::resolve(&env("GLRAY_MEMORY_MB", "300"), &[]).unwrap();
        assert_eq!(c.memory_limit(), Some(300 << 20));
        assert!(Config::resolve(&env("GLRAY_PAGING", "sometimes"), &[]).is_err());
    }

    #[test]
    fn defaults_apply_without_anything_set() {
        let c = Config::resolve(&vars(&[("HOME", "/nonexistent")]), &[]).unwrap();
        assert!(c.enable());
        assert_eq!(c.log_level(), crate::log::Level::Warn);
        assert!(c.entries().iter().all(|(_, _, s)| **s == Source::Default));
    }

    #[test]
    fn effect_settings_take_numbers_in_range_or_nothing() {
        let env = |k: &str, v: &str| vars(&[("HOME", "/nonexistent"), (k, v)]);
        let c = Config::resolve(&env("GLRAY_AO_SAMPLES", "36"), &[]).unwrap();
        assert_eq!(c.number("ao_samples"), Some(36.0));
        assert_eq!(c.number("reflections"), None, "empty: the preset's");
        assert_eq!(c.flag("shadows"), None);
        let c = Config::resolve(&env("GLRAY_SHADOWS", "on"), &[]).unwrap();
        assert_eq!(c.flag("shadows"), Some(true));
        for (k, v) in [
            ("GLRAY_AO_SAMPLES", "-1"),
            ("GLRAY_AO_INTENSITY", "1.5"),
            ("GLRAY_SAMPLES", "0"),
            ("GLRAY_AO_DISTANCE", "x"),
        ] {
            let e = Config::resolve(&env(k, v), &[]).unwrap_err().to_string();
            let key = k.trim_start_matches("GLRAY_").to_ascii_lowercase();
            assert!(e.contains(&format!("`{key}`")) && e.contains("or empty for the preset's"), "{e}");
        }
        let flags = [("preset".to_string(), "full".to_string()), ("reflectivity".to_string(), "0.5".to_string())];
        let c = Config::resolve(&vars(&[("HOME", "/nonexistent")]), &flags).unwrap();
        assert_eq!((c.preset(), c.number("reflectivity")), ("full", Some(0.5)));
    }

    #[test]
    fn precedence_is_file_then_env_then_flag() {
        let dir = std::env::temp_dir().join(format!("glray-cfg-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("c.toml");
        std::fs::write(&file, "enable = false\nlog = \"info\"\nintercept_dlopen = false\n").unwrap();
        let env = vars(&[("GLRAY_CONFIG", file.to_str().unwrap()), ("GLRAY_LOG", "debug"), ("GLRAY_ENABLE", "1")]);
        let c = Config::resolve(&env, &[("enable".into(), "off".into())]).unwrap();
        let by_key = |k: &str| c.entries().into_iter().find(|(s, _, _)| s.key == k).unwrap();
        assert_eq!(by_key("intercept_dlopen").1, "false");
        assert_eq!(*by_key("intercept_dlopen").2, Source::File(file.clone()));
        assert_eq!(by_key("log").1, "debug");
        assert_eq!(*by_key("log").2, Source::Env("GLRAY_LOG".into()));
        assert_eq!(by_key("enable").1, "false");
        assert_eq!(*by_key("enable").2, Source::Flag);
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn bad_value_names_setting_and_allowed_values() {
        let e = Config::resolve(&vars(&[("GLRAY_LOG", "loud")]), &[]).unwrap_err().0;
        assert!(e.contains("`log`") && e.contains("GLRAY_LOG") && e.contains("off, error, warn, info, debug"), "{e}");
        let e = Config::resolve(&vars(&[("GLRAY_ENABLE", "maybe")]), &[]).unwrap_err().0;
        assert!(e.contains("`enable`") && e.contains("true, false"), "{e}");
    }

    #[test]
    fn unknown_keys_are_named_everywhere() {
        let e = Config::resolve(&vars(&[("GLRAY_ENABEL", "1")]), &[]).unwrap_err().0;
        assert!(e.contains("GLRAY_ENABEL") && e.contains("GLRAY_ENABLE"), "{e}");
        let e = Config::resolve(&[], &[("colour".into(), "red".into())]).unwrap_err().0;
        assert!(e.contains("`colour`") && e.contains("known settings"), "{e}");
        let dir = std::env::temp_dir().join(format!("glray-cfg2-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("c.toml");
        std::fs::write(&file, "presett = \"gl\"\n").unwrap();
        let e = Config::resolve(&vars(&[("GLRAY_CONFIG", file.to_str().unwrap())]), &[]).unwrap_err().0;
        assert!(e.contains("`presett`") && e.contains(file.to_str().unwrap()), "{e}");
        std::fs::write(&file, "enable = [1, 2]\n").unwrap();
        let e = Config::resolve(&vars(&[("GLRAY_CONFIG", file.to_str().unwrap())]), &[]).unwrap_err().0;
        assert!(e.contains("`enable`"), "{e}");
        std::fs::write(&file, "enable = \n").unwrap();
        let e = Config::resolve(&vars(&[("GLRAY_CONFIG", file.to_str().unwrap())]), &[]).unwrap_err().0;
        assert!(e.contains("config file"), "{e}");
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn missing_config_file_named_by_env_is_an_error() {
        let e = Config::resolve(&vars(&[("GLRAY_CONFIG", "/nonexistent/glray.toml")]), &[]).unwrap_err().0;
        assert!(e.contains("/nonexistent/glray.toml") && e.contains("GLRAY_CONFIG"), "{e}");
    }
}
