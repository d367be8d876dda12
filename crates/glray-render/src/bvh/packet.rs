//! Coherent rays through the tree at once (camera rays of neighbouring pixels): one lane per
//! ray, so a node's box is tested against all of them in one SIMD test and the walk's
//! decisions, branch misses and memory latency are paid once for the packet. Coherent rays
//! visit mostly the same nodes; a ray that leaves the group's path is simply masked off.
//! Packets of four (a 2x2 quad, `Vec4`) everywhere; of eight (4x2, `F8`) where the CPU has
//! AVX, else as two of four. Where the eight rays' directions agree in sign, a node's boxes
//! are tested once for all of them (`frustum`) rather than once per child for each ray.
//! Every walk finds the hits each ray finds alone.

use glam::Vec4;
use obvhs::ray::Ray;

#[cfg(target_arch = "x86_64")]
use super::boxes::avx_available;
use super::boxes::WIDEN;
#[cfg(target_arch = "x86_64")]
use super::frustum::{leaves, Frustum};
use super::lanes::Lanes;
#[cfg(target_arch = "x86_64")]
use super::lanes::F8;
use super::node::Planes;
use super::stack::{Fixed, Pending, Spilling};
use super::{moller_trumbore, Crossing, Tri4, TriBvh, TriHit, EMPTY, LEAF, WIDTH};

/// `N` rays, one per lane.
struct Rays<L> {
    origin: [L; 3],
    direction: [L; 3],
    inverse: [L; 3],
    tmin: L,
    /// Per axis, 1 when every ray's direction is negative along it (the box's maximum is met
    /// first), 0 when none is: valid when `agree`.
    near: [usize; 3],
    /// Whether the rays' directions have the same signs on every axis (adjacent camera rays
    /// nearly always do).
    agree: bool,
}

impl<L> Rays<L> {
    // No closures here or below: a closure over AVX lanes is compiled without AVX and not
    // inlined into the AVX walk (each lane operation became a call).
    #[inline(always)]
    fn new<const N: usize>(rays: &[Ray; N]) -> Rays<L>
    where
        L: Lanes<N>,
    {
        let (mut o, mut d, mut i, mut tmin) = ([[0.0; N]; 3], [[0.0; N]; 3], [[0.0; N]; 3], [0.0; N]);
        for (k, r) in rays.iter().enumerate() {
            for axis in 0..3 {
                o[axis][k] = r.origin[axis];
                d[axis][k] = r.direction[axis];
                i[axis][k] = r.inv_direction[axis];
            }
            tmin[k] = r.tmin;
        }
        let negative = |axis: usize| rays.iter().filter(|r| r.inv_direction[axis] < 0.0).count();
        let counts = [negative(0), negative(1), negative(2)];
        Rays {
            near: counts.map(|c| (c == N) as usize),
            agree: counts.iter().all(|&c| c == 0 || c == N),
            origin: [L::from_array(o[0]), L::from_array(o[1]), L::from_array(o[2])],
            direction: [L::from_array(d[0]), L::from_array(d[1]), L::from_array(d[2])],
            inverse: [L::from_array(i[0]), L::from_array(i[1]), L::from_array(i[2])],
            tmin: L::from_array(tmin),
        }
    }
}

/// Where each ray enters child `k`'s box, and which rays (a lane each) meet it before their
/// `tmax`.
#[inline(always)]
fn hit_box<L: Lanes<N>, const N: usize, const AGREE: bool>(
    planes: &Planes,
    k: usize,
    r: &Rays<L>,
    tmax: L,
) -> (L::Mask, L) {
    let (x, y, z) = (
        slab::<L, N, AGREE>(planes, k, r, 0),
        slab::<L, N, AGREE>(planes, k, r, 1),
        slab::<L, N, AGREE>(planes, k, r, 2),
    );
    let tnear = x.0.max(y.0).max(z.0.max(r.tmin));
    let tfar = x.1.min(y.1).min(z.1.min(tmax)) * L::splat(WIDEN);
    (tnear.cmple(tfar), tnear)
}

/// Where the rays cross child `k`'s two planes across `axis`: (nearer, farther). With `AGREE`
/// (every ray's direction has the same sign on every axis: `Rays::agree`), which plane is
/// nearer is known for all of them, and no min and max are needed: the same values, since a
/// box's planes in order stay in order when multiplied by a positive reciprocal and swap with
/// a negative one (1M camera rays -4%). A function, not a closure: a closure over AVX lanes is
/// not inlined into the AVX walk.
#[inline(always)]
fn slab<L: Lanes<N>, const N: usize, const AGREE: bool>(planes: &Planes, k: usize, r: &Rays<L>, axis: usize) -> (L, L) {
    if AGREE {
        let near = (bound::<L, N>(planes, r.near[axis], axis, k) - r.origin[axis]) * r.inverse[axis];
        let far = (bound::<L, N>(planes, 1 - r.near[axis], axis, k) - r.origin[axis]) * r.inverse[axis];
        return (near, far);
    }
    let lo = (bound::<L, N>(planes, 0, axis, k) - r.origin[axis]) * r.inverse[axis];
    let hi = (bound::<L, N>(planes, 1, axis, k) - r.origin[axis]) * r.inverse[axis];
    (lo.min(hi), lo.max(hi))
}

/// Side `side` of child `k`'s box along `axis`, in every lane.
#[inline(always)]
fn bound<L: Lanes<N>, const N: usize>(planes: &Planes, side: usize, axis: usize, k: usize) -> L {
    L::splat(super::lane(&planes[side][axis][k / 4], k % 4))
}

/// Triangle `k` of a leaf against the rays: which rays hit it before their `tmax` (bit per
/// ray), where, and the determinants (see `moller_trumbore`).
#[inline(always)]
fn hit_triangle<L: Lanes<N>, const N: usize>(tri: &Tri4, k: usize, r: &Rays<L>, tmax: L) -> Crossing<L> {
    let (v0, e1, e2) = (lane(&tri.v0, k), lane(&tri.e1, k), lane(&tri.e2, k));
    moller_trumbore(&r.origin, &r.direction, &v0, &e1, &e2, r.tmin, tmax)
}

/// Lane `k` of each axis of `v`, in every lane.
#[inline(always)]
fn lane<L: Lanes<N>, const N: usize>(v: &[Vec4; 3], k: usize) -> [L; 3] {
    [L::splat(super::lane(&v[0], k)), L::splat(super::lane(&v[1], k)), L::splat(super::lane(&v[2], k))]
}

impl TriBvh {
    /// The closest hit of each of four rays, as `closest` would find it for each alone.
    #[inline]
    pub fn closest4(&self, rays: &[Ray; 4], best: &mut [Option<TriHit>; 4], accept: impl FnMut(u32, f32) -> bool) {
        #[cfg(target_arch = "x86_64")]
        if avx_available() {
            // SAFETY: the CPU has AVX (checked just now).
            return unsafe { self.closest4_avx(rays, best, accept) };
        }
        self.packet::<Vec4, 4>(rays, best, accept)
    }

    /// The closest hit of each of `N` rays (a multiple of four), as `closest` would find it for
    /// each alone, into `best` (None where a ray hits nothing): eight at once where `N` is
    /// eight and the CPU has AVX, else four by four. With `frustum`, eight rays whose
    /// directions agree in sign test each node once for all of them (worth it where the
    /// tree's triangles are not much smaller than the pixels between the rays: see
    /// `scene::FINE`). (Written in place: arrays of hits returned and copied were a tenth of
    /// a 98K frame's camera rays.)
    #[inline]
    pub fn closest_packet<const N: usize>(
        &self,
        rays: &[Ray; N],
        best: &mut [Option<TriHit>; N],
        frustum: bool,
        mut accept: impl FnMut(u32, f32) -> bool,
    ) {
        const { assert!(N % 4 == 0, "packets of fours") };
        #[cfg(target_arch = "x86_64")]
        if let (true, Ok(eight), Ok(out)) =
            (avx_available(), <&[Ray; 8]>::try_from(&rays[..]), <&mut [Option<TriHit>; 8]>::try_from(&mut best[..]))
        {
            // SAFETY: the CPU has AVX (checked just now).
            return unsafe { self.closest8_avx(eight, out, frustum, accept) };
        }
        for (rays, out) in rays.chunks_exact(4).zip(best.chunks_exact_mut(4)) {
            let four: &[Ray; 4] = rays.try_into().expect("chunks of four");
            self.closest4(four, out.try_into().expect("chunks of four"), &mut accept);
        }
    }

    /// `closest4` compiled for AVX: the same operations (so the same hits), three-operand and
    /// with a box's bounds broadcast straight from memory.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn closest4_avx(
        &self,
        rays: &[Ray; 4],
        best: &mut [Option<TriHit>; 4],
        accept: impl FnMut(u32, f32) -> bool,
    ) {
        self.packet::<Vec4, 4>(rays, best, accept)
    }

    /// `closest_packet` of eight rays in eight AVX lanes: with `frustum`, a node tested once
    /// for all of them where their directions agree in sign, else once per child for each.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn closest8_avx(
        &self,
        rays: &[Ray; 8],
        best: &mut [Option<TriHit>; 8],
        frustum: bool,
        accept: impl FnMut(u32, f32) -> bool,
    ) {
        *best = [None; 8];
        if self.is_empty() {
            return;
        }
        let r = Rays::<F8>::new(rays);
        if !(frustum && r.agree) {
            return self.packet_of::<F8, 8>(rays, r, best, accept);
        }
        let f = Frustum::new(rays, r.near);
        if self.shallow {
            self.frustum_on::<Fixed<_>>(rays, r, f, best, accept)
        } else {
            self.frustum_on::<Spilling<_>>(rays, r, f, best, accept)
        }
    }

    /// The walk of eight rays whose directions agree in sign, each node's boxes tested once
    /// for all of them (`Frustum::hit`). A leaf child is tested ray by ray as well, so that a
    /// leaf none of the rays meets is not visited and a leaf's triangles are tested for the
    /// rays that meet it (at 10M, where triangles are a tenth of a pixel, the packet's bounds
    /// meet many leaves its rays pass by). Its pending entries: a subtree, the earliest any ray
    /// enters it, and the rays that may meet it (a bit each).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn frustum_on<S: Pending<(u32, f32, u32)>>(
        &self,
        rays: &[Ray; 8],
        r: Rays<F8>,
        f: Frustum,
        best: &mut [Option<TriHit>; 8],
        mut accept: impl FnMut(u32, f32) -> bool,
    ) {
        const ALL: u32 = 0xff;
        let mut tmax = F8::from_array(rays.map(|r| r.tmax));
        // The bound the packet's node tests use: the largest of the rays' tmax.
        let mut farthest = tmax.max_element();
        let mut stack = S::new();
        let mut cur = (self.root, f32::NEG_INFINITY, ALL);
        loop {
            if cur.1 <= farthest {
                if cur.0 & LEAF == 0 {
                    let node = &self.nodes[cur.0 as usize];
                    let (mut met, entered) = f.hit(node, farthest);
                    let mut leaves = met & leaves(node);
                    let mut lanes = [ALL; WIDTH];
                    if leaves != 0 {
                        let planes = F8::planes(node);
                        while leaves != 0 {
                            let k = leaves.trailing_zeros() as usize;
                            leaves &= leaves - 1;
                            lanes[k] = F8::bitmask(hit_box::<F8, 8, true>(&planes, k, &r, tmax).0);
                            if lanes[k] == 0 {
                                met &= !(1 << k);
                            }
                        }
                    }
                    if met != 0 {
                        let entry = |k: usize| (entered[k], (node.child[k], entered[k], lanes[k]));
                        cur = self.nearest_pushing_rest(met, &mut stack, entry, |e| e.0);
                        continue;
                    }
                } else {
                    let shortened = self.leaf_hits(cur.0, cur.2, rays, &r, &mut tmax, best, &mut accept);
                    if shortened {
                        farthest = tmax.max_element();
                    }
                }
            }
            match stack.pop() {
                Some(next) => cur = next,
                None => return,
            }
        }
    }

    /// The packet walk, `N` rays in the `N` lanes of `L`, each ray's closest hit into `best`.
    #[inline(always)]
    fn packet<L: Lanes<N>, const N: usize>(
        &self,
        rays: &[Ray; N],
        best: &mut [Option<TriHit>; N],
        accept: impl FnMut(u32, f32) -> bool,
    ) {
        *best = [None; N];
        if !self.is_empty() {
            self.packet_of(rays, Rays::<L>::new(rays), best, accept);
        }
    }

    /// `packet` of rays made ready (`r`), in a tree that is not empty.
    #[inline(always)]
    fn packet_of<L: Lanes<N>, const N: usize>(
        &self,
        rays: &[Ray; N],
        r: Rays<L>,
        best: &mut [Option<TriHit>; N],
        accept: impl FnMut(u32, f32) -> bool,
    ) {
        match (self.shallow, r.agree) {
            (true, true) => self.packet_on::<L, N, Fixed<_>, true>(rays, r, best, accept),
            (true, false) => self.packet_on::<L, N, Fixed<_>, false>(rays, r, best, accept),
            (false, true) => self.packet_on::<L, N, Spilling<_>, true>(rays, r, best, accept),
            (false, false) => self.packet_on::<L, N, Spilling<_>, false>(rays, r, best, accept),
        }
    }

    /// `packet`, keeping its pending subtrees on a stack `S`.
    #[inline(always)]
    fn packet_on<L: Lanes<N>, const N: usize, S: Pending<(u32, L)>, const AGREE: bool>(
        &self,
        rays: &[Ray; N],
        r: Rays<L>,
        best: &mut [Option<TriHit>; N],
        mut accept: impl FnMut(u32, f32) -> bool,
    ) {
        let mut tmax = [0.0; N];
        for (t, r) in tmax.iter_mut().zip(rays) {
            *t = r.tmax;
        }
        let mut tmax = L::from_array(tmax);
        let infinity = L::splat(f32::INFINITY);
        // Entries: a subtree and where each ray enters its box (infinity: the ray missed it).
        let mut stack = S::new();
        let mut cur = (self.root, L::splat(f32::NEG_INFINITY));
        loop {
            let active = cur.1.cmple(tmax);
            let active_bits = L::bitmask(active);
            if active_bits != 0 {
                if cur.0 & LEAF == 0 {
                    let node = &self.nodes[cur.0 as usize];
                    let planes = L::planes(node);
                    // All the boxes first, then the children met, nearest (for the nearest
                    // ray) last: a branch per child on whether any ray met it mispredicted at
                    // nearly every child.
                    let mut entered = [infinity; WIDTH];
                    let mut met = 0u32;
                    for (k, entry) in entered.iter_mut().enumerate() {
                        // Children fill the node from the first slot: an empty one ends them.
                        if node.child[k] == EMPTY {
                            break;
                        }
                        let (mask, tnear) = hit_box::<L, N, AGREE>(&planes, k, &r, tmax);
                        let mask = mask & active;
                        *entry = L::select(mask, tnear, infinity);
                        met |= ((L::bitmask(mask) != 0) as u32) << k;
                    }
                    if met != 0 {
                        let entry = |k: usize| (entered[k].min_element(), (node.child[k], entered[k]));
                        cur = self.nearest_pushing_rest(met, &mut stack, entry, |e| e.0);
                        continue;
                    }
                } else {
                    self.leaf_hits(cur.0, active_bits, rays, &r, &mut tmax, best, &mut accept);
                }
            }
            match stack.pop() {
                Some(next) => cur = next,
                None => return,
            }
        }
    }

    /// Leaf `leaf`'s triangles against the rays in `lanes` (a bit each): a closer hit that
    /// `accept` takes goes into `best` and its distance into `tmax`. Whether any did.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn leaf_hits<L: Lanes<N>, const N: usize>(
        &self,
        leaf: u32,
        lanes: u32,
        rays: &[Ray; N],
        r: &Rays<L>,
        tmax: &mut L,
        best: &mut [Option<TriHit>; N],
        accept: &mut impl FnMut(u32, f32) -> bool,
    ) -> bool {
        let mut shortened = false;
        for tri in self.leaf(leaf) {
            for k in 0..4 {
                if tri.id[k] == EMPTY {
                    break;
                }
                let c = hit_triangle(tri, k, r, *tmax);
                let mut mask = c.mask & lanes;
                if mask == 0 {
                    continue;
                }
                let (ts, dets) = (c.t.to_array(), c.det.to_array());
                let mut bound = tmax.to_array();
                while mask != 0 {
                    let lane = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if ts[lane] < bound[lane] && accept(tri.id[k], dets[lane]) {
                        bound[lane] = ts[lane];
                        best[lane] = Some(tri.hit(k, ts[lane], &rays[lane]));
                        shortened = true;
                    }
                }
                *tmax = L::from_array(bound);
            }
        }
        shortened
    }
}

#[cfg(test)]
impl TriBvh {
    /// `closest_packet`'s hits, returned (with the frustum test, and without it).
    pub(super) fn packet_hits<const N: usize>(
        &self,
        rays: &[Ray; N],
        mut accept: impl FnMut(u32, f32) -> bool,
    ) -> [Option<TriHit>; N] {
        let (mut best, mut apart) = ([None; N], [None; N]);
        self.closest_packet(rays, &mut best, true, &mut accept);
        self.closest_packet(rays, &mut apart, false, &mut accept);
        assert_eq!(best, apart, "the frustum walk and the per-ray walk disagree");
        best
    }

    /// `closest4`'s hits, returned.
    fn quad_hits(&self, rays: &[Ray; 4], accept: impl FnMut(u32, f32) -> bool) -> [Option<TriHit>; 4] {
        let mut best = [None; 4];
        self.closest4(rays, &mut best, accept);
        best
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3A;

    use super::super::tests::random;
    use super::*;

    /// The tree over the shared test soup of small triangles.
    fn soup() -> TriBvh {
        let tris = super::super::tests::soup(3000);
        TriBvh::build(tris.len(), |i| tris[i])
    }

    /// Packet `k` of `N` nearly parallel rays, and now and then one that goes its own way or
    /// ends early.
    fn packet<const N: usize>(k: u32) -> [Ray; N] {
        let o = Vec3A::new(random(k * 5 + 50_000), random(k * 5 + 50_001), 2.0);
        std::array::from_fn(|j| {
            let spread = if k % 7 == 0 { 0.5 } else { 0.002 };
            let target = Vec3A::new(
                random(k * 5 + 50_002) + spread * (j % 4) as f32,
                random(k * 5 + 50_003) + spread * (j / 4) as f32,
                0.0,
            );
            let tmax = if j == 3 && k % 3 == 0 { 1.9 } else { f32::INFINITY };
            Ray::new(o, (target - o).normalize(), 0.0, tmax)
        })
    }

    /// The hits' triangles, distances and weights, bit for bit.
    fn bits<const N: usize>(hits: [Option<TriHit>; N]) -> [Option<[u32; 4]>; N] {
        hits.map(|h| h.map(|h| [h.index, h.t.to_bits(), h.uv.x.to_bits(), h.uv.y.to_bits()]))
    }

    #[test]
    fn four_rays_at_once_find_what_each_finds_alone() {
        let bvh = soup();
        for k in 0..400u32 {
            let rays: [Ray; 4] = packet(k);
            let alone = rays.map(|r| bvh.closest(&r, |_, _| true));
            assert_eq!(bvh.quad_hits(&rays, |_, _| true), alone, "quad {k}");
            // The baseline walk, whatever this CPU would choose: the same hits, bit for bit.
            let mut baseline = [None; 4];
            bvh.packet::<Vec4, 4>(&rays, &mut baseline, |_, _| true);
            assert_eq!(bits(baseline), bits(alone), "quad {k}, baseline");
            // With a filter (odd triangles only) too.
            let alone = rays.map(|r| bvh.closest(&r, |i, _| i % 2 == 1));
            assert_eq!(bvh.quad_hits(&rays, |i, _| i % 2 == 1), alone, "quad {k}, filtered");
        }
    }

    #[test]
    fn eight_rays_at_once_find_what_each_finds_alone_bit_for_bit() {
        let bvh = soup();
        // Both walks: rays whose directions agree in sign on every axis, and rays that do not.
        let mut agree = [0; 2];
        for k in 0..400u32 {
            let rays: [Ray; 8] = packet(k);
            let quad = |q: &[Ray]| Rays::<Vec4>::new(<&[Ray; 4]>::try_from(q).expect("four"));
            let (a, b) = (quad(&rays[..4]), quad(&rays[4..]));
            agree[(a.agree && b.agree && a.near == b.near) as usize] += 1;
            let alone = rays.map(|r| bvh.closest(&r, |_, _| true));
            assert_eq!(bits(bvh.packet_hits(&rays, |_, _| true)), bits(alone), "packet {k}");
            let alone = rays.map(|r| bvh.closest(&r, |i, _| i % 2 == 1));
            assert_eq!(bits(bvh.packet_hits(&rays, |i, _| i % 2 == 1)), bits(alone), "packet {k}, filtered");
        }
        assert!(agree[0] > 20 && agree[1] > 20, "packets whose signs differ, and agree: {agree:?}");
    }

    #[test]
    fn a_packet_finds_the_same_hits_with_the_spilling_stack() {
        let mut bvh = soup();
        let rays: Vec<[Ray; 8]> = (0..400u32).map(packet).collect();
        let fixed: Vec<_> = rays.iter().map(|r| bits(bvh.packet_hits(r, |_, _| true))).collect();
        assert!(bvh.shallow);
        bvh.shallow = false;
        let spilling: Vec<_> = rays.iter().map(|r| bits(bvh.packet_hits(r, |_, _| true))).collect();
        assert_eq!(fixed, spilling);
        assert!(fixed.iter().flatten().any(Option::is_some));
    }
}
