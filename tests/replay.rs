//! Recording and replay: the checked-in trace suite replays to its reference images; programs
//! recorded under glray and replayed into OSMesa give their own pictures back; bad traces stop
//! with a message naming the byte offset; `glray compare` and `glray dump` do what they say.

mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::process::Command;

fn glray(args: &[&str]) -> Command {
    let mut c = Command::new(glray_bin());
    c.args(args);
    c
}

fn replay(trace: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    let mut c = Command::new(glray_bin());
    c.arg("replay").arg(trace).arg("--out").arg(out).args(extra);
    run_ok(&mut c, &format!("glray replay {}", trace.display()))
}

/// `glray compare A B` with no pixel off by more than 5% (the default fuzz).
fn compare_ok(a: &Path, b: &Path, extra: &[&str]) {
    let mut c = Command::new(glray_bin());
    c.arg("compare").arg(a).arg(b).args(["--max-differing", "0"]).args(extra);
    let out = run_ok(&mut c, "glray compare");
    assert!(stdout(&out).contains("pass"), "{}", stdout(&out));
}

fn suite() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/traces")
}

#[test]
fn the_trace_suite_replays_to_the_programs_own_pictures() {
    // Each trace replayed into OSMesa gives the picture the program itself drew while it was
    // recorded (its own glReadPixels of Mesa's frame: no glray in the reference), and the
    // program draws that picture still (else the suite is out of date: re-record it with
    // scripts/record-test-traces). GLX and OSMesa are Mesa's llvmpipe both: the same bytes.
    // EGL's llvmpipe rounds some channels a level otherwise than OSMesa, drawing natively too.
    let x = Xvfb::start();
    let dir = scratch("suite");
    let traces = files_ending(&suite(), "trace");
    assert_eq!(traces.len(), TRACE_SUITE.len(), "tests/traces holds the traces common::TRACE_SUITE names");
    for t in &TRACE_SUITE {
        let now = dir.join(format!("{}-now.png", t.name));
        t.run_plainly(3, &x.display, &now);
        assert_same_file(&t.picture(), &now, &format!("{}: the program's picture today", t.name));
        let out = dir.join(t.name);
        let o = replay(&t.trace(), &out, &[]);
        assert!(stdout(&o).contains("3 frames written"), "{}: {}", t.name, stdout(&o));
        let replayed = out.join("frame-0002.png");
        if t.name == "egl-all" {
            assert_close(&t.picture(), &replayed, Measured { share: 0.0, psnr: 53.5 }, "egl-all replayed into OSMesa");
        } else {
            assert_same_file(&t.picture(), &replayed, t.name);
        }
    }
}

#[test]
fn frames_can_be_chosen() {
    let dir = scratch("frames");
    replay(&suite().join("osmesa-lists.trace"), &dir, &["--frames", "0,2"]);
    let mut files: Vec<String> =
        std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    files.sort();
    assert_eq!(files, ["frame-0000.png", "frame-0002.png"]);
    let bad = glray(&["replay", "x.trace", "--out", "/tmp/x", "--frames", "3-1"]).output().unwrap();
    assert_eq!(bad.status.code(), Some(2));
    assert!(stderr(&bad).contains("--frames"), "{}", stderr(&bad));
}

#[test]
fn ray_traced_replays_trace_only_the_frames_a_chosen_one_needs() {
    let dir = scratch("traced-frames");
    // A moving scene (the suite's), and a still one: an idle program's frames, all the same.
    let moving = suite().join("osmesa-all.trace");
    let still = dir.join("still.trace");
    let mut record = command(Way::Preload, &[], &example("osmesa_scene"), 60);
    record.arg(dir.join("still.png")).arg("3").env("SCENE_STILL", "1").env("GLRAY_RECORD", &still);
    run_ok(&mut record, "osmesa_scene recording, still");
    let run = |preset: &str, out: &str, frames: &[&str]| {
        let trace = if preset == "gl" { &moving } else { &still };
        let mut c = glray(&["replay", "--renderer", "glray", "--out"]);
        c.arg(dir.join(out)).arg(trace).args(frames).env("GLRAY_PRESET", preset);
        let o = run_ok(&mut c, "glray replay --renderer glray");
        (stdout(&o), stderr(&o))
    };
    let calls = |out: &str| -> u64 {
        let n = out.strip_prefix("ray traced ").and_then(|s| s.split(' ').next()).unwrap_or_else(|| panic!("{out}"));
        n.parse().unwrap_or_else(|e| panic!("{out}: {e}"))
    };
    // The GL look: frames 0 and 1 clear and are not written, so they are not traced, and
    // frame 2 is the same picture as when every frame is.
    let (chosen, _) = run("gl", "chosen", &["--frames", "2"]);
    assert!(chosen.contains(": 1 frame (") && chosen.contains("(1 frame traced, 1 pass)"), "{chosen}");
    let (all, _) = run("gl", "all", &[]);
    assert!(all.contains("(3 frames traced, 3 passes)"), "{all}");
    assert_same_file(&dir.join("all/frame-0002.png"), &dir.join("chosen/frame-0002.png"), "the GL look");
    // Ambient occlusion refines over unchanged frames (the still scene): frame 2 holds frames 0
    // and 1's samples,
    // gathered at frame 2 alone (three passes, said on standard error), not by tracing
    // frames 0 and 1: the same picture as the replay of every frame.
    let (ao_chosen, said) = run("ao", "ao-chosen", &["--frames", "2"]);
    assert!(ao_chosen.contains("(1 frame traced, 3 passes)"), "{ao_chosen}");
    assert!(said.contains("frame 2: gathering 3 passes (3 samples per pixel)"), "{said}");
    let (ao_all, said) = run("ao", "ao-all", &[]);
    assert!(ao_all.contains("(3 frames traced, 3 passes)"), "{ao_all}");
    assert!(!said.contains("gathering"), "{said}");
    assert_same_file(&dir.join("ao-all/frame-0002.png"), &dir.join("ao-chosen/frame-0002.png"), "ao");
    // `--frames 0`: one frame traced, one pass, and the trace read no further than frame 0.
    let (first, _) = run("ao", "ao-first", &["--frames", "0"]);
    assert!(first.contains(": 1 frame (") && first.contains("(1 frame traced, 1 pass)"), "{first}");
    assert!(calls(&first) < calls(&ao_all), "stops after frame 0: {first} / {ao_all}");
    assert_same_file(&dir.join("ao-all/frame-0000.png"), &dir.join("ao-first/frame-0000.png"), "ao frame 0");
    // Without a terminal, a replay shorter than the plain lines' period prints no progress.
    let (_, said) = run("ao", "ao-quiet", &["--frames", "1"]);
    assert!(!said.contains("replay: frame"), "{said}");
}

/// Records `program args` under glray (with `way`'s preloads), replays into OSMesa, and returns
/// the replay's directory.
fn record_and_replay(name: &str, cmd: &mut Command, dir: &Path, replay_args: &[&str]) -> PathBuf {
    let trace = dir.join(format!("{name}.trace"));
    cmd.env("GLRAY_RECORD", &trace);
    run_ok(cmd, &format!("{name} recording"));
    let out = dir.join(format!("{name}-replay"));
    replay(&trace, &out, replay_args);
    out
}

#[test]
fn our_programs_replay_to_their_own_pictures() {
    let x = Xvfb::start();
    let dir = scratch("examples-replay");
    for name in ["osmesa_scene", "glx_scene", "egl_scene"] {
        let png = dir.join(format!("{name}.png"));
        let mut cmd = command(Way::Preload, &[], &example(name), 60);
        cmd.arg(&png).arg("3").env("DISPLAY", &x.display);
        let out = record_and_replay(name, &mut cmd, &dir, &[]);
        if name == "egl_scene" {
            // EGL's llvmpipe and OSMesa round a few edge pixels differently (a channel off by a
            // few levels): the same happens drawing natively with each, without any trace.
            compare_ok(&png, &out.join("frame-0002.png"), &["--min-psnr", "40"]);
        } else {
            assert_same_file(&png, &out.join("frame-0002.png"), name);
        }
    }
}

/// A real program's frame N (grabbed by frameshot) against frame N-1 (0-based) of its replay.
fn real_program_replays(name: &str, program: &Path, args: &[&str], frame: u32) {
    let x = Xvfb::start();
    let dir = scratch(&format!("replay-{name}"));
    let ppm = dir.join("live.ppm");
    let mut cmd = frameshot_command(Way::Preload, program, args, &x.display, &ppm, frame);
    let want = format!("{}", frame - 1);
    let out = record_and_replay(name, &mut cmd, &dir, &["--frames", &want]);
    let replayed = out.join(format!("frame-{:04}.png", frame - 1));
    // Byte-identical pixels: compare decodes PPM and PNG alike.
    let c = run_ok(
        Command::new(glray_bin()).arg("compare").arg(&ppm).arg(&replayed).args(["--fuzz", "0"]),
        &format!("{name} compare"),
    );
    assert!(stdout(&c).starts_with("0 of "), "{name}: {}", stdout(&c));
}

#[test]
fn glxgears_replays_to_its_own_frame() {
    real_program_replays("glxgears", &which("glxgears"), &[], 3);
}

#[test]
fn xscreensaver_lament_replays_to_its_own_frame() {
    // Textures bound inside display lists, EGL.
    real_program_replays("lament", Path::new("/usr/libexec/xscreensaver/lament"), &["-window"], 4);
}

#[test]
fn xscreensaver_sproingies_replays_to_its_own_frame() {
    // GL_POLYGON with glVertex3i, client arrays, a clip plane.
    real_program_replays("sproingies", Path::new("/usr/libexec/xscreensaver/sproingies"), &["-window"], 4);
}

#[test]
fn openscad_replays_to_its_own_png() {
    let x = Xvfb::start();
    let dir = scratch("replay-openscad");
    let model = dir.join("model.scad");
    std::fs::write(&model, "difference() { cube(10, center=true); sphere(6.5, $fn=48); }\n").unwrap();
    let png = dir.join("openscad.png");
    let mut cmd = command(Way::Preload, &[], &which("openscad"), 120);
    cmd.arg("-o").arg(&png).arg(&model).env("DISPLAY", &x.display);
    // OpenSCAD draws into a framebuffer object and reads it back: its picture is what that
    // glReadPixels returned.
    let out = record_and_replay("openscad", &mut cmd, &dir, &["--readpixels"]);
    let c = run_ok(
        Command::new(glray_bin()).arg("compare").arg(&png).arg(out.join("readpixels-0000.png")).args(["--fuzz", "0"]),
        "openscad compare",
    );
    assert!(stdout(&c).starts_with("0 of "), "{}", stdout(&c));
}

/// `glray replay` on a damaged trace: exit status 2, a message with the byte offset, no panic.
fn replay_fails(data: &[u8], name: &str, expect: &[&str]) {
    let dir = scratch(&format!("bad-{name}"));
    let trace = dir.join("bad.trace");
    std::fs::write(&trace, data).unwrap();
    let out = glray(&["replay"]).arg(&trace).arg("--out").arg(dir.join("out")).output().unwrap();
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{name}: {:?} {err}", out.status);
    assert!(!err.contains("panicked"), "{name}: {err}");
    for e in expect {
        assert!(err.contains(e), "{name}: message lacks {e:?}: {err}");
    }
}

#[test]
fn damaged_traces_are_refused_with_the_offset() {
    let good = std::fs::read(suite().join("osmesa-lists.trace")).unwrap();
    replay_fails(&good[..good.len() / 2], "truncated", &["byte ", "(call ", "truncated"]);
    replay_fails(b"NOTATRACE", "magic", &["not a glray trace"]);
    let mut version = good.clone();
    version[8] = 7;
    replay_fails(&version, "version", &["byte 8", "version 7"]);
    // A blob claiming 2^60 bytes after the header: refused before any allocation.
    let mut huge = good[..16].to_vec();
    huge.extend_from_slice(&[0x06, 12]);
    huge.extend_from_slice(b"glTexImage2D");
    huge.extend_from_slice(&[0x01, 0, 0, 1, 0x12, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x10]);
    replay_fails(&huge, "huge", &["byte ", "(call 0)", "impossible count"]);
    // A command this glray does not know.
    let mut unknown = good[..16].to_vec();
    unknown.extend_from_slice(&[0x06, 11]);
    unknown.extend_from_slice(b"glNotAThing");
    unknown.extend_from_slice(&[0x01, 0, 0, 0, 0]);
    replay_fails(&unknown, "unknown", &["glNotAThing", "does not know"]);
    // Calls that do not fit their command, made in a context (calls without one are skipped).
    replay_fails(&in_a_context(|e| e.no_return()), "arity", &["glBegin", "0 arguments recorded, the command takes 1"]);
    replay_fails(
        &in_a_context(|e| {
            e.f32(4.0);
            e.no_return()
        }),
        "type",
        &["glBegin", "argument 0: expected an integer"],
    );
}

/// A trace that makes an OSMesa context current on a 4x4 drawable, then calls glBegin with the
/// arguments `args` writes (a correct call would be one integer).
fn in_a_context(args: impl Fn(&mut glray_core::trace::Encoder)) -> Vec<u8> {
    let mut e = glray_core::trace::Encoder::new();
    e.header();
    e.name(b"OSMesaCreateContextExt");
    e.begin_call(0, 0, 5);
    e.uint(0x1908);
    e.int(16);
    e.int(0);
    e.int(0);
    e.null();
    e.opaque(0x1000);
    e.name(b"OSMesaMakeCurrent");
    e.begin_call(1, 0, 5);
    e.opaque(0x1000);
    e.opaque(0x2000);
    e.uint(0x1401);
    e.int(4);
    e.int(4);
    e.uint(1);
    e.drawable(0, 0x2000, 4, 4);
    e.name(b"glBegin");
    let before = e.len();
    e.begin_call(2, 0, 0);
    let mut tail = glray_core::trace::Encoder::new();
    args(&mut tail);
    let mut data = e.bytes().to_vec();
    // The argument count byte must match what `args` wrote: one value, or none.
    if !tail.is_empty() && tail.bytes() != [0] {
        data[before + 3] = 1;
    }
    data.extend_from_slice(tail.bytes());
    data
}

#[test]
fn compare_reports_and_its_exit_status_follows_the_thresholds() {
    let dir = scratch("compare");
    let a = suite().join("osmesa-all.png");
    let b = suite().join("osmesa-lists.png");
    let same = glray(&["compare"]).arg(&a).arg(&a).output().unwrap();
    assert_eq!(same.status.code(), Some(0));
    assert!(stdout(&same).contains("PSNR inf"), "{}", stdout(&same));
    let diff = dir.join("diff.png");
    let different = glray(&["compare", "--json"]).arg(&a).arg(&b).arg("--diff").arg(&diff).output().unwrap();
    assert_eq!(different.status.code(), Some(1), "{}", stdout(&different));
    let json = stdout(&different);
    assert!(json.contains("\"pass\":false") && json.contains("\"differing\":"), "{json}");
    assert!(std::fs::metadata(&diff).unwrap().len() > 100);
    let lenient = glray(&["compare", "--max-differing", "1"]).arg(&a).arg(&b).output().unwrap();
    assert_eq!(lenient.status.code(), Some(0));
    let missing = glray(&["compare"]).arg(&a).arg(dir.join("missing.png")).output().unwrap();
    assert_eq!(missing.status.code(), Some(2));
    assert!(stderr(&missing).contains("missing.png"));
    // The defaults are the documented rule: up to 2% of pixels may differ by more than 5%.
    // Two images 1.5% apart pass with no flags, 2.5% apart fail; percentages are accepted.
    let image = |name: &str, off: usize| {
        let mut rgb = vec![100u8; 100 * 100 * 3];
        rgb[..off * 3].fill(200);
        let path = dir.join(name);
        glray_core::image::Image { width: 100, height: 100, rgb }.write_png(&path).unwrap();
        path
    };
    let (base, near, far) = (image("base.png", 0), image("near.png", 150), image("far.png", 250));
    assert_eq!(glray(&["compare"]).arg(&base).arg(&near).output().unwrap().status.code(), Some(0));
    let out = glray(&["compare"]).arg(&base).arg(&far).output().unwrap();
    assert_eq!(out.status.code(), Some(1), "{}", stdout(&out));
    assert!(stdout(&out).contains("250 of 10000 pixels differ by more than 5.0% (2.500%)"), "{}", stdout(&out));
    let pct = glray(&["compare", "--max-differing", "3%"]).arg(&base).arg(&far).output().unwrap();
    assert_eq!(pct.status.code(), Some(0), "{}", stderr(&pct));
    // A bad value is refused naming its flag, and only it.
    let bad = glray(&["compare", "--max-differing", "5"]).arg(&base).arg(&far).output().unwrap();
    assert_eq!(bad.status.code(), Some(2));
    let err = stderr(&bad);
    assert!(err.contains("--max-differing") && err.contains("5%") && !err.contains("--fuzz"), "{err}");
}

#[test]
fn bench_makes_the_anchors_mesh_or_reads_an_obj() {
    // No mesh given: the anchors' isosurface, generated (N = 26 for about 20K triangles).
    let small = ["--frames", "1", "--builds", "1", "--width", "64", "--height", "36", "--json"];
    let out = run_ok(glray(&["bench", "--triangles", "20K"]).args(small), "glray bench --triangles 20K");
    let json = stdout(&out);
    assert!(json.contains("\"mesh\":\"isosurface N=26 (generated)\""), "{json}");
    let field = |json: &str, key: &str| -> f64 {
        let rest = json.split(&format!("\"{key}\":")).nth(1).unwrap_or_else(|| panic!("{key}: {json}"));
        rest.split([',', '}']).next().unwrap().parse().unwrap()
    };
    let triangles = field(&json, "triangles");
    assert!((18_000.0..22_000.0).contains(&triangles), "{json}");
    assert!(field(&json, "hits") > 100.0, "the camera sees the mesh: {json}");
    // An OBJ of a user's own: a far-away, huge octahedron, moved to where the camera looks.
    let dir = scratch("bench-obj");
    let obj = dir.join("octahedron.obj");
    let mut text = String::new();
    for v in [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]] {
        text += &format!("v {} {} {}\n", 500 + 100 * v[0], -300 + 100 * v[1], 100 * v[2]);
    }
    text += "f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n";
    std::fs::write(&obj, text).unwrap();
    let out = run_ok(glray(&["bench", "--mesh"]).arg(&obj).args(small), "glray bench --mesh octahedron.obj");
    let json = stdout(&out);
    assert_eq!(field(&json, "triangles"), 8.0, "{json}");
    assert!(field(&json, "hits") > 100.0, "the camera sees the mesh: {json}");
    // A bad file and a bad count say what is wrong.
    std::fs::write(&obj, "v 0 0 0\nf 1 2 3\n").unwrap();
    let bad = glray(&["bench", "--mesh"]).arg(&obj).output().unwrap();
    assert_eq!(bad.status.code(), Some(2));
    assert!(stderr(&bad).contains("octahedron.obj: line 2: an index out of range"), "{}", stderr(&bad));
    let bad = glray(&["bench", "--triangles", "lots"]).output().unwrap();
    assert_eq!(bad.status.code(), Some(2));
    assert!(stderr(&bad).contains("--triangles") && stderr(&bad).contains("100K"), "{}", stderr(&bad));
}

#[test]
fn dump_lists_the_calls() {
    let out = run_ok(glray(&["dump"]).arg(suite().join("osmesa-textures.trace")), "glray dump");
    let text = stdout(&out);
    for want in [
        "OSMesaCreateContextExt(",
        "glTexImage2D(3553, 0, 6407, 8, 8, 0, 6407, 5121, <192 bytes>)",
        "-- frame 2 --",
        "-- end --",
    ] {
        assert!(text.contains(want), "dump lacks {want:?}");
    }
}

/// apitrace's own traces (Snappy files) replay through glray like its own.
#[test]
fn apitrace_traces_replay_to_the_programs_pictures() {
    let x = Xvfb::start();
    let dir = scratch("apitrace-replay");
    let apitrace = which("apitrace");
    // Our GLX program, traced by apitrace: its own PNG is the reference.
    let png = dir.join("glx_scene.png");
    let trace = dir.join("glx_scene.trace");
    run_ok(
        command(Way::Plain, &[], &apitrace, 120)
            .arg("trace")
            .arg("-o")
            .arg(&trace)
            .arg(example("glx_scene"))
            .arg(&png)
            .arg("3")
            .env("DISPLAY", &x.display),
        "apitrace trace glx_scene",
    );
    let out = dir.join("glx_scene-replay");
    let o = replay(&trace, &out, &[]);
    assert!(stderr(&o).contains("is an apitrace trace"), "{}", stderr(&o));
    assert_same_file(&png, &out.join("frame-0002.png"), "apitrace glx_scene");

    // glxgears (GLX, display lists) and an EGL hack with client arrays (apitrace records them
    // as blobs in fake pointer calls), stopped by frameshot, preloaded before apitrace's wrapper
    // inside the traced shell: frame 4 replayed byte for byte.
    let mut last_trace = PathBuf::new();
    for (name, api, program) in [
        ("glxgears", "gl", which("glxgears").display().to_string()),
        ("sproingies", "egl", "/usr/libexec/xscreensaver/sproingies -window".to_string()),
    ] {
        let ppm = dir.join(format!("{name}.ppm"));
        let trace = dir.join(format!("{name}.trace"));
        let script = format!("LD_PRELOAD={}:$LD_PRELOAD exec {program}", frameshot().display());
        let _ = command(Way::Plain, &[], &apitrace, 120)
            .args(["trace", "--api", api, "-o"])
            .arg(&trace)
            .args(["sh", "-c", &script])
            .env("DISPLAY", &x.display)
            .env("FRAMESHOT_OUT", &ppm)
            .env("FRAMESHOT_FRAME", "4")
            .output()
            .unwrap();
        assert!(ppm.exists(), "{name} did not reach frame 4 under apitrace");
        let out = dir.join(format!("{name}-replay"));
        let o = replay(&trace, &out, &["--frames", "3"]);
        assert!(stderr(&o).contains("is an apitrace trace"), "{}", stderr(&o));
        let c = run_ok(
            Command::new(glray_bin()).arg("compare").arg(&ppm).arg(out.join("frame-0003.png")).args(["--fuzz", "0"]),
            &format!("compare {name}"),
        );
        assert!(stdout(&c).starts_with("0 of "), "{name}: {}", stdout(&c));
        last_trace = trace;
    }
    let trace = last_trace;

    // A damaged apitrace file is refused with its offset.
    let bytes = std::fs::read(&trace).unwrap();
    replay_fails(&bytes[..bytes.len() - 7], "apitrace-truncated", &["byte "]);
}

/// `%p` gives each GL process its own trace; a process that never calls GL (the shell) leaves
/// no file behind.
#[test]
fn each_gl_process_records_its_own_trace() {
    let dir = scratch("record-per-process");
    let template = dir.join("t-%p.trace");
    let scene = example("osmesa_scene");
    let script = format!("{0} {1}/a.png 1 && {0} {1}/b.png 1", scene.display(), dir.display());
    run_ok(
        Command::new(glray_bin()).arg("run").arg("--record").arg(&template).args(["--", "sh", "-c", &script]),
        "two recorded programs",
    );
    let traces = files_ending(&dir, "trace");
    assert_eq!(traces.len(), 2, "{traces:?}");
    for t in &traces {
        let out = dir.join(t.file_stem().unwrap());
        replay(t, &out, &[]);
        assert!(out.join("frame-0000.png").exists());
    }
}
