//! Meshes whose triangles are not all here (`distribute = paged`): a paged mesh is a list of
//! blocks (`Layout`), each a part of the mesh (`Mesh::part`) with its own BVH (`Block`), owned
//! by the rank whose host drew it. The tracer walks a small tree over the blocks' boxes (in the
//! mesh's object space, on every rank) and asks its `Pager` for a block when a ray reaches its
//! box; the pager gives its own blocks at once and fetches other ranks' (glray-distribute's
//! paging: request and reply on the MPI thread, a bounded cache).
//!
//! A block is the tree of its triangles, built here the same way on every rank (binned SAH, one
//! thread: the same tree bit for bit), so a ray finds in a block what it finds on the rank that
//! owns it. A hit's index is the block's first triangle in the layout plus its index in the
//! block (`Layout::locate` finds them back for shading).

use std::sync::Arc;

use glam::{Vec3, Vec3A};
use glray_scene::mesh::Mesh;
use obvhs::aabb::Aabb;
use obvhs::ray::Ray;

use crate::bvh::{Quality, TriBvh, TriHit, BUNDLE};
use crate::top::Top;

/// A block of a paged mesh: its triangles and their tree.
pub struct Block {
    pub mesh: Mesh,
    pub(crate) bvh: TriBvh,
}

impl Block {
    /// The block of `mesh`'s triangles, its tree built by SAH (every rank builds the same).
    pub fn new(mesh: Mesh) -> Block {
        let bvh = TriBvh::build_as(mesh.triangles.len(), |i| mesh.corners(i), Quality::Sah);
        Block { mesh, bvh }
    }

    /// The tree's bytes (`TriBvh::to_bytes`): sent with the mesh, so that the rank that
    /// fetches a block does not build the tree again.
    pub fn tree_bytes(&self) -> Vec<u8> {
        self.bvh.to_bytes()
    }

    /// The block of `mesh` with the tree `tree` (`tree_bytes`), checked against the mesh.
    pub fn with_tree(mesh: Mesh, tree: &[u8]) -> Result<Block, String> {
        let bvh = TriBvh::from_bytes(tree, mesh.triangles.len())?;
        Ok(Block { mesh, bvh })
    }

    /// The bytes it holds (its mesh and its tree): what a cache of blocks counts.
    pub fn bytes(&self) -> usize {
        self.mesh.bytes() + self.bvh.bytes()
    }
}

/// One block of a layout as every rank knows it: its key (unique in the job: the id of its
/// mesh), its object-space box, how many triangles it holds and its bytes (`Block::bytes`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockRef {
    pub key: u64,
    pub min: Vec3,
    pub max: Vec3,
    pub triangles: u32,
    pub bytes: u64,
}

/// The blocks of a paged mesh, their triangles numbered one block after the other, and a tree
/// over their boxes when they are many.
pub struct Layout {
    pub blocks: Vec<BlockRef>,
    starts: Vec<u32>,
    top: Top,
    pub min: Vec3,
    pub max: Vec3,
}

impl Layout {
    pub fn new(blocks: Vec<BlockRef>) -> Layout {
        let mut starts = Vec::with_capacity(blocks.len());
        let mut n = 0u32;
        let (mut min, mut max) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for b in &blocks {
            starts.push(n);
            n += b.triangles;
            (min, max) = (min.min(b.min), max.max(b.max));
        }
        let top = Top::new(blocks.iter().map(|b| Aabb::new(b.min.into(), b.max.into())).collect());
        Layout { blocks, starts, top, min, max }
    }

    /// The layouts of the pieces of one mesh (drawn by several ranks) as one, in their order.
    pub fn joined(pieces: &[Arc<Layout>]) -> Layout {
        Layout::new(pieces.iter().flat_map(|l| l.blocks.iter().copied()).collect())
    }

    /// Triangles of every block.
    pub fn triangles(&self) -> u64 {
        self.blocks.iter().map(|b| u64::from(b.triangles)).sum()
    }

    /// Which block holds triangle `index` of the layout, and its index there.
    pub fn locate(&self, index: u32) -> Option<(usize, u32)> {
        let b = self.starts.partition_point(|&s| s <= index).checked_sub(1)?;
        let local = index - self.starts[b];
        (local < self.blocks[b].triangles).then_some((b, local))
    }

    /// Offers `visit` every block whose box the ray meets (`Top::visit`).
    fn visit(&self, ray: Ray, first: bool, visit: impl FnMut(&Ray, usize) -> f32) -> bool {
        self.top.visit(ray, first, visit)
    }
}

/// Where a rank's tracer gets the blocks of paged meshes.
pub trait Pager: Send + Sync {
    /// The layout of paged mesh `mesh` (a stand-in's id), if it is one.
    fn layout(&self, mesh: u64) -> Option<Arc<Layout>>;
    /// Block `key`, its own or fetched (waiting for it, within the pager's limit); None when it
    /// could not be had (the pager keeps why, and the frame fails with it).
    fn block(&self, key: u64) -> Option<Arc<Block>>;
    /// Whether the pager parks (`park`); false: `block` always waits.
    fn parks(&self) -> bool {
        false
    }
    /// Parking, on this thread from now on: a block not here is asked for and `block` returns
    /// None at once instead of waiting, so that the thread goes on with other work while the
    /// block travels.
    fn park(&self) {}
    /// Ends `park` on this thread: whether a block was missing since, so that what was traced
    /// meanwhile is wrong and must be traced again.
    fn unpark(&self) -> bool {
        false
    }
}

/// A paged mesh as the scene walks it: the same answers as one tree over all its triangles
/// gives (each block's walk is the whole tree's on its triangles; the nearest of them wins).
pub(crate) struct PagedMesh {
    pub layout: Arc<Layout>,
    pub pager: Arc<dyn Pager>,
}

impl PagedMesh {
    fn block(&self, k: usize) -> Option<Arc<Block>> {
        self.pager.block(self.layout.blocks[k].key)
    }

    pub fn closest(&self, ray: &Ray, mut accept: impl FnMut(u32, f32) -> bool) -> Option<TriHit> {
        let mut best = None;
        self.layout.visit(*ray, false, |r, k| {
            let Some(block) = self.block(k) else { return f32::INFINITY };
            match block.bvh.closest(r, &mut accept) {
                Some(h) => {
                    best = Some(TriHit { index: self.layout.starts[k] + h.index, ..h });
                    h.t
                }
                None => f32::INFINITY,
            }
        });
        best
    }

    pub fn occluded(&self, ray: &Ray) -> bool {
        self.layout.visit(*ray, true, |r, k| match self.block(k) {
            Some(block) if block.bvh.occluded(r) => r.tmin,
            _ => f32::INFINITY,
        })
    }

    pub fn each_hit(&self, ray: &Ray, mut visit: impl FnMut(TriHit, f32)) {
        self.layout.visit(*ray, false, |r, k| {
            if let Some(block) = self.block(k) {
                let start = self.layout.starts[k];
                block.bvh.each_hit(r, |h, det| visit(TriHit { index: start + h.index, ..h }, det));
            }
            f32::INFINITY
        });
    }

    /// `closest` for each ray of a packet.
    pub fn closest_packet<const N: usize>(
        &self,
        rays: &[Ray; N],
        best: &mut [Option<TriHit>; N],
        mut accept: impl FnMut(u32, f32) -> bool,
    ) {
        for (b, r) in best.iter_mut().zip(rays) {
            *b = self.closest(r, &mut accept);
        }
    }

    /// `TriBvh::occluded_from`, ray by ray (the same rays, so the same answers).
    pub fn occluded_from(&self, origin: Vec3A, directions: &[Vec3A; BUNDLE], tmax: f32, known: u32) -> u32 {
        let mut out = known;
        for (j, d) in directions.iter().enumerate() {
            if out & (1 << j) == 0 && self.occluded(&crate::bvh::ray(origin, *d, 0.0, tmax)) {
                out |= 1 << j;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_layouts_triangles_are_found_back_in_their_blocks() {
        let r = |key, triangles| BlockRef { key, min: Vec3::ZERO, max: Vec3::ONE, triangles, bytes: 0 };
        let l = Layout::new(vec![r(1, 3), r(2, 0), r(3, 5)]);
        assert_eq!(l.triangles(), 8);
        assert_eq!(l.locate(0), Some((0, 0)));
        assert_eq!(l.locate(2), Some((0, 2)));
        assert_eq!(l.locate(3), Some((2, 0)), "the empty block holds nothing");
        assert_eq!(l.locate(7), Some((2, 4)));
        assert_eq!(l.locate(8), None);
    }
}
