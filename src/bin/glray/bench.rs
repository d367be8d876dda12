//! `glray bench --mesh FILE`: glray's tracer on the anchors' scene (../shared/anchors: the same
//! mesh file format, camera, light and material as embree_bench and osmesa_bench), measured in
//! embree_bench's terms: BVH build time, primary-ray frame time and Mrays/s, ambient-occlusion
//! frame time and Mrays/s, peak memory. The mesh becomes one display-list mesh drawn once, as
//! osmesa_bench's `dl` frames are under glray, so the numbers are the library's own path.

use std::path::Path;
use std::time::Instant;

use glam::{DMat4, DVec3, DVec4, Vec3};
use glray_core::image::Image;
use glray_render::effects::occlusion;
use glray_render::meshes::Meshes;
use glray_render::offset::Origin;
use glray_render::options::BvhBuild;
use glray_render::pieces::{for_each_block, TILE};
use glray_render::sampling::Sampler;
use glray_render::scene::{Ray, Scene};
use glray_render::{Effects, Options, Renderer};
use glray_scene::camera::Viewport;
use glray_scene::draw_lighting::Lighting;
use glray_scene::frame::{Frame, View};
use glray_scene::instance::Instance;
use glray_scene::lighting::{Light, LightModel, Material};
use glray_scene::mesh::Mesh;
use glray_scene::surface::Surface;
use rayon::prelude::*;

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
    pub bvh: BvhBuild,
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
    let mut m = glray_capture::fixed::matrices::Matrices::default();
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
    let instance = Instance::new(std::sync::Arc::new(mesh), view, projection);
    Frame {
        instances: vec![instance],
        surfaces: vec![Surface::depth_tested()],
        projection: Some(projection),
        viewport: Some(viewport),
        depth_range: (0.0, 1.0),
        clear_color: glam::Vec4::new(0.0, 0.0, 0.0, 1.0),
        cleared: true,
        depth_cleared: Some(1.0),
        lightings: vec![Lighting::new(vec![light], LightModel::default(), [material; 2], None)],
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

/// A camera ray's hit, as embree_bench keeps it: where, and the normal facing the ray.
#[derive(Clone, Copy)]
struct HitRecord {
    p: Vec3,
    n: Vec3,
}

/// embree_bench's two kernels on glray's scene and BVH, without the GL look: a camera ray per
/// pixel keeping each hit's point and normal, then 16 (`ao`) ambient-occlusion rays per hit
/// from those records. Times in ms per pass, best and median of `frames`.
struct Kernels {
    primary: Vec<f64>,
    ao: Vec<f64>,
    hits: usize,
    ao_rays: u64,
}

fn kernels(frame: &Frame, ao: u32, frames: u32, bvh: BvhBuild) -> Kernels {
    let mut meshes = Meshes::default();
    // The mesh is drawn unchanged, as in the frames below: no tree is built again next frame.
    let scene = Scene::build(frame, &mut meshes, bvh, 0.0);
    let camera = glray_scene::camera::Camera::new(
        frame.projection.expect("the bench frame has a projection"),
        frame.viewport.expect("and a viewport"),
        frame.depth_range,
    )
    .expect("an invertible projection");
    let (w, h) = (frame.width as usize, frame.height as usize);
    let mut records: Vec<Option<HitRecord>> = vec![None; w * h];
    let record = |ray: &Ray, hit: Option<glray_render::scene::Hit>| {
        hit.map(|hit| {
            let d = Vec3::from(ray.direction);
            let mut n = hit.normal.normalize_or_zero();
            if n.dot(d) > 0.0 {
                n = -n;
            }
            HitRecord { p: Vec3::from(ray.origin) + d * hit.t, n }
        })
    };
    let ray = |r: glray_scene::camera::Ray| {
        glray_render::bvh::ray(r.origin.as_vec3a(), r.direction.as_vec3a(), 0.0, r.t_max as f32)
    };
    // In 4x2 blocks of camera rays, as the renderer traces them.
    let trace = |records: &mut Vec<Option<HitRecord>>| {
        records.par_chunks_mut(2 * w).enumerate().for_each(|(pair, rows)| {
            let y0 = 2 * pair;
            let two = rows.len() > w;
            for x0 in (0..w).step_by(4) {
                let at = |k: usize| ((x0 + k % 4).min(w - 1), if two { y0 + k / 4 } else { y0 });
                let centres: [(f64, f64); 8] = std::array::from_fn(|k| {
                    let (x, y) = at(k);
                    (x as f64 + 0.5, y as f64 + 0.5)
                });
                let rays: [Ray; 8] = camera.rays(&centres).map(ray);
                let mut hits = [None; 8];
                scene.closest_packet(&rays, &mut hits);
                for k in 0..8 {
                    let (x, y) = at(k);
                    rows[(y - y0) * w + x] = record(&rays[k], hits[k]);
                }
            }
        });
    };
    let mut primary = Vec::new();
    trace(&mut records);
    for _ in 0..frames {
        let start = Instant::now();
        trace(&mut records);
        primary.push(start.elapsed().as_secs_f64() * 1e3);
    }
    let distance = scene.diagonal() * Effects::default().ao_distance;
    let eps = scene.diagonal() * 1e-4;
    let mut shade = vec![0.0f32; w * h];
    let mut ao_ms = Vec::new();
    for pass in 0..=frames {
        let start = Instant::now();
        // In the renderer's order: bands of rows, tile by tile, each tile's 4x2 blocks.
        shade.par_chunks_mut(TILE * w).zip(records.par_chunks(TILE * w)).enumerate().for_each(
            |(band, (rows, hits))| {
                let y0 = TILE * band;
                for_each_block(0..w, y0..=y0 + hits.len() / w - 1, |x, ya, yb| {
                    for py in ya..=yb {
                        for px in x..(x + 4).min(w) {
                            let at = (py - y0) * w + px;
                            if let Some(hit) = &hits[at] {
                                let mut sampler = Sampler::new(&[px as u32, py as u32, 0]);
                                let from = Origin { p: hit.p, n: hit.n, draw: u32::MAX };
                                rows[at] = occlusion(&scene, &from, ao, distance, eps, &mut sampler);
                            }
                        }
                    }
                });
            },
        );
        if pass > 0 {
            ao_ms.push(start.elapsed().as_secs_f64() * 1e3);
        }
    }
    let hits = records.iter().filter(|r| r.is_some()).count();
    Kernels { primary, ao: ao_ms, hits, ao_rays: hits as u64 * ao as u64 }
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
    let gl = Options { effects: Effects { progressive: false, ..Effects::GL }, bvh: a.bvh, ..Options::default() };
    // Builds: a fresh renderer each time, so the mesh's BVH is built anew.
    let mut builds = Vec::new();
    for _ in 0..a.builds.max(1) {
        let mut r = Renderer::new(gl);
        r.render(&frame, a.width, a.height, None);
        builds.push(r.stats().build.as_secs_f64());
    }
    let k = kernels(&frame, a.ao, a.frames.max(1), a.bvh);
    let mut renderer = Renderer::new(gl);
    let (primary, image) = time_frames(&mut renderer, &frame, a.frames.max(1));
    let hits = image.rgba.chunks(4).filter(|p| p[..3] != [0, 0, 0]).count();
    // One BVH alive at a time, as in embree_bench: the peak is one scene's.
    drop((renderer, image));
    let ao_options = Options { effects: Effects { ao_samples: a.ao, ..gl.effects }, ..gl };
    let mut ao_renderer = Renderer::new(ao_options);
    let (ao, ao_image) = time_frames(&mut ao_renderer, &frame, a.frames.max(1));
    let mrays = |t: &Timed, ms: f64| if ms > 0.0 { t.rays as f64 / (ms * 1e3) } else { 0.0 };
    let per_ms = |rays: u64, ms: f64| if ms > 0.0 { rays as f64 / (ms * 1e3) } else { 0.0 };
    let (k_min, k_med) = (min(&k.primary), median(k.primary.clone()));
    let (ka_min, ka_med) = (min(&k.ao), median(k.ao.clone()));
    let pixels = a.width as u64 * a.height as u64;
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
             \"load_s\":{load_s:.4},\"build_s_min\":{:.4},\"build_s_median\":{:.4},\"primary_ms_min\":{k_min:.2},\
             \"primary_ms_median\":{k_med:.2},\"primary_mrays_s\":{:.2},\"hits\":{},\"ao_rays_per_hit\":{},\
             \"ao_ms_min\":{ka_min:.2},\"ao_ms_median\":{ka_med:.2},\"ao_mrays_s\":{:.2},\
             \"frame_ms_min\":{p_min:.2},\"frame_ms_median\":{p_med:.2},\"lit_pixels\":{hits},\
             \"ao_frame_ms_min\":{a_min:.2},\"ao_frame_ms_median\":{a_med:.2},\"peak_mb\":{peak:.1}}}",
            a.width,
            a.height,
            min(&builds),
            median(builds.clone()),
            per_ms(pixels, k_min),
            k.hits,
            a.ao,
            per_ms(k.ao_rays, ka_min),
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
        "RESULT primary threads={threads} frames={} frame_ms_min={k_min:.2} frame_ms_median={k_med:.2} mrays_s={:.2} hits={}",
        k.primary.len(),
        per_ms(pixels, k_min),
        k.hits,
    );
    println!(
        "RESULT ao threads={threads} frames={} rays_per_hit={} ao_pass_ms_min={ka_min:.2} ao_pass_ms_median={ka_med:.2} \
         rays={} mrays_s={:.2}",
        k.ao.len(),
        a.ao,
        k.ao_rays,
        per_ms(k.ao_rays, ka_min),
    );
    println!(
        "RESULT frame look=gl threads={threads} frames={} frame_ms_min={p_min:.2} frame_ms_median={p_med:.2} mrays_s={:.2} lit_pixels={hits}",
        primary.ms.len(),
        mrays(&primary, p_min),
    );
    println!(
        "RESULT frame look=ao rays_per_hit={} threads={threads} frames={} frame_ms_min={a_min:.2} frame_ms_median={a_med:.2} \
         rays={} mrays_s={:.2}",
        a.ao,
        ao.ms.len(),
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

    /// A ball of `n` x `2n` quads (two triangles each) of radius 0.8 at the origin, where the
    /// anchors' camera looks.
    fn ball(n: u32) -> Mesh {
        let mut positions = Vec::new();
        for i in 0..=n {
            for j in 0..=2 * n {
                let (th, ph) = (std::f32::consts::PI * i as f32 / n as f32, std::f32::consts::PI * j as f32 / n as f32);
                positions.push(0.8 * Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()));
            }
        }
        let at = |i: u32, j: u32| i * (2 * n + 1) + j;
        let mut triangles = Vec::new();
        for i in 0..n {
            for j in 0..2 * n {
                triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        let normals = positions.iter().map(|p| p.normalize()).collect();
        Mesh::indexed(positions, normals, triangles).unwrap()
    }

    #[test]
    fn the_kernels_hit_where_the_frame_is_lit() {
        let (w, h) = (96, 54);
        let f = frame(ball(24), w, h);
        let k = kernels(&f, 4, 1, BvhBuild::Sah);
        let image =
            Renderer::new(Options { effects: Effects { progressive: false, ..Effects::GL }, ..Options::default() })
                .render(&f, w, h, None);
        let lit = image.rgba.chunks(4).filter(|p| p[..3] != [0, 0, 0]).count();
        // The ball fills a good part of the view; the kernels' camera rays find the same pixels
        // the GL look lights (give or take an edge pixel).
        assert!(lit > (w * h / 8) as usize, "{lit} lit pixels");
        assert!(k.hits.abs_diff(lit) <= 2, "kernels hit {} pixels, the frame lit {lit}", k.hits);
        assert_eq!(k.ao_rays, 4 * k.hits as u64);
        assert_eq!((k.primary.len(), k.ao.len()), (1, 1));
    }
}
