//! Four coherent rays through the tree at once (camera rays of a 2x2 pixel quad): one lane per
//! ray, so a node's box is tested against all four in one SIMD test and the walk's decisions,
//! branch misses and memory latency are paid once for four rays. Coherent rays visit mostly
//! the same nodes; a ray that leaves the group's path is simply masked off.

use glam::{BVec4A, Vec4};
use obvhs::ray::Ray;

use super::{insert_farthest_first, moller_trumbore, Node, Stack, Tri4, TriBvh, TriHit, EMPTY, LEAF, WIDTH};

/// Four rays, one per lane.
struct Rays4 {
    origin: [Vec4; 3],
    direction: [Vec4; 3],
    inverse: [Vec4; 3],
    tmin: Vec4,
}

impl Rays4 {
    fn new(rays: &[Ray; 4]) -> Rays4 {
        let lanes = |f: &dyn Fn(&Ray) -> [f32; 3]| {
            let v = rays.map(|r| f(&r));
            [0, 1, 2].map(|axis| Vec4::new(v[0][axis], v[1][axis], v[2][axis], v[3][axis]))
        };
        Rays4 {
            origin: lanes(&|r| r.origin.into()),
            direction: lanes(&|r| r.direction.into()),
            inverse: lanes(&|r| r.inv_direction.into()),
            tmin: Vec4::from_array(rays.map(|r| r.tmin)),
        }
    }
}

/// Where each ray enters child `k`'s box, and which rays (a lane each) meet it before their
/// `tmax`.
#[inline(always)]
fn hit_box(node: &Node, k: usize, r: &Rays4, tmax: Vec4) -> (BVec4A, Vec4) {
    let slab = |axis: usize| {
        let lo = (Vec4::splat(node.bound(0, axis, k)) - r.origin[axis]) * r.inverse[axis];
        let hi = (Vec4::splat(node.bound(1, axis, k)) - r.origin[axis]) * r.inverse[axis];
        (lo.min(hi), lo.max(hi))
    };
    let (x, y, z) = (slab(0), slab(1), slab(2));
    let tnear = x.0.max(y.0).max(z.0.max(r.tmin));
    let tfar = x.1.min(y.1).min(z.1.min(tmax)) * (1.0 + 4.0 * f32::EPSILON);
    (tnear.cmple(tfar), tnear)
}

/// Triangle `k` of a leaf against the four rays: which rays hit it before their `tmax` (bit
/// per ray), where, and the determinants (see `moller_trumbore`).
#[inline(always)]
fn hit_triangle(tri: &Tri4, k: usize, r: &Rays4, tmax: Vec4) -> (u32, Vec4, Vec4) {
    let lane = |v: &[Vec4; 3]| [Vec4::splat(v[0][k]), Vec4::splat(v[1][k]), Vec4::splat(v[2][k])];
    moller_trumbore(&r.origin, &r.direction, &lane(&tri.v0), &lane(&tri.e1), &lane(&tri.e2), r.tmin, tmax)
}

impl TriBvh {
    /// The closest hit of each of four rays, as `closest` would find it for each alone.
    #[inline]
    pub fn closest4(&self, rays: &[Ray; 4], accept: impl FnMut(u32, f32) -> bool) -> [Option<TriHit>; 4] {
        #[cfg(target_arch = "x86_64")]
        if super::boxes::avx_available() {
            // SAFETY: the CPU has AVX (checked just now).
            return unsafe { self.closest4_avx(rays, accept) };
        }
        self.closest4_with(rays, accept)
    }

    /// `closest4` compiled for AVX: the same operations (so the same hits), three-operand and
    /// with a box's bounds broadcast straight from memory.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn closest4_avx(&self, rays: &[Ray; 4], accept: impl FnMut(u32, f32) -> bool) -> [Option<TriHit>; 4] {
        self.closest4_with(rays, accept)
    }

    #[inline(always)]
    fn closest4_with(&self, rays: &[Ray; 4], mut accept: impl FnMut(u32, f32) -> bool) -> [Option<TriHit>; 4] {
        let mut best = [None; 4];
        if self.root == EMPTY {
            return best;
        }
        let r = Rays4::new(rays);
        let mut tmax = Vec4::from_array(rays.map(|r| r.tmax));
        // Entries: a subtree and where each ray enters its box (infinity: the ray missed it).
        let mut stack: Stack<(u32, Vec4)> = Stack::new();
        let mut cur = (self.root, Vec4::splat(f32::NEG_INFINITY));
        loop {
            let active = cur.1.cmple(tmax);
            if active.any() {
                if cur.0 & LEAF == 0 {
                    let node = &self.nodes[cur.0 as usize];
                    // The children some active ray meets, nearest (for the nearest ray) last.
                    // All the boxes first, then the children met: a branch per child on
                    // whether any ray met it mispredicted at nearly every child.
                    let mut entered = [Vec4::INFINITY; WIDTH];
                    let mut met = 0u32;
                    for (k, entry) in entered.iter_mut().enumerate() {
                        // Children fill the node from the first slot: an empty one ends them.
                        if node.child[k] == EMPTY {
                            break;
                        }
                        let (mask, tnear) = hit_box(node, k, &r, tmax);
                        let mask = mask & active;
                        *entry = Vec4::select(mask, tnear, Vec4::INFINITY);
                        met |= (mask.any() as u32) << k;
                    }
                    let mut hits = [(0.0f32, (0u32, Vec4::ZERO)); WIDTH];
                    let mut n = 0;
                    while met != 0 {
                        let k = met.trailing_zeros() as usize;
                        met &= met - 1;
                        insert_farthest_first(&mut hits, n, (entered[k].min_element(), (node.child[k], entered[k])));
                        n += 1;
                    }
                    if n > 0 {
                        for &(_, entry) in &hits[..n - 1] {
                            self.prefetch_child(entry.0);
                            stack.push(entry);
                        }
                        cur = hits[n - 1].1;
                        continue;
                    }
                } else {
                    let tri = &self.leaves[(cur.0 & !LEAF) as usize];
                    for k in 0..4 {
                        if tri.id[k] == EMPTY {
                            break;
                        }
                        let (mut mask, t, det) = hit_triangle(tri, k, &r, tmax);
                        mask &= active.bitmask();
                        if mask == 0 {
                            continue;
                        }
                        let (ts, dets) = (t.to_array(), det.to_array());
                        let mut bound = tmax.to_array();
                        while mask != 0 {
                            let lane = mask.trailing_zeros() as usize;
                            mask &= mask - 1;
                            if ts[lane] < bound[lane] && accept(tri.id[k], dets[lane]) {
                                bound[lane] = ts[lane];
                                best[lane] = Some(tri.hit(k, ts[lane]));
                            }
                        }
                        tmax = Vec4::from_array(bound);
                    }
                }
            }
            match stack.pop() {
                Some(next) => cur = next,
                None => return best,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::{Vec3, Vec3A};

    use super::*;
    use crate::sampling::hash;

    fn random(seed: u32) -> f32 {
        hash(&[seed]) as f32 / u32::MAX as f32
    }

    #[test]
    fn four_rays_at_once_find_what_each_finds_alone() {
        let tris: Vec<[Vec3; 3]> = (0..3000)
            .map(|i| {
                let c = Vec3::new(random(i * 9), random(i * 9 + 1), random(i * 9 + 2));
                [1, 2, 3].map(|k| {
                    c + 0.04 * Vec3::new(random(i * 9 + 3 * k), random(i * 9 + 3 * k + 1), random(i * 9 + 3 * k + 2))
                })
            })
            .collect();
        let bvh = TriBvh::build(tris.len(), |i| tris[i]);
        for k in 0..400u32 {
            // A quad of nearly parallel rays, and now and then one that goes its own way.
            let o = Vec3A::new(random(k * 5 + 50_000), random(k * 5 + 50_001), 2.0);
            let rays: [Ray; 4] = std::array::from_fn(|j| {
                let spread = if k % 7 == 0 { 0.5 } else { 0.002 };
                let target = Vec3A::new(random(k * 5 + 50_002) + spread * j as f32, random(k * 5 + 50_003), 0.0);
                let tmax = if j == 3 && k % 3 == 0 { 1.9 } else { f32::INFINITY };
                Ray::new(o, (target - o).normalize(), 0.0, tmax)
            });
            let alone = rays.map(|r| bvh.closest(&r, |_, _| true));
            assert_eq!(bvh.closest4(&rays, |_, _| true), alone, "quad {k}");
            // The baseline walk, whatever this CPU would choose: the same hits, bit for bit.
            let bits = |hits: [Option<TriHit>; 4]| hits.map(|h| h.map(|h| (h.index, h.t.to_bits())));
            assert_eq!(bits(bvh.closest4_with(&rays, |_, _| true)), bits(alone), "quad {k}, baseline");
            // With a filter (odd triangles only) too.
            let alone = rays.map(|r| bvh.closest(&r, |i, _| i % 2 == 1));
            assert_eq!(bvh.closest4(&rays, |i, _| i % 2 == 1), alone, "quad {k}, filtered");
        }
    }
}
