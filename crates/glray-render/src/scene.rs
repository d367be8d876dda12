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

use glam::{Affine3A, DMat4, Mat3, Vec2, Vec3, Vec3A};
use glray_scene::frame::{Frame, Solid, TriangleId};
use glray_scene::instance::Instance;
use glray_scene::mesh::Mesh;
use obvhs::aabb::Aabb;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::cwbvh::CwBvh;
pub use obvhs::ray::Ray;
use obvhs::ray::RayHit;
use obvhs::BvhBuildParams;
use rayon::prelude::*;

use crate::bvh::{Quality, TriBvh, TriHit, BUNDLE};
use crate::bvh_choice::{BvhBuild, BIG_MESH};
use crate::effects::{leaving, Origin};
use crate::sampling::Hemisphere;

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

/// A mesh's BVH (its leaves hold their triangles' corners: a leaf is read from one place
/// instead of gathered through the mesh's vertex indices).
pub struct MeshBvh {
    bvh: TriBvh,
}

impl MeshBvh {
    fn build(mesh: &Mesh, quality: Quality) -> MeshBvh {
        MeshBvh { bvh: TriBvh::build_as(mesh.triangles.len(), |i| mesh.corners(i), quality) }
    }

    /// This tree refitted to `mesh` (`TriBvh::refit`), and whether any triangle moved.
    fn refit(self, mesh: &Mesh) -> Option<(MeshBvh, bool)> {
        let (bvh, moved) = self.bvh.refit(mesh.triangles.len(), |i| mesh.corners(i), |i, c| mesh.load_corners(i, c))?;
        Some((MeshBvh { bvh }, moved))
    }
}

/// A tree for a new mesh: a gone mesh's to refit, or the one made for it (refitted or built),
/// how it was built, its cost then once it has been refitted (`Kept::built_cost`), the shape
/// it fits once that has been asked (`Kept::shape`), and whether it came from a gone mesh.
struct Tree {
    bvh: MeshBvh,
    quality: Quality,
    built_cost: Option<f32>,
    shape: Option<[i64; 4]>,
    refitted: bool,
}

/// What `Meshes::prepare` made: how many trees it built fast (`bvh_choice`), how many it
/// refitted.
#[derive(Clone, Copy, Default)]
pub struct Made {
    pub fast_builds: u32,
    pub refits: u32,
}

/// `bvh` (built at cost `built_cost`, if known) refitted to `mesh`, and the cost it was built
/// at; None where it cannot be refitted or has grown too costly (`REFIT_LIMIT`).
fn refitted(bvh: MeshBvh, mesh: &Mesh, built_cost: Option<f32>) -> Option<(MeshBvh, f32)> {
    let built_cost = built_cost.unwrap_or_else(|| bvh.bvh.cost());
    let (bvh, moved) = bvh.refit(mesh)?;
    // Unmoved, the tree is the one that was within the limit already.
    (!moved || bvh.bvh.cost() <= built_cost * REFIT_LIMIT).then_some((bvh, built_cost))
}

/// A tree refitted from one time step to the next is built anew once it costs this much more
/// than when it was built (`TriBvh::cost`: its triangles have moved far): half as much again,
/// about as much more time per ray (a 10M fast build is ~0.5 s, a GL-look frame ~0.1 s).
const REFIT_LIMIT: f32 = 1.5;

/// A kept mesh's BVH, how it was built, and in how many frames the mesh has been drawn.
struct Kept {
    mesh: Weak<Mesh>,
    bvh: Arc<MeshBvh>,
    quality: Quality,
    triangles: usize,
    frames: u32,
    /// The tree's cost when it was built (`TriBvh::cost`), once it has been refitted.
    built_cost: Option<f32>,
    /// The mesh's `Mesh::shape_hash`, once its tree has been refitted (or kept) for it: the
    /// next step's mesh of the same shape takes the tree as it is.
    shape: Option<[i64; 4]>,
}

/// The BVHs of kept meshes (display lists, buffer objects, big client-array and immediate-mode
/// draws), kept across frames for as long as capture holds the mesh.
#[derive(Default)]
pub struct Meshes {
    built: HashMap<u64, Kept>,
    /// Whether the program replaces its meshes frame after frame: the last mesh of `BIG_MESH`
    /// triangles or more that went was drawn in one frame only, and none has been drawn in two
    /// frames since (smaller meshes, a label or a cursor made anew beside a kept dataset, tell
    /// nothing of it). A new mesh's BVH is then one the next frame builds again (`BvhBuild`).
    replacing: bool,
    /// The BVHs of meshes gone since the last frame was traced, until it is: a new mesh of
    /// as many triangles (the next time step of the same mesh, most often) gets one refitted.
    gone: Vec<(u64, Kept)>,
}

/// Whether a mesh drawn in its second frame, whose BVH `auto` built fast, gets an SAH tree now:
/// the program keeps it (it stopped on a time step), and every frame from now on walks the
/// tree (with effects, a still picture's 64 passes; at 10M triangles a fast tree's AO frame is
/// ~140 ms slower, an SAH build ~2 s once).
fn rebuilt_for_keeps(kept: &Kept, choice: BvhBuild) -> bool {
    choice == BvhBuild::Auto && kept.quality == Quality::Fast && kept.frames == 2
}

impl Meshes {
    /// The BVH of each of the frame's instances' meshes: built (in parallel) for meshes not
    /// seen before, as `choice` says for a tree the next frame builds again when the program
    /// replaces its meshes (`replacing`); those of meshes capture no longer holds are dropped,
    /// each handed first to a new mesh of as many triangles to refit (`Made`).
    fn prepare(&mut self, frame: &Frame, choice: BvhBuild, ray_work: f64) -> (Vec<Arc<MeshBvh>>, Made) {
        self.prune();
        let mut new: Vec<&Arc<Mesh>> =
            frame.instances.iter().map(|i| &i.mesh).filter(|m| !self.built.contains_key(&m.id)).collect();
        new.sort_by_key(|m| m.id);
        new.dedup_by_key(|m| m.id);
        // Under `auto`, each new mesh the oldest gone tree of its size that nothing else holds
        // (`sah` and `fast` build every tree their way); the trees left go now, before the
        // builds, which may take their memory (`glray_core::reuse`).
        let mut gone = std::mem::take(&mut self.gone);
        let mut donors: Vec<Option<Tree>> = new
            .iter()
            .map(|m| {
                if choice != BvhBuild::Auto {
                    return None;
                }
                let at = gone
                    .iter()
                    .position(|(_, k)| k.triangles == m.triangles.len() && Arc::strong_count(&k.bvh) == 1)?;
                let (_, k) = gone.remove(at);
                let bvh = Arc::into_inner(k.bvh)?;
                Some(Tree { bvh, quality: k.quality, built_cost: k.built_cost, shape: k.shape, refitted: false })
            })
            .collect();
        drop(gone);
        let replacing = self.replacing;
        let quality = |m: &Mesh| choice.quality(m.triangles.len(), replacing, ray_work);
        let bvhs: Vec<(&Arc<Mesh>, Tree)> = new
            .par_iter()
            .zip(donors.par_iter_mut())
            .map(|(m, donor)| {
                if let Some(Tree { bvh, quality, built_cost, shape, .. }) = donor.take() {
                    // The same positions and triangles again: the tree as it is. (Reading them
                    // in order for the hash is a fraction of a refit's reads in tree order.)
                    let now = m.shape_hash();
                    if shape == Some(now) {
                        return (*m, Tree { bvh, quality, built_cost, shape, refitted: true });
                    }
                    if let Some((bvh, built_cost)) = refitted(bvh, m, built_cost) {
                        let shape = Some(now);
                        return (*m, Tree { bvh, quality, built_cost: Some(built_cost), shape, refitted: true });
                    }
                }
                let quality = quality(m);
                (*m, Tree { bvh: MeshBvh::build(m, quality), quality, built_cost: None, shape: None, refitted: false })
            })
            .collect();
        let made = Made {
            fast_builds: bvhs.iter().filter(|(_, t)| t.quality == Quality::Fast && !t.refitted).count() as u32,
            refits: bvhs.iter().filter(|(_, t)| t.refitted).count() as u32,
        };
        for (m, Tree { bvh, quality, built_cost, shape, .. }) in bvhs {
            let triangles = m.triangles.len();
            let bvh = Arc::new(bvh);
            let kept = Kept { mesh: Arc::downgrade(m), bvh, quality, triangles, frames: 0, built_cost, shape };
            self.built.insert(m.id, kept);
        }
        let mut drawn: Vec<&Arc<Mesh>> = frame.instances.iter().map(|i| &i.mesh).collect();
        drawn.sort_by_key(|m| m.id);
        drawn.dedup_by_key(|m| m.id);
        let mut kept_now = Vec::new();
        let mut kept_for_good = false;
        for m in drawn {
            let kept = self.built.get_mut(&m.id).expect("built above");
            kept.frames += 1;
            kept_for_good |= kept.frames == 2 && kept.triangles >= BIG_MESH;
            if rebuilt_for_keeps(kept, choice) {
                kept_now.push(m);
            }
        }
        if kept_for_good {
            self.set_replacing(false);
        }
        let rebuilt: Vec<(u64, Arc<MeshBvh>)> =
            kept_now.par_iter().map(|m| (m.id, Arc::new(MeshBvh::build(m, Quality::Sah)))).collect();
        for (id, bvh) in rebuilt {
            let kept = self.built.get_mut(&id).expect("drawn above");
            (kept.bvh, kept.quality, kept.built_cost) = (bvh, Quality::Sah, None);
        }
        (frame.instances.iter().map(|i| self.built[&i.mesh.id].bvh.clone()).collect(), made)
    }

    /// Sets aside the BVHs of meshes capture no longer holds (`gone`, until the next frame is
    /// traced), noting whether the last big one was drawn in one frame only (`replacing`).
    pub fn prune(&mut self) {
        let mut ids: Vec<u64> =
            self.built.iter().filter(|(_, k)| k.mesh.strong_count() == 0).map(|(&id, _)| id).collect();
        ids.sort_unstable();
        let gone: Vec<(u64, Kept)> = ids.into_iter().filter_map(|id| self.built.remove_entry(&id)).collect();
        // The latest mesh first (ids grow as meshes are made).
        if let Some((_, kept)) = gone.iter().filter(|g| g.1.triangles >= BIG_MESH).max_by_key(|g| g.0) {
            self.set_replacing(kept.frames == 1);
        }
        self.gone.extend(gone);
    }

    /// Drops the trees set aside for refits (`gone`): a frame shown again traces nothing,
    /// and the next new mesh may be many frames away.
    pub fn forget_gone(&mut self) {
        self.gone.clear();
    }

    /// Notes whether the program replaces its meshes, and has the allocator keep what the
    /// last frame's meshes free for the next ones as long as it does (`glray_core::reuse`).
    fn set_replacing(&mut self, replacing: bool) {
        self.replacing = replacing;
        glray_core::reuse::keep_freed(replacing);
    }

    /// How many trees of gone meshes are held for a refit.
    pub fn set_aside(&self) -> usize {
        self.gone.len()
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
    /// How many of the scene's BVHs were built fast for it (`bvh_choice`), and how many
    /// meshes' trees were refitted rather than built (`Meshes`).
    pub fast_builds: u32,
    pub refits: u32,
    /// Whether the frame's own triangles' packets test a node once for all their rays (as
    /// `Placed::frustum` for a mesh).
    frustum: bool,
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

/// Up to this many instances are tried one box after the other: cheaper than a top-level
/// traversal (a big mesh drawn once is the common case).
const FEW_INSTANCES: usize = 8;

impl<'f> Scene<'f> {
    /// The scene of `frame`, its trees built as `choice` says for a frame tracing `ray_work`
    /// rays (`bvh_choice`); the frame's own triangles' tree is built again next frame.
    pub fn build(frame: &'f Frame, meshes: &mut Meshes, choice: BvhBuild, ray_work: f64) -> Scene<'f> {
        let quality = choice.quality(frame.triangles.len(), true, ray_work);
        let bvh = TriBvh::build_as(frame.triangles.len(), |i| frame.triangles[i].positions, quality);
        let (bvhs, made) = meshes.prepare(frame, choice, ray_work);
        let fast_builds = made.fast_builds + u32::from(quality == Quality::Fast && !frame.triangles.is_empty());
        let placed: Vec<Placed> = frame
            .instances
            .iter()
            .zip(bvhs)
            .map(|(instance, bvh)| {
                let m = instance.modelview.as_mat4();
                let (a, b, c) = (m.x_axis.truncate(), m.y_axis.truncate(), m.z_axis.truncate());
                Placed {
                    instance,
                    frustum: coarse(instance.mesh.triangles.len(), frame),
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
        let frustum = coarse(frame.triangles.len(), frame);
        Scene {
            frame,
            bvh,
            fast_builds,
            refits: made.refits,
            frustum,
            placed,
            boxes: bounds,
            top,
            bounds: all,
            solids: &frame.solids,
            solid_bvh,
            translucent,
        }
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
        if self.translucent || self.solid_bvh.is_some() || self.top.is_some() {
            return (0..count)
                .map(|_| {
                    let ray = leaving(at.p, at.n, around.at(local()), eps, distance);
                    1.0 - self.transmittance(ray, Some(at.draw))
                })
                .sum();
        }
        // Every direction is on the side the normal faces: the rays all start there.
        let start = Vec3A::from(at.p + at.n * eps);
        // (Directions are unit to within rounding: a thousandth more covers where any ends.)
        let reach = Aabb::new(start - distance * 1.001, start + distance * 1.001);
        let mut near = [(0, Vec3A::ZERO, *around); FEW_INSTANCES];
        let mut n = 0;
        for (k, b) in self.boxes.iter().enumerate() {
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
                blocked = self.placed[*k].bvh.bvh.occluded_from(*o, &along(h), distance, blocked);
            }
            hidden += blocked.count_ones();
            left -= BUNDLE as u32;
        }
        for _ in 0..left {
            let l = local();
            let walk = |bvh: &TriBvh, o: Vec3A, h: &Hemisphere| {
                bvh.occluded(&crate::bvh::ray(o, h.at(l).into(), 0.0, distance))
            };
            let blocked = (flat && walk(&self.bvh, start, around))
                || near[..n].iter().any(|(k, o, h)| walk(&self.placed[*k].bvh.bvh, *o, h));
            hidden += blocked as u32;
        }
        hidden as f32
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
    /// as `closest` finds each, into `best`.
    pub fn closest_packet<const N: usize>(&self, rays: &[Ray; N], best: &mut [Option<Hit>; N]) {
        if self.top.is_some() {
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
        for (k, b) in self.boxes.iter().enumerate() {
            if (0..N).all(|j| b.intersect_ray(&rays[j]) > reach(best, j)) {
                continue;
            }
            let p = &self.placed[k];
            let object = std::array::from_fn(|j| p.ray(&Ray { tmax: reach(best, j), ..rays[j] }));
            p.bvh.bvh.closest_packet(&object, &mut found, p.frustum, |_, det| p.drawn(det));
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
    fn a_mesh_that_replaces_one_of_as_many_triangles_gets_its_tree_refitted_unless_it_moved_far() {
        use crate::sampling::hash;
        let random = |seed: u32| hash(&[seed]) as f32 / u32::MAX as f32;
        // A grid of 2 x 40 x 40 triangles, its corners each moved by up to `reach`.
        let grid = |reach: f32, seed: u32| {
            let n = 41u32;
            let jitter = |k: u32, a: u32| reach * (2.0 * random(seed * 1_000_000 + 3 * k + a) - 1.0);
            let positions: Vec<Vec3> = (0..n * n)
                .map(|k| {
                    Vec3::new((k % n) as f32, (k / n) as f32, 0.0) / 40.0
                        + Vec3::new(jitter(k, 0), jitter(k, 1), jitter(k, 2))
                })
                .collect();
            let triangles = (0..(n - 1) * (n - 1))
                .flat_map(|c| {
                    let k = c / (n - 1) * n + c % (n - 1);
                    [[k, k + 1, k + n + 1], [k, k + n + 1, k + n]]
                })
                .collect();
            let normals = vec![Vec3::Z; positions.len()];
            Arc::new(Mesh::indexed(positions, normals, triangles).unwrap())
        };
        let frame_of = |mesh: &Arc<Mesh>| {
            let instance =
                Instance::new(mesh.clone(), DMat4::from_translation(glam::DVec3::NEG_Z * 3.0), DMat4::IDENTITY);
            Frame { instances: vec![instance], ..Frame::default() }
        };
        let mut meshes = Meshes::default();
        let mut step = |mesh: Arc<Mesh>, choice: BvhBuild| {
            let frame = frame_of(&mesh);
            let refits = Scene::build(&frame, &mut meshes, choice, 0.0).refits;
            // A refitted tree knows the shape it fits: the next step of the same shape takes it.
            let shape = meshes.built[&mesh.id].shape;
            assert_eq!(shape.is_some(), refits == 1);
            assert!(shape.is_none_or(|s| s == mesh.shape_hash()));
            // The mesh goes, as capture drops a time step's buffers for the next one's.
            drop(frame);
            drop(mesh);
            meshes.prune();
            refits
        };
        assert_eq!(step(grid(0.0, 1), BvhBuild::Auto), 0, "the first mesh is built");
        assert_eq!(step(grid(0.001, 2), BvhBuild::Auto), 1, "moved a little: refitted");
        assert_eq!(step(grid(0.001, 2), BvhBuild::Auto), 1, "not moved: refitted");
        assert_eq!(step(grid(0.5, 3), BvhBuild::Auto), 0, "moved far: built anew");
        assert_eq!(step(grid(0.001, 4), BvhBuild::Sah), 0, "`sah` builds every tree");
        assert_eq!(step(grid(0.001, 5), BvhBuild::Auto), 1);
        // A mesh of other triangles: nothing to refit; its scene's hits are its own.
        let other =
            Arc::new(Mesh::indexed(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![Vec3::Z; 3], vec![[0, 1, 2]]).unwrap());
        assert_eq!(step(other, BvhBuild::Auto), 0);
        assert_eq!(meshes.gone.len() + meshes.len(), 1, "the gone trees go once the next frame is traced");
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
