//! glray's own BVH over triangles, the accelerator every ray of a frame goes through.
//!
//! `WIDTH` (eight) children per node, their boxes quantized to 8-bit steps (`node`: 128
//! bytes, half the lines a float node takes) and decoded axis by axis so that one SIMD test
//! (glam's `Vec4`: SSE on x86-64, NEON on aarch64, plain floats elsewhere: the target's
//! baseline, since the library runs on whatever node loads it) meets four at once, or all
//! eight with AVX where the CPU has it (chosen at run time, the same hits bit for bit:
//! `boxes`, `lanes`); eight rather than four halves the tree's depth, and so the dependent
//! misses of a walk (docs/performance.md). Leaves of one or two blocks of four triangles, each
//! block stored the same way (corner and edges precomputed) and tested at once. `build` makes
//! it (binned SAH). Why not obvhs's CWBVH: its generic single-ray traversal was half of every
//! frame's profile, 4x slower per ray than Embree's, and its PLOC build 3-4x slower than
//! Embree's with 3x the memory (docs/performance.md).

mod boxes;
mod build;
mod bundle;
mod frustum;
mod lanes;
mod morton;
mod node;
mod packet;
mod refit;
mod stack;
mod wire;

use glam::{Vec2, Vec3, Vec3A, Vec4};
use glray_core::prefetch;
use obvhs::ray::Ray;

pub use build::Quality;
pub use bundle::BUNDLE;

use boxes::{Boxes, Sse};
use lanes::Lanes;
use node::Node;
use stack::{Fixed, Pending, Spilling};

/// obvhs's `Ray::new`, the same ray bit for bit, with the three reciprocals of the direction
/// in one SIMD division instead of three divisions and three branches: every camera ray is made
/// once in eye space and again in each instance's space it enters, and every secondary ray
/// once, so these were a few percent of a frame.
#[inline]
pub fn ray(origin: Vec3A, direction: Vec3A, tmin: f32, tmax: f32) -> Ray {
    // `safe_inverse`: a component within f32::EPSILON of zero inverts to +-1/EPSILON.
    let tiny = direction.abs().cmple(Vec3A::splat(f32::EPSILON));
    let inv_direction = Vec3A::select(tiny, direction.signum() / f32::EPSILON, direction.recip());
    Ray { origin, direction, inv_direction, tmin, tmax }
}

/// A child reference with this bit set is a leaf: bit `BLOCKS_AT` and up, how many blocks of
/// four triangles (`Tri4`) it has, less one; below, the index of its first block in `leaves`.
const LEAF: u32 = 1 << 31;
const BLOCKS_AT: u32 = 30;
/// The most blocks a leaf has (leaves the SAH would make of three or four blocks were a few in
/// a thousand: a bit for them would halve the blocks a tree can index).
const MAX_BLOCKS: u32 = 2;
/// The most blocks a tree can index, and so the most triangles it is built over (a block
/// holds at least one).
const MAX_LEAVES: u32 = 1 << BLOCKS_AT;
/// An unused child slot (its box is inverted: no ray meets it).
const EMPTY: u32 = u32::MAX;
/// A subtree of at most this many triangles is always one leaf (one block); one of up to
/// `MAX_BLOCKS` blocks is a leaf where the SAH finds that cheaper than a node (`build`).
const LEAF_SIZE: u32 = 4;

/// The reference to a leaf of `blocks` blocks from `first` on.
#[inline]
fn leaf_ref(first: u32, blocks: u32) -> u32 {
    debug_assert!((1..=MAX_BLOCKS).contains(&blocks) && first < MAX_LEAVES);
    LEAF | (blocks - 1) << BLOCKS_AT | first
}

/// The blocks of leaf reference `c`: (first, count).
#[inline(always)]
fn leaf_blocks(c: u32) -> (usize, usize) {
    ((c & (MAX_LEAVES - 1)) as usize, ((c & !LEAF) >> BLOCKS_AT) as usize + 1)
}

/// Children per node, tested four at a time (one 128-bit test per group of four) or, with
/// AVX, all at once.
const WIDTH: usize = 8;
const GROUPS: usize = WIDTH / 4;

/// Lane `k` of `v`, read through its lanes as an array: `Vec4`'s own indexing picks a lane
/// through a jump table when `k` is not a constant, an indirect branch per box or triangle in
/// the packet walk.
#[inline(always)]
fn lane(v: &Vec4, k: usize) -> f32 {
    let lanes: &[f32; 4] = v.as_ref();
    lanes[k]
}

/// Up to four triangles, one per lane: first corner, edges to the other two, and the caller's
/// index of each (`EMPTY` for unused lanes, whose edges are zero: no ray meets them).
#[derive(Clone, Copy)]
struct Tri4 {
    v0: [Vec4; 3],
    e1: [Vec4; 3],
    e2: [Vec4; 3],
    id: [u32; 4],
}

impl Tri4 {
    /// The triangles `ids` (at most four), whose corners `corners` gives.
    fn new(ids: &[u32], corners: impl Fn(u32) -> [Vec3; 3]) -> Tri4 {
        let mut lanes = [[[0.0f32; 4]; 3]; 3];
        let mut id = [EMPTY; 4];
        for (lane, &i) in ids.iter().enumerate() {
            let [v0, v1, v2] = corners(i);
            for (k, v) in [v0, v1 - v0, v2 - v0].into_iter().enumerate() {
                for axis in 0..3 {
                    lanes[k][axis][lane] = v[axis];
                }
            }
            id[lane] = i;
        }
        let v = |k: usize| lanes[k].map(Vec4::from_array);
        Tri4 { v0: v(0), e1: v(1), e2: v(2), id }
    }

    /// Lane `k`'s geometric normal e1 x e2 (not normalised): the walk has the leaf in cache,
    /// where looking it up later through the mesh's indices would be two more misses per hit.
    #[inline(always)]
    fn normal(&self, k: usize) -> Vec3 {
        let at = |v: &[Vec4; 3]| Vec3::new(lane(&v[0], k), lane(&v[1], k), lane(&v[2], k));
        at(&self.e1).cross(at(&self.e2))
    }

    /// Lane `k`'s hit by `ray` at `t`. The weights of the corners there are worked out again
    /// for this one lane, from the same numbers in the same order as the SIMD test: returned by
    /// the test, two more vectors through every leaf of the walk slowed a 1M-triangle frame's
    /// camera rays by several percent, for a hit kept once or twice a ray.
    #[inline(always)]
    fn hit(&self, k: usize, t: f32, ray: &Ray) -> TriHit {
        let at = |v: &[Vec4; 3]| Vec3::new(lane(&v[0], k), lane(&v[1], k), lane(&v[2], k));
        let (e1, e2) = (at(&self.e1), at(&self.e2));
        let (o, d) = (Vec3::from(ray.origin), Vec3::from(ray.direction));
        // glam's scalar cross and dot are the SIMD test's operations (its products commute
        // exactly, its sums go x, y, z in the same order).
        let s = o - at(&self.v0);
        let (q, p) = (s.cross(e1), d.cross(e2));
        let inv = 1.0 / e1.dot(p);
        let (u, v) = (s.dot(p) * inv, d.dot(q) * inv);
        TriHit { index: self.id[k], t, normal: self.normal(k), uv: Vec2::new(u, v) }
    }
}

/// A tree of more bytes than this is `far`: most of it is out of the caches.
const FAR: usize = 32 << 20;

impl TriBvh {
    /// Starts loading child `c` (a node or a leaf) that the walk will visit later, so that its
    /// misses overlap the subtree visited first (a deep 10M tree misses on most nodes).
    #[inline(always)]
    fn prefetch_child(&self, c: u32) {
        self.prefetch_first(c);
        if c & LEAF != 0 {
            self.leaf(c).iter().skip(1).for_each(prefetch::all);
        }
    }

    /// Starts loading child `c`: a node whole, a leaf's first block.
    #[inline(always)]
    fn prefetch_first(&self, c: u32) {
        if c & LEAF == 0 {
            if let Some(node) = self.nodes.get(c as usize) {
                prefetch::all(node);
            }
        } else if let Some(block) = self.leaves.get(leaf_blocks(c).0) {
            prefetch::all(block);
        }
    }

    /// The blocks of leaf `c`.
    #[inline(always)]
    fn leaf(&self, c: u32) -> &[Tri4] {
        let (first, count) = leaf_blocks(c);
        &self.leaves[first..first + count]
    }
}

/// A ray's hit on a triangle of the tree: the index the triangle had in the slice the tree was
/// built from, where along the ray, its geometric normal (e1 x e2 of its corners in the order
/// given, in the tree's space, not normalised), and where on the triangle: the barycentric
/// weights of its second and third corners (the first's is 1 - u - v). The weights hold in any
/// space an affine map takes the triangle to, eye space included: a hit's colours are mixed
/// with them without the corners being looked up again.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriHit {
    pub index: u32,
    pub t: f32,
    pub normal: Vec3,
    pub uv: Vec2,
}

/// A ray made ready for the SIMD tests: every component in all four lanes, and for each axis
/// which side of a box it meets first.
struct Prepared {
    origin: [Vec4; 3],
    direction: [Vec4; 3],
    inverse: [Vec4; 3],
    /// Per axis, 1 when the direction is negative: the box's maximum is met first.
    near: [usize; 3],
    tmin: f32,
}

impl Prepared {
    #[inline(always)]
    fn new(ray: &Ray) -> Prepared {
        let splat = |v: Vec3A| [Vec4::splat(v.x), Vec4::splat(v.y), Vec4::splat(v.z)];
        let inv = ray.inv_direction;
        Prepared {
            origin: splat(ray.origin),
            direction: splat(ray.direction),
            inverse: splat(inv),
            near: [(inv.x < 0.0) as usize, (inv.y < 0.0) as usize, (inv.z < 0.0) as usize],
            tmin: ray.tmin,
        }
    }
}

/// How far outside a triangle's edges (in barycentric units) a hit still counts: a ray through
/// a pixel centre exactly on an edge two triangles share must hit one of them, as GL's fill
/// rule guarantees; a strict test can miss both and leave a crack.
const EDGE: f32 = 1e-6;

/// Where `moller_trumbore` found rays and triangles to cross, lane by lane.
struct Crossing<L> {
    /// Lanes that hit within [tmin, tmax], a bit each.
    mask: u32,
    t: L,
    /// The determinant: its sign says which face the ray sees (the geometric normal e1 x e2
    /// dotted with the direction is -det).
    det: L,
}

/// Moller-Trumbore, four (ray, triangle) pairs at once, one per lane (see `Crossing`). A lane
/// is a ray against four triangles (`hit_triangles`) or one of four or eight rays against one
/// triangle (`packet`).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn moller_trumbore<L: Lanes<N>, const N: usize>(
    origin: &[L; 3],
    direction: &[L; 3],
    v0: &[L; 3],
    e1: &[L; 3],
    e2: &[L; 3],
    tmin: L,
    tmax: L,
) -> Crossing<L> {
    moller_trumbore_from(direction, e1, e2, &FromOrigin::new(origin, v0, e1, e2), tmin, tmax)
}

/// What Moller-Trumbore works out from the ray's origin and the triangle alone, before the
/// direction: rays from one point (a bundle's) share it.
struct FromOrigin<L> {
    /// origin - v0
    s: [L; 3],
    /// s x e1
    q: [L; 3],
    /// e2 . q
    e2q: L,
}

impl<L: Copy> FromOrigin<L> {
    #[inline(always)]
    fn new<const N: usize>(origin: &[L; 3], v0: &[L; 3], e1: &[L; 3], e2: &[L; 3]) -> FromOrigin<L>
    where
        L: Lanes<N>,
    {
        let [e1x, e1y, e1z] = *e1;
        let (sx, sy, sz) = (origin[0] - v0[0], origin[1] - v0[1], origin[2] - v0[2]);
        let (qx, qy, qz) = (sy * e1z - sz * e1y, sz * e1x - sx * e1z, sx * e1y - sy * e1x);
        FromOrigin { s: [sx, sy, sz], q: [qx, qy, qz], e2q: e2[0] * qx + e2[1] * qy + e2[2] * qz }
    }
}

/// `moller_trumbore` from what the origin gave (`FromOrigin`): the same operations on the same
/// values, so the same hits bit for bit.
#[inline(always)]
fn moller_trumbore_from<L: Lanes<N>, const N: usize>(
    direction: &[L; 3],
    e1: &[L; 3],
    e2: &[L; 3],
    o: &FromOrigin<L>,
    tmin: L,
    tmax: L,
) -> Crossing<L> {
    let [dx, dy, dz] = *direction;
    let [e1x, e1y, e1z] = *e1;
    let [e2x, e2y, e2z] = *e2;
    let ([sx, sy, sz], [qx, qy, qz]) = (o.s, o.q);
    let (px, py, pz) = (dy * e2z - dz * e2y, dz * e2x - dx * e2z, dx * e2y - dy * e2x);
    let det = e1x * px + e1y * py + e1z * pz;
    let inv = L::splat(1.0) / det;
    let u = (sx * px + sy * py + sz * pz) * inv;
    let v = (dx * qx + dy * qy + dz * qz) * inv;
    let t = o.e2q * inv;
    let (lo, hi) = (L::splat(-EDGE), L::splat(1.0 + EDGE));
    let ok = det.cmpne(L::splat(0.0))
        & det.is_finite_mask()
        & u.cmpge(lo)
        & u.cmple(hi)
        & v.cmpge(lo)
        & (u + v).cmple(hi)
        & t.cmpge(tmin)
        & t.cmple(tmax);
    Crossing { mask: L::bitmask(ok), t, det }
}

/// One ray against a leaf's four triangles (see `moller_trumbore`).
#[inline(always)]
fn hit_triangles(tri: &Tri4, r: &Prepared, tmax: f32) -> Crossing<Vec4> {
    let (tmin, tmax) = (Vec4::splat(r.tmin), Vec4::splat(tmax));
    moller_trumbore(&r.origin, &r.direction, &tri.v0, &tri.e1, &tri.e2, tmin, tmax)
}

/// Puts `entry` (distance first) among the first `n` of `hits`, which are sorted farthest
/// first, keeping them so.
#[inline(always)]
fn insert_farthest_first<T: Copy, const N: usize>(hits: &mut [(f32, T); N], n: usize, entry: (f32, T)) {
    let mut j = n;
    while j > 0 && hits[j - 1].0 < entry.0 {
        hits[j] = hits[j - 1];
        j -= 1;
    }
    hits[j] = entry;
}

/// A BVH over triangles; hits report the index each triangle had in the slice it was built from.
pub struct TriBvh {
    nodes: Vec<Node>,
    leaves: Vec<Tri4>,
    root: u32,
    /// Whether a walk's pending subtrees always fit a `Fixed` stack (`build::Built::most_pending`).
    shallow: bool,
    /// Whether the tree is bigger than the caches hold (`FAR`): how a bundle prefetches.
    far: bool,
}

impl TriBvh {
    /// The tree over `count` triangles, whose corners `corners` gives by index.
    pub fn build(count: usize, corners: impl Fn(usize) -> [Vec3; 3] + Sync) -> TriBvh {
        TriBvh::build_as(count, corners, Quality::Sah)
    }

    /// The same, built as `quality` says (`Quality::Fast`: sooner, walked more slowly).
    pub fn build_as(count: usize, corners: impl Fn(usize) -> [Vec3; 3] + Sync, quality: Quality) -> TriBvh {
        let count = build::capped(count);
        let build::Built { nodes, leaves, root, most_pending } = match quality {
            Quality::Sah => build::sah(count, corners),
            Quality::Fast => morton::build(count, corners),
        };
        let bytes = nodes.len() * size_of::<Node>() + leaves.len() * size_of::<Tri4>();
        TriBvh { nodes, leaves, root, shallow: most_pending <= stack::FIXED, far: bytes > FAR }
    }

    /// The bytes its nodes and leaves take.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * size_of::<Node>() + self.leaves.len() * size_of::<Tri4>()
    }

    /// Whether the tree holds no triangle.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.root == EMPTY
    }

    /// How every walk that wants the nearest hit goes on from a node: of the children met
    /// (`met`, a bit each, at least one), the nearest's stack entry, to visit now, the others
    /// pushed on `stack` farthest first (so that they come back nearest first), each one's
    /// loads started as it is pushed. `entry(k)`: child k's distance, by which they are
    /// ordered, and its stack entry; `child`: an entry's subtree. The walks differ only in
    /// their entries: a ray's (subtree, entry distance), a packet's (subtree, each ray's entry
    /// distance), a frustum's (subtree, earliest entry, rays).
    #[inline(always)]
    fn nearest_pushing_rest<E: Copy, S: Pending<E>>(
        &self,
        mut met: u32,
        stack: &mut S,
        entry: impl Fn(usize) -> (f32, E),
        child: impl Fn(&E) -> u32,
    ) -> E {
        debug_assert!(met != 0);
        // The first child met fills the array (and is its first entry), the rest are sorted in.
        let mut hits = [entry(met.trailing_zeros() as usize); WIDTH];
        met &= met - 1;
        let mut n = 1;
        while met != 0 {
            let k = met.trailing_zeros() as usize;
            met &= met - 1;
            insert_farthest_first(&mut hits, n, entry(k));
            n += 1;
        }
        for (_, e) in &hits[..n - 1] {
            self.prefetch_child(child(e));
            stack.push(*e);
        }
        hits[n - 1].1
    }

    /// Walks the tree children nearest first (what a closest hit wants: a near hit prunes what
    /// lies behind), offering `leaf` each leaf the ray reaches within the current `tmax`, which
    /// `leaf` may shorten. `B`: how the node's boxes are tested (see `boxes`).
    #[inline(always)]
    fn walk_nearest<B: Boxes>(&self, ray: &Ray, leaf: impl FnMut(&Tri4, &Prepared, &mut f32)) {
        if self.is_empty() {
            return;
        }
        if self.shallow {
            self.walk_nearest_on::<B, Fixed<_>>(ray, leaf)
        } else {
            self.walk_nearest_on::<B, Spilling<_>>(ray, leaf)
        }
    }

    /// `walk_nearest`, keeping the subtrees it will come back to (and where the ray enters
    /// each) on a stack `S`.
    #[inline(always)]
    fn walk_nearest_on<B: Boxes, S: Pending<(u32, f32)>>(
        &self,
        ray: &Ray,
        mut leaf: impl FnMut(&Tri4, &Prepared, &mut f32),
    ) {
        let r = Prepared::new(ray);
        let boxes = B::new(&r);
        let mut tmax = ray.tmax;
        let mut stack = S::new();
        let mut cur = self.root;
        loop {
            if cur & LEAF == 0 {
                let node = &self.nodes[cur as usize];
                let (mask, tnear) = boxes.hit(node, tmax);
                if mask != 0 {
                    if mask & (mask - 1) == 0 {
                        cur = node.child[mask.trailing_zeros() as usize];
                        continue;
                    }
                    // Two or more: visit the nearest now, the others nearest first after it.
                    let entry = |k: usize| (tnear[k], (node.child[k], tnear[k]));
                    cur = self.nearest_pushing_rest(mask, &mut stack, entry, |e| e.0).0;
                    continue;
                }
            } else {
                for tri in self.leaf(cur) {
                    leaf(tri, &r, &mut tmax);
                }
            }
            // The next subtree the ray still reaches.
            loop {
                match stack.pop() {
                    Some((c, tnear)) if tnear <= tmax => {
                        cur = c;
                        break;
                    }
                    Some(_) => continue,
                    None => return,
                }
            }
        }
    }

    /// Walks the tree in whatever order comes cheapest (any hit will do), offering `leaf` each
    /// leaf the ray reaches within [tmin, tmax]; `leaf` returns true to stop the walk.
    #[inline(always)]
    fn walk_any<B: Boxes>(&self, ray: &Ray, leaf: impl FnMut(&Tri4, &Prepared, f32) -> bool) {
        if self.is_empty() {
            return;
        }
        if self.shallow {
            self.walk_any_on::<B, Fixed<_>>(ray, leaf)
        } else {
            self.walk_any_on::<B, Spilling<_>>(ray, leaf)
        }
    }

    /// `walk_any`, keeping the subtrees it will come back to on a stack `S`: only which, since
    /// tmax never shrinks and every one pushed is still reached.
    #[inline(always)]
    fn walk_any_on<B: Boxes, S: Pending<u32>>(&self, ray: &Ray, mut leaf: impl FnMut(&Tri4, &Prepared, f32) -> bool) {
        let r = Prepared::new(ray);
        let boxes = B::new(&r);
        let tmax = ray.tmax;
        let mut stack = S::new();
        let mut cur = self.root;
        loop {
            if cur & LEAF == 0 {
                let node = &self.nodes[cur as usize];
                let (mut mask, _) = boxes.hit(node, tmax);
                if mask != 0 {
                    cur = node.child[mask.trailing_zeros() as usize];
                    mask &= mask - 1;
                    while mask != 0 {
                        let c = node.child[mask.trailing_zeros() as usize];
                        mask &= mask - 1;
                        self.prefetch_child(c);
                        stack.push(c);
                    }
                    continue;
                }
            } else if self.leaf(cur).iter().any(|tri| leaf(tri, &r, tmax)) {
                return;
            }
            match stack.pop() {
                Some(c) => cur = c,
                None => return,
            }
        }
    }

    /// The closest hit in [tmin, tmax] among triangles `accept` takes (given the triangle's
    /// index and the determinant of the hit, see `hit_triangles`).
    #[inline]
    pub fn closest(&self, ray: &Ray, accept: impl FnMut(u32, f32) -> bool) -> Option<TriHit> {
        #[cfg(target_arch = "x86_64")]
        if boxes::avx_available() {
            // SAFETY: the CPU has AVX (checked just now).
            return unsafe { self.closest_avx(ray, accept) };
        }
        self.closest_with::<Sse>(ray, accept)
    }

    /// Whether any triangle lies along the ray within [tmin, tmax]. Always inlined: a call
    /// only to dispatch was ~40 instructions of every shadow and AO ray's ~1200.
    #[inline(always)]
    pub fn occluded(&self, ray: &Ray) -> bool {
        // An empty tree (a scene's flat triangles, often none beside its instances) answers
        // here, before a call into the walk for every shadow and AO ray.
        if self.is_empty() {
            return false;
        }
        #[cfg(target_arch = "x86_64")]
        if boxes::avx_available() {
            // SAFETY: the CPU has AVX (checked just now).
            return unsafe { self.occluded_avx(ray) };
        }
        self.occluded_with::<Sse>(ray)
    }

    /// Every hit within [tmin, tmax], in no particular order: `visit(hit, det)`.
    #[inline]
    pub fn each_hit(&self, ray: &Ray, mut visit: impl FnMut(TriHit, f32)) {
        self.walk_any::<Sse>(ray, |tri, r, tmax| {
            let c = hit_triangles(tri, r, tmax);
            let (t, det) = (c.t.to_array(), c.det.to_array());
            let mut mask = c.mask;
            while mask != 0 {
                let k = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                visit(tri.hit(k, t[k], ray), det[k]);
            }
            false
        });
    }

    /// `closest`, the whole walk compiled for AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn closest_avx(&self, ray: &Ray, accept: impl FnMut(u32, f32) -> bool) -> Option<TriHit> {
        self.closest_with::<boxes::Avx>(ray, accept)
    }

    /// `occluded`, the whole walk compiled for AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn occluded_avx(&self, ray: &Ray) -> bool {
        self.occluded_with::<boxes::Avx>(ray)
    }

    #[inline(always)]
    fn closest_with<B: Boxes>(&self, ray: &Ray, mut accept: impl FnMut(u32, f32) -> bool) -> Option<TriHit> {
        let mut best = None;
        self.walk_nearest::<B>(ray, |tri, r, tmax| {
            let c = hit_triangles(tri, r, *tmax);
            let mut mask = c.mask;
            if mask == 0 {
                return;
            }
            let (t, det) = (c.t.to_array(), c.det.to_array());
            while mask != 0 {
                let k = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                if t[k] < *tmax && accept(tri.id[k], det[k]) {
                    *tmax = t[k];
                    best = Some(tri.hit(k, t[k], ray));
                }
            }
        });
        best
    }

    #[inline(always)]
    fn occluded_with<B: Boxes>(&self, ray: &Ray) -> bool {
        let mut hit = false;
        self.walk_any::<B>(ray, |tri, r, tmax| {
            hit = hit_triangles(tri, r, tmax).mask != 0;
            hit
        });
        hit
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::hash;

    /// A uniform number in [0, 1] from `seed` (the tests of `bvh`'s modules share these).
    pub(super) fn random(seed: u32) -> f32 {
        hash(&[seed]) as f32 / u32::MAX as f32
    }

    type Triangle = [Vec3; 3];

    fn build(tris: &[Triangle]) -> TriBvh {
        TriBvh::build(tris.len(), |i| tris[i])
    }

    /// A soup of small random triangles in the unit cube.
    pub(super) fn soup(n: u32) -> Vec<Triangle> {
        (0..n)
            .map(|i| {
                let c = Vec3::new(random(i * 9), random(i * 9 + 1), random(i * 9 + 2));
                let corner = |k: u32| {
                    c + 0.05 * Vec3::new(random(i * 9 + 3 * k), random(i * 9 + 3 * k + 1), random(i * 9 + 3 * k + 2))
                };
                [corner(1), corner(2), corner(3)]
            })
            .collect()
    }

    pub(super) fn brute(tris: &[Triangle], ray: &Ray) -> Option<(u32, f32)> {
        let r = Prepared::new(ray);
        let mut best: Option<(u32, f32)> = None;
        for (i, _) in tris.iter().enumerate() {
            let c = hit_triangles(&Tri4::new(&[i as u32], |i| tris[i as usize]), &r, ray.tmax);
            if c.mask & 1 != 0 && best.is_none_or(|b| c.t.x < b.1) {
                best = Some((i as u32, c.t.x));
            }
        }
        best
    }

    #[test]
    fn a_ray_made_here_is_obvhs_ray_bit_for_bit() {
        let e = f32::EPSILON;
        let values =
            [0.0, -0.0, 1.0, -1.0, 0.3, -2.5e-3, e, -e, 1.5 * e, 0.5 * e, -0.5 * e, 1e-30, 7e5, f32::MIN_POSITIVE];
        for (k, &x) in values.iter().enumerate() {
            let d = Vec3A::new(x, values[(k + 3) % values.len()], values[(k + 7) % values.len()]);
            let o = Vec3A::new(0.5, -1.0, 2.0);
            let (a, b) = (ray(o, d, -0.25, 9.0), Ray::new(o, d, -0.25, 9.0));
            let bits = |v: Vec3A| v.to_array().map(f32::to_bits);
            assert_eq!(bits(a.inv_direction), bits(b.inv_direction), "direction {d}");
            assert_eq!(
                (bits(a.origin), bits(a.direction), a.tmin, a.tmax),
                (bits(b.origin), bits(b.direction), b.tmin, b.tmax)
            );
        }
    }

    #[test]
    fn rays_from_afar_never_enter_a_nodes_unused_slots() {
        // A cluster a thousandth wide seen from a million away: an unused slot's decoded box
        // (inverted by only 255 steps of a tiny node) is thinner than the slab test's widening
        // there, so only `Node::occupied` keeps the walks out of its `EMPTY` child.
        let tris: Vec<Triangle> = soup(6).iter().map(|t| t.map(|p| p * 1e-3)).collect();
        let bvh = build(&tris);
        for k in 0..200u32 {
            let target = Vec3A::new(random(k * 5), random(k * 5 + 1), random(k * 5 + 2)) * 1e-3;
            let from = Vec3A::new(random(k * 5 + 3) - 0.5, random(k * 5 + 4) - 0.5, 1.0).normalize() * 1e6;
            let ray = Ray::new(from, (target - from).normalize(), 0.0, f32::INFINITY);
            // At a million away the triangles' distances differ by a few ulps, less than the
            // ray-triangle test's own rounding there (a box's entry may come out past a hit
            // inside it: the walk then keeps a hit a few ulps further, as it did with boxes in
            // floats): hits are compared to that precision.
            let want = brute(&tris, &ray).map(|h| h.1);
            let near = |got: Option<f32>| match (got, want) {
                (Some(a), Some(b)) => (a - b).abs() <= b * 4.0 * f32::EPSILON,
                (a, b) => a == b,
            };
            assert!(near(bvh.closest(&ray, |_, _| true).map(|h| h.t)), "ray {k}: want {want:?}");
            assert_eq!(bvh.occluded(&ray), want.is_some(), "ray {k}");
            let packet = bvh.packet_hits(&[ray; 8], |_, _| true);
            assert!(packet.iter().all(|h| near(h.map(|h| h.t))), "ray {k}: want {want:?}");
            let hidden = bvh.occluded_from(from, &[ray.direction; BUNDLE], f32::INFINITY, 0);
            assert_eq!(hidden, if want.is_some() { (1 << BUNDLE) - 1 } else { 0 }, "ray {k}");
        }
    }

    #[test]
    fn the_tree_finds_what_testing_every_triangle_finds() {
        // Each tree walked with the fixed stack its depth allows, then with the spilling one.
        for (n, spilling) in [1, 3, 4, 5, 17, 2000].into_iter().flat_map(|n| [(n, false), (n, true)]) {
            let tris = soup(n);
            let mut bvh = build(&tris);
            assert!(bvh.shallow);
            bvh.shallow = !spilling;
            for k in 0..500 {
                let o = Vec3A::new(random(k * 7 + 100_000), random(k * 7 + 100_001), 2.0);
                let target = Vec3A::new(random(k * 7 + 100_002), random(k * 7 + 100_003), 0.0);
                let ray = Ray::new(o, (target - o).normalize(), 0.0, f32::INFINITY);
                let expected = brute(&tris, &ray);
                let found = bvh.closest(&ray, |_, _| true);
                assert_eq!(found.map(|h| (h.index, h.t)), expected, "{n} triangles, ray {k}");
                if let Some(h) = found {
                    let [a, b, c] = tris[h.index as usize];
                    assert!(h.normal.cross((b - a).cross(c - a)).length() <= 1e-6 * h.normal.length_squared());
                    assert!(h.normal.dot((b - a).cross(c - a)) > 0.0);
                    // The weights give back the point the ray reached.
                    let at = a + (b - a) * h.uv.x + (c - a) * h.uv.y;
                    let want = Vec3::from(ray.origin + ray.direction * h.t);
                    assert!(at.distance(want) < 1e-5, "{n} triangles, ray {k}: {at} at t, {want} from uv");
                    assert!(h.uv.min_element() >= -EDGE && h.uv.element_sum() <= 1.0 + EDGE, "{}", h.uv);
                }
                assert_eq!(bvh.occluded(&ray), expected.is_some());
                let mut all = 0;
                bvh.each_hit(&ray, |_, _| all += 1);
                let every = (0..n).filter(|&i| brute(&tris[i as usize..=i as usize], &ray).is_some()).count();
                assert_eq!(all, every, "{n} triangles, ray {k}: every hit");
                // A ray that ends before the first hit meets nothing.
                if let Some((_, t)) = expected {
                    let short = Ray { tmax: t * 0.999, ..ray };
                    assert!(bvh.closest(&short, |_, _| true).is_none());
                    assert!(!bvh.occluded(&short));
                }
            }
        }
    }

    /// Checks that every triangle under `c` lies inside `lo..hi` (the boxes on its way from the
    /// root, intersected: a walk reaches it only through all of them) and counts them in `seen`.
    fn check(bvh: &TriBvh, tris: &[Triangle], c: u32, lo: Vec3, hi: Vec3, seen: &mut [u32]) {
        let inside = |p: Vec3| p.cmpge(lo).all() && p.cmple(hi).all();
        if c & LEAF != 0 {
            for &id in bvh.leaf(c).iter().flat_map(|leaf| &leaf.id).filter(|&&id| id != EMPTY) {
                seen[id as usize] += 1;
                assert!(tris[id as usize].iter().all(|&p| inside(p)), "triangle {id} outside a box on its way");
            }
            return;
        }
        let node = &bvh.nodes[c as usize];
        for k in (0..WIDTH).filter(|&k| node.child[k] != EMPTY) {
            let b = |side: usize| Vec3::new(node.bound(side, 0, k), node.bound(side, 1, k), node.bound(side, 2, k));
            check(bvh, tris, node.child[k], lo.max(b(0)), hi.min(b(1)), seen);
        }
    }

    /// A tree's nodes and leaves as bits, read from the root down: where the threads put
    /// their subtrees in the node vector depends on which finished first, and does not matter.
    fn tree(t: &TriBvh) -> Vec<u32> {
        fn bits(t: &TriBvh, at: u32, out: &mut Vec<u32>) {
            if at == EMPTY {
                return;
            }
            if at & LEAF != 0 {
                for l in t.leaf(at) {
                    let corners = [l.v0, l.e1, l.e2].into_iter().flatten().flat_map(|v| v.to_array().map(f32::to_bits));
                    out.extend(corners.chain(l.id));
                }
            } else {
                let n = &t.nodes[at as usize];
                out.extend(n.planes().iter().flatten().flatten().flat_map(|v| v.to_array().map(f32::to_bits)));
                for c in n.child {
                    out.push(c & LEAF);
                    bits(t, c, out);
                }
            }
        }
        let mut out = Vec::new();
        bits(t, t.root, &mut out);
        out
    }

    #[test]
    fn a_fast_tree_holds_every_triangle_once_and_finds_what_testing_every_triangle_finds() {
        let fast = |tris: &[Triangle]| TriBvh::build_as(tris.len(), |i| tris[i], Quality::Fast);
        // One leaf, a node of leaves, deeper trees, and one past morton::PARALLEL (32K): its
        // top built on several threads.
        for n in [1, 3, 4, 5, 8, 9, 17, 2000, 50_000] {
            let tris = soup(n);
            let bvh = fast(&tris);
            let mut seen = vec![0u32; n as usize];
            check(&bvh, &tris, bvh.root, Vec3::NEG_INFINITY, Vec3::INFINITY, &mut seen);
            assert!(seen.iter().all(|&k| k == 1), "{n} triangles: every triangle in exactly one leaf");
            let most = if bvh.root & LEAF != 0 { 0 } else { stack::most_pending(&bvh.nodes, bvh.root) };
            assert!(bvh.shallow == (most <= stack::FIXED), "{n} triangles");
            for k in 0..300 {
                let o = Vec3A::new(random(k * 7 + 200_000), random(k * 7 + 200_001), 2.0);
                let target = Vec3A::new(random(k * 7 + 200_002), random(k * 7 + 200_003), 0.0);
                let ray = Ray::new(o, (target - o).normalize(), 0.0, f32::INFINITY);
                let expected = brute(&tris, &ray);
                assert_eq!(bvh.closest(&ray, |_, _| true).map(|h| (h.index, h.t)), expected, "{n} triangles, ray {k}");
                assert_eq!(bvh.occluded(&ray), expected.is_some(), "{n} triangles, ray {k}");
                let packet = bvh.packet_hits(&[ray; 8], |_, _| true);
                assert!(packet.iter().all(|h| h.map(|h| (h.index, h.t)) == expected), "{n} triangles, ray {k}");
            }
        }
        // The same tree on one thread or three.
        let tris = soup(50_000);
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let three = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
        assert!(tree(&one.install(|| fast(&tris))) == tree(&three.install(|| fast(&tris))), "threads change the tree");
        // Triangles on top of each other (one code: the ranges halve), and some not finite
        // (left out, as the SAH build leaves them).
        let mut heap = vec![soup(1)[0]; 1000];
        heap[500] = [Vec3::NAN; 3];
        heap[7] = [Vec3::INFINITY, Vec3::ZERO, Vec3::ONE];
        let bvh = fast(&heap);
        let mut seen = vec![0u32; heap.len()];
        check(&bvh, &heap, bvh.root, Vec3::NEG_INFINITY, Vec3::INFINITY, &mut seen);
        assert_eq!(seen.iter().filter(|&&k| k == 1).count(), 998);
        assert_eq!((seen[500], seen[7]), (0, 0), "triangles not finite are left out");
        assert!(fast(&[[Vec3::NAN; 3]; 3]).is_empty() && fast(&[]).is_empty());
    }

    #[test]
    fn a_tree_built_in_parallel_holds_every_triangle_once_inside_its_boxes() {
        // Past build::PARALLEL (32K): the top of the tree is built on several threads.
        let n = 100_000;
        let tris = soup(n);
        let bvh = build(&tris);
        let mut seen = vec![0u32; n as usize];
        check(&bvh, &tris, bvh.root, Vec3::NEG_INFINITY, Vec3::INFINITY, &mut seen);
        assert!(seen.iter().all(|&k| k == 1), "every triangle in exactly one leaf");
        for k in 0..100 {
            let o = Vec3A::new(random(k * 3 + 50_000), random(k * 3 + 50_001), 2.0);
            let ray = Ray::new(o, Vec3A::NEG_Z, 0.0, f32::INFINITY);
            assert_eq!(bvh.closest(&ray, |_, _| true).map(|h| (h.index, h.t)), brute(&tris, &ray), "ray {k}");
        }
        // The same tree, bit for bit, on one thread or three (the splits made ahead in
        // parallel depend on the ranges alone), so that every node of a cluster traces the same.
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            assert!(tree(&pool.install(|| build(&tris))) == tree(&bvh), "{threads} threads build another tree");
        }
    }

    #[test]
    fn every_walk_tests_both_blocks_of_a_two_block_leaf() {
        // Heaps of eight nearly stacked small triangles, scattered: the build keeps many heaps
        // as leaves of two blocks (`build::as_node`).
        let tris: Vec<Triangle> = (0..1600u32)
            .map(|i| {
                let heap = i / 8;
                let at = Vec3::new(random(heap * 3 + 1), random(heap * 3 + 2), random(heap * 3 + 3));
                let d = 0.002 * (i % 8) as f32;
                [at + Vec3::new(d, 0.0, 0.0), at + Vec3::new(0.03, d, 0.0), at + Vec3::new(0.0, 0.03, d)]
            })
            .collect();
        let bvh = build(&tris);
        let mut seen = vec![0u32; tris.len()];
        check(&bvh, &tris, bvh.root, Vec3::NEG_INFINITY, Vec3::INFINITY, &mut seen);
        assert!(seen.iter().all(|&k| k == 1), "every triangle in exactly one leaf");
        let two = bvh.nodes.iter().flat_map(|n| n.child).filter(|&c| c != EMPTY && c & LEAF != 0);
        let two = two.filter(|&c| bvh.leaf(c).len() == 2).count();
        assert!(two > 20, "only {two} leaves of two blocks");
        let (mut hits, mut rays) = (0, Vec::new());
        for k in 0..800u32 {
            let o = Vec3A::new(random(k * 5 + 20_000), random(k * 5 + 20_001), 2.0);
            let target = Vec3A::new(random(k * 5 + 20_002), random(k * 5 + 20_003), 0.0) * 1.1;
            let ray = Ray::new(o, (target - o).normalize(), 0.0, f32::INFINITY);
            let want = brute(&tris, &ray);
            hits += want.is_some() as u32;
            assert_eq!(bvh.closest(&ray, |_, _| true).map(|h| (h.index, h.t)), want, "ray {k}");
            assert_eq!(bvh.occluded(&ray), want.is_some(), "ray {k}");
            let mut all = 0;
            bvh.each_hit(&ray, |_, _| all += 1);
            let every = (0..tris.len()).filter(|&i| brute(&tris[i..=i], &ray).is_some()).count();
            assert_eq!(all, every, "ray {k}: every hit");
            let hidden = bvh.occluded_from(o, &[ray.direction; BUNDLE], f32::INFINITY, 0);
            assert_eq!(hidden, if want.is_some() { (1 << BUNDLE) - 1 } else { 0 }, "ray {k}");
            rays.push((ray, want));
        }
        for packet in rays.chunks_exact(8) {
            let found = bvh.packet_hits(&std::array::from_fn::<_, 8, _>(|j| packet[j].0), |_, _| true);
            for (got, (_, want)) in found.iter().zip(packet) {
                assert_eq!(got.map(|h| (h.index, h.t)), *want);
            }
        }
        assert!(hits > 100, "only {hits} rays hit");
    }

    #[test]
    fn degenerate_and_broken_triangles_build_and_trace_without_trouble() {
        // A thousand copies of one triangle: every centroid in one place.
        let one = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let bvh = build(&vec![one; 1000]);
        let ray = Ray::new(Vec3A::new(0.2, 0.2, 1.0), Vec3A::NEG_Z, 0.0, f32::INFINITY);
        assert!(bvh.closest(&ray, |_, _| true).is_some());
        let mut n = 0;
        bvh.each_hit(&ray, |_, _| n += 1);
        assert_eq!(n, 1000);
        // NaN and infinite corners are never hit, and do not hide the triangles around them.
        let mut tris = soup(300);
        for (k, bad) in [Vec3::NAN, Vec3::INFINITY, Vec3::NEG_INFINITY].into_iter().enumerate() {
            tris[7 + 50 * k][1] = bad;
            tris[299 - k][0] = bad;
            tris[100 + k][2] = bad;
        }
        let bvh = build(&tris);
        for k in 0..300 {
            let o = Vec3A::new(random(k * 3 + 9_000), random(k * 3 + 9_001), 2.0);
            let ray = Ray::new(o, Vec3A::NEG_Z, 0.0, f32::INFINITY);
            assert_eq!(bvh.closest(&ray, |_, _| true).map(|h| (h.index, h.t)), brute(&tris, &ray), "ray {k}");
        }
        // Nothing but broken triangles: an empty tree.
        let bvh = build(&[[Vec3::NAN; 3]; 3]);
        assert!(bvh.closest(&ray, |_, _| true).is_none());
    }

    #[test]
    fn the_wide_box_test_finds_what_the_baseline_finds_bit_for_bit() {
        #[cfg(target_arch = "x86_64")]
        {
            if !boxes::avx_available() {
                eprintln!("no AVX on this CPU: only the baseline box test runs here");
                return;
            }
            let tris = soup(5000);
            let bvh = build(&tris);
            for k in 0..3000u32 {
                let o = Vec3A::new(random(k * 7 + 1), random(k * 7 + 2), random(k * 7 + 3)) * 1.4 - 0.2;
                // Every fourth ray along an axis (infinite inverse components), the rest anywhere.
                let d = match k % 4 {
                    0 => [Vec3A::X, Vec3A::NEG_Y, Vec3A::Z][(k / 4 % 3) as usize],
                    _ => (Vec3A::new(random(k * 7 + 4), random(k * 7 + 5), random(k * 7 + 6)) - 0.5).normalize(),
                };
                let tmax = if k % 3 == 0 { 0.3 } else { f32::INFINITY };
                let ray = Ray::new(o, d, 0.0, tmax);
                // Node by node: the same boxes met, entered at the same distance.
                let r = Prepared::new(&ray);
                let (sse, avx) = (Sse::new(&r), boxes::Avx::new(&r));
                for node in bvh.nodes.iter().step_by(17) {
                    let (m0, e0) = sse.hit(node, tmax);
                    let (m1, e1) = avx.hit(node, tmax);
                    assert_eq!((m0, e0.map(f32::to_bits)), (m1, e1.map(f32::to_bits)), "ray {k}");
                }
                let baseline = bvh.closest_with::<Sse>(&ray, |_, _| true);
                // SAFETY: AVX checked above.
                let wide = unsafe { bvh.closest_avx(&ray, |_, _| true) };
                assert_eq!(
                    wide.map(|h| (h.index, h.t.to_bits())),
                    baseline.map(|h| (h.index, h.t.to_bits())),
                    "ray {k}"
                );
                assert_eq!(unsafe { bvh.occluded_avx(&ray) }, bvh.occluded_with::<Sse>(&ray), "ray {k}");
                assert_eq!(baseline.is_some(), bvh.occluded_with::<Sse>(&ray), "ray {k}");
            }
        }
    }

    #[test]
    fn accept_skips_triangles_and_the_next_one_behind_counts() {
        // Two parallel squares' triangles facing +z, at z = 0 and z = -1.
        let quad = |z: f32| {
            let v = |x: f32, y: f32| Vec3::new(x, y, z);
            [[v(-1.0, -1.0), v(1.0, -1.0), v(1.0, 1.0)], [v(-1.0, -1.0), v(1.0, 1.0), v(-1.0, 1.0)]]
        };
        let tris: Vec<Triangle> = quad(0.0).into_iter().chain(quad(-1.0)).collect();
        let bvh = build(&tris);
        let ray = Ray::new(Vec3A::new(0.2, -0.3, 5.0), Vec3A::NEG_Z, 0.0, f32::INFINITY);
        let TriHit { index: near, t, normal, .. } = bvh.closest(&ray, |_, _| true).unwrap();
        assert!(normal.normalize().abs_diff_eq(Vec3::Z, 1e-6), "{normal}");
        assert!(near < 2 && (t - 5.0).abs() < 1e-5);
        let TriHit { index: far, t, .. } = bvh.closest(&ray, |i, _| i >= 2).unwrap();
        assert!(far >= 2 && (t - 6.0).abs() < 1e-5);
        // Front faces seen from +z: the normal e1 x e2 is +z, so -det < 0 for a ray going -z.
        bvh.each_hit(&ray, |_, det| assert!(det > 0.0));
    }

    #[test]
    fn a_ray_along_a_shared_edge_hits_one_of_the_two_triangles() {
        let v = |x: f32, y: f32| Vec3::new(x, y, 0.0);
        let tris = [[v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0)], [v(0.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)]];
        let bvh = build(&tris);
        for k in 1..100 {
            let x = k as f32 / 100.0;
            let ray = Ray::new(Vec3A::new(x, x, 1.0), Vec3A::NEG_Z, 0.0, f32::INFINITY);
            assert!(bvh.closest(&ray, |_, _| true).is_some(), "crack at {x}");
        }
    }
}
