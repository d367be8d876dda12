//! The GL look of one hit: the fragment a rasterizer would have produced at that pixel.
//! Colours and texture coordinates are interpolated with the hit's barycentric coordinates in
//! eye space, which is GL's perspective-correct interpolation; then texturing with the texture
//! environment, the secondary colour, and fog from the corners' eye distances (OpenGL 2.1,
//! 3.8-3.10).

use glam::{DVec2, DVec3, Vec2, Vec3, Vec4, Vec4Swizzles};
use glray_scene::camera::Camera;
use glray_scene::frame::Frame;
use glray_scene::lighting::{light_vertex_prepared, Light};
use glray_scene::surface::{Coverage, FogMode, TexEnvMode};
use glray_scene::texture::BaseFormat;
use glray_scene::triangle::{Triangle, NO_LIGHTING};

/// A fragment: its colour (before blending) and window depth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fragment {
    pub color: Vec4,
    pub depth: f64,
    /// Where it is, in eye coordinates (for user clip planes).
    pub eye: DVec3,
    /// Its draw's surface (`Frame::surfaces`).
    pub surface: u32,
}

/// Barycentric weights of `p` in the triangle (in the plane of the triangle).
pub(crate) fn barycentric(t: &Triangle, p: DVec3) -> DVec3 {
    let [a, b, c] = t.positions.map(|v| v.as_dvec3());
    let (e1, e2, d) = (b - a, c - a, p - a);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let den = d11 * d22 - d12 * d12;
    if den == 0.0 {
        return DVec3::new(1.0, 0.0, 0.0);
    }
    let v = (d22 * d1 - d12 * d2) / den;
    let w = (d11 * d2 - d12 * d1) / den;
    DVec3::new(1.0 - v - w, v, w)
}

/// The interpolation weights the rasterizer uses at `p`: barycentric coordinates on the screen,
/// made perspective-correct with each corner's own clip w (so that a draw brought in from
/// another camera interpolates as it was drawn). A triangle drawn with `camera`'s own
/// projection takes the eye-space weights, which are the same thing (perspective-correct
/// interpolation is interpolation in eye space) for a fraction of the work: no corner is
/// projected. They are also the fallback when a corner lies behind the eye (the rasterizer
/// would have clipped the triangle first).
fn weights(frame: &Frame, t: &Triangle, camera: &Camera, p: DVec3) -> DVec3 {
    if own_camera(frame, t.camera, camera) || t.clip_w.iter().any(|w| *w <= 0.0) {
        return barycentric(t, p);
    }
    let w = t.positions.map(|v| {
        let (x, y) = camera.window_position(v.as_dvec3());
        DVec2::new(x, y)
    });
    let (x, y) = camera.window_position(p);
    let q = DVec2::new(x, y);
    let area = (w[1] - w[0]).perp_dot(w[2] - w[0]);
    if area == 0.0 || !area.is_finite() {
        return barycentric(t, p);
    }
    let b = DVec3::new(
        (w[1] - q).perp_dot(w[2] - q) / area,
        (w[2] - q).perp_dot(w[0] - q) / area,
        (w[0] - q).perp_dot(w[1] - q) / area,
    );
    let persp: DVec3 = b / DVec3::from_array(t.clip_w.map(|w| w as f64));
    let sum = persp.x + persp.y + persp.z;
    if sum == 0.0 || !sum.is_finite() {
        return barycentric(t, p);
    }
    persp / sum
}

/// Whether camera `index` of the frame is `camera`: the same projection and viewport. A
/// triangle carried over from another viewport (`Frame::unified`) keeps its screen weights.
pub(crate) fn own_camera(frame: &Frame, index: u32, camera: &Camera) -> bool {
    frame
        .cameras
        .get(index as usize)
        .is_some_and(|v| v.viewport == camera.viewport && v.projection == *camera.projection())
}

/// The texture level of detail at point `p` of triangle `t` (OpenGL 2.1, 3.8.8): log2 of the
/// longer of the steps, in texels of a texture of `size` (its base level's width and height),
/// that one pixel to the right and one pixel up make in the texture. Per pixel, as the
/// rasterizer works it out (per 2x2 quad): a long triangle seen at a grazing angle (a tunnel's
/// wall) takes sharper levels near the viewer than far away. The neighbouring pixels' points
/// are where their camera rays meet the triangle's plane, so that corners behind the eye need
/// no projecting.
fn lod(t: &Triangle, camera: &Camera, p: DVec3, size: DVec2) -> f32 {
    let [a, b, c] = t.positions.map(|v| v.as_dvec3());
    let n = (b - a).cross(c - a);
    let uv = t.texcoords.map(|c| c.as_dvec2());
    let uv_at = |q: DVec3| {
        let w = barycentric(t, q);
        uv[0] * w.x + uv[1] * w.y + uv[2] * w.z
    };
    let on_plane = |x: f64, y: f64| {
        let r = camera.ray(x, y);
        let along = r.direction.dot(n);
        (along != 0.0).then(|| r.origin + r.direction * ((a - r.origin).dot(n) / along))
    };
    let (x, y) = camera.window_position(p);
    let (Some(right), Some(up)) = (on_plane(x + 1.0, y), on_plane(x, y + 1.0)) else { return 0.0 };
    let here = uv_at(p);
    let rho = ((uv_at(right) - here) * size).length().max(((uv_at(up) - here) * size).length());
    if rho > 0.0 && rho.is_finite() {
        rho.log2() as f32
    } else {
        0.0
    }
}

/// How much of each light reaches a point (shadows: 0 blocked, 1 unobstructed, between
/// through translucent surfaces), when that is asked.
pub type Visibility<'a> = Option<&'a dyn Fn(&Light) -> f32>;

/// The fragment of `triangle` at eye-space point `p`. With `per_pixel`, lit triangles run the
/// lighting equation at the point with the interpolated normal (Phong shading) instead of
/// interpolating the colours lit at the corners (Gouraud, what GL does). With `visible`, they
/// are lit per pixel, each light's diffuse and specular terms scaled by how much of it reaches
/// the point (shadows; its ambient term stays, as GL's ambient is not directional).
pub fn shade(frame: &Frame, camera: &Camera, t: &Triangle, p: DVec3, per_pixel: bool, visible: Visibility) -> Fragment {
    let surface = &frame.surfaces[t.surface as usize];
    let b = weights(frame, t, camera, p).as_vec3();
    let mix4 = |v: [Vec4; 3]| v[0] * b.x + v[1] * b.y + v[2] * b.z;
    let mix3 = |v: [Vec3; 3]| v[0] * b.x + v[1] * b.y + v[2] * b.z;
    let mix2 = |v: [Vec2; 3]| v[0] * b.x + v[1] * b.y + v[2] * b.z;
    // Triangles carried in from another camera have no lighting left (Frame::unified).
    let lit_here = t.lighting != NO_LIGHTING
        && (per_pixel || visible.is_some() || frame.lightings[t.lighting as usize].model().per_fragment);
    let (mut c, sec) = if lit_here {
        let l = &frame.lightings[t.lighting as usize];
        let mats = l.materials(mix4(t.base_colors).as_dvec4());
        let n = mix3(t.normals).as_dvec3().normalize_or_zero();
        let m = &mats[t.back as usize];
        let (primary, secondary) = match visible {
            Some(reaches) => {
                let lights: Vec<Light> = l
                    .lights()
                    .iter()
                    .map(|x| {
                        let v = reaches(x) as f64;
                        Light { diffuse: x.diffuse * v, specular: x.specular * v, ..*x }
                    })
                    .collect();
                light_vertex_prepared(p, n, m, &lights, l.prepared(), l.model())
            }
            None => light_vertex_prepared(p, n, m, l.lights(), l.prepared(), l.model()),
        };
        (primary.as_vec4(), secondary.truncate().as_vec3())
    } else {
        (mix4(t.colors), mix3(t.secondary))
    };
    if let Some(tx) = &surface.texturing {
        let l0 = &tx.texture.levels[0];
        let height = if tx.texture.one_d { 0.0 } else { l0.height as f64 };
        let lod = if tx.texture.reads_lod() { lod(t, camera, p, DVec2::new(l0.width as f64, height)) } else { 0.0 };
        let s = tx.texture.sample(mix2(t.texcoords), lod);
        let base = tx.texture.base_format;
        let (cf, af, ct, at) = (c.xyz(), c.w, s.xyz(), s.w);
        c = match tx.env_mode {
            TexEnvMode::Replace => match base {
                BaseFormat::Alpha => cf.extend(at),
                BaseFormat::Rgb | BaseFormat::Luminance => ct.extend(af),
                _ => s,
            },
            TexEnvMode::Decal => match base {
                BaseFormat::Rgb => ct.extend(af),
                _ => (cf * (1.0 - at) + ct * at).extend(af),
            },
            TexEnvMode::Blend => (cf * (Vec3::ONE - ct) + tx.env_color.xyz() * ct).extend(af * at),
            TexEnvMode::Add => (cf + ct).min(Vec3::ONE).extend(af * at),
            TexEnvMode::Modulate => match base {
                BaseFormat::Alpha => cf.extend(af * at),
                _ => (cf * ct).extend(af * at),
            },
            // GL_COMBINE's stages are not followed.
            TexEnvMode::Combine => c,
        };
    }
    if let Some(coverage) = surface.coverage {
        c.w *= covered(coverage, t, camera, p);
    }
    finish(frame, camera, t.surface, c, sec, p, || fog_distance(t.positions.map(|q| q.z), b))
}

/// How much of the pixel at point `p` an antialiased line or round point covers, on the quad
/// triangle `t` made for it (see `Coverage` for its corners' order): 1 within half a pixel
/// inside its edge, falling to 0 half a pixel outside, by the pixel centre's distance from the
/// line's axis or the point's centre on the window.
fn covered(coverage: Coverage, t: &Triangle, camera: &Camera, p: DVec3) -> f32 {
    let window = |e: DVec3| {
        let (x, y) = camera.window_position(e);
        DVec2::new(x, y)
    };
    let w = t.positions.map(|v| window(v.as_dvec3()));
    let q = window(p);
    let (half, distance) = match coverage {
        Coverage::Line(width) => {
            let along = (w[2] - w[1]).normalize_or_zero();
            (width as f64 / 2.0, (q - (w[0] + w[1]) / 2.0).perp_dot(along).abs())
        }
        Coverage::Point(size) => (size as f64 / 2.0, (q - (w[0] + w[2]) / 2.0).length()),
    };
    (half + 0.5 - distance).clamp(0.0, 1.0) as f32
}

/// The fragment of an untextured triangle on surface `surface` at eye-space point `p` from
/// its corners' colours (`primary`, `secondary`) and the weights `b` of the corners there: GL's
/// Gouraud shading, which is all `shade` does for such a triangle drawn with the frame's own
/// camera and lit at its corners, without the rest of the triangle.
pub fn mixed(
    frame: &Frame,
    camera: &Camera,
    surface: u32,
    (primary, secondary): &([Vec4; 3], [Vec3; 3]),
    b: Vec3,
    p: DVec3,
    corner_z: impl FnOnce() -> [f32; 3],
) -> Fragment {
    let c = primary[0] * b.x + primary[1] * b.y + primary[2] * b.z;
    let sec = secondary[0] * b.x + secondary[1] * b.y + secondary[2] * b.z;
    finish(frame, camera, surface, c, sec, p, || fog_distance(corner_z(), b))
}

/// Mesa's fog coordinate where the corners' weights are `b`: each corner's eye-space distance
/// along z (`corner_z`, eye z), mixed across the triangle. GL works it out per vertex; within a
/// triangle in front of the eye the mix is the point's own distance, but a triangle reaching
/// behind the eye (a floor running under the viewer: gibson's) is clipped, and its clipped
/// corners keep the mix of distances, larger than the point's own near the eye.
fn fog_distance(corner_z: [f32; 3], b: Vec3) -> f32 {
    corner_z[0].abs() * b.x + corner_z[1].abs() * b.y + corner_z[2].abs() * b.z
}

/// The end of every fragment (OpenGL 2.1, 3.9-3.10): colour `c` (textured already) plus the
/// secondary colour `sec`, fogged as surface `surface` says by the fog coordinate `fog_z` gives
/// (`fog_distance`), at point `p`.
fn finish(
    frame: &Frame,
    camera: &Camera,
    surface: u32,
    c: Vec4,
    sec: Vec3,
    p: DVec3,
    fog_z: impl FnOnce() -> f32,
) -> Fragment {
    let mut c = (c.xyz() + sec).min(Vec3::ONE).extend(c.w);
    if let Some(fog) = &frame.surfaces[surface as usize].fog {
        let z = fog_z();
        let f = match fog.mode {
            FogMode::Linear => {
                if fog.end == fog.start {
                    1.0
                } else {
                    (fog.end - z) / (fog.end - fog.start)
                }
            }
            FogMode::Exp2 => (-(fog.density * z).powi(2)).exp(),
            FogMode::Exp => (-fog.density * z).exp(),
        }
        .clamp(0.0, 1.0);
        c = (c.xyz() * f + fog.color.xyz() * (1.0 - f)).extend(c.w);
    }
    Fragment { color: c.clamp(Vec4::ZERO, Vec4::ONE), depth: camera.window_depth(p), eye: p, surface }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// An unlit, untextured triangle of the frame's first surface and camera.
    pub(crate) fn plain(positions: [Vec3; 3], clip_w: [f32; 3]) -> Triangle {
        Triangle {
            positions,
            colors: [Vec4::ZERO; 3],
            secondary: [Vec3::ZERO; 3],
            texcoords: [Vec2::ZERO; 3],
            surface: 0,
            sequence: 0,
            camera: 0,
            clip_w,
            normals: [Vec3::Z; 3],
            base_colors: [Vec4::ONE; 3],
            lighting: NO_LIGHTING,
            back: false,
        }
    }

    #[test]
    fn barycentric_weights_reproduce_the_point() {
        let t = plain([Vec3::ZERO, Vec3::X, Vec3::Y], [1.0; 3]);
        let b = barycentric(&t, DVec3::new(0.25, 0.5, 0.0));
        assert!((b - DVec3::new(0.25, 0.25, 0.5)).length() < 1e-12, "{b}");
    }

    #[test]
    fn eye_space_weights_are_the_perspective_correct_screen_weights_under_the_own_camera() {
        use glam::DMat4;
        use glray_scene::camera::Viewport;
        use glray_scene::frame::View;
        let mut m = glray_capture::fixed::matrices::Matrices::default();
        m.frustum(-0.4, 0.4, -0.3, 0.3, 0.5, 50.0).unwrap();
        let projection = *m.top();
        let viewport = Viewport { x: 0, y: 0, width: 300, height: 200 };
        let camera = Camera::new(projection, viewport, (0.0, 1.0)).unwrap();
        // A triangle steeply inclined in depth: screen-linear and perspective-correct weights differ.
        let positions = [Vec3::new(-1.0, -0.5, -2.0), Vec3::new(2.0, -0.4, -12.0), Vec3::new(0.3, 1.5, -5.0)];
        let clip_w = positions.map(|p| (projection * p.as_dvec3().extend(1.0)).w as f32);
        let t = plain(positions, clip_w);
        let own = Frame { cameras: vec![View { projection, viewport }], ..Frame::default() };
        // Without its camera in the frame, the corners are projected (the screen weights).
        let other = Frame { cameras: vec![View { projection: DMat4::IDENTITY, viewport }], ..Frame::default() };
        for want in [DVec3::new(0.2, 0.3, 0.5), DVec3::new(0.7, 0.2, 0.1), DVec3::new(0.05, 0.05, 0.9)] {
            let [a, b, c] = positions.map(|p| p.as_dvec3());
            let p = a * want.x + b * want.y + c * want.z;
            let screen = weights(&other, &t, &camera, p);
            let eye = weights(&own, &t, &camera, p);
            assert!((screen - want).length() < 1e-6, "screen {screen} want {want}");
            assert!((eye - want).length() < 1e-6, "eye {eye} want {want}");
        }
    }
}
