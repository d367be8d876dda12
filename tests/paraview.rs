//! ParaView 5.11 (VTK 9's shader pipeline) under glray: pvbatch's contour coloured by a scalar
//! (tests/paraview/contour.py) under Xvfb, one process. In the GL look the screenshot is
//! ParaView's own within the rule the GL look is held to (2% of pixels off by more than 5%);
//! with ambient occlusion the surface is ray traced while the orientation axes and the scalar
//! bar, which VTK draws after its 3D pass, are still drawn on top, as ParaView draws them.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{glray_bin, libglray, run_ok, scratch, which, without_glray, Xvfb};

const W: u32 = 640;
const H: u32 = 360;

/// pvbatch running the contour script into `out` on `display`, with glray preloaded and `env`
/// set (None: without glray); bounded in time.
fn pvbatch(display: &str, out: &Path, glray: Option<&[(&str, &str)]>) -> std::process::Output {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/paraview/contour.py");
    let mut cmd = Command::new("timeout");
    cmd.args(["-k", "5", "180"]).arg(which("pvbatch")).arg(&script).arg(out).arg(W.to_string()).arg(H.to_string());
    without_glray(&mut cmd);
    cmd.env("DISPLAY", display);
    if let Some(env) = glray {
        cmd.env("LD_PRELOAD", libglray());
        for (k, v) in env {
            cmd.env(k, v);
        }
    }
    run_ok(&mut cmd, "pvbatch contour.py")
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
    pvbatch(&x.display, &mesa, None);

    // The GL look: ParaView's own picture within the GL look's rule.
    let gl = dir.join("gl.png");
    let stats = dir.join("gl.jsonl");
    let s = stats.display().to_string();
    pvbatch(&x.display, &gl, Some(&[("GLRAY_PRESET", "gl"), ("GLRAY_STATS", &s)]));
    let lines = std::fs::read_to_string(&stats).unwrap();
    assert!(
        lines
            .lines()
            .any(|l| l.contains(&format!("\"width\":{W},\"height\":{H}")) && l.contains("\"triangles\":10364")),
        "frames traced at the render target's size with the whole contour:\n{lines}"
    );
    let cmp = Command::new(glray_bin()).arg("compare").arg(&mesa).arg(&gl).output().unwrap();
    assert!(cmp.status.success(), "GL look against ParaView's own: {}", String::from_utf8_lossy(&cmp.stdout));

    // Ambient occlusion: the surface changes, the overlays drawn after it do not.
    let ao = dir.join("ao.png");
    pvbatch(&x.display, &ao, Some(&[("GLRAY_PRESET", "ao")]));
    let (m, a) = (rgb(&mesa), rgb(&ao));
    let surface = differing(&m, &a, (200, 60, 440, 300));
    assert!(surface > 0.2, "AO darkens the contour's folds: {:.1}% of its box changed", 100.0 * surface);
    let scalar_bar = differing(&m, &a, (515, 220, 640, 360));
    let axes = differing(&m, &a, (30, 280, 80, 340));
    assert!(scalar_bar < 0.01 && axes < 0.01, "overlays on top: scalar bar {scalar_bar:.3}, axes {axes:.3}");
}
