//! Sixteen shadow rays through the tree together, each tested alone: the short rays ambient
//! occlusion sends from one point in every direction reach mostly the same nodes, but not the
//! same children of them. A coherent packet (`packet`) tests each child against all its rays,
//! eight tests per node whichever rays are still there (three of eight are, on average, in an
//! AO walk); a ray alone fetches and decides on every node itself. A bundle does both halves
//! right: each node is fetched and its children pushed once for the bundle, and each ray still
//! in it meets the node's eight boxes in one test of its own (`Boxes`), so the work follows the
//! rays that are left. Which rays meet which child is, for each group of eight rays, an 8 x 8
//! matrix of bits, turned around in a few operations (`transpose`) into the rays each child
//! takes along. Sixteen (an AO pass's rays per point) rather than eight: 3-9% faster still,
//! each node serving more rays.

use glam::{Vec3A, Vec4};
use obvhs::ray::Ray;

use super::boxes::{Boxes, Sse};
use super::stack::{Fixed, Pending, Spilling};
use super::{moller_trumbore_from, FromOrigin, Prepared, TriBvh, LEAF, WIDTH};

/// Rays in a bundle (a bit each): two groups of eight.
pub const BUNDLE: usize = 16;

const _: () = assert!(WIDTH == 8 && BUNDLE == 16, "a node's boxes against a group: an 8 x 8 matrix of bits");

/// The 8 x 8 bit matrix `m` (byte `i`, bit `j`: row `i`, column `j`) turned around: byte `j`,
/// bit `i` (Hacker's Delight, 7-3: swapping ever larger blocks about the diagonal).
#[inline(always)]
fn transpose(m: u64) -> u64 {
    let m = (m & 0xAA55_AA55_AA55_AA55) | ((m & 0x00AA_00AA_00AA_00AA) << 7) | ((m >> 7) & 0x00AA_00AA_00AA_00AA);
    let m = (m & 0xCCCC_3333_CCCC_3333) | ((m & 0x0000_CCCC_0000_CCCC) << 14) | ((m >> 14) & 0x0000_CCCC_0000_CCCC);
    (m & 0xF0F0_F0F0_0F0F_0F0F) | ((m & 0x0000_0000_F0F0_F0F0) << 28) | ((m >> 28) & 0x0000_0000_F0F0_F0F0)
}

impl TriBvh {
    /// What the bundle's walk does on reaching `node`: in a `far` tree, starts loading all
    /// its children at once (a node whole, a leaf's first block: a two-block leaf's second
    /// too cost the 1M AO pass 5%), before their boxes are tested, so that the child visited next
    /// misses while the sixteen rays' tests run rather than after them (a 10M tree's AO pass
    /// -17%). In a tree the caches hold that is work for nothing (98K: +7-10%), and only the
    /// children pushed for later are loaded (`pushed`). The camera rays' packet walk loses
    /// with it even at 1M (+8%): a coherent packet meets few of a node's children, and the
    /// others' loads only take bandwidth.
    #[inline(always)]
    fn reached(&self, node: &super::Node) {
        if self.far {
            for &c in &node.child {
                if c != super::EMPTY {
                    self.prefetch_first(c);
                }
            }
        }
    }

    /// What the bundle's walk does on pushing child `c` to come back to later (see `reached`).
    #[inline(always)]
    fn pushed(&self, c: u32) {
        if !self.far {
            self.prefetch_child(c);
        }
    }

    /// Which of the bundle's rays (bit per ray), from `origin` along `directions` within
    /// [0, tmax], meet a triangle, as `occluded` finds for each alone (the same box and
    /// triangle tests, bit for bit). Rays already known to be hidden (bits of `known`, from
    /// another tree) are not traced and are set in the answer.
    #[inline]
    pub fn occluded_from(&self, origin: Vec3A, directions: &[Vec3A; BUNDLE], tmax: f32, known: u32) -> u32 {
        let all = (1u32 << BUNDLE) - 1;
        if self.is_empty() || known & all == all {
            return known;
        }
        let rays = directions.map(|d| super::ray(origin, d, 0.0, tmax));
        #[cfg(target_arch = "x86_64")]
        if super::boxes::avx_available() {
            // SAFETY: the CPU has AVX (checked just now).
            return unsafe { self.occluded_from_avx(&rays, known) };
        }
        self.bundle_with::<Sse>(&rays, known)
    }

    /// `occluded_from`, the whole walk compiled for AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn occluded_from_avx(&self, rays: &[Ray; BUNDLE], known: u32) -> u32 {
        self.bundle_with::<super::boxes::Avx>(rays, known)
    }

    #[inline(always)]
    fn bundle_with<B: Boxes>(&self, rays: &[Ray; BUNDLE], known: u32) -> u32 {
        if self.shallow {
            self.bundle_on::<B, Fixed<_>>(rays, known)
        } else {
            self.bundle_on::<B, Spilling<_>>(rays, known)
        }
    }

    /// The bundle's walk (its rays all from one point, over one [tmin, tmax], as
    /// `occluded_from` makes them): entries on the stack `S` are a subtree and the rays (bits)
    /// that meet its box; a ray leaves the bundle at its first hit, and the walk ends when all
    /// have. What the rays' common origin gives (a node's planes less it, a leaf's
    /// `FromOrigin`) is worked out once per visit.
    #[inline(always)]
    fn bundle_on<B: Boxes, S: Pending<(u32, u32)>>(&self, rays: &[Ray; BUNDLE], known: u32) -> u32 {
        let all = (1u32 << BUNDLE) - 1;
        let mut hidden = known & all;
        let prepared: [Prepared; BUNDLE] = std::array::from_fn(|r| Prepared::new(&rays[r]));
        let boxes: [B; BUNDLE] = std::array::from_fn(|r| B::new(&prepared[r]));
        let (origin, tmin, tmax) = (&prepared[0].origin, Vec4::splat(rays[0].tmin), rays[0].tmax);
        let mut stack = S::new();
        let mut cur = (self.root, all);
        loop {
            let mut active = cur.1 & !hidden;
            if active != 0 {
                if cur.0 & LEAF == 0 {
                    let node = &self.nodes[cur.0 as usize];
                    self.reached(node);
                    let relative = boxes[0].relative(node);
                    // Row r of group g: the children ray 8g + r meets; `any`: those some ray
                    // meets.
                    let (mut rows, mut any) = ([0u64; 2], 0u32);
                    while active != 0 {
                        let r = active.trailing_zeros() as usize;
                        active &= active - 1;
                        let met = boxes[r].hit_relative(&relative, tmax);
                        rows[r / 8] |= (met as u64) << (8 * (r % 8));
                        any |= met;
                    }
                    // Unused slots' boxes are not boxes (`Node::occupied`).
                    any &= node.occupied;
                    if any != 0 {
                        // Column k: the rays that meet child k.
                        let columns = rows.map(transpose);
                        let take = |k: u32| {
                            let group = |g: usize| (columns[g] >> (8 * k)) as u32 & 0xff;
                            (node.child[k as usize], group(0) | group(1) << 8)
                        };
                        let k = any.trailing_zeros();
                        any &= any - 1;
                        let first = take(k);
                        while any != 0 {
                            let k = any.trailing_zeros();
                            any &= any - 1;
                            let entry = take(k);
                            self.pushed(entry.0);
                            stack.push(entry);
                        }
                        cur = first;
                        continue;
                    }
                } else {
                    let tmax = Vec4::splat(tmax);
                    for tri in self.leaf(cur.0) {
                        let from = FromOrigin::new(origin, &tri.v0, &tri.e1, &tri.e2);
                        let mut open = active;
                        while open != 0 {
                            let r = open.trailing_zeros() as usize;
                            open &= open - 1;
                            let d = &prepared[r].direction;
                            let met = moller_trumbore_from(d, &tri.e1, &tri.e2, &from, tmin, tmax).mask;
                            if met != 0 {
                                hidden |= 1 << r;
                            }
                        }
                        active &= !hidden;
                    }
                    if hidden == all {
                        return all;
                    }
                }
            }
            match stack.pop() {
                Some(next) => cur = next,
                None => return hidden,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{random, soup};
    use super::*;
    use crate::sampling::hash;

    #[test]
    fn the_transpose_turns_every_bit_about_the_diagonal() {
        for seed in 0..200u32 {
            let m = (hash(&[seed, 1]) as u64) << 32 | hash(&[seed, 2]) as u64;
            let t = transpose(m);
            for (i, j) in (0..8).flat_map(|i| (0..8).map(move |j| (i, j))) {
                assert_eq!(m >> (8 * i + j) & 1, t >> (8 * j + i) & 1, "matrix {m:#x}, bit ({i}, {j})");
            }
            assert_eq!(transpose(t), m);
        }
    }

    #[test]
    fn a_bundle_finds_what_each_ray_finds_alone() {
        // A soup of small triangles, and bundles of rays from points among them in every
        // direction, as ambient occlusion sends them: short, long, along the axes.
        let tris = soup(4000);
        let mut bvh = TriBvh::build(tris.len(), |i| tris[i]);
        let (mut hidden, mut open) = (0, 0);
        // Both stacks, and both ways of prefetching (a walk of a small tree is never `far`).
        for (spilling, far) in [(false, false), (true, false), (false, true)] {
            (bvh.shallow, bvh.far) = (!spilling, far);
            for b in 0..600u32 {
                let o = Vec3A::new(random(b * 3 + 70_000), random(b * 3 + 70_001), random(b * 3 + 70_002));
                let reach = [0.02, 0.1, 0.5, f32::INFINITY][b as usize % 4];
                let directions: [Vec3A; BUNDLE] = std::array::from_fn(|r| {
                    let s = b * BUNDLE as u32 + r as u32;
                    match s % 11 {
                        0 => Vec3A::NEG_Y,
                        _ => (Vec3A::new(random(s * 3 + 1), random(s * 3 + 2), random(s * 3 + 3)) - 0.5).normalize(),
                    }
                });
                let rays = directions.map(|d| super::super::ray(o, d, 0.0, reach));
                let alone = rays.iter().enumerate().fold(0, |m, (r, ray)| m | (bvh.occluded(ray) as u32) << r);
                assert_eq!(bvh.occluded_from(o, &directions, reach, 0), alone, "bundle {b}");
                // Rays already known hidden stay so, and the others are found as before.
                let known = hash(&[b]) & hash(&[b, 1]) & 0xffff;
                assert_eq!(
                    bvh.occluded_from(o, &directions, reach, known),
                    alone | known,
                    "bundle {b}, known {known:#x}"
                );
                // The baseline walk, whatever this CPU would choose.
                assert_eq!(bvh.bundle_with::<Sse>(&rays, 0), alone, "bundle {b}, the baseline walk");
                hidden += alone.count_ones();
                open += BUNDLE as u32 - alone.count_ones();
            }
        }
        assert!(hidden > 500 && open > 500, "both outcomes tested: {hidden} hidden, {open} open");
    }
}
