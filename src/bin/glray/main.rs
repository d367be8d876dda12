//! The `glray` command: runs a program under glray (`glray run`), and tells what glray would do
//! (`glray info`). Settings given as flags win over the environment and the config file; they
//! reach the library as GLRAY_* environment variables of the program.

use std::ffi::OsString;
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};
use glray_core::config::{env_name, Config, Kind, SETTINGS};
use glray_core::log::plural;
use glray_core::reallib::{self, FileId, RealKind};

mod apitrace;
mod bench;
#[allow(dead_code)]
#[path = "../../abi/commands.rs"]
mod commands;
mod meshgen;
mod mpi_launch;
mod progress;
mod raytrace;
mod replay;

/// Where `glray replay` sends the calls.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Renderer {
    /// Mesa's OSMesa: the reference rasterizer.
    Osmesa,
    /// glray's capture and ray tracer.
    Glray,
    /// Both, into OUT/osmesa and OUT/glray, with difference images (OUT/diff-NNNN.png) and a
    /// comparison of each frame.
    Both,
}

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
        /// Drop-in instead of preload: put a directory whose libGL.so.1, libOpenGL.so.0,
        /// libGLX.so.0, libEGL.so.1 and libOSMesa.so.8 are glray first on LD_LIBRARY_PATH.
        #[arg(long)]
        dropin: bool,
        /// A setting for this run, KEY=VALUE (see `glray info`); may be repeated.
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Record the program's GL calls into this trace (the same as --set record=PATH).
        #[arg(long, value_name = "TRACE")]
        record: Option<PathBuf>,
        /// libglray.so to use (default: the one installed beside this command).
        #[arg(long, value_name = "PATH")]
        library: Option<PathBuf>,
        /// Serve the live control panel on 127.0.0.1 (at PORT; without one, a free port): its
        /// address and access token are printed at start (docs/panel.md). The same as
        /// --set panel=PORT.
        #[arg(long, value_name = "PORT", num_args = 0..=1, default_missing_value = "0", require_equals = true)]
        panel: Option<u16>,
        /// Run N ranks of PROGRAM under Open MPI's mpirun, each with glray and every GLRAY_*
        /// setting (image-parallel: docs/distributed.md).
        #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
        np: Option<u32>,
        /// With --np: the hosts to run on (mpirun --host), e.g. node1,node2 or node1:4,node2:4.
        #[arg(long, value_name = "H1,H2", requires = "np")]
        hosts: Option<String>,
        /// With --np: one more argument for mpirun (repeat for several), e.g.
        /// --mpirun-arg=--mca --mpirun-arg=btl --mpirun-arg=self,tcp.
        #[arg(long = "mpirun-arg", value_name = "ARG", requires = "np", allow_hyphen_values = true)]
        mpirun_args: Vec<String>,
        /// The program and its arguments (`--` before them is optional: every word from the
        /// program's name on is the program's).
        #[arg(required = true, trailing_var_arg = true, allow_hyphen_values = true, value_name = "PROGRAM ARGS")]
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
    /// Compare two images (PNG or PPM): the share of pixels with a channel off by more than the
    /// fuzz, PSNR, and a red difference image. Exit status 0 when the thresholds hold, 1 when
    /// not, 2 on an error (unreadable file, sizes differ).
    Compare {
        a: PathBuf,
        b: PathBuf,
        /// A channel may be off by this share of 255 before its pixel counts as differing
        /// (0.05 or 5%).
        #[arg(long, default_value = "0.05", value_name = "SHARE", value_parser = parse_share)]
        fuzz: f64,
        /// The largest share of differing pixels that passes (0.02 or 2%: the rule glray's
        /// GL look is held to against Mesa, docs/compatibility.md).
        #[arg(long, default_value = "0.02", value_name = "SHARE", value_parser = parse_share)]
        max_differing: f64,
        /// The lowest PSNR in dB that passes (default: no PSNR threshold).
        #[arg(long)]
        min_psnr: Option<f64>,
        /// Write the difference image here (red = differing pixel).
        #[arg(long, value_name = "PNG")]
        diff: Option<PathBuf>,
        /// Print one JSON object instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Replay a recorded trace (glray run --record) and write each frame as OUT/frame-NNNN.png.
    Replay {
        trace: PathBuf,
        #[arg(long, value_enum, default_value = "osmesa")]
        renderer: Renderer,
        /// Directory for the images (created if missing).
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Only these frames, e.g. 0,3,5-7 (default: all).
        #[arg(long, value_name = "LIST")]
        frames: Option<String>,
        /// Also write what each glReadPixels of RGB/RGBA bytes returned (readpixels-NNNN.png):
        /// the picture of programs that draw offscreen and read it back, like OpenSCAD.
        #[arg(long)]
        readpixels: bool,
    },
    /// Benchmark the tracer on the anchors' isosurface (made here, or read from a file), with
    /// the anchors' camera and light: BVH build, primary and ambient-occlusion frames, peak
    /// memory, in embree_bench's terms.
    Bench {
        /// The mesh: an anchors file (meshgen's ISOMESH1 .bin) or a Wavefront .obj (moved and
        /// scaled to where the camera looks). Default: the anchors' isosurface, generated.
        #[arg(long, value_name = "FILE")]
        mesh: Option<PathBuf>,
        /// The size of the generated isosurface (without --mesh): the anchors' 100K, 1M or
        /// 10M, or any count (250K, 2.5M, 40000).
        #[arg(long, default_value = "1M", value_name = "COUNT", value_parser = parse_count, conflicts_with = "mesh")]
        triangles: u64,
        #[arg(long, default_value_t = 1280)]
        width: u32,
        #[arg(long, default_value_t = 720)]
        height: u32,
        /// Ambient-occlusion rays per hit in the AO frames.
        #[arg(long, default_value_t = 16)]
        ao: u32,
        /// Threads (default: one per core).
        #[arg(long)]
        threads: Option<usize>,
        /// Timed frames of each kind, after one warm-up.
        #[arg(long, default_value_t = 5)]
        frames: u32,
        /// Timed BVH builds.
        #[arg(long, default_value_t = 3)]
        builds: u32,
        /// How the BVH is built (the `bvh` setting; `auto` builds the bench's mesh, drawn
        /// unchanged, by SAH).
        #[arg(long, default_value = "auto", value_parser = glray_render::options::BVH_CHOICES.to_vec())]
        bvh: String,
        /// Print one JSON object instead of RESULT lines.
        #[arg(long)]
        json: bool,
        /// Write the last AO frame here (PNG).
        #[arg(long, value_name = "PNG")]
        out: Option<PathBuf>,
        /// Only write the generated isosurface to FILE (the anchors' ISOMESH1 format, as
        /// meshgen.c writes it) and stop: for benchmarks of other programs on the same mesh
        /// (scripts/bench-mpi).
        #[arg(long, value_name = "FILE", conflicts_with = "mesh")]
        save_mesh: Option<PathBuf>,
    },
    /// Print a trace's events, one per line.
    Dump {
        trace: PathBuf,
        /// Stop after this many calls.
        #[arg(long)]
        calls: Option<u64>,
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
        Command::Compare { a, b, fuzz, max_differing, min_psnr, diff, json } => {
            return compare(&a, &b, fuzz, max_differing, min_psnr, diff.as_deref(), json);
        }
        Command::Run { dropin, mut set, record, library, panel, np, hosts, mpirun_args, program } => {
            if let Some(port) = panel {
                set.push(format!("panel={port}"));
            }
            if let Some(r) = record {
                // Absolute, so that a program that changes directory records where it was asked.
                let r = std::path::absolute(&r).unwrap_or(r);
                set.push(format!("record={}", r.display()));
            }
            let ranks = np.map(|np| mpi_launch::Ranks { np, hosts, extra: mpirun_args });
            run(dropin, &set, library, ranks.as_ref(), &program)
        }
        Command::Info { set, library } => info(&set, library),
        Command::Replay { trace, renderer, out, frames, readpixels } => {
            replay(&trace, renderer, &out, frames, readpixels)
        }
        Command::Dump { trace, calls } => dump(&trace, calls),
        Command::Bench { save_mesh: Some(path), triangles, .. } => bench::save_mesh(&path, triangles),
        Command::Bench {
            mesh,
            triangles,
            width,
            height,
            ao,
            threads,
            frames,
            builds,
            bvh,
            json,
            out,
            save_mesh: None,
        } => bench::run(&bench::Args {
            mesh: mesh.as_deref(),
            triangles,
            bvh: glray_render::options::BvhBuild::from_setting(&bvh).unwrap_or_default(),
            width,
            height,
            ao,
            threads,
            frames,
            builds,
            json,
            out: out.as_deref(),
        }),
        Command::DropinDir { library } => {
            find_library(library).and_then(|lib| dropin_dir(&lib)).map(|d| println!("{}", d.display()))
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("glray: error: {e}");
            ExitCode::from(2)
        }
    }
}

fn read_trace(path: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))
}

/// A trace in glray's format: read as is, or converted from an apitrace file.
fn load_trace(trace: &Path) -> Result<Vec<u8>, String> {
    let data = read_trace(trace)?;
    if !apitrace::is_apitrace(&data) {
        return Ok(data);
    }
    let (converted, c) = apitrace::convert(&data).map_err(|e| format!("{}: {e}", trace.display()))?;
    eprintln!("glray: {} is an apitrace trace: {} calls read", trace.display(), c.calls);
    if !c.unknown.is_empty() {
        let names: Vec<String> = c.unknown.iter().map(|(n, k)| format!("{n} ({k})")).collect();
        eprintln!("glray: warning: skipped calls glray does not know: {}", names.join(", "));
    }
    Ok(converted)
}

fn replay(
    trace: &Path,
    renderer: Renderer,
    out: &Path,
    frames: Option<String>,
    readpixels: bool,
) -> Result<(), String> {
    let frames = frames.as_deref().map(replay::FrameSet::parse).transpose()?.unwrap_or_default();
    let data = load_trace(trace)?;
    let config = Config::resolve(&process_env(), &[])?;
    match renderer {
        Renderer::Osmesa => replay_osmesa(trace, &data, out, frames, readpixels, &config),
        Renderer::Glray => replay_glray(trace, &data, out, &frames, readpixels, &config),
        Renderer::Both => {
            let (mesa, ours) = (out.join("osmesa"), out.join("glray"));
            replay_osmesa(trace, &data, &mesa, frames.clone(), readpixels, &config)?;
            replay_glray(trace, &data, &ours, &frames, readpixels, &config)?;
            compare_dirs(&mesa, &ours, out)
        }
    }
}

fn replay_glray(
    trace: &Path,
    data: &[u8],
    out: &Path,
    frames: &replay::FrameSet,
    readpixels: bool,
    config: &Config,
) -> Result<(), String> {
    // The preset and effect settings in force; `off` (nothing ray traced live) replays the GL look.
    let options = glray_render::Options::from_config(config).unwrap_or_default();
    let s = raytrace::run(data, out, frames, readpixels, &options, false)
        .map_err(|e| format!("{}: {e}", trace.display()))?;
    println!(
        "ray traced {}: {} ({}) written to {}{} ({} traced, {})",
        plural(s.calls, "call"),
        plural(s.frames_written, "frame"),
        plural(s.triangles, "triangle"),
        out.display(),
        if readpixels { format!(", {}", plural(s.readpixels_written, "glReadPixels image")) } else { String::new() },
        plural(s.frames_traced, "frame"),
        plural(s.passes_traced, "pass")
    );
    Ok(())
}

/// Compares every image of `mesa` with glray's of the same name, the way `glray compare`
/// counts (a pixel differs when a channel is off by more than 5%), writing OUT/diff-NAME.
fn compare_dirs(mesa: &Path, ours: &Path, out: &Path) -> Result<(), String> {
    use glray_core::image::{compare, Image};
    let mut names: Vec<_> = std::fs::read_dir(mesa)
        .map_err(|e| format!("{}: {e}", mesa.display()))?
        .filter_map(|e| e.ok().map(|e| e.file_name()))
        .filter(|n| n.to_string_lossy().ends_with(".png"))
        .collect();
    names.sort();
    for name in names {
        let (a, b) = (mesa.join(&name), ours.join(&name));
        let n = name.to_string_lossy();
        if !b.exists() {
            println!("{n}: glray wrote no image");
            continue;
        }
        let c = compare(&Image::read(&a)?, &Image::read(&b)?, 0.05)?;
        c.diff.write_png(&out.join(format!("diff-{n}")))?;
        println!("{n}: {:.3}% of pixels differ by more than 5%; PSNR {:.2} dB", c.differing_share() * 100.0, c.psnr);
    }
    Ok(())
}

fn replay_osmesa(
    trace: &Path,
    data: &[u8],
    out: &Path,
    frames: replay::FrameSet,
    readpixels: bool,
    config: &Config,
) -> Result<(), String> {
    let mut r = replay::Replayer::new(out, frames, readpixels, config.real_path("real_osmesa"))?;
    let summary = r.run(data).map_err(|e| format!("{}: {e}", trace.display()))?;
    println!(
        "replayed {}: {} written to {}{}",
        plural(summary.calls, "call"),
        plural(summary.frames_written, "frame"),
        out.display(),
        if readpixels {
            format!(", {}", plural(summary.readpixels_written, "glReadPixels image"))
        } else {
            String::new()
        }
    );
    if !summary.missing.is_empty() {
        eprintln!("glray: warning: OSMesa lacks {} (those calls were skipped)", summary.missing.join(", "));
    }
    Ok(())
}

fn dump(trace: &Path, max_calls: Option<u64>) -> Result<(), String> {
    use glray_core::trace::Reader;
    use std::io::Write;
    let data = load_trace(trace)?;
    let fail = |e: glray_core::trace::TraceError| format!("{}: {e}", trace.display());
    let mut r = Reader::new(&data).map_err(fail)?;
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    // A closed pipe (`glray dump t.trace | head`) ends the dump quietly.
    let mut closed = false;
    let mut write = |line: String| -> Result<(), String> {
        match writeln!(out, "{line}") {
            Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {
                closed = true;
                Err(String::new())
            }
            other => other.map_err(|e| e.to_string()),
        }
    };
    let result = dump_events(&mut r, &mut write, max_calls, &fail);
    match result {
        Err(e) if e.is_empty() && closed => Ok(()),
        other => other,
    }
}

fn dump_events(
    r: &mut glray_core::trace::Reader,
    write: &mut dyn FnMut(String) -> Result<(), String>,
    max_calls: Option<u64>,
    fail: &dyn Fn(glray_core::trace::TraceError) -> String,
) -> Result<(), String> {
    use glray_core::trace::Event;
    write(format!("glray trace version {}", r.version))?;
    while let Some(event) = r.next_event().map_err(fail)? {
        match event {
            Event::Name { .. } => {}
            Event::Call { cmd, thread, args, ret } => {
                let args: Vec<String> = args.iter().map(show_value).collect();
                let ret = ret.map(|v| format!(" = {}", show_value(&v))).unwrap_or_default();
                let name = String::from_utf8_lossy(r.name(cmd));
                write(format!("{} [{thread}] {name}({}){ret}", r.calls() - 1, args.join(", ")))?;
                if max_calls.is_some_and(|m| r.calls() >= m) {
                    break;
                }
            }
            Event::Frame { number } => write(format!("-- frame {number} --"))?,
            Event::Drawable { thread, id, width, height } => {
                write(format!("   [{thread}] drawable {id:#x}: {width}x{height}"))?
            }
            Event::Arrays { thread, arrays } => {
                for a in arrays {
                    write(format!(
                        "   [{thread}] array kind {} #{}: size {} type {:#x} stride {} from element {}, {} bytes",
                        a.kind,
                        a.index,
                        a.size,
                        a.gl_type,
                        a.stride,
                        a.first,
                        a.bytes.len()
                    ))?;
                }
            }
            Event::End => write("-- end --".into())?,
        }
    }
    Ok(())
}

fn show_value(v: &glray_core::trace::Value) -> String {
    use glray_core::trace::Value;
    match v {
        Value::Int(x) => x.to_string(),
        Value::UInt(x) if *x > 0xFFFF => format!("{x:#x}"),
        Value::UInt(x) => x.to_string(),
        Value::F32(x) => format!("{x}"),
        Value::F64(x) => format!("{x}"),
        Value::Null => "NULL".into(),
        Value::Opaque(x) => format!("<{x:#x}>"),
        Value::Offset(x) => format!("offset {x}"),
        Value::Blob(b) => format!("<{} bytes>", b.len()),
        Value::Str(s) => format!("{:?}", String::from_utf8_lossy(s)),
        Value::Strings(l) => format!("[{} strings]", l.len()),
    }
}

fn compare(
    a: &Path,
    b: &Path,
    fuzz: f64,
    max_differing: f64,
    min_psnr: Option<f64>,
    diff: Option<&Path>,
    json: bool,
) -> ExitCode {
    use glray_core::image::{compare, Image};
    let result = (|| -> Result<bool, String> {
        let c = compare(&Image::read(a)?, &Image::read(b)?, fuzz)?;
        if let Some(d) = diff {
            c.diff.write_png(d)?;
        }
        let pass = c.differing_share() <= max_differing && min_psnr.is_none_or(|m| c.psnr >= m);
        let db = |x: f64| if x.is_finite() { format!("{x:.2}") } else { "inf".into() };
        let psnr = db(c.psnr);
        let json_db = |x: f64| if x.is_finite() { db(x) } else { "null".into() };
        if json {
            println!(
                "{{\"pixels\":{},\"differing\":{},\"differing_share\":{},\"psnr\":{},\"psnr_objects\":{},\"max_channel_error\":{},\"fuzz\":{},\"pass\":{}}}",
                c.pixels,
                c.differing,
                c.differing_share(),
                json_db(c.psnr),
                json_db(c.psnr_objects),
                c.max_channel_error,
                fuzz,
                pass
            );
        } else {
            println!(
                "{} of {} pixels differ by more than {:.1}% ({:.3}%); PSNR {psnr} dB ({} dB over the objects); largest channel error {}; {}",
                c.differing,
                c.pixels,
                fuzz * 100.0,
                c.differing_share() * 100.0,
                db(c.psnr_objects),
                c.max_channel_error,
                if pass { "pass" } else { "FAIL" }
            );
        }
        Ok(pass)
    })();
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("glray: error: {e}");
            ExitCode::from(2)
        }
    }
}

/// A count such as 40000, 100K, 2.5M (`glray bench --triangles`).
fn parse_count(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let (number, scale) = match t.char_indices().last() {
        Some((i, 'k' | 'K')) => (&t[..i], 1e3),
        Some((i, 'm' | 'M')) => (&t[..i], 1e6),
        _ => (t, 1.0),
    };
    match number.parse::<f64>() {
        Ok(v) if v * scale >= 1.0 && v * scale <= 1e9 => Ok((v * scale).round() as u64),
        _ => Err("a count between 1 and 1000M, such as 40000, 100K or 2.5M".into()),
    }
}

/// A share between 0 and 1, given as such (0.02) or as a percentage (2%): `glray compare`'s
/// thresholds. Clap names the flag whose value this refuses.
fn parse_share(text: &str) -> Result<f64, String> {
    let (number, scale) = match text.trim().strip_suffix('%') {
        Some(pct) => (pct.trim(), 100.0),
        None => (text.trim(), 1.0),
    };
    let share = number.parse::<f64>().map(|v| v / scale).ok().filter(|v| (0.0..=1.0).contains(v));
    share.ok_or_else(|| {
        if scale == 1.0 && number.parse::<f64>().is_ok_and(|v| (1.0..=100.0).contains(&v)) {
            format!(
                "a share between 0 and 1 (did you mean {text}%, that is {}?)",
                number.parse::<f64>().unwrap() / 100.0
            )
        } else {
            "a share between 0 and 1, such as 0.02, or a percentage such as 2%".to_string()
        }
    })
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
    std::env::vars_os().filter_map(|(k, v)| Some((k.into_string().ok()?, v.into_string().ok()?))).collect()
}

/// libglray.so: --library, else beside this executable, else in ../lib/glray or ../lib.
fn find_library(explicit: Option<PathBuf>) -> Result<PathBuf, String> {
    if let Some(p) = explicit {
        return p.canonicalize().map_err(|e| format!("--library {}: {e}", p.display()));
    }
    let exe = std::env::current_exe().map_err(|e| format!("cannot locate the glray command: {e}"))?;
    let dir = exe.parent().unwrap_or(Path::new("/"));
    let candidates = [dir.join("libglray.so"), dir.join("../lib/glray/libglray.so"), dir.join("../lib/libglray.so")];
    candidates.iter().find(|p| p.exists()).and_then(|p| p.canonicalize().ok()).ok_or_else(|| {
        format!(
            "cannot find libglray.so beside {} (looked in {}); build it with `cargo build --release` \
                 or pass --library PATH",
            exe.display(),
            candidates.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
        )
    })
}

/// The drop-in directory: every GL library name (libGL, libOpenGL, libGLX, libEGL, libOSMesa,
/// versioned and not) linked to libglray.so. The loader sees one file under all these names and
/// loads it once; glray then opens the real libraries by path (docs/design.md). Beside the
/// library if writable, else in the user's cache directory.
fn dropin_dir(lib: &Path) -> Result<PathBuf, String> {
    const NAMES: [&str; 10] = [
        "libGL.so.1",
        "libGL.so",
        "libOpenGL.so.0",
        "libOpenGL.so",
        "libGLX.so.0",
        "libGLX.so",
        "libEGL.so.1",
        "libEGL.so",
        "libOSMesa.so.8",
        "libOSMesa.so",
    ];
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

fn run(
    dropin: bool,
    set: &[String],
    library: Option<PathBuf>,
    ranks: Option<&mpi_launch::Ranks>,
    program: &[OsString],
) -> Result<(), String> {
    let flags = parse_flags(set)?;
    // Refuse to start with a bad setting: the library would only fall back to pass-through.
    Config::resolve(&process_env(), &flags)?;
    let lib = find_library(library)?;
    let mut env: Vec<(String, OsString)> = flags.iter().map(|(k, v)| (env_name(k), OsString::from(v))).collect();
    if dropin {
        let dir = dropin_dir(&lib)?;
        env.push(("LD_LIBRARY_PATH".into(), prepend("LD_LIBRARY_PATH", &dir, ':')));
    } else {
        env.push(("LD_PRELOAD".into(), append("LD_PRELOAD", &lib, ':')));
    }
    let mut cmd = match ranks {
        Some(ranks) => mpi_launch::command(ranks, &env, program)?,
        None => {
            let mut cmd = std::process::Command::new(&program[0]);
            cmd.args(&program[1..]);
            cmd
        }
    };
    for (k, v) in &env {
        cmd.env(k, v);
    }
    // exec: the program's (or mpirun's) exit status is the command's.
    let err = cmd.exec();
    let name = if ranks.is_some() { OsString::from("mpirun") } else { program[0].clone() };
    Err(format!("cannot run {}: {err}", Path::new(&name).display()))
}

/// "RENDERER, GL VERSION" of Mesa, from a 1x1 OSMesa context (no display needed).
fn osmesa_renderer(lib: &reallib::RealLib) -> Option<String> {
    use std::ffi::{c_void, CStr};
    type GetString = unsafe extern "C" fn(u32) -> *const std::ffi::c_char;
    let api = reallib::OSMesaApi::load(lib).ok()?;
    let get_string = lib.sym(c"glGetString");
    if get_string.is_null() {
        return None;
    }
    // SAFETY: OSMesa's functions with osmesa.h's signatures; the buffer outlives the context,
    // which is destroyed before returning.
    unsafe {
        let get_string: GetString = std::mem::transmute::<*mut c_void, GetString>(get_string);
        let ctx = (api.create_ext)(0x1908 /* OSMESA_RGBA */, 0, 0, 0, std::ptr::null_mut());
        if ctx.is_null() {
            return None;
        }
        let mut pixel = [0u8; 4];
        let mut text = None;
        if (api.make_current)(ctx, pixel.as_mut_ptr().cast(), 0x1401 /* GL_UNSIGNED_BYTE */, 1, 1) != 0 {
            let s = |name: u32| {
                let p = get_string(name);
                (!p.is_null()).then(|| CStr::from_ptr(p).to_string_lossy().into_owned())
            };
            text = Some(format!(
                "{}, OpenGL {}",
                s(0x1F01 /* GL_RENDERER */).unwrap_or_default(),
                s(0x1F02 /* GL_VERSION */).unwrap_or_default()
            ));
        }
        (api.destroy)(ctx);
        text
    }
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
            Ok(l) => {
                println!("  {:<15} {}", kind.soname(), l.path);
                if kind == RealKind::OSMesa {
                    match osmesa_renderer(&l) {
                        Some(r) => println!("  {:<15} {r}", "renderer"),
                        None => println!("  {:<15} unknown (no OSMesa context could be made)", "renderer"),
                    }
                }
            }
            Err(e) => println!("  {:<15} not found: {e}", kind.soname()),
        }
    }
    match &config.file {
        Some(f) => println!("config file: {}", f.display()),
        None => println!("config file: none (set GLRAY_CONFIG, or create ~/.config/glray/config.toml)"),
    }
    println!("settings (KEY = VALUE  [where it came from]  environment variable):");
    for (key, value, source) in effective_settings(&config) {
        println!("  {key:<17} = {value:<8} [{source}]  {}", env_name(key));
    }
    Ok(())
}

/// Every setting's value in force and where it came from: the default, a file, the
/// environment or a flag; for an effect setting left empty, the preset's value ("preset ao");
/// for an empty path, what that means ("(none)", or "(auto)" for the real libraries and the
/// MPI edge, which glray finds itself); "(auto)" for an MPI time limit decided per frame.
fn effective_settings(config: &Config) -> Vec<(&'static str, String, String)> {
    let effects = glray_render::Options::from_config(config).map(|o| o.effects);
    let preset = config.preset();
    let entries = config.entries();
    debug_assert_eq!(entries.len(), SETTINGS.len());
    entries
        .into_iter()
        .map(|(s, value, source)| {
            let from_preset = |v: String| (v, format!("preset {preset}"));
            let (value, source) = match (value, &effects) {
                // Decided when it applies (docs/settings.md says how).
                ("", _) if s.key == "mpi_timeout" || s.key == "mpi_library" => ("(auto)".into(), source.to_string()),
                ("", _) if s.key == "panel" => ("(off)".into(), source.to_string()),
                ("", Some(e)) if s.kind != Kind::Path => match s.key {
                    "ao_samples" => from_preset(e.ao_samples.to_string()),
                    "ao_distance" => from_preset(e.ao_distance.to_string()),
                    "ao_intensity" => from_preset(e.ao_intensity.to_string()),
                    "shadows" => from_preset(e.shadows.to_string()),
                    "reflections" => from_preset(e.reflections.to_string()),
                    "reflectivity" => from_preset(e.reflectivity.to_string()),
                    "samples" => from_preset(e.samples.to_string()),
                    _ => (String::new(), source.to_string()),
                },
                // Preset off: nothing is ray traced, so no effect applies.
                ("", None) if s.kind != Kind::Path => ("(off)".into(), format!("preset {preset}")),
                ("", _) if s.key.starts_with("real_") => ("(auto)".into(), source.to_string()),
                ("", _) => ("(none)".into(), source.to_string()),
                (v, _) => (v.to_string(), source.to_string()),
            };
            (s.key, value, source)
        })
        .collect()
}
