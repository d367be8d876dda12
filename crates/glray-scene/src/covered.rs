//! Where a frame's drawing lands in the window (`covered`): the rectangle around everything it
//! draws, projected as each draw was drawn. Under MPI a rank is sent back only this part of the
//! shared picture: it is the part a sort-last compositor takes from it (IceT reads a rank's
//! pixels inside its data's screen box; a depth compositor takes the nearest fragment, and
//! outside the rectangle the rank holds only its background, behind everything), so the
//! composite is whole while no rank receives the whole picture.

use glam::{DMat4, DVec3, DVec4};

use crate::camera::Viewport;
use crate::frame::Frame;

/// Pixels of margin around what a frame covers (rounding, and lines' and points' widths in
/// pixels beyond their solids).
const MARGIN: f64 = 2.0;

/// A rectangle of the window: first column and row (rows from the bottom), width, height.
pub type WindowRect = (u32, u32, u32, u32);

/// The part of its `width` x `height` window `frame` draws into (None: nothing; the whole
/// window when a point of its drawing lies behind the eye, where it projects nowhere
/// dependable).
pub fn covered(frame: &Frame) -> Option<WindowRect> {
    let (width, height) = frame.size();
    if width == 0 || height == 0 {
        return None;
    }
    let mut area = Area::default();
    let view = |camera: u32| frame.cameras.get(camera as usize).map(|c| (c.projection, c.viewport));
    for i in &frame.instances {
        let (Some((_, viewport)), lo, hi) = (view(i.camera), i.mesh.min.as_dvec3(), i.mesh.max.as_dvec3()) else {
            return whole(width, height);
        };
        if !area.add_box(&i.object_to_clip, lo, hi, viewport) {
            return whole(width, height);
        }
    }
    for t in &frame.triangles {
        let Some((projection, viewport)) = view(t.camera) else { return whole(width, height) };
        for p in t.positions {
            if !area.add(&projection, p.as_dvec3(), viewport) {
                return whole(width, height);
            }
        }
    }
    for s in &frame.solids {
        let Some((projection, viewport)) = view(s.camera) else { return whole(width, height) };
        let r = DVec3::splat(f64::from(s.radius));
        let (a, b) = (s.a.as_dvec3(), s.b.as_dvec3());
        if !area.add_box(&projection, a.min(b) - r, a.max(b) + r, viewport) {
            return whole(width, height);
        }
    }
    area.rect(width, height)
}

fn whole(width: u32, height: u32) -> Option<WindowRect> {
    Some((0, 0, width, height))
}

/// The window positions met so far.
struct Area {
    min: (f64, f64),
    max: (f64, f64),
}

impl Default for Area {
    fn default() -> Area {
        Area { min: (f64::INFINITY, f64::INFINITY), max: (f64::NEG_INFINITY, f64::NEG_INFINITY) }
    }
}

impl Area {
    /// Point `p` through `to_clip` into `viewport`; false when it is at or behind the eye.
    fn add(&mut self, to_clip: &DMat4, p: DVec3, viewport: Viewport) -> bool {
        let c: DVec4 = *to_clip * p.extend(1.0);
        if c.w.is_nan() || c.w <= 1e-9 * c.truncate().length().max(1.0) {
            return false;
        }
        let (x, y) = (c.x / c.w, c.y / c.w);
        let wx = f64::from(viewport.x) + (x + 1.0) * 0.5 * f64::from(viewport.width);
        let wy = f64::from(viewport.y) + (y + 1.0) * 0.5 * f64::from(viewport.height);
        self.min = (self.min.0.min(wx), self.min.1.min(wy));
        self.max = (self.max.0.max(wx), self.max.1.max(wy));
        true
    }

    /// The corners of the box `lo`..`hi`.
    fn add_box(&mut self, to_clip: &DMat4, lo: DVec3, hi: DVec3, viewport: Viewport) -> bool {
        (0..8).all(|k| {
            let pick = |bit: usize, a: f64, b: f64| if k & bit == 0 { a } else { b };
            self.add(to_clip, DVec3::new(pick(1, lo.x, hi.x), pick(2, lo.y, hi.y), pick(4, lo.z, hi.z)), viewport)
        })
    }

    /// Whole pixels around what was met, with the margin, within the window.
    fn rect(&self, width: u32, height: u32) -> Option<WindowRect> {
        if !(self.min.0 <= self.max.0 && self.min.1 <= self.max.1) {
            return None;
        }
        let clamp = |v: f64, most: u32| v.clamp(0.0, f64::from(most)) as u32;
        let (x0, y0) = (clamp((self.min.0 - MARGIN).floor(), width), clamp((self.min.1 - MARGIN).floor(), height));
        let (x1, y1) = (clamp((self.max.0 + MARGIN).ceil(), width), clamp((self.max.1 + MARGIN).ceil(), height));
        (x1 > x0 && y1 > y0).then_some((x0, y0, x1 - x0, y1 - y0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::View;
    use crate::instance::Instance;
    use crate::mesh::Mesh;
    use glam::Vec3;
    use std::sync::Arc;

    #[test]
    fn a_frame_covers_where_its_draws_project() {
        // A unit square at x 0..1, y 0..1, z = 0, seen orthographically over x, y in -2..2 in a
        // 400 x 200 window: it covers the window's middle quarter, x 200..300, y 100..150.
        let ortho = DMat4::from_diagonal(DVec4::new(0.5, 0.5, -1.0, 1.0)); // glOrtho(-2, 2, -2, 2, -1, 1)
        let viewport = Viewport { x: 0, y: 0, width: 400, height: 200 };
        let mesh = Arc::new(
            Mesh::indexed(vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0)], vec![Vec3::Z; 3], vec![[0, 1, 2]])
                .unwrap(),
        );
        let frame = Frame {
            instances: vec![Instance::new(mesh, DMat4::IDENTITY, ortho)],
            cameras: vec![View { projection: ortho, viewport }],
            projection: Some(ortho),
            viewport: Some(viewport),
            width: 400,
            height: 200,
            ..Frame::default()
        };
        assert_eq!(covered(&frame), Some((198, 98, 104, 54)));
        assert_eq!(covered(&Frame { instances: vec![], ..frame.clone() }), None, "nothing drawn");
        // Behind the eye under a perspective: the whole window.
        // glFrustum(-0.1, 0.1, -0.1, 0.1, 0.1, 10).
        let perspective = DMat4::from_cols(
            DVec4::new(1.0, 0.0, 0.0, 0.0),
            DVec4::new(0.0, 1.0, 0.0, 0.0),
            DVec4::new(0.0, 0.0, -10.1 / 9.9, -1.0),
            DVec4::new(0.0, 0.0, -2.0 / 9.9, 0.0),
        );
        let mut behind = frame.clone();
        behind.cameras[0].projection = perspective;
        behind.instances[0].object_to_clip = perspective * DMat4::from_translation(DVec3::new(0.0, 0.0, 0.5));
        assert_eq!(covered(&behind), Some((0, 0, 400, 200)));
    }
}
