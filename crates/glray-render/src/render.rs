//! Rendering a captured frame: one ray per pixel centre inside the viewport (the GL look
//! samples where the rasterizer does), rows in parallel on rayon. Every pixel depends only on
//! the frame, so the image is the same for any number of threads.

use glam::Vec4;
use glray_capture::camera::Camera;
use glray_capture::frame::Frame;
use obvhs::ray::Ray;
use rayon::prelude::*;

use crate::fragment::{shade, Fragment};
use crate::resolve::{closest_hit_suffices, in_drawing_order, opaque};
use crate::scene::{Hit, Meshes, Scene};

/// A rendered frame, laid out as GL's framebuffer: rows bottom-up.
#[derive(Debug, Clone, PartialEq)]
pub struct Rendered {
    pub width: u32,
    pub height: u32,
    /// RGBA, 8 bits per channel.
    pub rgba: Vec<u8>,
    /// Window depth per pixel (1.0 where nothing was drawn).
    pub depth: Vec<f32>,
}

fn to_u8(c: Vec4) -> [u8; 4] {
    // Halves round to even, as llvmpipe converts to 8-bit unorm (0.3 clears to 76, not 77).
    c.to_array().map(|x| (x.clamp(0.0, 1.0) * 255.0).round_ties_even() as u8)
}

/// How to render.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Options {
    /// Evaluate lighting per pixel instead of interpolating per-vertex colours.
    pub per_pixel_lighting: bool,
}

/// Renders frames, keeping what outlives a frame: the BVHs of display-list meshes.
#[derive(Default)]
pub struct Renderer {
    pub options: Options,
    meshes: Meshes,
}

impl Renderer {
    pub fn new(options: Options) -> Renderer {
        Renderer { options, meshes: Meshes::default() }
    }

    /// Renders `frame` into a `width` x `height` image. A frame that did not clear the colour
    /// buffer is drawn over `previous` (the last frame of the same drawable), as GL would.
    pub fn render(&mut self, frame: &Frame, width: u32, height: u32, previous: Option<&Rendered>) -> Rendered {
        self.meshes.prune();
        render_with(frame, width, height, previous, &self.options, &mut self.meshes)
    }

    /// The display-list meshes whose BVHs are kept.
    pub fn kept_meshes(&self) -> usize {
        self.meshes.len()
    }
}

/// Renders one frame with nothing kept for the next (see `Renderer`).
pub fn render(frame: &Frame, width: u32, height: u32, previous: Option<&Rendered>, options: &Options) -> Rendered {
    render_with(frame, width, height, previous, options, &mut Meshes::default())
}

fn render_with(
    frame: &Frame,
    width: u32,
    height: u32,
    previous: Option<&Rendered>,
    options: &Options,
    meshes: &mut Meshes,
) -> Rendered {
    let unified;
    let frame = if frame.cameras.len() > 1 {
        unified = frame.unified();
        &unified
    } else {
        frame
    };
    let (w, h) = (width as usize, height as usize);
    let clear = to_u8(frame.clear_color);
    let (mut rgba, mut depth) = match previous {
        Some(p) if !frame.cleared && (p.width, p.height) == (width, height) => {
            let depth = if frame.depth_cleared { vec![1.0f32; w * h] } else { p.depth.clone() };
            (p.rgba.clone(), depth)
        }
        _ => (clear.repeat(w * h), vec![1.0f32; w * h]),
    };
    let camera = match (frame.projection, frame.viewport) {
        (Some(p), Some(v)) if !frame.is_empty() => Camera::new(p, v, frame.depth_range),
        _ => None,
    };
    let Some(camera) = camera else {
        return Rendered { width, height, rgba, depth };
    };
    let scene = Scene::build(frame, meshes);
    let simple = closest_hit_suffices(frame);
    let per_pixel = options.per_pixel_lighting;
    let v = camera.viewport;
    let x0 = v.x.max(0) as usize;
    let x1 = ((v.x as i64 + v.width as i64).max(0) as usize).min(w);
    rgba.par_chunks_mut(4 * w).zip(depth.par_chunks_mut(w)).enumerate().for_each(|(y, (row, drow))| {
        if (y as i64) < v.y as i64 || (y as i64) >= v.y as i64 + v.height as i64 {
            return;
        }
        let mut hits: Vec<Hit> = Vec::new();
        let mut frags: Vec<(Hit, Fragment)> = Vec::new();
        for x in x0..x1 {
            let r = camera.ray(x as f64 + 0.5, y as f64 + 0.5);
            // GL keeps what lies exactly on the near and far planes (backgrounds are often drawn
            // at z = 1): a hair of slack keeps float rounding from dropping them.
            let slack = (r.t_max * 1e-4) as f32;
            let ray = Ray::new(r.origin.as_vec3a(), r.direction.as_vec3a(), -slack, r.t_max as f32 + slack);
            let at = |hit: &Hit| r.origin + r.direction * hit.t as f64;
            let (color, d) = if simple {
                let Some(hit) = scene.closest(ray) else { continue };
                let Some(t) = frame.triangle(hit.id) else { continue };
                let f = shade(frame, &camera, &t, at(&hit), per_pixel);
                // Over the last frame (no clear), the depth it left still tests.
                if !frame.cleared && f.depth >= drow[x] as f64 {
                    continue;
                }
                (opaque(&f), f.depth)
            } else {
                scene.all(ray, &mut hits);
                if hits.is_empty() {
                    continue;
                }
                // A ray through a shared edge hits both triangles; the rasterizer's fill rule
                // gives the pixel to one of them, so one hit per draw and depth is kept.
                hits.sort_by(|a, b| a.sequence.cmp(&b.sequence).then(a.t.total_cmp(&b.t)).then(a.id.cmp(&b.id)));
                hits.dedup_by(|b, a| a.sequence == b.sequence && (a.t - b.t).abs() <= 1e-5 * a.t.abs().max(1e-3));
                frags.clear();
                frags.extend(hits.iter().filter_map(|hit| {
                    let t = frame.triangle(hit.id)?;
                    Some((*hit, shade(frame, &camera, &t, at(hit), per_pixel)))
                }));
                let under = &row[4 * x..4 * x + 4];
                let under = Vec4::from_array(std::array::from_fn(|i| under[i] as f32 / 255.0));
                in_drawing_order(frame, &mut frags, under, drow[x] as f64)
            };
            row[4 * x..4 * x + 4].copy_from_slice(&to_u8(color));
            drow[x] = d as f32;
        }
    });
    Rendered { width, height, rgba, depth }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DMat4, Vec2, Vec3};
    use glray_capture::camera::Viewport;
    use glray_capture::frame::{Fog, Surface, Triangle};

    fn surface() -> Surface {
        Surface {
            texturing: None,
            fog: None,
            depth_test: true,
            depth_func: 0x0201,
            depth_mask: true,
            blend: None,
            alpha_test: None,
            clip_planes: Vec::new(),
        }
    }

    fn quad(z: f32, color: Vec4, surface: u32, sequence: u32) -> [Triangle; 2] {
        let corners =
            [Vec3::new(-1.0, -1.0, z), Vec3::new(1.0, -1.0, z), Vec3::new(1.0, 1.0, z), Vec3::new(-1.0, 1.0, z)];
        let tri = |a: usize, b: usize, c: usize| Triangle {
            positions: [corners[a], corners[b], corners[c]],
            colors: [color; 3],
            secondary: [Vec3::ZERO; 3],
            texcoords: [Vec2::ZERO; 3],
            surface,
            sequence,
            camera: 0,
            clip_w: [1.0; 3],
            normals: [Vec3::Z; 3],
            base_colors: [color; 3],
            lighting: glray_capture::frame::NO_LIGHTING,
            back: false,
        };
        [tri(0, 1, 2), tri(0, 2, 3)]
    }

    /// An orthographic frame (eye z from -1 near to -10 far) of 8x8 pixels.
    fn frame(triangles: Vec<Triangle>, surfaces: Vec<Surface>) -> Frame {
        // glOrtho(-1, 1, -1, 1, 1, 10).
        let mut m = glray_capture::matrix::Matrices::default();
        m.matrix_mode(0x1701).unwrap();
        m.ortho(-1.0, 1.0, -1.0, 1.0, 1.0, 10.0).unwrap();
        let projection: DMat4 = *m.top();
        let viewport = Viewport { x: 0, y: 0, width: 8, height: 8 };
        Frame {
            triangles,
            surfaces,
            projection: Some(projection),
            viewport: Some(viewport),
            cameras: vec![glray_capture::frame::View { projection, viewport }],
            depth_range: (0.0, 1.0),
            clear_color: Vec4::new(0.0, 0.0, 1.0, 1.0),
            cleared: true,
            width: 8,
            height: 8,
            ..Frame::default()
        }
    }

    fn pixel(r: &Rendered, x: usize, y: usize) -> [u8; 4] {
        let i = 4 * (y * r.width as usize + x);
        r.rgba[i..i + 4].try_into().unwrap()
    }

    #[test]
    fn the_nearest_surface_wins_and_depth_is_written() {
        let red = quad(-5.0, Vec4::new(1.0, 0.0, 0.0, 1.0), 0, 0);
        let green = quad(-3.0, Vec4::new(0.0, 1.0, 0.0, 1.0), 0, 1);
        let f = frame([red, green].concat(), vec![surface()]);
        let r = render(&f, 8, 8, None, &Options::default());
        assert_eq!(pixel(&r, 4, 4), [0, 255, 0, 255]);
        // Window depth of eye z = -3 between near 1 and far 10 (orthographic: linear).
        assert!((r.depth[4 * 8 + 4] - 2.0 / 9.0).abs() < 1e-5, "{}", r.depth[36]);
        let empty = render(&frame(vec![], vec![surface()]), 8, 8, None, &Options::default());
        assert_eq!(pixel(&empty, 0, 0), [0, 0, 255, 255], "the clear colour");
    }

    #[test]
    fn blending_and_disabled_depth_test_follow_drawing_order() {
        // A half-transparent white quad drawn last, behind the red one, with depth test off.
        let mut over = surface();
        over.depth_test = false;
        over.blend = Some((0x0302, 0x0303));
        let red = quad(-3.0, Vec4::new(1.0, 0.0, 0.0, 1.0), 0, 0);
        let white = quad(-5.0, Vec4::new(1.0, 1.0, 1.0, 0.5), 1, 1);
        let r = render(&frame([red, white].concat(), vec![surface(), over]), 8, 8, None, &Options::default());
        // Alpha blends too: 0.5 * 0.5 + 1 * 0.5.
        assert_eq!(pixel(&r, 4, 4), [255, 128, 128, 191]);
    }

    #[test]
    fn user_clip_planes_cut_surfaces_away() {
        // The green quad in front is clipped where x < 0 (plane (1, 0, 0, 0)): red shows there.
        let mut clipped = surface();
        clipped.clip_planes = vec![glam::DVec4::new(1.0, 0.0, 0.0, 0.0)];
        let red = quad(-5.0, Vec4::new(1.0, 0.0, 0.0, 1.0), 0, 0);
        let green = quad(-3.0, Vec4::new(0.0, 1.0, 0.0, 1.0), 1, 1);
        let r = render(&frame([red, green].concat(), vec![surface(), clipped]), 8, 8, None, &Options::default());
        assert_eq!(pixel(&r, 1, 4), [255, 0, 0, 255]);
        assert_eq!(pixel(&r, 6, 4), [0, 255, 0, 255]);
    }

    #[test]
    fn fog_mixes_by_eye_distance() {
        let mut fogged = surface();
        fogged.fog = Some(Fog { mode: 0x2601, density: 1.0, start: 2.0, end: 6.0, color: Vec4::ONE });
        let black = quad(-4.0, Vec4::new(0.0, 0.0, 0.0, 1.0), 0, 0);
        let r = render(&frame(black.to_vec(), vec![fogged]), 8, 8, None, &Options::default());
        // Linear fog at distance 4 between 2 and 6: half fog colour.
        assert_eq!(pixel(&r, 4, 4)[..3], [128, 128, 128]);
    }

    #[test]
    fn lighting_per_pixel_catches_a_highlight_between_vertices() {
        use glray_capture::frame::Lighting;
        use glray_capture::lighting::{Light, LightModel, Material};
        // A big quad and a close positional light over its centre: at the corners the light
        // grazes, so per-vertex lighting leaves the centre dark; per pixel it is bright.
        let light = Light { enabled: true, position: glam::DVec4::new(0.0, 0.0, -4.0, 1.0), ..Light::new(0) };
        let lighting = Lighting {
            lights: vec![light],
            model: LightModel { ambient: glam::DVec4::ZERO, ..LightModel::default() },
            materials: [Material::default(); 2],
            color_material: None,
        };
        let mut q = quad(-5.0, Vec4::new(0.0, 0.0, 0.0, 1.0), 0, 0);
        for t in &mut q {
            t.lighting = 0;
            for p in &mut t.positions {
                p.x *= 100.0;
                p.y *= 100.0;
            }
        }
        let mut f = frame(q.to_vec(), vec![surface()]);
        f.lightings = vec![lighting];
        // The camera sees only the middle of the quad.
        let vertex = render(&f, 8, 8, None, &Options::default());
        let pixel = render(&f, 8, 8, None, &Options { per_pixel_lighting: true });
        assert_eq!(pixel_of(&vertex, 4, 4)[..3], [0, 0, 0], "the interpolated corner colours");
        assert!(pixel_of(&pixel, 4, 4)[0] > 180, "{:?}", pixel_of(&pixel, 4, 4));
    }

    fn pixel_of(r: &Rendered, x: usize, y: usize) -> [u8; 4] {
        pixel(r, x, y)
    }

    #[test]
    fn images_do_not_depend_on_the_thread_count() {
        let mut tris = Vec::new();
        for k in 0..50 {
            let z = -2.0 - k as f32 * 0.1;
            let mut q = quad(z, Vec4::new(k as f32 / 50.0, 0.5, 0.2, 1.0), 0, k);
            for t in &mut q {
                for p in &mut t.positions {
                    *p *= 0.2 + 0.015 * k as f32;
                    p.z = z;
                }
            }
            tris.extend(q);
        }
        let f = frame(tris, vec![surface()]);
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| render(&f, 8, 8, None, &Options::default()))
        };
        let one = run(1);
        assert_eq!(one, run(2));
        assert_eq!(one, run(8));
    }

    /// Follows calls (scalar arguments: integers, or floats as F64) in a fresh context with
    /// a perspective camera; returns the context.
    fn followed(calls: &[(&str, Vec<glray_core::trace::Value<'static>>)]) -> glray_capture::context::Context {
        use glray_core::trace::Value;
        let mut c = glray_capture::context::Context::default();
        c.set_drawable(48, 48);
        let setup: Vec<(&str, Vec<Value>)> = vec![
            ("glMatrixMode", vec![Value::Int(0x1701)]),
            ("glFrustum", [-0.5, 0.5, -0.5, 0.5, 1.0, 20.0].map(Value::F64).to_vec()),
            ("glMatrixMode", vec![Value::Int(0x1700)]),
            ("glEnable", vec![Value::Int(0x0B50)]), // GL_LIGHTING
            ("glEnable", vec![Value::Int(0x4000)]), // GL_LIGHT0
            ("glEnable", vec![Value::Int(0x0B57)]), // GL_COLOR_MATERIAL
            ("glEnable", vec![Value::Int(0x0B71)]), // GL_DEPTH_TEST
        ];
        for (name, args) in setup.iter().chain(calls) {
            let (op, ty) = glray_capture::ops::op_for(name).unwrap();
            c.call(op, ty, args);
        }
        c
    }

    /// A box of quads at (x, 0, -6), in a colour, with normals: four sides and a top.
    fn box_calls(x: f64, color: [f64; 3]) -> Vec<(&'static str, Vec<glray_core::trace::Value<'static>>)> {
        use glray_core::trace::Value::{Int, F64};
        vec![
            ("glPushMatrix", vec![]),
            ("glTranslatef", vec![F64(x), F64(0.0), F64(-6.0)]),
            ("glRotatef", vec![F64(30.0), F64(1.0), F64(1.0), F64(0.0)]),
            ("glColor3f", color.map(F64).to_vec()),
            ("glCallList", vec![Int(1)]),
            ("glPopMatrix", vec![]),
        ]
    }

    fn box_list() -> Vec<(&'static str, Vec<glray_core::trace::Value<'static>>)> {
        use glray_core::trace::Value::{Int, F64};
        let faces: [([f64; 3], [[f64; 3]; 4]); 3] = [
            ([0.0, 0.0, 1.0], [[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [1.0, 1.0, 1.0], [-1.0, 1.0, 1.0]]),
            ([1.0, 0.0, 0.0], [[1.0, -1.0, 1.0], [1.0, -1.0, -1.0], [1.0, 1.0, -1.0], [1.0, 1.0, 1.0]]),
            ([0.0, 1.0, 0.0], [[-1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, 1.0, -1.0], [-1.0, 1.0, -1.0]]),
        ];
        let mut v = vec![("glNewList", vec![Int(1), Int(0x1300)]), ("glBegin", vec![Int(7)])];
        for (n, corners) in faces {
            v.push(("glNormal3f", n.map(F64).to_vec()));
            for c in corners {
                v.push(("glVertex3f", c.map(F64).to_vec()));
            }
        }
        v.push(("glEnd", vec![]));
        v.push(("glEndList", vec![]));
        v
    }

    #[test]
    fn list_instances_render_as_their_triangles_would_and_keep_their_bvh() {
        let mut calls = box_list();
        calls.extend(box_calls(-1.2, [1.0, 0.5, 0.0]));
        calls.extend(box_calls(1.2, [0.0, 0.5, 1.0]));
        let mut c = followed(&calls);
        let frame = c.take_frame();
        assert_eq!((frame.instances.len(), frame.triangles.len()), (2, 0));
        let mut renderer = Renderer::default();
        let traced = renderer.render(&frame, 48, 48, None);
        assert_eq!(renderer.kept_meshes(), 1, "one mesh, two instances");
        // The same triangles, made flat: the picture must not change.
        let flat = Frame { triangles: frame.all_triangles(), instances: Vec::new(), ..frame.clone() };
        let reference = render(&flat, 48, 48, None, &Options::default());
        let differ = traced.rgba.iter().zip(&reference.rgba).filter(|(a, b)| a.abs_diff(**b) > 1).count();
        assert_eq!(differ, 0, "instances and flat triangles differ");
        let lit = traced.rgba.chunks(4).filter(|p| p[..3] != [0, 0, 0]).count();
        assert!(lit > 300, "both boxes are seen: {lit} pixels");
        // Deleting the list frees its mesh, and the tracer its BVH, at the next frame.
        let delete = [("glDeleteLists", vec![glray_core::trace::Value::Int(1), glray_core::trace::Value::Int(1)])];
        for (name, args) in &delete {
            let (op, ty) = glray_capture::ops::op_for(name).unwrap();
            c.call(op, ty, args);
        }
        drop((frame, flat));
        renderer.render(&c.take_frame(), 48, 48, None);
        assert_eq!(renderer.kept_meshes(), 0);
    }
}
