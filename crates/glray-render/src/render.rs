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
use crate::scene::{Hit, Scene};

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
    c.to_array().map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// Renders `frame` into a `width` x `height` image. A frame that did not clear the colour
/// buffer is drawn over `previous` (the last frame of the same drawable), as GL would.
pub fn render(frame: &Frame, width: u32, height: u32, previous: Option<&Rendered>) -> Rendered {
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
        (Some(p), Some(v)) if !frame.triangles.is_empty() => Camera::new(p, v, frame.depth_range),
        _ => None,
    };
    let Some(camera) = camera else {
        return Rendered { width, height, rgba, depth };
    };
    let scene = Scene::build(frame);
    let simple = closest_hit_suffices(frame);
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
                match scene.closest(ray) {
                    Some(hit)
                        if frame.cleared || shade(frame, &camera, hit.triangle, at(&hit)).depth < drow[x] as f64 =>
                    {
                        let f = shade(frame, &camera, hit.triangle, at(&hit));
                        (opaque(&f), f.depth)
                    }
                    _ => continue,
                }
            } else {
                scene.all(ray, &mut hits);
                if hits.is_empty() {
                    continue;
                }
                frags.clear();
                frags.extend(hits.iter().map(|hit| (*hit, shade(frame, &camera, hit.triangle, at(hit)))));
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
