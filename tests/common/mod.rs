//! What the integration tests share: where the built library, command and examples are; running a
//! program plainly, preloaded or dropped in; an Xvfb of the test's own; the frameshot helper; the
//! MPI example host.
#![allow(dead_code)]

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::OnceLock;

/// The directory of the build under test (target/release for `cargo test --release`).
pub fn build_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_glray")).parent().unwrap().to_path_buf()
}

pub fn glray_bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_glray"))
}

pub fn libglray() -> PathBuf {
    let p = build_dir().join("libglray.so");
    assert!(
        p.exists(),
        "{} is missing: build with `cargo build --release --all-targets` (scripts/test does)",
        p.display()
    );
    p
}

pub fn example(name: &str) -> PathBuf {
    let p = build_dir().join("examples").join(name);
    assert!(p.exists(), "{} is missing: build with `cargo build --release --all-targets`", p.display());
    p
}

/// A fresh scratch directory for one test.
pub fn scratch(test: &str) -> PathBuf {
    let dir = build_dir().join("test-scratch").join(test);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The files in `dir` whose names end in `.ext`, sorted.
pub fn files_ending(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == ext))
        .collect();
    files.sort();
    files
}

/// The drop-in directory, made by `glray dropin-dir`.
pub fn dropin_dir() -> PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let out = Command::new(glray_bin()).arg("dropin-dir").output().unwrap();
        assert!(out.status.success(), "glray dropin-dir: {}", String::from_utf8_lossy(&out.stderr));
        PathBuf::from(String::from_utf8(out.stdout).unwrap().trim())
    })
    .clone()
}

/// How a program is run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Way {
    /// Without glray: the reference.
    Plain,
    /// LD_PRELOAD=libglray.so (after any helper preloads).
    Preload,
    /// The drop-in directory first on LD_LIBRARY_PATH.
    Dropin,
}

pub const GLRAY_WAYS: [Way; 2] = [Way::Preload, Way::Dropin];

/// A command for `program` run `way`, with `preload` helpers (e.g. frameshot) before glray, and a
/// time limit (coreutils `timeout`, which kills it if it hangs). glray passes frames through
/// (GLRAY_PRESET=off): the interposer and recording tests compare with the real GL byte for
/// byte; tests of ray-traced frames set GLRAY_PRESET themselves.
pub fn command(way: Way, preload: &[&Path], program: &Path, seconds: u32) -> Command {
    let mut cmd = Command::new("timeout");
    cmd.arg("-k").arg("5").arg(seconds.to_string()).arg(program);
    set_way(&mut cmd, way, preload);
    cmd
}

/// `command` without the `timeout` wrapper: the process started is the program itself, so what
/// is loaded into it, its pid and its exit are the program's alone. Bound it with
/// `run_until_said`.
pub fn bare_command(way: Way, preload: &[&Path], program: &Path) -> Command {
    let mut cmd = Command::new(program);
    set_way(&mut cmd, way, preload);
    cmd
}

fn set_way(cmd: &mut Command, way: Way, preload: &[&Path]) {
    let mut preloads: Vec<String> = preload.iter().map(|p| p.display().to_string()).collect();
    without_glray(cmd);
    cmd.env_remove("LD_LIBRARY_PATH").env("GLRAY_PRESET", "off");
    match way {
        Way::Plain => {}
        Way::Preload => preloads.push(libglray().display().to_string()),
        Way::Dropin => {
            cmd.env("LD_LIBRARY_PATH", dropin_dir());
        }
    }
    if !preloads.is_empty() {
        cmd.env("LD_PRELOAD", preloads.join(":"));
    }
}

/// What a run said on standard error, and how it ended: `None` where the test stopped it.
pub struct Said {
    pub stderr: String,
    pub status: Option<std::process::ExitStatus>,
}

/// Starts `cmd` with its standard error into `log` and waits until what it said there makes
/// `done` true (then stops it by its pid, if it still runs) or it exits. Panics if neither
/// happened within `limit`, or if it exited without `done` becoming true.
pub fn run_until_said(cmd: &mut Command, log: &Path, limit: std::time::Duration, done: impl Fn(&str) -> bool) -> Said {
    run_bounded(cmd, log, limit, Some(&done))
}

/// Starts `cmd` with its standard error into `log` and waits for it to exit; stops it by its pid
/// and panics if it runs past `limit`.
pub fn run_to_end(cmd: &mut Command, log: &Path, limit: std::time::Duration) -> Said {
    run_bounded(cmd, log, limit, None)
}

fn run_bounded(cmd: &mut Command, log: &Path, limit: std::time::Duration, done: Option<&dyn Fn(&str) -> bool>) -> Said {
    let file = std::fs::File::create(log).unwrap();
    let child = cmd.stdout(Stdio::null()).stderr(file).spawn().unwrap_or_else(|e| panic!("{cmd:?}: {e}"));
    let mut child = Stopped(child);
    let started = std::time::Instant::now();
    loop {
        let exited = child.0.try_wait().unwrap();
        let text = std::fs::read_to_string(log).unwrap_or_default();
        if done.is_some_and(|done| done(&text)) || (done.is_none() && exited.is_some()) {
            let status = exited.or_else(|| child.0.try_wait().unwrap());
            drop(child);
            // All it said (a process stopped here says nothing more).
            let stderr = std::fs::read_to_string(log).unwrap_or_default();
            return Said { stderr, status };
        }
        assert!(exited.is_none(), "{cmd:?} ended ({exited:?}) before it said what was waited for:\n{text}");
        assert!(started.elapsed() < limit, "{cmd:?}: still running after {limit:?}:\n{text}");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
}

/// No GLRAY_* setting and no LD_PRELOAD of the test's own environment reach `cmd`.
pub fn without_glray(cmd: &mut Command) {
    for (k, _) in std::env::vars() {
        if k.starts_with("GLRAY_") {
            cmd.env_remove(k);
        }
    }
    cmd.env_remove("LD_PRELOAD");
}

/// Runs and returns the output; panics with stderr if it did not exit 0.
pub fn run_ok(cmd: &mut Command, what: &str) -> Output {
    let out = cmd.output().unwrap_or_else(|e| panic!("{what}: cannot start: {e}"));
    assert!(
        out.status.success(),
        "{what}: {:?}\nstdout: {}\nstderr: {}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Asserts two files are byte-identical.
pub fn assert_same_file(a: &Path, b: &Path, what: &str) {
    let x = std::fs::read(a).unwrap_or_else(|e| panic!("{what}: {}: {e}", a.display()));
    let y = std::fs::read(b).unwrap_or_else(|e| panic!("{what}: {}: {e}", b.display()));
    assert!(x.len() > 100, "{what}: {} is too small to be an image", a.display());
    assert!(x == y, "{what}: {} and {} differ", a.display(), b.display());
}

/// A process a test started, killed by its PID (and waited for) when dropped: on a failure too.
pub struct Stopped(pub Child);

impl Drop for Stopped {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// An X server of the test's own (Xvfb -noreset), stopped by PID when dropped.
pub struct Xvfb {
    _server: Stopped,
    pub display: String,
}

impl Xvfb {
    pub fn start() -> Xvfb {
        // -displayfd 1: Xvfb picks a free display number and writes it to its stdout.
        let mut child = Command::new("Xvfb")
            .args(["-displayfd", "1", "-noreset", "-nolisten", "tcp", "-screen", "0", "1280x1024x24"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("Xvfb is not installed: run scripts/test, which installs it");
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
        let n: u32 = line.trim().parse().unwrap_or_else(|_| panic!("Xvfb did not report a display: {line:?}"));
        Xvfb { _server: Stopped(child), display: format!(":{n}") }
    }
}

/// The frameshot helper (tests/helpers/frameshot.c), compiled once per test run.
pub fn frameshot() -> PathBuf {
    static LIB: OnceLock<PathBuf> = OnceLock::new();
    LIB.get_or_init(|| {
        let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/helpers/frameshot.c");
        let dir = build_dir().join("test-helpers");
        std::fs::create_dir_all(&dir).unwrap();
        let out = dir.join(format!("frameshot-{}.so", std::process::id()));
        run_ok(
            Command::new("cc").args(["-O2", "-shared", "-fPIC", "-o"]).arg(&out).arg(&src).arg("-ldl"),
            "compiling frameshot.c",
        );
        out
    })
    .clone()
}

pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

pub fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The path of an installed program, or a failure saying scripts/test installs it.
pub fn which(program: &str) -> PathBuf {
    let out = Command::new("sh").arg("-c").arg(format!("command -v {program}")).output().unwrap();
    assert!(out.status.success(), "{program} is not installed: scripts/test installs it");
    PathBuf::from(String::from_utf8(out.stdout).unwrap().trim())
}

/// `program args` on `display` under the frameshot helper, which grabs frame `frame` into `ppm`.
pub fn frameshot_command(way: Way, program: &Path, args: &[&str], display: &str, ppm: &Path, frame: u32) -> Command {
    let shot = frameshot();
    let mut cmd = command(way, &[&shot], program, 120);
    cmd.args(args).env("DISPLAY", display).env("FRAMESHOT_OUT", ppm).env("FRAMESHOT_FRAME", frame.to_string());
    cmd
}

/// The example host, compiled with mpicc (scripts/lib/build.sh does too; a test run alone
/// compiles it here).
pub fn icet_like() -> PathBuf {
    static BUILT: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    BUILT.get_or_init(|| build_mpi_example("icet_like", &["-lOSMesa", "-lz", "-lm"])).clone()
}

/// The second sort-last host (examples/mpi/direct_send.c: GLX windows, direct-send
/// compositing), compiled with mpicc likewise.
pub fn direct_send() -> PathBuf {
    static BUILT: std::sync::OnceLock<PathBuf> = std::sync::OnceLock::new();
    BUILT.get_or_init(|| build_mpi_example("direct_send", &["-lGL", "-lX11", "-lm"])).clone()
}

fn build_mpi_example(name: &str, libraries: &[&str]) -> PathBuf {
    let out = build_dir().join("examples").join(name);
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("examples/mpi/{name}.c"));
    let fresh = |p: &Path| p.metadata().and_then(|m| m.modified()).ok();
    if fresh(&out).is_none() || fresh(&out) < fresh(&source) {
        let tmp = out.with_extension(format!("{}.tmp", std::process::id()));
        let status = Command::new("mpicc")
            .arg(&source)
            .arg("-o")
            .arg(&tmp)
            .arg("-O2")
            .args(libraries)
            .status()
            .expect("mpicc is not installed: scripts/test installs libopenmpi-dev");
        assert!(status.success(), "mpicc {}", source.display());
        std::fs::rename(&tmp, &out).unwrap();
    }
    out
}

/// What a picture comparison measured when its bound was set (named in each test, beside the
/// comparison): the share of pixels with a channel off by more than 5% (`glray compare`'s
/// default fuzz, as apitrace's diff-images), and the PSNR in dB over what is drawn (the pixels
/// where either picture is not the background, its first pixel's colour: a sparse picture's
/// figure is not lifted by its empty space; infinite for equal pictures).
#[derive(Debug, Clone, Copy)]
pub struct Measured {
    pub share: f64,
    pub psnr: f64,
}

impl Measured {
    /// The most pixels off a test allows: three times what was measured, and at least 0.005%
    /// more (a few edge pixels, where none or one was off).
    pub fn share_bound(&self) -> f64 {
        (3.0 * self.share).max(self.share + 0.00005)
    }
    /// The least PSNR a test allows: 3 dB below what was measured (a shift of the whole
    /// picture too small for the share to see: a lighting term 5% off costs 10-20 dB), and no
    /// more than 60 dB (a few pixels off in a picture that had none).
    pub fn psnr_bound(&self) -> f64 {
        (self.psnr - 3.0).min(60.0)
    }
}

/// The share of pixels off by more than 5% and the PSNR of `picture` against `reference`.
pub fn measure(reference: &Path, picture: &Path) -> Measured {
    use glray_core::image::{compare, Image};
    let read = |p: &Path| Image::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    let c = compare(&read(reference), &read(picture), 0.05).unwrap_or_else(|e| panic!("{}: {e}", picture.display()));
    Measured { share: c.differing_share(), psnr: c.psnr_objects }
}

/// Asserts `picture` is as close to `reference` as `measured` says it was, within its bounds
/// (`Measured::share_bound`, `Measured::psnr_bound`); prints what it measures now.
pub fn assert_close(reference: &Path, picture: &Path, measured: Measured, what: &str) {
    let now = measure(reference, picture);
    eprintln!(
        "{what}: {:.4}% of pixels off by more than 5%, PSNR {:.1} dB (measured {:.4}%, {:.1} dB; bounds {:.4}%, {:.1} dB)",
        now.share * 100.0,
        now.psnr,
        measured.share * 100.0,
        measured.psnr,
        measured.share_bound() * 100.0,
        measured.psnr_bound()
    );
    assert!(
        now.share <= measured.share_bound() && now.psnr >= measured.psnr_bound(),
        "{what}: {:.4}% of pixels off by more than 5% and PSNR {:.1} dB against {}; measured when the bound was \
         set: {:.4}%, {:.1} dB",
        now.share * 100.0,
        now.psnr,
        reference.display(),
        measured.share * 100.0,
        measured.psnr
    );
}

/// A trace of the checked-in suite (tests/traces, made by scripts/record-test-traces): the
/// example program and arguments that recorded it. The program's own picture of its last frame
/// (Mesa's, read back by the program while it was recorded) is `NAME.png` beside it.
pub struct SuiteTrace {
    pub name: &'static str,
    pub program: &'static str,
    /// After the picture's path and the number of frames.
    pub parts: Option<&'static str>,
}

/// Every trace of the suite, as scripts/record-test-traces records them (3 frames each).
pub const TRACE_SUITE: [SuiteTrace; 8] = [
    SuiteTrace { name: "osmesa-lists", program: "osmesa_scene", parts: Some("lists") },
    SuiteTrace { name: "osmesa-immediate", program: "osmesa_scene", parts: Some("immediate") },
    SuiteTrace { name: "osmesa-arrays", program: "osmesa_scene", parts: Some("arrays") },
    SuiteTrace { name: "osmesa-buffers", program: "osmesa_scene", parts: Some("buffers") },
    SuiteTrace { name: "osmesa-textures", program: "osmesa_scene", parts: Some("textures") },
    SuiteTrace { name: "osmesa-all", program: "osmesa_scene", parts: Some("all") },
    SuiteTrace { name: "glx-all", program: "glx_scene", parts: None },
    SuiteTrace { name: "egl-all", program: "egl_scene", parts: None },
];

impl SuiteTrace {
    pub fn trace(&self) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/traces").join(format!("{}.trace", self.name))
    }
    /// The program's own picture of its last frame, kept with the trace.
    pub fn picture(&self) -> PathBuf {
        self.trace().with_extension("png")
    }
    /// Runs the program as it was recorded, without glray (Mesa draws), for `frames` frames on
    /// `display`, writing its picture of the last one into `png`.
    pub fn run_plainly(&self, frames: u32, display: &str, png: &Path) {
        let mut cmd = command(Way::Plain, &[], &example(self.program), 60);
        cmd.arg(png).arg(frames.to_string()).args(self.parts).env("DISPLAY", display);
        run_ok(&mut cmd, &format!("{} plainly, {frames} frames", self.program));
    }
}
