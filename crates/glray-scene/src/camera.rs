//! The camera a GL frame implies: rays through pixel centres from the projection matrix and the
//! viewport, in eye coordinates (where GL lights and the modelview put everything), and the
//! window depth of a hit, as the depth buffer (and glReadPixels of GL_DEPTH_COMPONENT) would
//! hold it. Unprojecting the near and far planes works for perspective and orthographic
//! projections alike, and bounds the ray to what GL would not clip.

use glam::{DMat4, DVec3, DVec4};
use serde::{Deserialize, Serialize};

/// glViewport.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Viewport {
    pub x: i32,
    pub y: i32,
    pub width: i32,
    pub height: i32,
}

/// A ray in eye coordinates: points origin + t * direction for t in [0, t_max], the near plane
/// at t = 0 and the far plane at t_max.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    pub origin: DVec3,
    pub direction: DVec3,
    pub t_max: f64,
}

#[derive(Debug, Clone)]
pub struct Camera {
    projection: DMat4,
    /// The inverse projection applied to NDC (0, 0, -1, 1) and (0, 0, 1, 1), and its x and y
    /// columns: unprojecting a pixel is then two multiply-adds per plane, not a matrix product.
    near0: DVec4,
    far0: DVec4,
    dx: DVec4,
    dy: DVec4,
    /// 2 / viewport width and height: window to NDC is a multiply (a camera ray is made for
    /// every pixel, twice; divisions were a sixth of a GL-look frame).
    ndc_scale: (f64, f64),
    /// 1 / w of the near and far points when w is the same over the whole window (the inverse
    /// projection's x and y columns have w = 0: every gluPerspective, glFrustum and glOrtho
    /// camera): unprojecting a pixel then divides only to normalize its direction.
    recip_w: Option<(f64, f64)>,
    pub viewport: Viewport,
    /// glDepthRange (near, far).
    pub depth_range: (f64, f64),
}

impl Camera {
    /// None for an empty viewport or a projection that cannot be inverted.
    pub fn new(projection: DMat4, viewport: Viewport, depth_range: (f64, f64)) -> Option<Camera> {
        if viewport.width <= 0 || viewport.height <= 0 || projection.determinant().abs() < 1e-300 {
            return None;
        }
        let inverse = projection.inverse();
        let (near0, far0) = (inverse * DVec4::new(0.0, 0.0, -1.0, 1.0), inverse * DVec4::new(0.0, 0.0, 1.0, 1.0));
        let (dx, dy) = (inverse.col(0), inverse.col(1));
        Some(Camera {
            projection,
            near0,
            far0,
            dx,
            dy,
            ndc_scale: (2.0 / viewport.width as f64, 2.0 / viewport.height as f64),
            recip_w: (dx.w == 0.0 && dy.w == 0.0).then(|| (near0.w.recip(), far0.w.recip())),
            viewport,
            depth_range,
        })
    }

    pub fn projection(&self) -> &DMat4 {
        &self.projection
    }

    /// Whether the projection is a perspective one (its last row is not (0, 0, 0, 1)).
    pub fn is_perspective(&self) -> bool {
        self.projection.row(3) != DVec4::new(0.0, 0.0, 0.0, 1.0)
    }

    /// The ray through window position (x, y): (x + 0.5, y + 0.5) is a pixel's centre, y up as
    /// in GL's window coordinates.
    #[inline]
    pub fn ray(&self, x: f64, y: f64) -> Ray {
        let v = self.viewport;
        let ndc_x = (x - v.x as f64) * self.ndc_scale.0 - 1.0;
        let ndc_y = (y - v.y as f64) * self.ndc_scale.1 - 1.0;
        let xy = self.dx * ndc_x + self.dy * ndc_y;
        let (near, far) = (self.near0 + xy, self.far0 + xy);
        let (near_w, far_w) = self.recip_w.unwrap_or_else(|| (near.w.recip(), far.w.recip()));
        let (near, far) = (near.truncate() * near_w, far.truncate() * far_w);
        let span = far - near;
        let t_max = span.length();
        Ray { origin: near, direction: span * t_max.recip(), t_max }
    }

    /// `ray` of each window position of `at`, the same rays bit for bit, worked out side by
    /// side (component arrays the compiler puts in SIMD lanes: the square root and division of
    /// each ray, made for every pixel, were most of the cost of making camera rays).
    #[inline]
    pub fn rays<const N: usize>(&self, at: &[(f64, f64); N]) -> [Ray; N] {
        let v = self.viewport;
        let (mut near, mut span) = ([[0.0; N]; 3], [[0.0; N]; 3]);
        let (mut near_w, mut far_w) = ([0.0; N], [0.0; N]);
        let mut xy = [[0.0; N]; 4];
        for k in 0..N {
            let ndc_x = (at[k].0 - v.x as f64) * self.ndc_scale.0 - 1.0;
            let ndc_y = (at[k].1 - v.y as f64) * self.ndc_scale.1 - 1.0;
            // As `ray` adds them: dx * ndc_x + dy * ndc_y, component by component.
            for (c, lanes) in xy.iter_mut().enumerate() {
                lanes[k] = self.dx[c] * ndc_x + self.dy[c] * ndc_y;
            }
        }
        match self.recip_w {
            Some((n, f)) => (near_w, far_w) = ([n; N], [f; N]),
            None => {
                for k in 0..N {
                    near_w[k] = (self.near0.w + xy[3][k]).recip();
                    far_w[k] = (self.far0.w + xy[3][k]).recip();
                }
            }
        }
        for c in 0..3 {
            for k in 0..N {
                near[c][k] = (self.near0[c] + xy[c][k]) * near_w[k];
                span[c][k] = (self.far0[c] + xy[c][k]) * far_w[k] - near[c][k];
            }
        }
        let mut t_max = [0.0; N];
        let mut recip = [0.0; N];
        for k in 0..N {
            t_max[k] = (span[0][k] * span[0][k] + span[1][k] * span[1][k] + span[2][k] * span[2][k]).sqrt();
            recip[k] = t_max[k].recip();
        }
        std::array::from_fn(|k| Ray {
            origin: DVec3::new(near[0][k], near[1][k], near[2][k]),
            direction: DVec3::new(span[0][k] * recip[k], span[1][k] * recip[k], span[2][k] * recip[k]),
            t_max: t_max[k],
        })
    }

    /// The window depth of an eye-space point: what the depth buffer would hold for it.
    #[inline]
    pub fn window_depth(&self, eye: DVec3) -> f64 {
        let clip = self.projection * eye.extend(1.0);
        let ndc_z = clip.z / clip.w;
        let (n, f) = self.depth_range;
        (ndc_z * (f - n) + (f + n)) / 2.0
    }

    /// The window position (x, y) an eye-space point lands on.
    #[inline]
    /// How wide one pixel is, in eye units, at eye-space point `eye` (across the window's x):
    /// how far apart the points two neighbouring pixels see there are. For a perspective
    /// camera it grows with the distance; for an orthographic one it is the same everywhere.
    /// Worked out from the rays through the point's pixel and the next one (any projection,
    /// rotated or sheared: OpenSCAD's hold the view's rotation), at the point's distance along
    /// its ray.
    pub fn pixel_size(&self, eye: DVec3) -> f64 {
        let (x, y) = self.window_position(eye);
        let (here, next) = (self.ray(x, y), self.ray(x + 1.0, y));
        let along = here.direction.length_squared();
        if along.is_nan() || along <= 0.0 {
            return 0.0;
        }
        let t = (eye - here.origin).dot(here.direction) / along;
        let size = (next.origin + next.direction * t - eye).length();
        if size.is_finite() {
            size
        } else {
            0.0
        }
    }

    pub fn window_position(&self, eye: DVec3) -> (f64, f64) {
        let clip = self.projection * eye.extend(1.0);
        let v = self.viewport;
        let (nx, ny) = (clip.x / clip.w, clip.y / clip.w);
        (v.x as f64 + (nx + 1.0) * v.width as f64 / 2.0, v.y as f64 + (ny + 1.0) * v.height as f64 / 2.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// glFrustum's and glOrtho's matrices (OpenGL 2.1, 2.11.1).
    struct Gl;

    impl Gl {
        fn frustum(&self, l: f64, r: f64, b: f64, t: f64, n: f64, f: f64) -> Option<DMat4> {
            Some(DMat4::from_cols(
                DVec4::new(2.0 * n / (r - l), 0.0, 0.0, 0.0),
                DVec4::new(0.0, 2.0 * n / (t - b), 0.0, 0.0),
                DVec4::new((r + l) / (r - l), (t + b) / (t - b), -(f + n) / (f - n), -1.0),
                DVec4::new(0.0, 0.0, -2.0 * f * n / (f - n), 0.0),
            ))
        }

        fn ortho(&self, l: f64, r: f64, b: f64, t: f64, n: f64, f: f64) -> Option<DMat4> {
            Some(DMat4::from_cols(
                DVec4::new(2.0 / (r - l), 0.0, 0.0, 0.0),
                DVec4::new(0.0, 2.0 / (t - b), 0.0, 0.0),
                DVec4::new(0.0, 0.0, -2.0 / (f - n), 0.0),
                DVec4::new(-(r + l) / (r - l), -(t + b) / (t - b), -(f + n) / (f - n), 1.0),
            ))
        }
    }

    fn projection(f: impl FnOnce(&Gl) -> DMat4) -> DMat4 {
        f(&Gl)
    }

    const VP: Viewport = Viewport { x: 0, y: 0, width: 200, height: 100 };

    #[test]
    fn perspective_rays_start_on_the_near_plane_and_pass_through_the_frustum_corners() {
        let p = projection(|m| m.frustum(-2.0, 2.0, -1.0, 1.0, 1.0, 10.0).unwrap());
        let cam = Camera::new(p, VP, (0.0, 1.0)).unwrap();
        assert!(cam.is_perspective());
        let centre = cam.ray(100.0, 50.0);
        assert!(centre.origin.abs_diff_eq(DVec3::new(0.0, 0.0, -1.0), 1e-12), "{:?}", centre.origin);
        assert!(centre.direction.abs_diff_eq(DVec3::new(0.0, 0.0, -1.0), 1e-12));
        assert!((centre.t_max - 9.0).abs() < 1e-9);
        // The window's top-right corner is the frustum's (2, 1) corner at the near plane.
        let corner = cam.ray(200.0, 100.0);
        assert!(corner.origin.abs_diff_eq(DVec3::new(2.0, 1.0, -1.0), 1e-9), "{:?}", corner.origin);
        assert!(corner.direction.abs_diff_eq(DVec3::new(2.0, 1.0, -1.0).normalize(), 1e-9));
        assert!((cam.window_depth(centre.origin)).abs() < 1e-12);
        assert!((cam.window_depth(centre.origin + centre.direction * centre.t_max) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn rays_side_by_side_are_each_pixels_ray_bit_for_bit() {
        let cameras = [
            projection(|m| m.frustum(-0.01, 0.01, -0.006, 0.006, 0.01, 1000.0).unwrap()),
            projection(|m| m.ortho(-2.0, 3.0, -1.0, 1.5, -4.0, 9.0).unwrap()),
            // A skewed frustum, and a projection whose w varies over the window.
            projection(|m| m.frustum(-0.3, 0.7, -0.2, 0.4, 0.5, 80.0).unwrap()),
            DMat4::from_cols_array(&[
                1.0, 0.0, 0.0, 0.1, 0.0, 1.0, 0.0, 0.05, 0.0, 0.0, -1.2, -1.0, 0.0, 0.0, -2.0, 0.0,
            ]),
        ];
        for p in cameras {
            let c = Camera::new(p, Viewport { x: 3, y: -2, width: 200, height: 100 }, (0.0, 1.0)).unwrap();
            for y in (-5i32..110).step_by(7) {
                for x in (-5i32..210).step_by(8) {
                    let at: [(f64, f64); 8] =
                        std::array::from_fn(|k| ((x + k as i32 % 4) as f64 + 0.5, (y + k as i32 / 4) as f64 + 0.3));
                    let side = c.rays(&at);
                    for (k, &(px, py)) in at.iter().enumerate() {
                        let one = c.ray(px, py);
                        let bits = |r: &Ray| {
                            (
                                r.origin.to_array().map(f64::to_bits),
                                r.direction.to_array().map(f64::to_bits),
                                r.t_max.to_bits(),
                            )
                        };
                        assert_eq!(bits(&side[k]), bits(&one), "{p:?} at ({px}, {py})");
                    }
                }
            }
        }
    }

    #[test]
    fn orthographic_rays_are_parallel() {
        let p = projection(|m| m.ortho(0.0, 200.0, 0.0, 100.0, -1.0, 1.0).unwrap());
        let cam = Camera::new(p, VP, (0.0, 1.0)).unwrap();
        assert!(!cam.is_perspective());
        let a = cam.ray(10.5, 20.5);
        let b = cam.ray(150.5, 90.5);
        assert!(a.direction.abs_diff_eq(b.direction, 1e-12));
        assert!(a.origin.abs_diff_eq(DVec3::new(10.5, 20.5, 1.0), 1e-9), "{:?}", a.origin);
        assert!((a.t_max - 2.0).abs() < 1e-12);
    }

    #[test]
    fn points_on_a_ray_land_on_its_pixel_at_increasing_depth() {
        let p = projection(|m| m.frustum(-1.0, 1.0, -0.5, 0.5, 0.5, 50.0).unwrap());
        // A projection that turns the frustum: its w varies over the window (the general
        // unprojection, not the constant-w one every glFrustum and glOrtho camera takes).
        let turned = p * DMat4::from_rotation_y(0.3) * DMat4::from_rotation_x(-0.2);
        let vp = Viewport { x: 10, y: 20, width: 64, height: 32 };
        for (p, constant_w) in [(p, true), (turned, false)] {
            let cam = Camera::new(p, vp, (0.25, 0.75)).unwrap();
            assert_eq!(cam.recip_w.is_some(), constant_w);
            for (px, py) in [(30.5, 41.5), (10.5, 20.5), (73.5, 51.5)] {
                let r = cam.ray(px, py);
                let mut last = f64::NEG_INFINITY;
                for t in [0.0, 0.5, 5.0, 20.0, r.t_max] {
                    let hit = r.origin + r.direction * t;
                    let (x, y) = cam.window_position(hit);
                    assert!((x - px).abs() < 1e-6 && (y - py).abs() < 1e-6, "t {t}: ({x}, {y})");
                    let d = cam.window_depth(hit);
                    assert!(d > last && (0.25 - 1e-9..=0.75 + 1e-9).contains(&d), "t {t}: depth {d}");
                    last = d;
                }
                assert!((cam.window_depth(r.origin + r.direction * r.t_max) - 0.75).abs() < 1e-9);
            }
        }
        assert!(Camera::new(DMat4::ZERO, vp, (0.0, 1.0)).is_none());
        assert!(Camera::new(p, Viewport { width: 0, ..vp }, (0.0, 1.0)).is_none());
    }
}
