//! The frame's triangles and a BVH over them. Built per frame (every triangle is already in eye
//! coordinates); obvhs's compressed-wide BVH with its closest-hit and all-hits traversals.

use std::time::Duration;

use glam::Vec3A;
use glray_capture::frame::Frame;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;

pub struct Scene {
    tris: Vec<Triangle>,
    bvh: Option<CwBvh>,
}

/// Ray-triangle intersection (Moller-Trumbore) that accepts hits a hair outside the edges:
/// a ray through a pixel centre that lies exactly on an edge two triangles share must hit one
/// of them, as GL's fill rule guarantees; a strict test can miss both and leave a crack.
fn intersect(tri: &Triangle, ray: &Ray) -> f32 {
    const EPS: f32 = 1e-6;
    let e1 = tri.v1 - tri.v0;
    let e2 = tri.v2 - tri.v0;
    let p = ray.direction.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return f32::INFINITY;
    }
    let inv = 1.0 / det;
    let s = ray.origin - tri.v0;
    let u = s.dot(p) * inv;
    if !(-EPS..=1.0 + EPS).contains(&u) {
        return f32::INFINITY;
    }
    let q = s.cross(e1);
    let v = ray.direction.dot(q) * inv;
    if v < -EPS || u + v > 1.0 + EPS {
        return f32::INFINITY;
    }
    let t = e2.dot(q) * inv;
    if t >= ray.tmin && t <= ray.tmax {
        t
    } else {
        f32::INFINITY
    }
}

/// A ray's hit: which of the frame's triangles, and where along the ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    pub triangle: usize,
    pub t: f32,
}

impl Scene {
    pub fn build(frame: &Frame) -> Scene {
        let tris: Vec<Triangle> = frame
            .triangles
            .iter()
            .map(|t| Triangle {
                v0: Vec3A::from(t.positions[0]),
                v1: Vec3A::from(t.positions[1]),
                v2: Vec3A::from(t.positions[2]),
            })
            .collect();
        let bvh = (!tris.is_empty())
            .then(|| build_cwbvh_from_tris(&tris, BvhBuildParams::fast_build(), &mut Duration::default()));
        Scene { tris, bvh }
    }

    /// The closest hit in [tmin, tmax].
    pub fn closest(&self, ray: Ray) -> Option<Hit> {
        let bvh = self.bvh.as_ref()?;
        let mut hit = RayHit::none();
        if bvh.ray_traverse(ray, &mut hit, |r, id| intersect(&self.tris[bvh.primitive_indices[id] as usize], r)) {
            Some(Hit { triangle: bvh.primitive_indices[hit.primitive_id as usize] as usize, t: hit.t })
        } else {
            None
        }
    }

    /// Every hit in [tmin, tmax], in no particular order.
    pub fn all(&self, ray: Ray, out: &mut Vec<Hit>) {
        out.clear();
        let Some(bvh) = self.bvh.as_ref() else { return };
        bvh.ray_traverse_anyhit(ray, |r, id| {
            let triangle = bvh.primitive_indices[id] as usize;
            let t = intersect(&self.tris[triangle], r);
            if t >= r.tmin && t <= r.tmax {
                out.push(Hit { triangle, t });
            }
        });
    }
}
