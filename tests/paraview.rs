//! ParaView 5.11 (VTK 9's shader pipeline) under glray: pvbatch's contour coloured by a scalar
//! (tests/paraview/contour.py) under Xvfb. In the GL look the screenshot is ParaView's own
//! within the bounds of what each comparison measured (`common::Measured`), in one process and
//! under `glray run --np 2` (IceT compositing), image-parallel and data-parallel; with ambient
//! occlusion the surface is ray traced while the orientation axes and the scalar bar, which VTK
//! draws after its 3D pass, are still drawn on top, as ParaView draws them.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{assert_close, glray_bin, libglray, run_ok, scratch, which, without_glray, Measured, Xvfb};

const W: u32 = 640;
const H: u32 = 360;

/// pvbatch running the contour script into `out` on `display`, bounded in time: with glray
/// preloaded and `glray` set (None: without glray), alone or under `glray run --np 2` (which
/// preloads glray and forwards every GLRAY_* setting to both ranks).
fn pvbatch(display: &str, out: &Path, glray: Option<&[(&str, &str)]>, np2: bool) {
    pvbatch_script(display, "contour.py", &[], out, glray, np2);
}

/// `script` (in tests/paraview/) with `args` after the output's path.
fn pvbatch_script(
    display: &str,
    script: &str,
    args: &[&str],
    out: &Path,
    glray: Option<&[(&str, &str)]>,
    np2: bool,
) -> String {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/paraview").join(script);
    let mut cmd = Command::new("timeout");
    cmd.args(["-k", "5", "240"]);
    if np2 {
        cmd.arg(glray_bin()).args(["run", "--np", "2", "--"]);
    }
    cmd.arg(which("pvbatch")).arg(&script).arg(out).args(args).arg(W.to_string()).arg(H.to_string());
    without_glray(&mut cmd);
    cmd.env("DISPLAY", display);
    if let Some(env) = glray {
        if !np2 {
            cmd.env("LD_PRELOAD", libglray());
        }
        for (k, v) in env {
            cmd.env(k, v);
        }
    }
    let out =
        run_ok(&mut cmd, &format!("pvbatch {}{}", script.display(), if np2 { " under glray run --np 2" } else { "" }));
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// What a comparison measured when its bound was set: `percent` of the pixels off by more than
/// 5%, PSNR `db` over what is drawn (`common::Measured`).
const fn measured(percent: f64, db: f64) -> Measured {
    Measured { share: percent / 100.0, psnr: db }
}

fn rgb(path: &Path) -> Vec<u8> {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().expect("a PNG of a size that fits")];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (W, H), "{}", path.display());
    let channels = buf.len() / (W * H) as usize;
    buf.chunks(channels).flat_map(|p| p[..3].to_vec()).collect()
}

/// The whole number `key` of a `GLRAY_STATS` JSON line.
fn field(line: &str, key: &str) -> u64 {
    let rest = line.split(&format!("\"{key}\":")).nth(1).unwrap_or_else(|| panic!("no {key} in {line}"));
    rest.split([',', '}']).next().unwrap().parse().unwrap_or_else(|e| panic!("{key} in {line}: {e}"))
}

/// Pixels differing by more than 5% of 255 in a channel, within the box `(x0, y0)..(x1, y1)` of
/// the image (rows from the top, as the PNG has them), as a share of the box.
fn differing(a: &[u8], b: &[u8], (x0, y0, x1, y1): (u32, u32, u32, u32)) -> f64 {
    let mut n = 0;
    for y in y0..y1 {
        for x in x0..x1 {
            let k = 3 * (y * W + x) as usize;
            n += usize::from((0..3).any(|c| a[k + c].abs_diff(b[k + c]) > 13));
        }
    }
    n as f64 / ((x1 - x0) * (y1 - y0)) as f64
}

#[test]
fn paraview_contour_is_ray_traced_with_its_overlays_on_top() {
    let dir: PathBuf = scratch("paraview");
    let x = Xvfb::start();
    let mesa = dir.join("mesa.png");
    pvbatch(&x.display, &mesa, None, false);

    // The GL look: ParaView's own picture within the GL look's rule.
    let gl = dir.join("gl.png");
    let stats = dir.join("gl.jsonl");
    let s = stats.display().to_string();
    pvbatch(&x.display, &gl, Some(&[("GLRAY_PRESET", "gl"), ("GLRAY_STATS", &s)]), false);
    let lines = std::fs::read_to_string(&stats).unwrap();
    assert!(
        lines
            .lines()
            .any(|l| l.contains(&format!("\"width\":{W},\"height\":{H}")) && l.contains("\"triangles\":10364")),
        "frames traced at the render target's size with the whole contour:\n{lines}"
    );
    assert_close(&mesa, &gl, measured(0.0035, 58.1), "the GL look against ParaView's own");
    // The overlays drawn over the last frame's picture are counted (FXAA, axes, scalar bar).
    assert!(
        lines.lines().skip(1).all(|l| {
            l.contains("\"passed_draws\":") && !l.contains("\"passed_draws\":0,") && !l.contains("\"passed_draws\":0}")
        }),
        "draws left to the real GL counted:\n{lines}"
    );

    // Ambient occlusion: the surface changes, the overlays drawn after it do not.
    // A batch program's screenshot: its frame traced with `batch_passes` (16) passes at once.
    let ao = dir.join("ao.png");
    let stats = dir.join("ao.jsonl");
    let s = stats.display().to_string();
    pvbatch(&x.display, &ao, Some(&[("GLRAY_PRESET", "ao"), ("GLRAY_STATS", &s)]), false);
    let lines = std::fs::read_to_string(&stats).unwrap();
    assert!(lines.lines().next().is_some_and(|l| l.contains("\"samples\":16")), "{lines}");
    let (m, a) = (rgb(&mesa), rgb(&ao));
    // Measured: 74.7% of the contour's box changed; 166,365 channels darker than ParaView's
    // own, 1,366 brighter (at the contour's edges); the scalar bar and the axes not a pixel
    // apart.
    let surface = differing(&m, &a, (200, 60, 440, 300));
    assert!(surface > 0.5, "AO darkens the contour's folds: {:.1}% of its box changed", 100.0 * surface);
    let brighter = m.iter().zip(&a).filter(|(m, a)| **a > m.saturating_add(2)).count();
    let darker = m.iter().zip(&a).filter(|(m, a)| a.saturating_add(2) < **m).count();
    assert!(darker > 55_000 && brighter < 4_100, "AO darkens: {darker} channels darker, {brighter} brighter");
    let scalar_bar = differing(&m, &a, (515, 220, 640, 360));
    let axes = differing(&m, &a, (30, 280, 80, 340));
    assert!(scalar_bar < 0.0005 && axes < 0.0005, "overlays on top: scalar bar {scalar_bar:.4}, axes {axes:.4}");
}

#[test]
fn paraview_under_two_ranks_composites_the_ray_traced_picture_whole() {
    // Each rank holds half the contour; IceT composites what each rank's glReadPixels returns,
    // taking a rank's pixels only inside its own half's screen box (Mesa's picture is the same
    // for one and two ranks).
    let dir: PathBuf = scratch("paraview-np2");
    let x = Xvfb::start();
    let mesa = dir.join("mesa.png");
    pvbatch(&x.display, &mesa, None, false);
    for distribute in ["replicated", "data-parallel"] {
        let out = dir.join(format!("{distribute}.png"));
        let stats = dir.join(format!("{distribute}.jsonl"));
        let s = stats.display().to_string();
        let env = [("GLRAY_PRESET", "gl"), ("GLRAY_DISTRIBUTE", distribute), ("GLRAY_STATS", &s)];
        pvbatch(&x.display, &out, Some(&env), true);
        // Image-parallel as close as data-parallel (it was 1.26% off, facets along the folds: the
        // ranks' cameras, apart by rounding, were taken for two, and rank 1's half lit as drawn).
        let was = if distribute == "replicated" { measured(0.0087, 53.0) } else { measured(0.0087, 52.9) };
        assert_close(&mesa, &out, was, &format!("the GL look, 2 ranks, {distribute}, against ParaView's own"));
        let lines = std::fs::read_to_string(&stats).unwrap();
        let first: Vec<&str> = lines.lines().filter(|l| l.starts_with("{\"frame\":0,")).collect();
        assert_eq!(first.len(), 2, "a first frame on each rank:\n{lines}");
        if distribute == "replicated" {
            // Both ranks traced tiles of the whole contour (10,364 triangles, where each rank
            // draws half), together all the frame's tiles.
            let tiles: Vec<u64> = first.iter().map(|l| field(l, "tiles")).collect();
            assert!(first.iter().all(|l| field(l, "ranks") == 2 && field(l, "triangles") == 10364), "{lines}");
            assert!(
                tiles.iter().all(|&t| t > 0) && tiles.iter().sum::<u64>() == field(first[0], "tiles_total"),
                "{lines}"
            );
        } else {
            // Each rank traced its own half, alone: the halves make the contour.
            assert!(first.iter().all(|l| !l.contains("\"ranks\":") && field(l, "rays") > 0), "{lines}");
            let halves: Vec<u64> = first.iter().map(|l| field(l, "triangles")).collect();
            assert!(halves.iter().all(|&t| t > 0 && t < 10364) && halves.iter().sum::<u64>() == 10364, "{lines}");
        }
    }
    // With ambient occlusion, the screenshot's frame is traced with 16 passes there too, each a
    // frame both ranks share.
    let ao = dir.join("ao.png");
    let stats = dir.join("ao.jsonl");
    let s = stats.display().to_string();
    pvbatch(&x.display, &ao, Some(&[("GLRAY_PRESET", "ao"), ("GLRAY_STATS", &s)]), true);
    // Each of the 16 passes of every frame is a frame of both ranks: every tile of 16 passes
    // handed out (tiles_total: 16 times the 60 tiles of 640x360), rank 1 tracing some of them,
    // the two ranks' tiles adding up to all of them.
    let lines = std::fs::read_to_string(&stats).unwrap();
    let frames: Vec<u64> = lines.lines().map(|l| field(l, "frame")).collect();
    assert!(frames.iter().filter(|&&f| f == 0).count() == 2, "{lines}");
    for frame in 0..=*frames.iter().max().unwrap() {
        let both: Vec<&str> = lines.lines().filter(|l| field(l, "frame") == frame).collect();
        let rank0 = both.iter().find(|l| field(l, "rank") == 0).unwrap_or_else(|| panic!("frame {frame}: {lines}"));
        let rank1 = both.iter().find(|l| field(l, "rank") == 1).unwrap_or_else(|| panic!("frame {frame}: {lines}"));
        assert_eq!(field(rank0, "samples"), 16 * (frame + 1), "frame {frame}: {rank0}");
        let total = field(rank0, "tiles_total");
        assert_eq!(total, 16 * 60, "frame {frame}: 16 passes of 60 tiles each: {rank0}");
        assert_eq!(field(rank1, "tiles_total"), total, "{rank1}");
        assert!(field(rank1, "tiles") > 0, "frame {frame}: rank 1 traced: {rank1}");
        assert_eq!(field(rank0, "tiles") + field(rank1, "tiles"), total, "frame {frame}:\n{rank0}\n{rank1}");
        // The contour's halves are kept meshes on both ranks, their trees built in the first
        // frame and kept (each rank's camera differs from the other's in the last bits: taken
        // for two cameras, rank 1's half was made loose triangles, built anew every pass).
        for line in [rank0, rank1] {
            assert_eq!(field(line, "loose_triangles"), 0, "frame {frame}: {line}");
            let builds = field(line, "builds");
            assert!(if frame == 0 { builds >= 2 } else { builds == 0 }, "frame {frame}: {line}");
        }
    }
}

#[test]
fn paraview_clips_lines_and_points_are_ray_traced_and_glyphs_and_translucency_left_to_paraview() {
    let dir: PathBuf = scratch("paraview-cases");
    let x = Xvfb::start();
    for case in ["clip", "specular", "wireframe", "points", "glyphs", "glyphs3d", "translucent"] {
        let mesa = dir.join(format!("{case}-mesa.png"));
        pvbatch_script(&x.display, "cases.py", &[case], &mesa, None, false);
        let gl = dir.join(format!("{case}-gl.png"));
        let stats = dir.join(format!("{case}.jsonl"));
        let s = stats.display().to_string();
        let said = pvbatch_script(
            &x.display,
            "cases.py",
            &[case],
            &gl,
            Some(&[("GLRAY_PRESET", "gl"), ("GLRAY_STATS", &s)]),
            false,
        );
        let traced = std::fs::read_to_string(&stats).unwrap_or_default();
        let told: Vec<&str> = said.lines().filter(|l| l.contains("left to the real GL")).collect();
        if matches!(case, "clip" | "specular" | "wireframe" | "points") {
            // A surface with a cut, highlights, lines, points: ray traced, as the contour is.
            let was = match case {
                "clip" => measured(0.0026, 55.3),
                "specular" => measured(0.0035, 57.4),
                "wireframe" => measured(0.1276, 39.3),
                _ => measured(0.0833, 33.6),
            };
            assert_close(&mesa, &gl, was, &format!("{case} in the GL look against ParaView's own"));
            assert!(!traced.is_empty() && told.is_empty(), "{traced}\n{said}");
        } else {
            // Not followed yet: ParaView's own picture, and glray says so once.
            assert_eq!(rgb(&mesa), rgb(&gl), "{case}: ParaView's own picture");
            assert!(traced.is_empty(), "{case}: no frame ray traced: {traced}");
            assert_eq!(told.len(), 1, "{case}: {said}");
        }
    }
}
