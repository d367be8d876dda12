//! `glray bench --mesh FILE`: glray's tracer on the anchors' scene (../shared/anchors: the same
//! mesh file format, camera, light and material as embree_bench and osmesa_bench), measured in
//! embree_bench's terms: BVH build time, primary-ray frame time and Mrays/s, ambient-occlusion
//! frame time and Mrays/s, peak memory. The mesh becomes one display-list mesh drawn once, as
//! osmesa_bench's `dl` frames are under glray, so the numbers are the library's own path.

use std::path::Path;
use std::time::Instant;

use glam::{DMat3, DMat4, DVec3, DVec4, Vec3};
use glray_capture::camera::Viewport;
use glray_capture::frame::{Frame, Lighting, Surface, View};
use glray_capture::instance::Instance;
use glray_capture::lighting::{Light, LightModel, Material};
use glray_capture::mesh::Mesh;
use glray_core::image::Image;
use glray_render::{Effects, Options, Renderer};

/// The anchors' camera and light (common.h).
const EYE: [f64; 3] = [1.45, 1.05, 1.95];
const FOVY_DEG: f64 = 40.0;
const NEAR: f64 = 0.5;
const FAR: f64 = 10.0;
const LIGHT_DIR: [f64; 3] = [-0.5, 0.8, 0.35];
const MATERIAL: [f64; 4] = [0.8, 0.7, 0.5, 1.0];

pub struct Args<'a> {
    pub mesh: &'a Path,
    pub width: u32,
    pub height: u32,
    pub ao: u32,
    pub threads: Option<usize>,
    pub frames: u32,
    pub builds: u32,
    pub json: bool,
    pub out: Option<&'a Path>,
}

/// Reads an anchors mesh: "ISOMESH1", u32 vertices, u32 triangles, positions, normals, indices.
pub fn load(path: &Path) -> Result<Mesh, String> {
    let data = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let bad = |what: &str| format!("{}: not an anchors mesh: {what}", path.display());
    if data.len() < 16 || &data[..8] != b"ISOMESH1" {
        return Err(bad("no ISOMESH1 header at offset 0"));
    }
    let u32_at = |o: usize| u32::from_le_bytes(data[o..o + 4].try_into().expect("4 bytes"));
    let (nv, nt) = (u32_at(8) as usize, u32_at(12) as usize);
    let need = 16 + nv * 24 + nt * 12;
    if data.len() != need {
        return Err(bad(&format!("{nv} vertices and {nt} triangles need {need} bytes, the file has {}", data.len())));
    }
    let f = |o: usize| f32::from_le_bytes(data[o..o + 4].try_into().expect("4 bytes"));
    let vec3s = |start: usize| -> Vec<Vec3> {
        (0..nv).map(|i| Vec3::new(f(start + 12 * i), f(start + 12 * i + 4), f(start + 12 * i + 8))).collect()
    };
    let positions = vec3s(16);
    let normals = vec3s(16 + nv * 12);
    let base = 16 + nv * 24;
    let triangles: Vec<[u32; 3]> = (0..nt).map(|t| [0, 1, 2].map(|k| u32_at(base + 12 * t + 4 * k))).collect();
    Mesh::indexed(positions, normals, triangles).ok_or_else(|| bad("an index past the last vertex"))
}

/// The frame osmesa_bench draws: the mesh once, lit by the directional light, from the camera.
pub fn frame(mesh: Mesh, width: u32, height: u32) -> Frame {
    // gluPerspective and gluLookAt, as osmesa_bench calls them.
    let top = NEAR * (FOVY_DEG.to_radians() / 2.0).tan();
    let right = top * width as f64 / height as f64;
    let mut m = glray_capture::matrix::Matrices::default();
    m.matrix_mode(0x1701).expect("GL_PROJECTION");
    m.frustum(-right, right, -top, top, NEAR, FAR).expect("a valid frustum");
    let projection = *m.top();
    let eye = DVec3::from(EYE);
    let f = (-eye).normalize();
    let s = f.cross(DVec3::Y).normalize();
    let u = s.cross(f);
    let view = DMat4::from_cols(
        DVec4::new(s.x, u.x, -f.x, 0.0),
        DVec4::new(s.y, u.y, -f.y, 0.0),
        DVec4::new(s.z, u.z, -f.z, 0.0),
        DVec4::new(-s.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
    );
    let dir = DVec3::from(LIGHT_DIR).normalize();
    let white = DVec4::ONE;
    let black = DVec4::new(0.0, 0.0, 0.0, 1.0);
    let light = Light {
        enabled: true,
        position: view * dir.extend(0.0),
        diffuse: white,
        ambient: black,
        specular: black,
        ..Light::new(0)
    };
    let m = DVec4::from(MATERIAL);
    let material = Material { ambient: m, diffuse: m, ..Material::default() };
    let viewport = Viewport { x: 0, y: 0, width: width as i32, height: height as i32 };
    let instance = Instance {
        mesh: std::sync::Arc::new(mesh),
        modelview: view,
        object_to_clip: projection * view,
        normal_matrix: DMat3::from_mat4(view).inverse().transpose(),
        normalize: false,
        rescale_normal: false,
        texture_matrix: DMat4::IDENTITY,
        normal: DVec3::Z,
        color: DVec4::ONE,
        texcoord: DVec4::W,
        surface: 0,
        camera: 0,
        sequence: 0,
        lighting: 0,
        flat: false,
        front_ccw: true,
        cull: None,
        mirrored: false,
    };
    Frame {
        instances: vec![instance],
        surfaces: vec![Surface::depth_tested()],
        projection: Some(projection),
        viewport: Some(viewport),
        depth_range: (0.0, 1.0),
        clear_color: glam::Vec4::new(0.0, 0.0, 0.0, 1.0),
        cleared: true,
        depth_cleared: true,
        lightings: vec![Lighting {
            lights: vec![light],
            model: LightModel::default(),
            materials: [material; 2],
            color_material: None,
        }],
        cameras: vec![View { projection, viewport }],
        width,
        height,
        ..Frame::default()
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        0.0
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn min(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::INFINITY, f64::min)
}

/// Peak resident memory of this process, in MB.
fn peak_mb() -> f64 {
    // SAFETY: getrusage fills the struct it is given.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) };
    u.ru_maxrss as f64 / 1024.0
}

struct Timed {
    ms: Vec<f64>,
    rays: u64,
}

/// `frames` frames of `frame` (after one warm-up), each timed by the tracer's own clock.
fn time_frames(renderer: &mut Renderer, frame: &Frame, frames: u32) -> (Timed, glray_render::Rendered) {
    let (w, h) = (frame.width, frame.height);
    let mut image = renderer.render(frame, w, h, None);
    let mut t = Timed { ms: Vec::new(), rays: 0 };
    for _ in 0..frames {
        image = renderer.render(frame, w, h, None);
        let s = renderer.stats();
        t.ms.push(s.trace.as_secs_f64() * 1e3);
        t.rays = s.rays;
    }
    (t, image)
}

pub fn run(a: &Args) -> Result<(), String> {
    if let Some(t) = a.threads {
        rayon::ThreadPoolBuilder::new().num_threads(t).build_global().map_err(|e| format!("--threads {t}: {e}"))?;
    }
    let threads = rayon::current_num_threads();
    let start = Instant::now();
    let mesh = load(a.mesh)?;
    let load_s = start.elapsed().as_secs_f64();
    let (nv, nt) = (mesh.positions.len(), mesh.triangles.len());
    let frame = frame(mesh, a.width, a.height);
    let gl = Options { effects: Effects { progressive: false, ..Effects::GL }, ..Options::default() };
    // Builds: a fresh renderer each time, so the mesh's BVH is built anew.
    let mut builds = Vec::new();
    for _ in 0..a.builds.max(1) {
        let mut r = Renderer::new(gl);
        r.render(&frame, a.width, a.height, None);
        builds.push(r.stats().build.as_secs_f64());
    }
    let mut renderer = Renderer::new(gl);
    let (primary, image) = time_frames(&mut renderer, &frame, a.frames.max(1));
    let hits = image.rgba.chunks(4).filter(|p| p[..3] != [0, 0, 0]).count();
    let ao_options = Options { effects: Effects { ao_samples: a.ao, ..gl.effects }, ..gl };
    let mut ao_renderer = Renderer::new(ao_options);
    let (ao, ao_image) = time_frames(&mut ao_renderer, &frame, a.frames.max(1));
    let mrays = |t: &Timed, ms: f64| if ms > 0.0 { t.rays as f64 / (ms * 1e3) } else { 0.0 };
    let (p_min, p_med) = (min(&primary.ms), median(primary.ms.clone()));
    let (a_min, a_med) = (min(&ao.ms), median(ao.ms.clone()));
    let peak = peak_mb();
    if let Some(out) = a.out {
        Image::from_bottom_up(a.width, a.height, &ao_image.rgba, 4).write_png(out)?;
    }
    let name = a.mesh.display();
    if a.json {
        println!(
            "{{\"mesh\":\"{name}\",\"vertices\":{nv},\"triangles\":{nt},\"width\":{},\"height\":{},\"threads\":{threads},\
             \"load_s\":{load_s:.4},\"build_s_min\":{:.4},\"build_s_median\":{:.4},\"primary_ms_min\":{p_min:.2},\
             \"primary_ms_median\":{p_med:.2},\"primary_mrays_s\":{:.2},\"hits\":{hits},\"ao_rays_per_hit\":{},\
             \"ao_ms_min\":{a_min:.2},\"ao_ms_median\":{a_med:.2},\"ao_mrays_s\":{:.2},\"peak_mb\":{peak:.1}}}",
            a.width,
            a.height,
            min(&builds),
            median(builds.clone()),
            mrays(&primary, p_min),
            a.ao,
            mrays(&ao, a_min),
        );
        return Ok(());
    }
    println!("mesh {name}: {nv} verts {nt} tris, load {load_s:.3} s; {}x{}, {threads} threads", a.width, a.height);
    println!(
        "RESULT build tris={nt} builds={} min_s={:.4} median_s={:.4} mprims_per_s={:.2}",
        builds.len(),
        min(&builds),
        median(builds.clone()),
        nt as f64 / min(&builds).max(1e-9) / 1e6
    );
    println!(
        "RESULT primary threads={threads} frames={} frame_ms_min={p_min:.2} frame_ms_median={p_med:.2} mrays_s={:.2} hits={hits}",
        primary.ms.len(),
        mrays(&primary, p_min),
    );
    println!(
        "RESULT ao threads={threads} frames={} rays_per_hit={} ao_pass_ms_min={a_min:.2} ao_pass_ms_median={a_med:.2} \
         rays={} mrays_s={:.2}",
        ao.ms.len(),
        a.ao,
        ao.rays,
        mrays(&ao, a_min),
    );
    println!("RESULT memory peak_MB={peak:.1}");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A two-triangle mesh file, and damaged ones.
    fn write(path: &Path, nv: u32, nt: u32, extra: usize) {
        let mut d = b"ISOMESH1".to_vec();
        d.extend(nv.to_le_bytes());
        d.extend(nt.to_le_bytes());
        let pos = [[0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
        for p in pos.iter().take(nv as usize) {
            d.extend(p.iter().flat_map(|x| x.to_le_bytes()));
        }
        for _ in 0..nv {
            d.extend([0f32, 0.0, 1.0].iter().flat_map(|x| x.to_le_bytes()));
        }
        for t in [[0u32, 1, 2], [1, 3, 2]].iter().take(nt as usize) {
            d.extend(t.iter().flat_map(|x| x.to_le_bytes()));
        }
        d.extend(vec![0u8; extra]);
        std::fs::write(path, d).unwrap();
    }

    #[test]
    fn meshes_load_and_bad_files_say_why() {
        let dir = std::env::temp_dir().join(format!("glray-bench-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let good = dir.join("good.bin");
        write(&good, 4, 2, 0);
        let m = load(&good).unwrap();
        assert_eq!((m.positions.len(), m.triangles.len()), (4, 2));
        assert_eq!(m.triangles[1], [1, 3, 2]);
        let short = dir.join("short.bin");
        write(&short, 4, 2, 3);
        assert!(load(&short).unwrap_err().contains("need 136 bytes, the file has 139"));
        let bad = dir.join("bad.bin");
        std::fs::write(&bad, b"PLY nonsense here").unwrap();
        assert!(load(&bad).unwrap_err().contains("no ISOMESH1 header"));
        let f = frame(m, 64, 36);
        assert_eq!(f.triangle_count(), 2);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
