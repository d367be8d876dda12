//! The frames several MPI ranks captured, made one (`merge`): what image-parallel tracing
//! traces on every rank, so that each rank's rays meet every rank's objects.
//!
//! A data-parallel host draws its pieces on its ranks in rank order, with the same camera,
//! lights and clears everywhere. The merged frame is the one a single process drawing every
//! piece in that order would have captured: rank after rank, each one's draws numbered on from
//! the last one's, surfaces and lightings shared with the draw before when they are the same
//! (as capture shares them), cameras shared when equal. A picture of the merged frame is
//! therefore the picture of one process drawing it all, whatever the number of ranks.

use crate::frame::Frame;
use crate::triangle::NO_LIGHTING;

/// The frames of ranks 0, 1, ... (in that order) as one frame. The clears, size and camera of
/// the first frame that drew something stand for all: every rank of a host clears alike.
pub fn merge(frames: Vec<Frame>) -> Frame {
    let mut frames = frames.into_iter();
    let Some(mut out) = frames.next() else {
        return Frame::default();
    };
    for frame in frames {
        append(&mut out, frame);
    }
    out
}

/// Where one rank's surfaces, lightings, cameras and draws land in the merged frame.
struct Renumbering {
    surfaces: Vec<u32>,
    lightings: Vec<u32>,
    cameras: Vec<u32>,
    /// Added to every draw's sequence number.
    sequence: u32,
}

impl Renumbering {
    fn lighting(&self, l: u32) -> u32 {
        if l == NO_LIGHTING {
            l
        } else {
            self.lightings[l as usize]
        }
    }
}

fn append(out: &mut Frame, frame: Frame) {
    if out.projection.is_none() && frame.projection.is_some() {
        // The first rank drew nothing: the camera comes from the first one that did.
        (out.projection, out.viewport, out.depth_range) = (frame.projection, frame.viewport, frame.depth_range);
    }
    if (out.width, out.height) == (0, 0) {
        (out.width, out.height) = (frame.width, frame.height);
    }
    let sequence = next_sequence(out);
    let mut map = Renumbering { surfaces: Vec::new(), lightings: Vec::new(), cameras: Vec::new(), sequence };
    // Capture shares a surface or lighting with the draw before when they are the same: so
    // here, at the seam between two ranks.
    for s in frame.surfaces {
        if out.surfaces.last() != Some(&s) {
            out.surfaces.push(s);
        }
        map.surfaces.push(out.surfaces.len() as u32 - 1);
    }
    for l in frame.lightings {
        if out.lightings.last() != Some(&l) {
            out.lightings.push(l);
        }
        map.lightings.push(out.lightings.len() as u32 - 1);
    }
    // Capture shares a camera with any earlier draw's; ranks' cameras that differ by rounding
    // alone are one camera (each rank works its camera out itself): made two, the later rank's
    // draws would be carried into the first's view as flat triangles (`Frame::unified`), their
    // BVH built anew every frame and their lighting fixed as drawn.
    for c in frame.cameras {
        let at = out.cameras.iter().rposition(|o| o.same_but_for_rounding(&c)).unwrap_or_else(|| {
            out.cameras.push(c);
            out.cameras.len() - 1
        });
        map.cameras.push(at as u32);
    }
    out.triangles.extend(frame.triangles.into_iter().map(|mut t| {
        t.surface = map.surfaces[t.surface as usize];
        t.lighting = map.lighting(t.lighting);
        t.camera = map.cameras[t.camera as usize];
        t.sequence += map.sequence;
        t
    }));
    out.instances.extend(frame.instances.into_iter().map(|mut i| {
        i.surface = map.surfaces[i.surface as usize];
        i.lighting = map.lighting(i.lighting);
        i.camera = map.cameras[i.camera as usize];
        i.sequence += map.sequence;
        i
    }));
    out.solids.extend(frame.solids.into_iter().map(|mut s| {
        s.camera = map.cameras[s.camera as usize];
        s.sequence += map.sequence;
        s
    }));
    out.depth_clears.extend(frame.depth_clears.into_iter().map(|mut d| {
        d.before += map.sequence;
        d
    }));
    out.masked_clears.extend(frame.masked_clears.into_iter().map(|mut c| {
        c.before += map.sequence;
        c
    }));
    out.unsupported_draws += frame.unsupported_draws;
    out.passed_draws += frame.passed_draws;
}

/// The sequence number after the last draw of `frame`.
fn next_sequence(frame: &Frame) -> u32 {
    let triangles = frame.triangles.iter().map(|t| t.sequence);
    let instances = frame.instances.iter().map(|i| i.sequence);
    let solids = frame.solids.iter().map(|s| s.sequence);
    triangles.chain(instances).chain(solids).max().map_or(0, |s| s + 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Viewport;
    use crate::frame::View;
    use crate::surface::Surface;
    use crate::triangle::Triangle;
    use glam::{DMat4, Vec2, Vec3, Vec4};

    fn triangle(surface: u32, sequence: u32, x: f32) -> Triangle {
        Triangle {
            positions: [Vec3::new(x, 0.0, -1.0), Vec3::new(x + 1.0, 0.0, -1.0), Vec3::new(x, 1.0, -1.0)],
            colors: [Vec4::ONE; 3],
            secondary: [Vec3::ZERO; 3],
            texcoords: [Vec2::ZERO; 3],
            surface,
            sequence,
            camera: 0,
            clip_w: [1.0; 3],
            normals: [Vec3::Z; 3],
            base_colors: [Vec4::ONE; 3],
            lighting: NO_LIGHTING,
            back: false,
        }
    }

    fn frame(draws: &[(u32, f32)], surfaces: Vec<Surface>) -> Frame {
        let view = View { projection: DMat4::IDENTITY, viewport: Viewport { x: 0, y: 0, width: 8, height: 8 } };
        Frame {
            triangles: draws.iter().enumerate().map(|(k, &(s, x))| triangle(s, k as u32, x)).collect(),
            surfaces,
            cameras: vec![view],
            projection: Some(view.projection),
            viewport: Some(view.viewport),
            cleared: true,
            width: 8,
            height: 8,
            ..Frame::default()
        }
    }

    #[test]
    fn ranks_merged_are_one_process_drawing_it_all() {
        let plain = Surface::depth_tested();
        let unmasked = Surface { blend: None, depth_mask: false, ..Surface::depth_tested() };
        // One process: three draws, the last with another surface.
        let whole = frame(&[(0, 0.0), (0, 1.0), (1, 2.0)], vec![plain.clone(), unmasked.clone()]);
        // Two ranks: the first draw, then the other two.
        let a = frame(&[(0, 0.0)], vec![plain.clone()]);
        let b = frame(&[(0, 1.0), (1, 2.0)], vec![plain.clone(), unmasked.clone()]);
        assert_eq!(merge(vec![a, b]), whole);
        // Three ranks, one drawing nothing.
        let a = frame(&[(0, 0.0), (0, 1.0)], vec![plain.clone()]);
        let empty = Frame { triangles: vec![], surfaces: vec![], ..frame(&[], vec![]) };
        let c = frame(&[(0, 2.0)], vec![unmasked.clone()]);
        assert_eq!(merge(vec![a, empty, c]), whole);
        assert_eq!(merge(vec![]), Frame::default());
    }

    #[test]
    fn ranks_cameras_that_differ_by_rounding_are_one_camera() {
        let plain = Surface::depth_tested();
        let a = frame(&[(0, 0.0)], vec![plain.clone()]);
        let mut b = frame(&[(0, 1.0)], vec![plain.clone()]);
        // ParaView's two ranks: the clipping range's term in the last bits.
        let projection = |far_term: f64| {
            DMat4::from_cols(
                glam::DVec4::new(2.099278572745318, 8.4e-9, -3.9e-8, 1.7e-17),
                glam::DVec4::new(-9.4e-9, 3.732050827450177, -8.4e-9, 5.6e-17),
                glam::DVec4::new(1.96e-8, -6.6e-8, -1.648657181718899, -1.0),
                glam::DVec4::new(3.5e-6, -1.2e-5, far_term, 0.0),
            )
        };
        let (mine, theirs) = (projection(-201.69076835056603), projection(-201.6907837383195));
        b.cameras[0].projection = theirs;
        let mut a0 = a.clone();
        a0.cameras[0].projection = mine;
        let merged = merge(vec![a0.clone(), b.clone()]);
        assert_eq!(merged.cameras.len(), 1, "one camera");
        assert!(merged.triangles.iter().all(|t| t.camera == 0));
        assert_eq!(merged.cameras[0].projection, mine, "the first rank's");
        // A camera that really differs stays a camera of its own.
        b.cameras[0].projection = projection(-210.0);
        assert_eq!(merge(vec![a0, b.clone()]).cameras.len(), 2);
        b.cameras[0].projection = mine;
        b.cameras[0].viewport.width = 4;
        assert_eq!(merge(vec![a, b]).cameras.len(), 2, "another viewport");
    }
}
