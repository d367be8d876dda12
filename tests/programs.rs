//! Real programs from Debian under glray with GLRAY_ENABLE=0 (pure pass-through), preloaded and
//! dropped in: they run, and their pictures are byte-identical to the runs without glray.
//! glxgears and the xscreensaver hacks are made repeatable by tests/helpers/frameshot.c (a fake
//! clock and pid), which also grabs their frame; OpenSCAD and glretrace write their own images.

mod common;

use common::*;
use std::path::{Path, PathBuf};

/// Runs `program args` under frameshot in all three ways and compares frame `frame`.
fn frames_identical(name: &str, program: &Path, args: &[&str], frame: u32) {
    let x = Xvfb::start();
    let dir = scratch(name);
    let mut images = Vec::new();
    for way in [Way::Plain, Way::Preload, Way::Dropin] {
        let ppm = dir.join(format!("{way:?}.ppm"));
        let mut cmd = frameshot_command(way, program, args, &x.display, &ppm, frame);
        cmd.env("GLRAY_ENABLE", "0").env("GLRAY_LOG", "debug");
        let out = run_ok(&mut cmd, &format!("{name} {way:?}"));
        let err = stderr(&out);
        assert!(err.contains(&format!("frameshot: frame {frame}")), "{name} {way:?}: no frame grabbed:\n{err}");
        // In the glray runs, glray forwarded the swap (it sits between frameshot and libGL).
        let swapped_through_glray = err.contains("glXSwapBuffers -> ") || err.contains("eglSwapBuffers -> ");
        assert_eq!(swapped_through_glray, way != Way::Plain, "{name} {way:?}: glray in path? stderr:\n{err}");
        images.push((way, ppm));
    }
    for (way, ppm) in &images[1..] {
        assert_same_file(&images[0].1, ppm, &format!("{name}: plain vs {way:?}"));
    }
}

fn hack(name: &str) -> PathBuf {
    let p = Path::new("/usr/libexec/xscreensaver").join(name);
    assert!(p.exists(), "{} is missing: scripts/test installs xscreensaver-gl-extra", p.display());
    p
}

#[test]
fn glxgears_is_unchanged() {
    frames_identical("glxgears", &which("glxgears"), &[], 3);
}

#[test]
fn xscreensaver_dangerball_is_unchanged() {
    // Display lists built from client arrays, ~31 glCallList a frame; EGL.
    frames_identical("dangerball", &hack("dangerball"), &["-window"], 4);
}

#[test]
fn xscreensaver_sproingies_is_unchanged() {
    // Thousands of GL_POLYGONs with glVertex3i, client arrays, a clip plane.
    frames_identical("sproingies", &hack("sproingies"), &["-window"], 4);
}

#[test]
fn xscreensaver_lament_is_unchanged() {
    // Textured lists with glBindTexture and glMaterialfv inside them.
    frames_identical("lament", &hack("lament"), &["-window"], 4);
}

#[test]
fn openscad_png_is_unchanged() {
    let x = Xvfb::start();
    let dir = scratch("openscad");
    let model = dir.join("model.scad");
    std::fs::write(&model, "difference() { cube(10, center=true); sphere(6.5, $fn=48); }\ntranslate([12,0,0]) cylinder(h=8, r=3, $fn=32);\n").unwrap();
    let openscad = which("openscad");
    let mut pngs = Vec::new();
    for way in [Way::Plain, Way::Preload, Way::Dropin] {
        let png = dir.join(format!("{way:?}.png"));
        // The glray ways go through `glray run`, as a user would.
        let mut cmd = match way {
            Way::Plain => command(Way::Plain, &[], &openscad, 120),
            _ => {
                let mut c = command(Way::Plain, &[], &glray_bin(), 120);
                c.arg("run");
                if way == Way::Dropin {
                    c.arg("--dropin");
                }
                c.args(["--set", "enable=false", "--set", "log=debug", "--"]).arg(&openscad);
                c
            }
        };
        cmd.arg("-o").arg(&png).arg(&model).env("DISPLAY", &x.display);
        let out = run_ok(&mut cmd, &format!("openscad {way:?}"));
        assert_eq!(
            stderr(&out).contains("glray: debug: glXMakeContextCurrent -> "),
            way != Way::Plain,
            "{way:?}: {}",
            stderr(&out)
        );
        pngs.push((way, png));
    }
    for (way, png) in &pngs[1..] {
        assert_same_file(&pngs[0].1, png, &format!("openscad: plain vs {way:?}"));
    }
}

/// apitrace's glretrace loads GL with dlopen("libGL.so.1"): it must end up in glray (the point of
/// the SONAME and the drop-in directory) and replay identically: preloaded, dropped in by hand,
/// and through `glray run --dropin`.
#[test]
fn glretrace_replays_identically_through_glray() {
    let x = Xvfb::start();
    let dir = scratch("glretrace");
    let trace = dir.join("scene.trace");
    run_ok(
        command(Way::Plain, &[], &which("apitrace"), 120)
            .arg("trace")
            .arg("-o")
            .arg(&trace)
            .arg(example("glx_scene"))
            .arg(dir.join("orig.png"))
            .arg("4")
            .env("DISPLAY", &x.display),
        "apitrace trace",
    );
    let glretrace = which("glretrace");
    // glretrace run `way`, or (None) as the README says to: `glray run --dropin -- glretrace`.
    let replay = |name: &str, way: Option<Way>| -> Vec<(String, Vec<u8>)> {
        let snaps = dir.join(name);
        std::fs::create_dir_all(&snaps).unwrap();
        let mut prefix = snaps.into_os_string();
        prefix.push("/");
        let mut cmd = match way {
            Some(way) => command(way, &[], &glretrace, 120),
            None => {
                let mut c = command(Way::Plain, &[], &glray_bin(), 120);
                c.args(["run", "--dropin", "--"]).arg(&glretrace);
                c
            }
        };
        cmd.arg("-s").arg(&prefix).arg(&trace).env("DISPLAY", &x.display);
        let out = run_ok(cmd.env("GLRAY_ENABLE", "0").env("GLRAY_LOG", "debug"), &format!("glretrace {name}"));
        assert_eq!(
            stderr(&out).contains("glray: debug: glXSwapBuffers -> "),
            way != Some(Way::Plain),
            "{name}: {}",
            stderr(&out)
        );
        let mut files: Vec<_> = std::fs::read_dir(dir.join(name)).unwrap().map(|e| e.unwrap().path()).collect();
        files.sort();
        files
            .iter()
            .map(|f| (f.file_name().unwrap().to_string_lossy().into_owned(), std::fs::read(f).unwrap()))
            .collect()
    };
    let a = replay("plain-a", Some(Way::Plain));
    let b = replay("plain-b", Some(Way::Plain));
    assert_eq!(a.len(), 4, "expected 4 snapshots");
    // glretrace snapshots the back buffer after each swap; after the first swap that buffer is
    // uninitialised memory, so Mesa itself differs run to run there (docs/compatibility.md).
    // Only the snapshots on which two plain replays agree are references.
    let stable: Vec<&(String, Vec<u8>)> = a.iter().zip(&b).filter(|(x, y)| x == y).map(|(x, _)| x).collect();
    assert!(stable.len() >= 3, "only {} of 4 plain snapshots are repeatable", stable.len());
    for way in [Some(Way::Preload), Some(Way::Dropin), None] {
        let g = replay(&way.map_or("launched".into(), |w| format!("{w:?}")), way);
        assert_eq!(g.len(), a.len());
        for (name, bytes) in &stable {
            let other = &g.iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("{way:?}: no {name}")).1;
            assert!(other == bytes, "glretrace {way:?}: snapshot {name} differs");
        }
    }
}
