//! The frame's geometry and its BVHs (triangles: `bvh::TriBvh`; instances and solids: obvhs's
//! CWBVH, few), in two levels:
//! - the triangles made this frame (immediate mode, array draws, lines and points), already in
//!   eye coordinates: one BVH, built per frame;
//! - display-list meshes: one BVH each, in object coordinates, built the first time a frame
//!   draws the mesh and kept while the mesh lives (`Meshes`), so that a list drawn every frame
//!   is built once; a top-level BVH over the frame's instances (their bounds in eye space),
//!   and rays taken into each instance's object space;
//! - paged meshes (`distribute = paged`): in place of a mesh's BVH, a tree over its blocks'
//!   boxes, each block's own tree had from the pager when a ray reaches it (`paged`).

use std::sync::Arc;
use std::time::Duration;

use glam::{Affine3A, DMat4, Mat3, Vec2, Vec3, Vec3A};
use glray_scene::frame::{Frame, Solid, TriangleId};
use glray_scene::instance::Instance;
use glray_scene::mesh::Mesh;
use glray_scene::triangle::Triangle;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::cwbvh::CwBvh;
pub use obvhs::ray::Ray;
use obvhs::BvhBuildParams;

use crate::bvh::{Quality, TriBvh, TriHit, BUNDLE};
use crate::meshes::{MeshBvh, Meshes};
use crate::offset::{leaving, Origin};
use crate::options::BvhBuild;
use crate::paged::{Block, PagedMesh, Pager};
use crate::sampling::Hemisphere;
use crate::top::Top;

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

/// A ray's hit: which triangle, where along the ray, its draw's place in drawing order, its
/// geometric normal (eye space, e1 x e2 of its corners in drawing order, not normalised), and
/// the barycentric weights there of its second and third corners (see `TriHit`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    pub id: TriangleId,
    pub t: f32,
    pub sequence: u32,
    pub normal: Vec3,
    pub uv: Vec2,
}

/// What an instance's rays walk: its mesh's BVH, or the blocks of a paged mesh.
enum Tree {
    Whole(Arc<MeshBvh>),
    Paged(PagedMesh),
}

impl Tree {
    #[inline]
    fn closest(&self, ray: &Ray, accept: impl FnMut(u32, f32) -> bool) -> Option<TriHit> {
        match self {
            Tree::Whole(m) => m.bvh.closest(ray, accept),
            Tree::Paged(p) => p.closest(ray, accept),
        }
    }

    #[inline]
    fn occluded(&self, ray: &Ray) -> bool {
        match self {
            Tree::Whole(m) => m.bvh.occluded(ray),
            Tree::Paged(p) => p.occluded(ray),
        }
    }

    #[inline]
    fn each_hit(&self, ray: &Ray, visit: impl FnMut(TriHit, f32)) {
        match self {
            Tree::Whole(m) => m.bvh.each_hit(ray, visit),
            Tree::Paged(p) => p.each_hit(ray, visit),
        }
    }

    #[inline]
    fn closest_packet<const N: usize>(
        &self,
        rays: &[Ray; N],
        best: &mut [Option<TriHit>; N],
        frustum: bool,
        accept: impl FnMut(u32, f32) -> bool,
    ) {
        match self {
            Tree::Whole(m) => m.bvh.closest_packet(rays, best, frustum, accept),
            Tree::Paged(p) => p.closest_packet(rays, best, accept),
        }
    }

    #[inline]
    fn occluded_from(&self, origin: Vec3A, directions: &[Vec3A; BUNDLE], tmax: f32, known: u32) -> u32 {
        match self {
            Tree::Whole(m) => m.bvh.occluded_from(origin, directions, tmax, known),
            Tree::Paged(p) => p.occluded_from(origin, directions, tmax, known),
        }
    }
}

/// The mesh a hit's triangle is in, and its index there: the instance's mesh, or the block of
/// a paged mesh that holds it.
pub enum Part<'f> {
    Whole(&'f Mesh, usize),
    Block(Arc<Block>, usize),
}

impl Part<'_> {
    pub fn mesh(&self) -> &Mesh {
        match self {
            Part::Whole(m, _) => m,
            Part::Block(b, _) => &b.mesh,
        }
    }

    pub fn index(&self) -> usize {
        match self {
            Part::Whole(_, i) | Part::Block(_, i) => *i,
        }
    }
}

/// An instance ready to trace: its mesh's BVH and the way into its object space.
struct Placed<'f> {
    instance: &'f Instance,
    tree: Tree,
    to_object: Affine3A,
    /// Whether its mesh's packets test a node once for all their rays (see `FINE`).
    frustum: bool,
    /// Takes an object-space e1 x e2 to the eye-space one: (M e1) x (M e2) = cof(M) (e1 x e2)
    /// for the modelview's linear part M (its cofactor matrix, so mirrors keep the winding).
    normal_to_eye: Mat3,
}

impl Placed<'_> {
    #[inline]
    fn ray(&self, r: &Ray) -> Ray {
        // A linear map keeps the ray's parameter: t is the same in both spaces.
        let o = self.to_object.transform_point3a(r.origin);
        let d = self.to_object.transform_vector3a(r.direction);
        crate::bvh::ray(o, d, r.tmin, r.tmax)
    }

    /// A hit on the instance's mesh as a hit of the scene.
    #[inline]
    fn hit(&self, k: usize, h: TriHit) -> Hit {
        let id = TriangleId { instance: k as u32, index: h.index };
        Hit { id, t: h.t, sequence: self.instance.sequence, normal: self.normal_to_eye * h.normal, uv: h.uv }
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
    /// How many meshes' BVHs were built for it (new meshes', and kept ones' built again by SAH;
    /// not the frame's own triangles', built every frame), how many of the scene's BVHs were
    /// built fast (`bvh_choice`), and how many meshes' trees were refitted rather than built
    /// (`Meshes`).
    pub builds: u32,
    pub fast_builds: u32,
    pub refits: u32,
    /// Whether the frame's own triangles' packets test a node once for all their rays (as
    /// `Placed::frustum` for a mesh).
    frustum: bool,
    placed: Vec<Placed<'f>>,
    /// The instances' eye-space boxes, and a BVH over them when there are many.
    top: Top,
    /// Eye-space bounds of everything.
    bounds: Aabb,
    /// Lines and points as solids, for secondary rays, and their BVH.
    solids: &'f [Solid],
    solid_bvh: Option<CwBvh>,
    /// The draws of lines and points (those the solids come from), sorted.
    line_draws: Vec<u32>,
    /// Some surface is drawn with blending or the alpha test: light may pass through it.
    translucent: bool,
}

/// A mesh of more triangles than this per pixel of the frame walks its packets ray by ray,
/// without the frustum test (`TriBvh::closest_packet`): its triangles are mostly smaller than
/// the pixels between a packet's rays, and the packet's bounds meet many leaves its rays pass
/// by. 10M triangles at 1280x720 (11 a pixel): camera rays 2% and the GL-look frame 5%
/// slower with the frustum; 1M (1.1 a pixel): camera rays 0-12% faster.
const FINE: u64 = 4;

/// Whether a mesh of `triangles` is coarse enough for the frustum test in `frame`.
fn coarse(triangles: usize, frame: &Frame) -> bool {
    let (w, h) = frame.size();
    triangles as u64 <= FINE * (w as u64 * h as u64).max(1)
}

impl<'f> Scene<'f> {
    /// The scene of `frame`, its trees built as `choice` says for a frame tracing `ray_work`
    /// rays (`bvh_choice`); the frame's own triangles' tree is built again next frame.
    pub fn build(frame: &'f Frame, meshes: &mut Meshes, choice: BvhBuild, ray_work: f64) -> Scene<'f> {
        Scene::build_paged(frame, meshes, choice, ray_work, None)
    }

    /// `build`, the meshes `pager` has layouts for walked as paged meshes.
    pub fn build_paged(
        frame: &'f Frame,
        meshes: &mut Meshes,
        choice: BvhBuild,
        ray_work: f64,
        pager: Option<&Arc<dyn Pager>>,
    ) -> Scene<'f> {
        let quality = choice.quality(frame.triangles.len(), true, ray_work);
        let bvh = TriBvh::build_as(frame.triangles.len(), |i| frame.triangles[i].positions, quality);
        let layout = |m: &Mesh| pager.and_then(|p| p.layout(m.id));
        let (bvhs, made) = meshes.prepare(frame, choice, ray_work, |m| layout(m).is_some());
        let fast_builds = made.fast_builds + u32::from(quality == Quality::Fast && !frame.triangles.is_empty());
        let placed: Vec<Placed> = frame
            .instances
            .iter()
            .zip(bvhs)
            .map(|(instance, bvh)| {
                let m = instance.modelview.as_mat4();
                let (a, b, c) = (m.x_axis.truncate(), m.y_axis.truncate(), m.z_axis.truncate());
                let (tree, triangles) = match (bvh, layout(&instance.mesh), pager) {
                    (Some(bvh), _, _) => (Tree::Whole(bvh), instance.mesh.triangles.len()),
                    (None, Some(layout), Some(pager)) => {
                        let n = layout.triangles() as usize;
                        (Tree::Paged(PagedMesh { layout, pager: pager.clone() }), n)
                    }
                    _ => unreachable!("a mesh without a tree is paged"),
                };
                Placed {
                    instance,
                    frustum: coarse(triangles, frame),
                    tree,
                    to_object: Affine3A::from_mat4(instance.modelview.inverse().as_mat4()),
                    normal_to_eye: Mat3::from_cols(b.cross(c), c.cross(a), a.cross(b)),
                }
            })
            .collect();
        let bounds: Vec<Aabb> = placed.iter().map(|p| eye_bounds(&p.instance.mesh, &p.instance.modelview)).collect();
        let mut all = placed_bounds(frame);
        for t in &frame.triangles {
            for v in t.positions {
                all.extend(v.into());
            }
        }
        let solid_boxes: Vec<Aabb> = frame
            .solids
            .iter()
            .map(|s| Aabb::new((s.a.min(s.b) - s.radius).into(), (s.a.max(s.b) + s.radius).into()))
            .collect();
        let solid_bvh = (!solid_boxes.is_empty())
            .then(|| build_cwbvh(&solid_boxes, BvhBuildParams::fast_build(), &mut Duration::default()));
        let translucent = frame.surfaces.iter().any(|s| s.blend.is_some() || s.alpha_test.is_some());
        let frustum = coarse(frame.triangles.len(), frame);
        Scene {
            frame,
            bvh,
            builds: made.builds,
            fast_builds,
            refits: made.refits,
            frustum,
            placed,
            top: Top::new(bounds),
            bounds: all,
            solids: &frame.solids,
            solid_bvh,
            line_draws: line_draws(frame),
            translucent,
        }
    }

    /// The frame it is the scene of.
    pub fn frame(&self) -> &'f Frame {
        self.frame
    }

    /// Whether draw `sequence` drew lines or points (as quads, with solids).
    pub fn is_line(&self, sequence: u32) -> bool {
        self.line_draws.binary_search(&sequence).is_ok()
    }

    /// Offers `visit` every instance whose box the ray meets (`Top::visit`).
    fn visit_instances(&self, ray: Ray, first: bool, visit: impl FnMut(&Ray, usize) -> f32) -> bool {
        self.top.visit(ray, first, visit)
    }

    /// The length of the eye-space diagonal of everything (0 for an empty scene).
    pub fn diagonal(&self) -> f32 {
        if self.bounds.min.x > self.bounds.max.x {
            return 0.0;
        }
        (self.bounds.max - self.bounds.min).length()
    }

    /// Whether anything lies along the ray in [tmin, tmax] (culled faces too: they are still
    /// there to cast shadows and occlude). Lines and points block as their solids, but those
    /// of draw `own`, where the ray starts; with `own` None (AO rays), not at all: a line is
    /// drawn on what it lies on and shows its AO (`Tracer::beneath`), it does not shade it.
    #[inline]
    pub fn occluded(&self, ray: Ray, own: Option<u32>) -> bool {
        if self.solid_blocks(ray, own) {
            return true;
        }
        if !self.line_draws.is_empty() {
            // Lines and points occlude as their solids: their quads face the camera, a ribbon
            // a pixel wide that would shade what they are drawn on.
            return HITS.with_borrow_mut(|hits| {
                self.all(ray, hits);
                hits.iter().any(|h| !self.is_line(h.sequence))
            });
        }
        if self.bvh.occluded(&ray) {
            return true;
        }
        self.visit_instances(ray, true, |r, k| {
            let p = &self.placed[k];
            if p.tree.occluded(&p.ray(r)) {
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
        own.is_some()
            && self.solid_bvh.as_ref().is_some_and(|bvh| {
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

    /// How much of `count` rays from `at` the scene hides (the sum of 1 - `transmittance` over
    /// them): ray k leaves along `around.at(local())`, its k-th local direction (on the side of
    /// the surface `at.n` faces), and reaches `distance`. Ambient occlusion's many short rays
    /// from one point: in a scene of opaque triangles and few instances, which instances lie
    /// within reach, where the point is in each one's object space and the hemisphere's basis
    /// there are worked out once for all the rays, instead of a box test and a change of space
    /// per ray and instance (a fifth of an AO ray's instructions outside the walk).
    pub fn hidden(
        &self,
        at: &Origin,
        around: &Hemisphere,
        count: u32,
        distance: f32,
        eps: f32,
        mut local: impl FnMut() -> Vec3,
    ) -> f32 {
        if self.translucent || !self.line_draws.is_empty() || self.top.tree.is_some() {
            return (0..count)
                .map(|_| {
                    let ray = leaving(at.p, at.n, around.at(local()), eps, distance);
                    1.0 - self.transmittance(ray, None)
                })
                .sum();
        }
        // Every direction is on the side the normal faces: the rays all start there.
        let start = Vec3A::from(at.p + at.n * eps);
        // (Directions are unit to within rounding: a thousandth more covers where any ends.)
        let reach = Aabb::new(start - distance * 1.001, start + distance * 1.001);
        let mut near = [(0, Vec3A::ZERO, *around); crate::top::FEW];
        let mut n = 0;
        for (k, b) in self.top.boxes.iter().enumerate() {
            if b.intersect_aabb(&reach) {
                let to_object = &self.placed[k].to_object;
                near[n] = (k, to_object.transform_point3a(start), around.mapped(to_object));
                n += 1;
            }
        }
        let flat = !self.bvh.is_empty();
        let mut hidden = 0;
        // `BUNDLE` (sixteen) rays at a time through each tree together (`TriBvh::occluded_from`:
        // the same answers as ray by ray); the rest one by one.
        let mut left = count;
        while left >= BUNDLE as u32 {
            let dirs: [Vec3; BUNDLE] = std::array::from_fn(|_| local());
            let along = |h: &Hemisphere| dirs.map(|l| Vec3A::from(h.at(l)));
            let mut blocked = if flat { self.bvh.occluded_from(start, &along(around), distance, 0) } else { 0 };
            for (k, o, h) in &near[..n] {
                blocked = self.placed[*k].tree.occluded_from(*o, &along(h), distance, blocked);
            }
            hidden += blocked.count_ones();
            left -= BUNDLE as u32;
        }
        for _ in 0..left {
            let l = local();
            let ray = |o: Vec3A, h: &Hemisphere| crate::bvh::ray(o, h.at(l).into(), 0.0, distance);
            let blocked = (flat && self.bvh.occluded(&ray(start, around)))
                || near[..n].iter().any(|(k, o, h)| self.placed[*k].tree.occluded(&ray(*o, h)));
            hidden += blocked as u32;
        }
        hidden as f32
    }

    /// How much light gets through along the ray (a unit direction), from 0 to 1: opaque
    /// geometry blocks it; a surface drawn with blending lets 1 - alpha through (its colours'
    /// alpha where the ray crosses it), one with the alpha test all or nothing, as GL would
    /// draw that fragment. Lines and points count as `occluded` says (`own`).
    #[inline]
    pub fn transmittance(&self, ray: Ray, own: Option<u32>) -> f32 {
        if !self.translucent {
            return if self.occluded(ray, own) { 0.0 } else { 1.0 };
        }
        if self.solid_blocks(ray, own) {
            return 0.0;
        }
        HITS.with_borrow_mut(|hits| {
            self.all(ray, hits);
            let mut through = 1.0f32;
            for &h in hits.iter().filter(|h| !self.is_line(h.sequence)) {
                let Some(t) = self.triangle(h.id) else { continue };
                let s = &self.frame.surfaces[t.surface as usize];
                if s.blend.is_none() && s.alpha_test.is_none() {
                    return 0.0;
                }
                let p = Vec3::from(ray.origin) + Vec3::from(ray.direction) * h.t;
                let alpha = corner_weights(&t.positions, p).dot(Vec3::new(t.colors[0].w, t.colors[1].w, t.colors[2].w));
                let alpha = match s.alpha_test {
                    Some((func, reference)) if !func.passes(alpha as f64, reference as f64) => 0.0,
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
        Hit { id, t: h.t, sequence: self.sequence(id), normal: h.normal, uv: h.uv }
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
            match p.tree.closest(&p.ray(r), |_, det| p.drawn(det)) {
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
    /// as `closest` finds each, into `best`.
    pub fn closest_packet<const N: usize>(&self, rays: &[Ray; N], best: &mut [Option<Hit>; N]) {
        if self.top.tree.is_some() {
            // Many instances: the top level is walked ray by ray.
            for (b, r) in best.iter_mut().zip(rays) {
                *b = self.closest(*r);
            }
            return;
        }
        let mut found = [None; N];
        self.bvh.closest_packet(rays, &mut found, self.frustum, |_, _| true);
        for (b, h) in best.iter_mut().zip(&found) {
            *b = h.map(|h| self.flat(h));
        }
        // Each ray as far as its closest hit so far: an instance whose box every ray misses
        // or enters beyond that is passed by.
        let reach = |best: &[Option<Hit>; N], j: usize| best[j].map_or(rays[j].tmax, |h| h.t);
        for (k, b) in self.top.boxes.iter().enumerate() {
            if (0..N).all(|j| b.intersect_ray(&rays[j]) > reach(best, j)) {
                continue;
            }
            let p = &self.placed[k];
            let object = std::array::from_fn(|j| p.ray(&Ray { tmax: reach(best, j), ..rays[j] }));
            p.tree.closest_packet(&object, &mut found, p.frustum, |_, det| p.drawn(det));
            for (b, h) in best.iter_mut().zip(&found) {
                if let Some(h) = h {
                    *b = Some(p.hit(k, *h));
                }
            }
        }
    }

    /// Every hit in [tmin, tmax], in no particular order.
    pub fn all(&self, ray: Ray, out: &mut Vec<Hit>) {
        out.clear();
        self.bvh.each_hit(&ray, |h, _| out.push(self.flat(h)));
        self.visit_instances(ray, false, |r, k| {
            let p = &self.placed[k];
            p.tree.each_hit(&p.ray(r), |h, det| {
                if p.drawn(det) {
                    out.push(p.hit(k, h));
                }
            });
            f32::INFINITY
        });
    }

    /// The mesh triangle `id` of an instance is in, and its index there (None for the frame's
    /// own triangles, and for a block that could not be had).
    pub fn part(&self, id: TriangleId) -> Option<Part<'_>> {
        let p = self.placed.get(id.instance as usize)?;
        match &p.tree {
            Tree::Whole(_) => Some(Part::Whole(&p.instance.mesh, id.index as usize)),
            Tree::Paged(paged) => {
                let (b, local) = paged.layout.locate(id.index)?;
                Some(Part::Block(paged.pager.block(paged.layout.blocks[b].key)?, local as usize))
            }
        }
    }

    /// Whether instance `instance`'s mesh is paged.
    pub fn is_paged(&self, instance: u32) -> bool {
        self.placed.get(instance as usize).is_some_and(|p| matches!(p.tree, Tree::Paged(_)))
    }

    /// `Frame::triangle`, a paged mesh's triangles taken from their blocks.
    #[inline]
    pub fn triangle(&self, id: TriangleId) -> Option<Triangle> {
        if id.instance == TriangleId::FLAT || !self.is_paged(id.instance) {
            return self.frame.triangle(id);
        }
        let instance = &self.frame.instances[id.instance as usize];
        let textured = self.frame.surfaces.get(instance.surface as usize).is_none_or(|s| s.texturing.is_some());
        let part = self.part(id)?;
        instance.triangle_of(part.mesh(), part.index(), &self.frame.lightings, textured)
    }

    /// `Frame::prefetch_triangle` (nothing for a paged mesh's: its block is looked up anyway).
    #[inline]
    pub fn prefetch_triangle(&self, id: TriangleId, vertices: bool, positions: bool) {
        if id.instance == TriangleId::FLAT || !self.is_paged(id.instance) {
            self.frame.prefetch_triangle(id, vertices, positions);
        }
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
    object_box_in_eye_space(mesh.min.as_dvec3(), mesh.max.as_dvec3(), modelview)
}

/// The eye-space bounds of `frame`'s instances as the scene's size takes them (the reach of
/// AO, the offset of secondary rays: shares of the diagonal): the object-space boxes of the
/// instances drawn under one transform joined first, then turned into eye space. A dataset
/// drawn in pieces under one transform (a data-parallel program's ranks, each drawing its
/// piece) then has the size it has drawn whole, bit for bit: the turned box of each piece is
/// larger than its piece, and their union was not the whole's (one mesh's AO reach was 0.4%
/// of a picture away from the same mesh's split over two ranks).
fn placed_bounds(frame: &Frame) -> Aabb {
    // (Minima and maxima: the same whatever order the boxes come in.)
    let mut joined: std::collections::HashMap<[u64; 16], (glam::DVec3, glam::DVec3)> = Default::default();
    for i in &frame.instances {
        let key = i.modelview.to_cols_array().map(f64::to_bits);
        let (lo, hi) = (i.mesh.min.as_dvec3(), i.mesh.max.as_dvec3());
        let b = joined.entry(key).or_insert((lo, hi));
        *b = (b.0.min(lo), b.1.max(hi));
    }
    let mut all = Aabb::INVALID;
    for (key, (lo, hi)) in joined {
        let b = object_box_in_eye_space(lo, hi, &DMat4::from_cols_array(&key.map(f64::from_bits)));
        all.extend(b.min);
        all.extend(b.max);
    }
    all
}

/// The eye-space box around the object-space box `lo`..`hi` placed by `modelview`.
fn object_box_in_eye_space(lo: glam::DVec3, hi: glam::DVec3, modelview: &DMat4) -> Aabb {
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

// Secondary rays are many: one buffer per thread for the hits of those that need them all.
thread_local! {
    static HITS: std::cell::RefCell<Vec<Hit>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// The draws of `frame` that drew lines or points (those its solids come from), sorted.
fn line_draws(frame: &Frame) -> Vec<u32> {
    let mut draws: Vec<u32> = frame.solids.iter().map(|s| s.sequence).collect();
    draws.sort_unstable();
    draws.dedup();
    draws
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ray(o: [f32; 3], d: [f32; 3]) -> Ray {
        Ray::new(Vec3A::from_array(o), Vec3::from_array(d).normalize().into(), 0.0, f32::INFINITY)
    }

    #[test]
    fn meshes_of_more_than_fine_triangles_a_pixel_walk_packets_ray_by_ray() {
        let frame = Frame { width: 1280, height: 720, ..Frame::default() };
        assert!(coarse(1_000_000, &frame), "1M triangles at 1280x720");
        assert!(!coarse(10_000_000, &frame), "10M triangles at 1280x720");
        assert!(coarse(4 * 1280 * 720, &frame) && !coarse(4 * 1280 * 720 + 1, &frame));
        // A frame without a size yet: only tiny meshes count as coarse.
        assert!(!coarse(5, &Frame::default()));
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
    fn a_mesh_drawn_in_pieces_under_one_transform_has_the_size_it_has_whole() {
        use glam::DVec3;
        // A strip of triangles along a diagonal, turned: its pieces' turned boxes are each
        // larger than the piece, and their union was smaller than the whole's turned box.
        let strip = |from: usize, to: usize| {
            let mut corners = Vec::new();
            let mut triangles = Vec::new();
            for k in from..to {
                let (x, y) = (k as f32, 0.7 * k as f32);
                let base = corners.len() as u32;
                corners.extend([Vec3::new(x, y, 0.0), Vec3::new(x + 1.0, y, 0.3), Vec3::new(x, y + 1.0, -0.2)]);
                triangles.push([base, base + 1, base + 2]);
            }
            let n = corners.len();
            Arc::new(Mesh::indexed(corners, vec![Vec3::Z; n], triangles).unwrap())
        };
        let place = DMat4::from_translation(DVec3::new(0.5, -1.0, -9.0))
            * DMat4::from_rotation_z(0.7)
            * DMat4::from_rotation_x(0.4);
        let frame = |meshes: Vec<Arc<Mesh>>| Frame {
            instances: meshes.into_iter().map(|m| Instance::new(m, place, DMat4::IDENTITY)).collect(),
            ..Frame::default()
        };
        let size = |f: &Frame| Scene::build(f, &mut Meshes::default(), BvhBuild::Sah, 0.0).diagonal();
        let whole = size(&frame(vec![strip(0, 8)]));
        assert!(whole > 10.0, "{whole}");
        assert_eq!(size(&frame(vec![strip(0, 3), strip(3, 8)])), whole, "two pieces");
        assert_eq!(size(&frame(vec![strip(5, 8), strip(0, 2), strip(2, 5)])), whole, "three, in another order");
        // The pieces' own turned boxes, joined, are not the whole's: what the size was.
        let mut pieces = Aabb::INVALID;
        for m in [strip(0, 3), strip(3, 8)] {
            let b = eye_bounds(&m, &place);
            (pieces.min, pieces.max) = (pieces.min.min(b.min), pieces.max.max(b.max));
        }
        assert!(((pieces.max - pieces.min).length() - whole).abs() > 0.01 * whole);
    }

    #[test]
    fn ambient_occlusion_from_one_point_counts_what_its_rays_one_by_one_count() {
        use crate::sampling::{cosine_local, Sampler};
        use glam::DVec3;
        // A floor and a wall, each a square of two triangles drawn as an instance: the floor
        // scaled unevenly and turned, the wall mirrored, so that the hemispheres taken into
        // their object spaces are neither unit nor orthogonal.
        let square = |lo: Vec3, u: Vec3, v: Vec3| {
            let corners = vec![lo, lo + u, lo + u + v, lo + v];
            Arc::new(Mesh::indexed(corners, vec![u.cross(v).normalize(); 4], vec![[0, 1, 2], [0, 2, 3]]).unwrap())
        };
        let floor = Instance::new(
            square(Vec3::new(-1.0, 0.0, -1.0), Vec3::X * 2.0, Vec3::Z * 2.0),
            DMat4::from_translation(DVec3::new(0.0, -1.0, -5.0))
                * DMat4::from_rotation_y(0.3)
                * DMat4::from_scale(DVec3::new(2.0, 1.0, 0.5)),
            DMat4::IDENTITY,
        );
        let wall = Instance::new(
            square(Vec3::new(0.0, 0.0, 0.0), Vec3::X * 2.0, Vec3::Y * 2.0),
            DMat4::from_translation(DVec3::new(0.0, -1.0, -5.5))
                * DMat4::from_rotation_y(0.4)
                * DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.5)),
            DMat4::IDENTITY,
        );
        let frame = Frame { instances: vec![floor, wall], ..Frame::default() };
        let scene = Scene::build(&frame, &mut Meshes::default(), BvhBuild::Sah, 0.0);
        let (distance, eps) = (1.5, 1e-4);
        let (mut fast, mut one_by_one, mut some, mut differ) = (0.0, 0.0, 0, 0);
        for k in 0..200u32 {
            // Points on the floor (y = -1 in eye space), some close to the wall.
            let p = Vec3::new(-1.0 + 0.01 * k as f32, -1.0, -5.45 + 0.004 * k as f32);
            let at = Origin { p, n: Vec3::Y, draw: u32::MAX };
            let around = Hemisphere::around(at.n);
            let mut s = Sampler::new(&[k]);
            let hidden = scene.hidden(&at, &around, 16, distance, eps, || cosine_local(s.next2()));
            let mut s = Sampler::new(&[k]);
            let each: f32 = (0..16)
                .map(|_| {
                    let ray = leaving(at.p, at.n, around.cosine(s.next2()), eps, distance);
                    1.0 - scene.transmittance(ray, None)
                })
                .sum();
            // Only a ray grazing an edge may go either way (the directions are rounded apart).
            assert!((hidden - each).abs() <= 1.0, "point {k}: {hidden} vs {each}");
            (fast, one_by_one) = (fast + hidden, one_by_one + each);
            some += (hidden > 0.0) as u32;
            differ += (hidden != each) as u32;
        }
        assert!(some > 50 && some < 200, "{some} points see the wall");
        assert!(differ <= 2, "{differ} points of 200 differ: {fast} vs {one_by_one}");
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
            let scene = Scene::build(&frame, &mut Meshes::default(), BvhBuild::Sah, 0.0);
            let centre = (a + b + c) / 3.0;
            let r = ray([0.0, 0.0, 0.0], centre.to_array());
            let hit = scene.closest(r).expect("the ray through the triangle's centre hits it");
            assert!(
                hit.normal.normalize().abs_diff_eq(expected.normalize(), 1e-5),
                "{m}: {} vs {expected}",
                hit.normal
            );
            let mut four = [None; 4];
            scene.closest_packet(&[r; 4], &mut four);
            assert!(four.iter().all(|h| *h == Some(hit)));
            let mut eight = [None; 8];
            scene.closest_packet(&[r; 8], &mut eight);
            assert!(eight.iter().all(|h| *h == Some(hit)));
            let mut all = Vec::new();
            scene.all(r, &mut all);
            assert_eq!(all, [hit]);
        }
    }
}
