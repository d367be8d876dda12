//! The frame's geometry and its BVHs (triangles: `bvh::TriBvh`; instances and solids: obvhs's
//! CWBVH, few), in two levels:
//! - the triangles made this frame (immediate mode, array draws, lines and points), already in
//!   eye coordinates: one BVH, built per frame;
//! - display-list meshes: one BVH each, in object coordinates, built the first time a frame
//!   draws the mesh and kept while the mesh lives (`Meshes`), so that a list drawn every frame
//!   is built once; a top-level BVH over the frame's instances (their bounds in eye space),
//!   and rays taken into each instance's object space.

use std::collections::HashMap;
use std::sync::{Arc, Weak};
use std::time::Duration;

use glam::{Affine3A, DMat4, Mat3, Vec3, Vec3A};
use glray_capture::frame::{Frame, Solid, TriangleId};
use glray_capture::instance::Instance;
use glray_capture::mesh::Mesh;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::cwbvh::CwBvh;
pub use obvhs::ray::Ray;
use obvhs::ray::RayHit;
use obvhs::BvhBuildParams;
use rayon::prelude::*;

use crate::bvh::{TriBvh, TriHit};

/// Where a ray (unit direction) enters a capsule around the segment from `a` to `b` (a ball when
/// they meet), or infinity (Quilez's capsule test: the cylinder, then the cap it came in by).
fn capsule(s: &Solid, ray: &Ray) -> f32 {
    let (ro, rd) = (Vec3::from(ray.origin), Vec3::from(ray.direction));
    let r2 = s.radius * s.radius;
    let sphere = |c: Vec3| {
        let oc = ro - c;
        let b = rd.dot(oc);
        let h = b * b - (oc.dot(oc) - r2);
        if h < 0.0 {
            f32::INFINITY
        } else {
            -b - h.sqrt()
        }
    };
    let ba = s.b - s.a;
    let oa = ro - s.a;
    let baba = ba.dot(ba);
    let t = if baba == 0.0 {
        sphere(s.a)
    } else {
        let (bard, baoa) = (ba.dot(rd), ba.dot(oa));
        let a = baba - bard * bard;
        let b = baba * rd.dot(oa) - baoa * bard;
        let c = baba * oa.dot(oa) - baoa * baoa - r2 * baba;
        let h = b * b - a * c;
        if h < 0.0 || a == 0.0 {
            // Misses the infinite cylinder, or runs along the axis: only a cap can be met.
            sphere(if baoa <= 0.0 { s.a } else { s.b }).min(sphere(s.b)).min(sphere(s.a))
        } else {
            let t = (-b - h.sqrt()) / a;
            let y = baoa + t * bard;
            if y > 0.0 && y < baba {
                t
            } else {
                sphere(if y <= 0.0 { s.a } else { s.b })
            }
        }
    };
    if t >= ray.tmin && t <= ray.tmax {
        t
    } else {
        f32::INFINITY
    }
}

/// A ray's hit: which triangle, where along the ray, its draw's place in drawing order, and
/// its geometric normal (eye space, e1 x e2 of its corners in drawing order, not normalised).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    pub id: TriangleId,
    pub t: f32,
    pub sequence: u32,
    pub normal: Vec3,
}

/// A mesh's BVH (its leaves hold their triangles' corners: a leaf is read from one place
/// instead of gathered through the mesh's vertex indices).
pub struct MeshBvh {
    bvh: TriBvh,
}

impl MeshBvh {
    fn build(mesh: &Mesh) -> MeshBvh {
        MeshBvh { bvh: TriBvh::build(mesh.triangles.len(), |i| mesh.corners(i)) }
    }
}

/// The BVHs of display-list meshes, kept across frames for as long as a list holds the mesh.
#[derive(Default)]
pub struct Meshes {
    built: HashMap<u64, (Weak<Mesh>, Arc<MeshBvh>)>,
}

impl Meshes {
    /// The BVH of each of the frame's instances' meshes: built (in parallel) for meshes not
    /// seen before; those of meshes no list holds any more are dropped.
    fn prepare(&mut self, frame: &Frame) -> Vec<Arc<MeshBvh>> {
        self.prune();
        let mut new: Vec<&Arc<Mesh>> =
            frame.instances.iter().map(|i| &i.mesh).filter(|m| !self.built.contains_key(&m.id)).collect();
        new.sort_by_key(|m| m.id);
        new.dedup_by_key(|m| m.id);
        let bvhs: Vec<(u64, Weak<Mesh>, Arc<MeshBvh>)> =
            new.par_iter().map(|m| (m.id, Arc::downgrade(m), Arc::new(MeshBvh::build(m)))).collect();
        for (id, mesh, bvh) in bvhs {
            self.built.insert(id, (mesh, bvh));
        }
        frame.instances.iter().map(|i| self.built[&i.mesh.id].1.clone()).collect()
    }

    /// Drops the BVHs of meshes no list holds any more.
    pub fn prune(&mut self) {
        self.built.retain(|_, (mesh, _)| mesh.strong_count() > 0);
    }

    /// How many meshes have a BVH.
    pub fn len(&self) -> usize {
        self.built.len()
    }

    pub fn is_empty(&self) -> bool {
        self.built.is_empty()
    }
}

/// An instance ready to trace: its mesh's BVH and the way into its object space.
struct Placed<'f> {
    instance: &'f Instance,
    bvh: Arc<MeshBvh>,
    to_object: Affine3A,
    /// Takes an object-space e1 x e2 to the eye-space one: (M e1) x (M e2) = cof(M) (e1 x e2)
    /// for the modelview's linear part M (its cofactor matrix, so mirrors keep the winding).
    normal_to_eye: Mat3,
}

impl Placed<'_> {
    fn ray(&self, r: &Ray) -> Ray {
        // A linear map keeps the ray's parameter: t is the same in both spaces.
        let o = self.to_object.transform_point3a(r.origin);
        let d = self.to_object.transform_vector3a(r.direction);
        crate::bvh::ray(o, d, r.tmin, r.tmax)
    }

    /// A hit on the instance's mesh as a hit of the scene.
    fn hit(&self, k: usize, h: TriHit) -> Hit {
        let id = TriangleId { instance: k as u32, index: h.index };
        Hit { id, t: h.t, sequence: self.instance.sequence, normal: self.normal_to_eye * h.normal }
    }

    /// Whether a hit (with determinant `det`, see `bvh`) is on a face the instance draws: the
    /// geometric normal dotted with the object-space direction is -det.
    #[inline(always)]
    fn drawn(&self, det: f32) -> bool {
        self.instance.cull.is_none() || self.instance.keeps_seen(-det)
    }
}

pub struct Scene<'f> {
    frame: &'f Frame,
    bvh: TriBvh,
    placed: Vec<Placed<'f>>,
    /// The instances' eye-space boxes, and a BVH over them when there are many.
    boxes: Vec<Aabb>,
    top: Option<CwBvh>,
    /// Eye-space bounds of everything.
    bounds: Aabb,
    /// Lines and points as solids, for secondary rays, and their BVH.
    solids: &'f [Solid],
    solid_bvh: Option<CwBvh>,
    /// Some surface is drawn with blending or the alpha test: light may pass through it.
    translucent: bool,
}

/// Up to this many instances are tried one box after the other: cheaper than a top-level
/// traversal (a big mesh drawn once is the common case).
const FEW_INSTANCES: usize = 8;

impl<'f> Scene<'f> {
    pub fn build(frame: &'f Frame, meshes: &mut Meshes) -> Scene<'f> {
        let bvh = TriBvh::build(frame.triangles.len(), |i| frame.triangles[i].positions);
        let bvhs = meshes.prepare(frame);
        let placed: Vec<Placed> = frame
            .instances
            .iter()
            .zip(bvhs)
            .map(|(instance, bvh)| {
                let m = instance.modelview.as_mat4();
                let (a, b, c) = (m.x_axis.truncate(), m.y_axis.truncate(), m.z_axis.truncate());
                Placed {
                    instance,
                    bvh,
                    to_object: Affine3A::from_mat4(instance.modelview.inverse().as_mat4()),
                    normal_to_eye: Mat3::from_cols(b.cross(c), c.cross(a), a.cross(b)),
                }
            })
            .collect();
        let bounds: Vec<Aabb> = placed.iter().map(|p| eye_bounds(&p.instance.mesh, &p.instance.modelview)).collect();
        let top = (bounds.len() > FEW_INSTANCES)
            .then(|| build_cwbvh(&bounds, BvhBuildParams::fast_build(), &mut Duration::default()));
        let mut all = Aabb::INVALID;
        for t in &frame.triangles {
            for v in t.positions {
                all.extend(v.into());
            }
        }
        for b in &bounds {
            all.extend(b.min);
            all.extend(b.max);
        }
        let solid_boxes: Vec<Aabb> = frame
            .solids
            .iter()
            .map(|s| Aabb::new((s.a.min(s.b) - s.radius).into(), (s.a.max(s.b) + s.radius).into()))
            .collect();
        let solid_bvh = (!solid_boxes.is_empty())
            .then(|| build_cwbvh(&solid_boxes, BvhBuildParams::fast_build(), &mut Duration::default()));
        let translucent = frame.surfaces.iter().any(|s| s.blend.is_some() || s.alpha_test.is_some());
        Scene { frame, bvh, placed, boxes: bounds, top, bounds: all, solids: &frame.solids, solid_bvh, translucent }
    }

    /// Offers `visit` every instance whose box the ray meets (the top-level BVH's way when
    /// there are many). `visit` returns where it hit (infinity: nowhere); a hit shortens the
    /// ray for the instances after it; with `first`, the first hit ends the search. True if
    /// anything was hit.
    fn visit_instances(&self, ray: Ray, first: bool, mut visit: impl FnMut(&Ray, usize) -> f32) -> bool {
        match &self.top {
            Some(top) if first => !top.ray_traverse_miss(ray, |r, slot| visit(r, top.primitive_indices[slot] as usize)),
            Some(top) => {
                let mut hit = RayHit::none();
                top.ray_traverse(ray, &mut hit, |r, slot| visit(r, top.primitive_indices[slot] as usize))
            }
            None => {
                let mut r = ray;
                let mut any = false;
                for (k, b) in self.boxes.iter().enumerate() {
                    if b.intersect_ray(&r) == f32::INFINITY {
                        continue;
                    }
                    let t = visit(&r, k);
                    if t < r.tmax {
                        any = true;
                        if first {
                            break;
                        }
                        r.tmax = t;
                    }
                }
                any
            }
        }
    }

    /// The length of the eye-space diagonal of everything (0 for an empty scene).
    pub fn diagonal(&self) -> f32 {
        if self.bounds.min.x > self.bounds.max.x {
            return 0.0;
        }
        (self.bounds.max - self.bounds.min).length()
    }

    /// Whether anything lies along the ray in [tmin, tmax] (culled faces too: they are still
    /// there to cast shadows and occlude; lines and points as solids, but those of draw
    /// `own`, where the ray starts).
    #[inline]
    pub fn occluded(&self, ray: Ray, own: Option<u32>) -> bool {
        if self.solid_blocks(ray, own) {
            return true;
        }
        if self.bvh.occluded(&ray) {
            return true;
        }
        self.visit_instances(ray, true, |r, k| {
            let p = &self.placed[k];
            if p.bvh.bvh.occluded(&p.ray(r)) {
                r.tmin
            } else {
                f32::INFINITY
            }
        })
    }

    /// Whether a line or point solid lies along the ray (not those of draw `own`). Inlined:
    /// every shadow and AO ray asks, and most scenes have no solids.
    #[inline]
    fn solid_blocks(&self, ray: Ray, own: Option<u32>) -> bool {
        self.solid_bvh.as_ref().is_some_and(|bvh| {
            !bvh.ray_traverse_miss(ray, |r, slot| {
                let s = &self.solids[bvh.primitive_indices[slot] as usize];
                if Some(s.sequence) == own {
                    f32::INFINITY
                } else {
                    capsule(s, r)
                }
            })
        })
    }

    /// How much light gets through along the ray (a unit direction), from 0 to 1: opaque
    /// geometry blocks it; a surface drawn with blending lets 1 - alpha through (its colours'
    /// alpha where the ray crosses it), one with the alpha test all or nothing, as GL would
    /// draw that fragment. Solids of draw `own` do not count, as for `occluded`.
    #[inline]
    pub fn transmittance(&self, ray: Ray, own: Option<u32>) -> f32 {
        if !self.translucent {
            return if self.occluded(ray, own) { 0.0 } else { 1.0 };
        }
        if self.solid_blocks(ray, own) {
            return 0.0;
        }
        // Secondary rays are many: one buffer per thread for their hits.
        thread_local! {
            static HITS: std::cell::RefCell<Vec<Hit>> = const { std::cell::RefCell::new(Vec::new()) };
        }
        HITS.with_borrow_mut(|hits| {
            self.all(ray, hits);
            let mut through = 1.0f32;
            for &h in hits.iter() {
                let Some(t) = self.frame.triangle(h.id) else { continue };
                let s = &self.frame.surfaces[t.surface as usize];
                if s.blend.is_none() && s.alpha_test.is_none() {
                    return 0.0;
                }
                let p = Vec3::from(ray.origin) + Vec3::from(ray.direction) * h.t;
                let alpha = corner_weights(&t.positions, p).dot(Vec3::new(t.colors[0].w, t.colors[1].w, t.colors[2].w));
                let alpha = match s.alpha_test {
                    Some((func, reference)) if !crate::resolve::passes(func, alpha as f64, reference as f64) => 0.0,
                    Some(_) if s.blend.is_none() => 1.0,
                    _ => alpha.clamp(0.0, 1.0),
                };
                through *= 1.0 - alpha;
                if through <= 1e-3 {
                    return 0.0;
                }
            }
            through
        })
    }

    /// A hit on the eye-space triangles as a hit of the scene.
    fn flat(&self, h: TriHit) -> Hit {
        let id = TriangleId { instance: TriangleId::FLAT, index: h.index };
        Hit { id, t: h.t, sequence: self.sequence(id), normal: h.normal }
    }

    /// The closest hit in [tmin, tmax].
    pub fn closest(&self, ray: Ray) -> Option<Hit> {
        let mut ray = ray;
        let mut best = self.bvh.closest(&ray, |_, _| true).map(|h| self.flat(h));
        if let Some(h) = best {
            ray.tmax = h.t;
        }
        self.visit_instances(ray, false, |r, k| {
            let p = &self.placed[k];
            match p.bvh.bvh.closest(&p.ray(r), |_, det| p.drawn(det)) {
                Some(h) => {
                    best = Some(p.hit(k, h));
                    h.t
                }
                None => f32::INFINITY,
            }
        });
        best
    }

    /// The closest hits of `N` rays (a multiple of four; coherent ones: a block of camera rays),
    /// as `closest` finds each.
    pub fn closest_packet<const N: usize>(&self, rays: [Ray; N]) -> [Option<Hit>; N] {
        if self.top.is_some() {
            // Many instances: the top level is walked ray by ray.
            return rays.map(|r| self.closest(r));
        }
        let mut rays = rays;
        let keep = |best: &mut [Option<Hit>; N], rays: &mut [Ray; N], hits: [Option<Hit>; N]| {
            for (j, hit) in hits.into_iter().enumerate() {
                if let Some(h) = hit {
                    best[j] = Some(h);
                    rays[j].tmax = h.t;
                }
            }
        };
        let mut best = [None; N];
        let hits = self.bvh.closest_packet(&rays, |_, _| true);
        keep(&mut best, &mut rays, hits.map(|h| h.map(|h| self.flat(h))));
        for (k, b) in self.boxes.iter().enumerate() {
            if rays.iter().all(|r| b.intersect_ray(r) == f32::INFINITY) {
                continue;
            }
            let p = &self.placed[k];
            let hits = p.bvh.bvh.closest_packet(&rays.map(|r| p.ray(&r)), |_, det| p.drawn(det));
            keep(&mut best, &mut rays, hits.map(|h| h.map(|h| p.hit(k, h))));
        }
        best
    }

    /// Every hit in [tmin, tmax], in no particular order.
    pub fn all(&self, ray: Ray, out: &mut Vec<Hit>) {
        out.clear();
        self.bvh.each_hit(&ray, |h, _| out.push(self.flat(h)));
        self.visit_instances(ray, false, |r, k| {
            let p = &self.placed[k];
            p.bvh.bvh.each_hit(&p.ray(r), |h, det| {
                if p.drawn(det) {
                    out.push(p.hit(k, h));
                }
            });
            f32::INFINITY
        });
    }

    fn sequence(&self, id: TriangleId) -> u32 {
        if id.instance == TriangleId::FLAT {
            self.frame.triangles[id.index as usize].sequence
        } else {
            self.placed[id.instance as usize].instance.sequence
        }
    }
}

/// Barycentric weights of `p` (in the triangle's plane) for its corners.
fn corner_weights(c: &[Vec3; 3], p: Vec3) -> Vec3 {
    let (e1, e2, d) = (c[1] - c[0], c[2] - c[0], p - c[0]);
    let (d11, d12, d22, d1, d2) = (e1.dot(e1), e1.dot(e2), e2.dot(e2), d.dot(e1), d.dot(e2));
    let det = d11 * d22 - d12 * d12;
    if det == 0.0 {
        return Vec3::splat(1.0 / 3.0);
    }
    let v = (d22 * d1 - d12 * d2) / det;
    let w = (d11 * d2 - d12 * d1) / det;
    Vec3::new(1.0 - v - w, v, w)
}

/// The eye-space box around a mesh drawn with `modelview`.
fn eye_bounds(mesh: &Mesh, modelview: &DMat4) -> Aabb {
    let (lo, hi) = (mesh.min.as_dvec3(), mesh.max.as_dvec3());
    let mut b = Aabb::INVALID;
    for k in 0..8 {
        let c = glam::DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        b.extend(Vec3A::from(modelview.transform_point3(c).as_vec3()));
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ray(o: [f32; 3], d: [f32; 3]) -> Ray {
        Ray::new(Vec3A::from_array(o), Vec3::from_array(d).normalize().into(), 0.0, f32::INFINITY)
    }

    #[test]
    fn capsules_are_met_on_their_side_and_caps_and_balls_all_round() {
        let s =
            Solid { a: Vec3::new(-1.0, 0.0, 0.0), b: Vec3::new(1.0, 0.0, 0.0), radius: 0.5, sequence: 0, camera: 0 };
        // The side, from above.
        assert!((capsule(&s, &ray([0.0, 5.0, 0.0], [0.0, -1.0, 0.0])) - 4.5).abs() < 1e-5);
        // A cap, along the axis.
        assert!((capsule(&s, &ray([5.0, 0.0, 0.0], [-1.0, 0.0, 0.0])) - 3.5).abs() < 1e-5);
        // Past the end, the rounded cap: at x = 1.3 it is sqrt(0.25 - 0.09) = 0.4 high.
        assert!((capsule(&s, &ray([1.3, 5.0, 0.0], [0.0, -1.0, 0.0])) - 4.6).abs() < 1e-5);
        assert_eq!(capsule(&s, &ray([1.6, 5.0, 0.0], [0.0, -1.0, 0.0])), f32::INFINITY, "beyond the cap");
        assert_eq!(capsule(&s, &ray([0.0, 5.0, 0.0], [0.0, 1.0, 0.0])), f32::INFINITY, "pointing away");
        let ball = Solid { b: s.a, ..s };
        assert!((capsule(&ball, &ray([-1.0, 0.0, 3.0], [0.0, 0.0, -1.0])) - 2.5).abs() < 1e-5);
        let short = Ray { tmax: 2.0, ..ray([-1.0, 0.0, 3.0], [0.0, 0.0, -1.0]) };
        assert_eq!(capsule(&ball, &short), f32::INFINITY, "beyond the ray's reach");
    }

    /// A scene of one triangle drawn with `modelview`, as an instance of a mesh.
    fn one_instance(modelview: DMat4) -> (Frame, [Vec3; 3]) {
        let corners = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
        let mesh = Mesh::indexed(corners.to_vec(), vec![Vec3::Z; 3], vec![[0, 1, 2]]).unwrap();
        let instance = Instance::new(Arc::new(mesh), modelview, DMat4::IDENTITY);
        let eye = corners.map(|c| modelview.transform_point3(c.as_dvec3()).as_vec3());
        (Frame { instances: vec![instance], ..Frame::default() }, eye)
    }

    #[test]
    fn hits_carry_the_eye_space_normal_of_their_triangle_in_its_winding() {
        use glam::DVec3;
        // Moved, scaled unevenly, rotated, and mirrored (the winding turns with the mirror).
        let modelviews = [
            DMat4::from_translation(DVec3::new(0.0, 0.0, -5.0)),
            DMat4::from_translation(DVec3::new(0.5, -0.2, -4.0))
                * DMat4::from_rotation_y(0.4)
                * DMat4::from_scale(DVec3::new(3.0, 0.5, 2.0)),
            DMat4::from_translation(DVec3::new(0.0, 0.0, -3.0)) * DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0)),
        ];
        for m in modelviews {
            let (frame, [a, b, c]) = one_instance(m);
            let expected = (b - a).cross(c - a);
            let scene = Scene::build(&frame, &mut Meshes::default());
            let centre = (a + b + c) / 3.0;
            let r = ray([0.0, 0.0, 0.0], centre.to_array());
            let hit = scene.closest(r).expect("the ray through the triangle's centre hits it");
            assert!(
                hit.normal.normalize().abs_diff_eq(expected.normalize(), 1e-5),
                "{m}: {} vs {expected}",
                hit.normal
            );
            let four = scene.closest_packet([r; 4]);
            assert!(four.iter().all(|h| *h == Some(hit)));
            let eight = scene.closest_packet([r; 8]);
            assert!(eight.iter().all(|h| *h == Some(hit)));
            let mut all = Vec::new();
            scene.all(r, &mut all);
            assert_eq!(all, [hit]);
        }
    }
}
