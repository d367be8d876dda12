//! How a walk tests one ray against a node's `WIDTH` (eight) boxes: `Sse`, two groups of four
//! with the x86-64 baseline's (or NEON's) 128-bit vectors, everywhere; `Avx`, all eight at once
//! with 256-bit vectors, on CPUs that have them (checked at run time: the library runs on
//! whatever node loads it). Both do the same IEEE operations in the same order, so they find
//! the same boxes bit for bit: a frame's tiles are the same picture whichever node traced them.

use glam::Vec4;

use super::node::{Node, Planes};
use super::{Prepared, GROUPS, WIDTH};

/// A ray made ready to meet a node's boxes.
pub(super) trait Boxes {
    /// A node's box planes less the origin of the rays that meet it: what rays from one point
    /// (a bundle's) have in common in their slab tests, worked out once for all of them.
    type Relative;
    fn new(ray: &Prepared) -> Self;
    /// Which of the node's boxes the ray meets within [tmin, tmax] (bit per child; unused
    /// slots never), and where it enters each.
    fn hit(&self, node: &Node, tmax: f32) -> (u32, [f32; WIDTH]);
    /// The node's planes less this ray's origin.
    fn relative(&self, node: &Node) -> Self::Relative;
    /// `hit`'s mask, from the node's planes less this ray's origin (`relative` of a ray from
    /// the same point): the same operations on the same values, so the same boxes (unused
    /// slots included: the caller masks them with `Node::occupied`).
    fn hit_relative(&self, relative: &Self::Relative, tmax: f32) -> u32;
}

/// The slab test: per child, the ray's entry (the farthest of its near planes and tmin) and
/// exit (the nearest far plane and tmax), widened by this factor (a few ulps) so that rounding
/// in the slabs cannot lose a box the ray grazes. The packet walk widens by it too.
pub(super) const WIDEN: f32 = 1.0 + 4.0 * f32::EPSILON;

/// 128-bit vectors, four children per test.
pub(super) struct Sse {
    origin: [Vec4; 3],
    inverse: [Vec4; 3],
    near: [usize; 3],
    tmin: Vec4,
}

impl Boxes for Sse {
    type Relative = Planes;

    #[inline(always)]
    fn new(r: &Prepared) -> Sse {
        Sse { origin: r.origin, inverse: r.inverse, near: r.near, tmin: Vec4::splat(r.tmin) }
    }

    #[inline(always)]
    fn relative(&self, node: &Node) -> Self::Relative {
        let planes = node.planes();
        std::array::from_fn(|side| std::array::from_fn(|axis| planes[side][axis].map(|b| b - self.origin[axis])))
    }

    #[inline(always)]
    // `g` picks a group three levels down in `relative`, as `hit` does in the node.
    #[allow(clippy::needless_range_loop)]
    fn hit_relative(&self, relative: &Self::Relative, tmax: f32) -> u32 {
        let mut mask = 0;
        for g in 0..GROUPS {
            let slab = |axis: usize, side: usize| relative[side][axis][g] * self.inverse[axis];
            let near = |axis: usize| slab(axis, self.near[axis]);
            let far = |axis: usize| slab(axis, 1 - self.near[axis]);
            let tnear = near(0).max(near(1)).max(near(2).max(self.tmin));
            let tfar = far(0).min(far(1)).min(far(2).min(Vec4::splat(tmax))) * WIDEN;
            mask |= tnear.cmple(tfar).bitmask() << (4 * g);
        }
        mask
    }

    #[inline(always)]
    fn hit(&self, node: &Node, tmax: f32) -> (u32, [f32; WIDTH]) {
        let mut mask = 0;
        let mut entry = [0.0; WIDTH];
        let planes = node.planes();
        for g in 0..GROUPS {
            let slab = |axis: usize, side: usize| (planes[side][axis][g] - self.origin[axis]) * self.inverse[axis];
            let near = |axis: usize| slab(axis, self.near[axis]);
            let far = |axis: usize| slab(axis, 1 - self.near[axis]);
            let tnear = near(0).max(near(1)).max(near(2).max(self.tmin));
            let tfar = far(0).min(far(1)).min(far(2).min(Vec4::splat(tmax))) * WIDEN;
            mask |= tnear.cmple(tfar).bitmask() << (4 * g);
            entry[4 * g..4 * g + 4].copy_from_slice(&tnear.to_array());
        }
        (mask & node.occupied, entry)
    }
}

#[cfg(target_arch = "x86_64")]
pub(super) use avx::{available as avx_available, plane, slabs, Avx};

#[cfg(target_arch = "x86_64")]
mod avx {
    use std::arch::x86_64::*;

    use super::{Boxes, Node, Prepared, WIDEN, WIDTH};

    const _: () = assert!(WIDTH == 8, "one 256-bit test per node");

    /// Whether this CPU has AVX (and the OS saves its registers); std caches the answer.
    #[inline(always)]
    pub fn available() -> bool {
        std::is_x86_feature_detected!("avx")
    }

    /// 256-bit vectors, all eight children in one test. Made only where `available()`.
    pub struct Avx {
        origin: [__m256; 3],
        inverse: [__m256; 3],
        near: [usize; 3],
        tmin: __m256,
    }

    impl Boxes for Avx {
        type Relative = [[__m256; 3]; 2];

        #[inline(always)]
        fn new(r: &Prepared) -> Avx {
            // SAFETY: an `Avx` is made only by walks that checked `available()`.
            unsafe { new(r) }
        }

        #[inline(always)]
        fn hit(&self, node: &Node, tmax: f32) -> (u32, [f32; WIDTH]) {
            // SAFETY: as in `new`.
            unsafe { hit(self, node, tmax) }
        }

        #[inline(always)]
        fn relative(&self, node: &Node) -> Self::Relative {
            // SAFETY: as in `new`.
            unsafe { relative(self, node) }
        }

        #[inline(always)]
        fn hit_relative(&self, relative: &Self::Relative, tmax: f32) -> u32 {
            // SAFETY: as in `new`.
            unsafe { hit_relative(self, relative, tmax) }
        }
    }

    #[inline]
    #[target_feature(enable = "avx")]
    unsafe fn relative(a: &Avx, node: &Node) -> [[__m256; 3]; 2] {
        let less = |side: usize, axis: usize| _mm256_sub_ps(plane(node, side, axis), a.origin[axis]);
        // Written out: `array::from_fn`'s closures would be compiled without AVX.
        [[less(0, 0), less(0, 1), less(0, 2)], [less(1, 0), less(1, 1), less(1, 2)]]
    }

    /// `hit`'s operations from the planes less the origin, in its order.
    #[inline]
    #[target_feature(enable = "avx")]
    unsafe fn hit_relative(a: &Avx, relative: &[[__m256; 3]; 2], tmax: f32) -> u32 {
        let slab = |axis: usize, side: usize| _mm256_mul_ps(relative[side][axis], a.inverse[axis]);
        let near = |axis: usize| slab(axis, a.near[axis]);
        let far = |axis: usize| slab(axis, 1 - a.near[axis]);
        let tnear = _mm256_max_ps(_mm256_max_ps(near(0), near(1)), _mm256_max_ps(near(2), a.tmin));
        let tfar = _mm256_min_ps(_mm256_min_ps(far(0), far(1)), _mm256_min_ps(far(2), _mm256_set1_ps(tmax)));
        let tfar = _mm256_mul_ps(tfar, _mm256_set1_ps(WIDEN));
        _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tnear, tfar)) as u32
    }

    #[inline]
    #[target_feature(enable = "avx")]
    unsafe fn new(r: &Prepared) -> Avx {
        let splat = |v: &[glam::Vec4; 3]| v.map(|lanes| _mm256_set1_ps(lanes.x));
        Avx { origin: splat(&r.origin), inverse: splat(&r.inverse), near: r.near, tmin: _mm256_set1_ps(r.tmin) }
    }

    /// `Sse::hit`'s operations, in its order, eight lanes wide.
    #[inline]
    #[target_feature(enable = "avx")]
    unsafe fn hit(a: &Avx, node: &Node, tmax: f32) -> (u32, [f32; WIDTH]) {
        let slab = |axis: usize, side: usize| {
            _mm256_mul_ps(_mm256_sub_ps(plane(node, side, axis), a.origin[axis]), a.inverse[axis])
        };
        let near = |axis: usize| slab(axis, a.near[axis]);
        let far = |axis: usize| slab(axis, 1 - a.near[axis]);
        slabs([near(0), near(1), near(2)], [far(0), far(1), far(2)], a.tmin, tmax, node.occupied)
    }

    /// The children met, from where a ray crosses their near and far planes along each axis:
    /// a bit per child met within [tmin, tmax] (of those `occupied`), and where it enters each.
    /// (The frustum's test ends the same way.)
    #[inline]
    #[target_feature(enable = "avx")]
    pub unsafe fn slabs(
        near: [__m256; 3],
        far: [__m256; 3],
        tmin: __m256,
        tmax: f32,
        occupied: u32,
    ) -> (u32, [f32; WIDTH]) {
        // glam's max and min are _mm_max_ps(self, other): the same operand order here.
        let tnear = _mm256_max_ps(_mm256_max_ps(near[0], near[1]), _mm256_max_ps(near[2], tmin));
        let tfar = _mm256_min_ps(_mm256_min_ps(far[0], far[1]), _mm256_min_ps(far[2], _mm256_set1_ps(tmax)));
        let tfar = _mm256_mul_ps(tfar, _mm256_set1_ps(WIDEN));
        let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tnear, tfar)) as u32;
        let mut entry = [0.0f32; WIDTH];
        // SAFETY: `entry` holds eight floats; the store is unaligned.
        unsafe { _mm256_storeu_ps(entry.as_mut_ptr(), tnear) };
        (mask & occupied, entry)
    }

    /// Side `side` of the eight children's boxes along `axis`, decoded as `Node::bound` does
    /// it (the step count converted exactly, times a power of two, plus the origin: the same
    /// operations, so the same floats). AVX has no 256-bit integer widening (AVX2 does): two
    /// 128-bit ones (SSE4.1, which every AVX CPU has).
    #[inline]
    #[target_feature(enable = "avx")]
    pub unsafe fn plane(node: &Node, side: usize, axis: usize) -> __m256 {
        let q = node.steps(side, axis);
        let lo = _mm_cvtepu8_epi32(_mm_cvtsi32_si128(i32::from_le_bytes([q[0], q[1], q[2], q[3]])));
        let hi = _mm_cvtepu8_epi32(_mm_cvtsi32_si128(i32::from_le_bytes([q[4], q[5], q[6], q[7]])));
        let steps = _mm256_cvtepi32_ps(_mm256_set_m128i(hi, lo));
        let step = _mm256_set1_ps(node.step[axis]);
        _mm256_add_ps(_mm256_set1_ps(node.origin[axis]), _mm256_mul_ps(steps, step))
    }
}
