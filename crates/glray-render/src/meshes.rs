//! The BVHs of kept meshes (display lists, buffer objects, big client-array and immediate-mode
//! draws), kept across frames for as long as capture holds the mesh (`Meshes`): built the
//! first time a frame draws a mesh, refitted from a gone mesh's tree when the program sends
//! the next time step of the same mesh, dropped when the mesh goes. `scene` walks them.

use std::collections::HashMap;
use std::sync::{Arc, Weak};

use glray_scene::frame::Frame;
use glray_scene::mesh::Mesh;
use rayon::prelude::*;

use crate::bvh::{Quality, TriBvh};
use crate::bvh_choice::BIG_MESH;
use crate::options::BvhBuild;

/// A mesh's BVH (its leaves hold their triangles' corners: a leaf is read from one place
/// instead of gathered through the mesh's vertex indices).
pub struct MeshBvh {
    pub(crate) bvh: TriBvh,
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
/// how it was built, its cost then once it has been refitted (`KeptTree::built_cost`), the shape
/// it fits once that has been asked (`KeptTree::shape`), and whether it came from a gone mesh.
struct Tree {
    bvh: MeshBvh,
    quality: Quality,
    built_cost: Option<f32>,
    shape: Option<[i64; 4]>,
    refitted: bool,
}

/// What `Meshes::prepare` made: how many trees it built (for new meshes, or again by SAH for
/// kept ones), how many of those fast (`bvh_choice`), how many it refitted.
#[derive(Clone, Copy, Default)]
pub struct TreesMade {
    pub builds: u32,
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
struct KeptTree {
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
    built: HashMap<u64, KeptTree>,
    /// Whether the program replaces its meshes frame after frame: the last mesh of `BIG_MESH`
    /// triangles or more that went was drawn in one frame only, and none has been drawn in two
    /// frames since (smaller meshes, a label or a cursor made anew beside a kept dataset, tell
    /// nothing of it). A new mesh's BVH is then one the next frame builds again (`BvhBuild`).
    replacing: bool,
    /// The BVHs of meshes gone since the last frame was traced, until it is: a new mesh of
    /// as many triangles (the next time step of the same mesh, most often) gets one refitted.
    gone: Vec<(u64, KeptTree)>,
}

/// Whether a mesh drawn in its second frame, whose BVH `auto` built fast, gets an SAH tree now:
/// the program keeps it (it stopped on a time step), and every frame from now on walks the
/// tree (with effects, a still picture's 64 passes; at 10M triangles a fast tree's AO frame is
/// ~140 ms slower, an SAH build ~2 s once).
fn rebuilt_for_keeps(kept: &KeptTree, choice: BvhBuild) -> bool {
    choice == BvhBuild::Auto && kept.quality == Quality::Fast && kept.frames == 2
}

impl Meshes {
    /// The BVH of each of the frame's instances' meshes: built (in parallel) for meshes not
    /// seen before, as `choice` says for a tree the next frame builds again when the program
    /// replaces its meshes (`replacing`); those of meshes capture no longer holds are dropped,
    /// each handed first to a new mesh of as many triangles to refit (`TreesMade`). Meshes
    /// `paged` says are paged (stand-ins, whose blocks have trees of their own) get none.
    pub(crate) fn prepare(
        &mut self,
        frame: &Frame,
        choice: BvhBuild,
        ray_work: f64,
        paged: impl Fn(&Mesh) -> bool,
    ) -> (Vec<Option<Arc<MeshBvh>>>, TreesMade) {
        self.prune();
        let mut new: Vec<&Arc<Mesh>> =
            frame.instances.iter().map(|i| &i.mesh).filter(|m| !self.built.contains_key(&m.id) && !paged(m)).collect();
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
        let mut made = TreesMade {
            builds: bvhs.iter().filter(|(_, t)| !t.refitted).count() as u32,
            fast_builds: bvhs.iter().filter(|(_, t)| t.quality == Quality::Fast && !t.refitted).count() as u32,
            refits: bvhs.iter().filter(|(_, t)| t.refitted).count() as u32,
        };
        for (m, Tree { bvh, quality, built_cost, shape, .. }) in bvhs {
            let triangles = m.triangles.len();
            let bvh = Arc::new(bvh);
            let kept = KeptTree { mesh: Arc::downgrade(m), bvh, quality, triangles, frames: 0, built_cost, shape };
            self.built.insert(m.id, kept);
        }
        let mut drawn: Vec<&Arc<Mesh>> = frame.instances.iter().map(|i| &i.mesh).filter(|m| !paged(m)).collect();
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
        made.builds += rebuilt.len() as u32;
        for (id, bvh) in rebuilt {
            let kept = self.built.get_mut(&id).expect("drawn above");
            (kept.bvh, kept.quality, kept.built_cost) = (bvh, Quality::Sah, None);
        }
        (frame.instances.iter().map(|i| self.built.get(&i.mesh.id).map(|k| k.bvh.clone())).collect(), made)
    }

    /// Sets aside the BVHs of meshes capture no longer holds (`gone`, until the next frame is
    /// traced), noting whether the last big one was drawn in one frame only (`replacing`).
    pub fn prune(&mut self) {
        let mut ids: Vec<u64> =
            self.built.iter().filter(|(_, k)| k.mesh.strong_count() == 0).map(|(&id, _)| id).collect();
        ids.sort_unstable();
        let gone: Vec<(u64, KeptTree)> = ids.into_iter().filter_map(|id| self.built.remove_entry(&id)).collect();
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use glam::{DMat4, Vec3};
    use glray_scene::instance::Instance;

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
}
