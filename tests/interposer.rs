//! The interposer: exports, GetProcAddress, pass-through of our own GLX, EGL and OSMesa programs
//! in both ways in, threads and mixed contexts, misuse, dlopen redirection, settings.

mod common;

use common::*;
use std::ffi::{c_void, CStr};
use std::path::Path;
use std::process::Command;

fn defining_file(p: *const c_void) -> String {
    let mut info: libc::Dl_info = unsafe { std::mem::zeroed() };
    assert!(unsafe { libc::dladdr(p, &mut info) } != 0, "dladdr failed");
    unsafe { CStr::from_ptr(info.dli_fname) }.to_string_lossy().into_owned()
}

fn same_file(a: &str, b: &Path) -> bool {
    std::fs::canonicalize(a).ok().as_deref() == std::fs::canonicalize(b).ok().as_deref()
}

#[test]
fn the_library_exports_thousands_of_generated_commands() {
    let out = run_ok(Command::new("nm").arg("-D").arg("--defined-only").arg(libglray()), "nm -D");
    let names: Vec<String> =
        stdout(&out).lines().filter_map(|l| l.split_whitespace().nth(2).map(str::to_string)).collect();
    let gl = names.iter().filter(|n| n.starts_with("gl") && !n.starts_with("glX")).count();
    let glx = names.iter().filter(|n| n.starts_with("glX")).count();
    let egl = names.iter().filter(|n| n.starts_with("egl")).count();
    let osmesa = names.iter().filter(|n| n.starts_with("OSMesa")).count();
    assert!(gl > 3000, "only {gl} GL exports");
    assert!(glx >= 100, "only {glx} GLX exports");
    assert!(egl >= 44, "only {egl} EGL exports (EGL 1.5 alone has 44)");
    assert_eq!(osmesa, 13);
    for must in [
        "glDrawElementsInstancedARB",
        "glXCreateContextAttribsARB",
        "glXSwapIntervalEXT",
        "eglGetPlatformDisplay",
        "glBindBufferARB",
        "glAlphaFuncx",
        "dlopen",
    ] {
        assert!(names.iter().any(|n| n == must), "{must} is not exported");
    }
    let dynamic = run_ok(Command::new("readelf").arg("-d").arg(libglray()), "readelf -d");
    let dynamic = stdout(&dynamic);
    assert!(dynamic.contains("Library soname: [libGL.so.1]"), "{dynamic}");
    assert!(dynamic.contains("[libGLX.so.0]") && dynamic.contains("[libOpenGL.so.0]"), "{dynamic}");
}

#[test]
fn key_symbols_and_get_proc_address_resolve_to_glray() {
    let lib = unsafe { libloading::Library::new(libglray()) }.expect("load libglray.so");
    let addr = |name: &str| -> *const c_void {
        *unsafe { lib.get::<*const c_void>(name.as_bytes()) }.unwrap_or_else(|e| panic!("{name}: {e}"))
    };
    for name in [
        "glBegin",
        "glDrawRangeElements",
        "glXSwapBuffers",
        "eglSwapBuffers",
        "OSMesaMakeCurrent",
        "glXGetProcAddress",
        "glXGetProcAddressARB",
        "eglGetProcAddress",
        "OSMesaGetProcAddress",
    ] {
        let file = defining_file(addr(name));
        assert!(same_file(&file, &libglray()), "{name} resolves to {file}");
    }

    type GetProc = unsafe extern "C" fn(*const u8) -> *const c_void;
    let getters: Vec<(&str, GetProc)> =
        ["glXGetProcAddress", "glXGetProcAddressARB", "eglGetProcAddress", "OSMesaGetProcAddress"]
            .iter()
            .map(|g| (*g, unsafe { std::mem::transmute::<*const c_void, GetProc>(addr(g)) }))
            .collect();
    for (getter, f) in &getters {
        // Every name glray exports comes back as glray's own function.
        for name in [
            "glBegin",
            "glDrawElementsInstancedARB",
            "glXSwapBuffers",
            "eglSwapBuffers",
            "OSMesaMakeCurrent",
            "glXCreateContextAttribsARB",
        ] {
            let c = std::ffi::CString::new(name).unwrap();
            let p = unsafe { f(c.as_ptr().cast()) };
            assert_eq!(p, addr(name), "{getter}({name}) is not glray's {name}");
        }
        // A name nobody knows: NULL. A NULL name: NULL, not a crash.
        assert!(unsafe { f(c"notAFunction".as_ptr().cast()) }.is_null(), "{getter}(notAFunction)");
        assert!(unsafe { f(std::ptr::null()) }.is_null(), "{getter}(NULL)");
    }
    // A GL-looking name glray does not know goes to the real glXGetProcAddressARB, which answers
    // as it would without glray (glvnd makes a dispatch stub for any gl* name).
    let real_glx = unsafe { libloading::Library::new("libGLX.so.0") }.unwrap();
    let real: GetProc = *unsafe { real_glx.get::<GetProc>(b"glXGetProcAddressARB") }.unwrap();
    let name = c"glUnheardOfFunctionGLRAY";
    let ours = getters[1].1;
    assert_eq!(unsafe { ours(name.as_ptr().cast()) }.is_null(), unsafe { real(name.as_ptr().cast()) }.is_null());
}

/// Runs an example that writes OUT.png plainly and in both glray ways, with GLRAY_ENABLE=0, and
/// checks the images are byte-identical and that the calls went through glray.
fn example_passes_through(example_name: &str, display: Option<&str>, traced_call: &str) {
    let dir = scratch(example_name);
    let program = example(example_name);
    let mut outputs = Vec::new();
    for way in [Way::Plain, Way::Preload, Way::Dropin] {
        let png = dir.join(format!("{way:?}.png"));
        let mut cmd = command(way, &[], &program, 60);
        cmd.arg(&png).arg("3").env("GLRAY_ENABLE", "0").env("GLRAY_LOG", "debug");
        if let Some(d) = display {
            cmd.env("DISPLAY", d);
        }
        let out = run_ok(&mut cmd, &format!("{example_name} {way:?}"));
        let err = stderr(&out);
        if way == Way::Plain {
            assert!(!err.contains("glray:"), "glray ran in the plain run: {err}");
        } else {
            // glray was in the path: it resolved the real function for this call.
            assert!(
                err.contains(&format!("glray: debug: {traced_call} -> ")),
                "{example_name} {way:?}: {traced_call} did not go through glray:\n{err}"
            );
        }
        outputs.push((way, png));
    }
    for (way, png) in &outputs[1..] {
        assert_same_file(&outputs[0].1, png, &format!("{example_name}: plain vs {way:?}"));
    }
}

#[test]
fn glx_program_passes_through_unchanged() {
    let x = Xvfb::start();
    example_passes_through("glx_scene", Some(&x.display), "glXSwapBuffers");
}

#[test]
fn egl_program_passes_through_unchanged() {
    example_passes_through("egl_scene", None, "eglSwapBuffers");
}

#[test]
fn osmesa_program_passes_through_unchanged() {
    example_passes_through("osmesa_scene", None, "glBegin");
}

#[test]
fn threads_with_their_own_contexts_stay_apart() {
    let dir = scratch("threads");
    let program = example("threads_scene");
    // References: each kind of context alone, without glray.
    for kind in ["osmesa", "egl"] {
        run_ok(command(Way::Plain, &[], &program, 60).arg(dir.join(kind)).arg("1").arg(kind), kind);
    }
    for way in GLRAY_WAYS {
        for kind in ["osmesa", "egl", "mixed"] {
            let prefix = dir.join(format!("{kind}-{way:?}"));
            run_ok(command(way, &[], &program, 60).arg(&prefix).arg("4").arg(kind), &format!("{kind} {way:?}"));
            for t in 0..4 {
                let own_kind = if kind == "egl" || (kind == "mixed" && t % 2 == 1) { "egl" } else { "osmesa" };
                assert_same_file(
                    &dir.join(format!("{own_kind}-0.png")),
                    Path::new(&format!("{}-{t}.png", prefix.display())),
                    &format!("{kind} thread {t} {way:?}"),
                );
            }
        }
    }
}

#[test]
fn misuse_gets_the_real_gl_behaviour() {
    let program = example("gl_misuse");
    let plain = run_ok(&mut command(Way::Plain, &[], &program, 60), "gl_misuse plain");
    let text = stdout(&plain);
    // The program really does provoke the errors (a test that cannot fail is no test).
    for expect in [
        "glEnable(0xFFFF): glGetError = 0x500",
        "glViewport(-1, -1): glGetError = 0x501",
        "glGenLists inside glBegin/glEnd: glGetError = 0x502",
        "40 x glPushMatrix: glGetError = 0x503",
        "41 x glPopMatrix: glGetError = 0x504",
        "no context: glGetError = 0x0",
        "eglGetError = 0x3008",
        "glDrawArrays(bad mode): glGetError = 0x500",
        "glDrawArrays(count -1): glGetError = 0x501",
        "glDrawElements(GL_FLOAT indices): glGetError = 0x500",
        "glBegin inside glBegin: glGetError = 0x502",
        "glEnd again: glGetError = 0x502",
        "done",
    ] {
        assert!(text.contains(expect), "plain run lacks {expect:?}:\n{text}");
    }
    for way in GLRAY_WAYS {
        // Pass-through, and ray traced (where glray, not the real GL, gets the geometry).
        for (enable, preset) in [("0", "off"), ("1", "off"), ("1", "gl")] {
            let scenes = scratch(&format!("misuse-{way:?}-{enable}-{preset}"));
            let mut cmd = command(way, &[], &program, 60);
            cmd.env("GLRAY_ENABLE", enable).env("GLRAY_PRESET", preset).env("GLRAY_DUMP_SCENE", &scenes);
            let out = run_ok(&mut cmd, &format!("gl_misuse {way:?} preset={preset}"));
            assert_eq!(
                stdout(&out),
                text,
                "gl_misuse under glray ({way:?}, GLRAY_ENABLE={enable}, preset={preset}) differs"
            );
            // With the gl preset the frames were ray traced: the draws after them reached glray only.
            let traced = std::fs::read_dir(&scenes).map_or(0, |d| d.count());
            assert_eq!(traced > 0, preset == "gl", "{way:?} preset={preset}: {traced} scene files");
        }
    }
}

#[test]
fn programs_that_dlopen_gl_reach_glray() {
    let program = example("dlopen_probe");
    let lines = |way: Way, intercept: &str| -> Vec<(String, String)> {
        let out = run_ok(command(way, &[], &program, 30).env("GLRAY_INTERCEPT_DLOPEN", intercept), "dlopen_probe");
        stdout(&out)
            .lines()
            .map(|l| {
                let f: Vec<&str> = l.split_whitespace().collect();
                (f[0].to_string(), f[2].to_string())
            })
            .collect()
    };
    let is_glray = |file: &str| same_file(file, &libglray());
    for (lib, file) in lines(Way::Plain, "1") {
        assert!(!is_glray(&file), "plain: {lib} came from glray");
    }
    let preload = lines(Way::Preload, "1");
    assert_eq!(preload.len(), 6);
    for (lib, file) in &preload {
        assert!(is_glray(file), "preload: dlopen({lib}) reached {file}, not glray");
    }
    // Turned off, only the name glray owns (its SONAME) still reaches it.
    for (lib, file) in lines(Way::Preload, "0") {
        assert_eq!(is_glray(&file), lib == "libGL.so.1", "preload, intercept off: {lib} -> {file}");
    }
    // Drop-in: the directory holds every GL library name, so all reach glray without any dlopen
    // redirection (glray is not even loaded when the program calls dlopen).
    let dropin = lines(Way::Dropin, "0");
    assert_eq!(dropin.len(), 6);
    for (lib, file) in dropin {
        assert!(is_glray(&file), "drop-in: dlopen({lib}) reached {file}, not glray");
    }
}

#[test]
fn a_bad_setting_is_named_and_the_program_still_runs_unchanged() {
    let dir = scratch("bad-setting");
    let program = example("osmesa_scene");
    run_ok(command(Way::Plain, &[], &program, 60).arg(dir.join("plain.png")), "plain");
    for (var, value, words) in [
        ("GLRAY_LOG", "loud", vec!["GLRAY_LOG", "\"loud\"", "off, error, warn, info, debug", "pass-through"]),
        ("GLRAY_ENABEL", "0", vec!["GLRAY_ENABEL", "GLRAY_ENABLE"]),
    ] {
        let png = dir.join(format!("{var}.png"));
        let out = run_ok(command(Way::Preload, &[], &program, 60).arg(&png).env(var, value), var);
        let err = stderr(&out);
        for w in words {
            assert!(err.contains(w), "{var}={value}: message lacks {w:?}: {err}");
        }
        assert_same_file(&dir.join("plain.png"), &png, var);
    }
}

#[test]
fn a_real_library_setting_that_is_glray_or_missing_is_reported_not_a_crash() {
    let dir = scratch("bad-real");
    let program = example("egl_scene");
    let out = command(Way::Preload, &[], &program, 60)
        .arg(dir.join("x.png"))
        .env("GLRAY_REAL_EGL", libglray())
        .output()
        .unwrap();
    let err = stderr(&out);
    assert!(err.contains("resolves to glray itself") && err.contains("real_egl"), "{err}");
    // The program sees EGL fail (as with no EGL at all) and exits through its own error path.
    assert_eq!(out.status.code(), Some(1), "{:?}: {err}", out.status);

    let out = command(Way::Preload, &[], &example("osmesa_scene"), 60)
        .arg(dir.join("y.png"))
        .env("GLRAY_REAL_OSMESA", "/nonexistent/libOSMesa.so.8")
        .output()
        .unwrap();
    let err = stderr(&out);
    assert!(err.contains("/nonexistent/libOSMesa.so.8: no such file") && err.contains("GLRAY_REAL_OSMESA"), "{err}");
    assert_eq!(out.status.code(), Some(1), "{:?}: {err}", out.status);
}

#[test]
fn glray_run_sets_up_both_ways_and_refuses_bad_settings() {
    let show = |args: &[&str], extra_env: &[(&str, &str)]| {
        let mut cmd = Command::new(glray_bin());
        cmd.args(args).env_remove("LD_PRELOAD").env_remove("LD_LIBRARY_PATH");
        for (k, v) in extra_env {
            cmd.env(k, v);
        }
        cmd.output().unwrap()
    };
    let script = "echo \"$LD_PRELOAD|$LD_LIBRARY_PATH|$GLRAY_LOG\"";
    let out = show(&["run", "--set", "log=info", "--", "sh", "-c", script], &[("LD_PRELOAD", "/tmp/other.so")]);
    let line = stdout(&out);
    assert_eq!(line.trim(), format!("/tmp/other.so:{}||info", libglray().display()), "preload run");
    let out = show(&["run", "--dropin", "--", "sh", "-c", script], &[]);
    assert_eq!(stdout(&out).trim(), format!("|{}|", dropin_dir().display()));
    for name in ["libGL.so.1", "libOpenGL.so.0", "libGLX.so.0", "libEGL.so.1", "libOSMesa.so.8"] {
        assert!(same_file(dropin_dir().join(name).to_str().unwrap(), &libglray()), "{name}");
    }

    let out = show(&["run", "--set", "log=loud", "--", "true"], &[]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("off, error, warn, info, debug"), "{}", stderr(&out));
    let out = show(&["run", "--set", "colour=red", "--", "true"], &[]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("unknown setting `colour`"), "{}", stderr(&out));
    let out = show(&["run", "--", "true"], &[("GLRAY_ENABLE", "perhaps")]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("GLRAY_ENABLE"), "{}", stderr(&out));
    let out = show(&["run", "--", "/nonexistent/program"], &[]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("/nonexistent/program"), "{}", stderr(&out));
    // Without `--` too: the first word that is not glray's own flag starts the program, and
    // every word after it (flags included) is the program's.
    let out = show(&["run", "--set", "log=info", "sh", "-c", script, "--set"], &[]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert_eq!(stdout(&out).trim(), format!("{}||info", libglray().display()), "run without --");
    let out = show(&["run", "--set", "log=info", "sh", "-c", "echo \"$0 $1\"", "--record", "x"], &[]);
    assert_eq!(stdout(&out).trim(), "--record x", "the program's flags stay the program's");
}

#[test]
fn glray_info_shows_every_setting_with_its_source_and_the_real_gl() {
    let dir = scratch("info");
    let file = dir.join("glray.toml");
    std::fs::write(&file, "intercept_dlopen = false\nlog = \"error\"\n").unwrap();
    let out = run_ok(
        Command::new(glray_bin())
            .args(["info", "--set", "enable=false"])
            .env("GLRAY_CONFIG", &file)
            .env("GLRAY_LOG", "debug"),
        "glray info",
    );
    let text = stdout(&out);
    assert!(text.contains(&format!("library: {}", libglray().display())), "{text}");
    for soname in ["libOpenGL.so.0", "libGLX.so.0", "libEGL.so.1", "libOSMesa.so.8"] {
        let line =
            text.lines().find(|l| l.trim_start().starts_with(soname)).unwrap_or_else(|| panic!("{soname}: {text}"));
        assert!(line.contains('/') && !line.contains("not found"), "{line}");
    }
    let line = |key: &str| {
        text.lines()
            .find(|l| l.trim_start().starts_with(&format!("{key} ")))
            .unwrap_or_else(|| panic!("{key}: {text}"))
            .to_string()
    };
    assert!(line("enable").contains("false") && line("enable").contains("[glray run flag]"), "{}", line("enable"));
    assert!(line("log").contains("debug") && line("log").contains("[environment GLRAY_LOG]"), "{}", line("log"));
    assert!(
        line("intercept_dlopen").contains("false")
            && line("intercept_dlopen").contains(&format!("[file {}]", file.display()))
    );
    assert!(line("real_egl").contains("[default]"));
    for s in glray_core::config::SETTINGS {
        assert!(text.contains(&glray_core::config::env_name(s.key)), "info omits {}", s.key);
    }
    // Every value is shown as it is in force: an effect left to the preset shows the preset's,
    // an empty path what it means.
    let out = run_ok(
        Command::new(glray_bin()).args(["info", "--set", "preset=full", "--set", "ao_samples=8"]),
        "glray info preset=full",
    );
    let text = stdout(&out);
    let line = |key: &str| {
        let l =
            text.lines().find(|l| l.trim_start().starts_with(&format!("{key} "))).unwrap_or_else(|| panic!("{text}"));
        l.split_whitespace().collect::<Vec<_>>().join(" ")
    };
    assert!(line("ao_samples").starts_with("ao_samples = 8 [glray run flag]"), "{}", line("ao_samples"));
    assert!(line("samples").starts_with("samples = 4 [preset full]"), "{}", line("samples"));
    assert!(line("shadows").starts_with("shadows = true [preset full]"), "{}", line("shadows"));
    assert!(line("reflections").starts_with("reflections = 1 [preset full]"), "{}", line("reflections"));
    assert!(line("record").starts_with("record = (none) [default]"), "{}", line("record"));
    assert!(line("dump_scene").starts_with("dump_scene = (none) [default]"), "{}", line("dump_scene"));
    assert!(line("real_egl").starts_with("real_egl = (auto) [default]"), "{}", line("real_egl"));
    assert!(line("dump_frames").starts_with("dump_frames = 10 [default]"), "{}", line("dump_frames"));
    for s in glray_core::config::SETTINGS {
        assert!(!line(s.key).contains("= ["), "a blank value: {}", line(s.key));
    }

    std::fs::write(&file, "presett = \"gl\"\n").unwrap();
    let out = Command::new(glray_bin()).arg("info").env("GLRAY_CONFIG", &file).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("unknown setting `presett`"), "{}", stderr(&out));
}

#[test]
fn every_setting_is_documented() {
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/settings.md")).unwrap();
    for s in glray_core::config::SETTINGS {
        let env = glray_core::config::env_name(s.key);
        assert!(
            doc.contains(&format!("`{env}`")) && doc.contains(&format!("`{}`", s.key)),
            "docs/settings.md lacks {env}"
        );
    }
}
