//! The SIMD vectors the tests are written in, one ray (or one triangle) per lane: glam's
//! `Vec4` (four lanes, the baseline everywhere) and `F8` (eight lanes of AVX, on x86-64 CPUs
//! that have it). `Lanes` gives both the operations Moller-Trumbore and the packet walk use,
//! with the baseline's semantics (operand order of min and max, NaN in comparisons), so that a
//! packet of eight finds the same hits, bit for bit, as two of four.

use std::ops::{Add, BitAnd, Div, Mul, Sub};

use glam::{BVec4A, Vec4};

use super::node::{Node, Planes};

/// `N` floats, one per lane.
pub(super) trait Lanes<const N: usize>:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    type Mask: Copy + BitAnd<Output = Self::Mask>;
    fn splat(v: f32) -> Self;
    fn from_array(a: [f32; N]) -> Self;
    fn to_array(self) -> [f32; N];
    /// Lane by lane, as SSE's `minps self, other` (glam's order): `other` where either is NaN.
    fn min(self, other: Self) -> Self;
    fn max(self, other: Self) -> Self;
    fn min_element(self) -> f32;
    /// The largest lane (of lanes none of which is NaN).
    fn max_element(self) -> f32;
    /// Ordered comparisons (false where either is NaN), but `cmpne`, which is true there.
    fn cmple(self, other: Self) -> Self::Mask;
    fn cmpge(self, other: Self) -> Self::Mask;
    fn cmpne(self, other: Self) -> Self::Mask;
    fn is_finite_mask(self) -> Self::Mask;
    /// `a` where `mask` is set, `b` elsewhere.
    fn select(mask: Self::Mask, a: Self, b: Self) -> Self;
    /// Bit k set where lane k of `mask` is.
    fn bitmask(mask: Self::Mask) -> u32;
    /// A node's boxes decoded (`Node::planes`), with these lanes' instructions.
    fn planes(node: &Node) -> Planes {
        node.planes()
    }
}

impl Lanes<4> for Vec4 {
    type Mask = BVec4A;

    #[inline(always)]
    fn splat(v: f32) -> Vec4 {
        Vec4::splat(v)
    }

    #[inline(always)]
    fn from_array(a: [f32; 4]) -> Vec4 {
        Vec4::from_array(a)
    }

    #[inline(always)]
    fn to_array(self) -> [f32; 4] {
        Vec4::to_array(&self)
    }

    #[inline(always)]
    fn min(self, other: Vec4) -> Vec4 {
        Vec4::min(self, other)
    }

    #[inline(always)]
    fn max(self, other: Vec4) -> Vec4 {
        Vec4::max(self, other)
    }

    #[inline(always)]
    fn min_element(self) -> f32 {
        Vec4::min_element(self)
    }

    #[inline(always)]
    fn max_element(self) -> f32 {
        Vec4::max_element(self)
    }

    #[inline(always)]
    fn cmple(self, other: Vec4) -> BVec4A {
        Vec4::cmple(self, other)
    }

    #[inline(always)]
    fn cmpge(self, other: Vec4) -> BVec4A {
        Vec4::cmpge(self, other)
    }

    #[inline(always)]
    fn cmpne(self, other: Vec4) -> BVec4A {
        Vec4::cmpne(self, other)
    }

    #[inline(always)]
    fn is_finite_mask(self) -> BVec4A {
        Vec4::is_finite_mask(self)
    }

    #[inline(always)]
    fn select(mask: BVec4A, a: Vec4, b: Vec4) -> Vec4 {
        Vec4::select(mask, a, b)
    }

    #[inline(always)]
    fn bitmask(mask: BVec4A) -> u32 {
        mask.bitmask()
    }
}

#[cfg(target_arch = "x86_64")]
pub(super) use avx::F8;

#[cfg(target_arch = "x86_64")]
mod avx {
    use std::arch::x86_64::*;
    use std::ops::{Add, BitAnd, Div, Mul, Sub};

    use super::super::boxes::plane;
    use super::{Lanes, Node, Planes};

    /// Eight lanes of AVX. Made only inside walks compiled for AVX and entered after checking
    /// that the CPU has it (`boxes::avx_available`): every operation below assumes so.
    #[derive(Clone, Copy)]
    pub struct F8(__m256);

    /// An eight-lane mask (all bits set per true lane).
    #[derive(Clone, Copy)]
    pub struct M8(__m256);

    macro_rules! binary {
        ($trait:ident, $method:ident, $intrinsic:ident) => {
            impl $trait for F8 {
                type Output = F8;
                #[inline(always)]
                fn $method(self, other: F8) -> F8 {
                    // SAFETY: see `F8`.
                    F8(unsafe { $intrinsic(self.0, other.0) })
                }
            }
        };
    }
    binary!(Add, add, _mm256_add_ps);
    binary!(Sub, sub, _mm256_sub_ps);
    binary!(Mul, mul, _mm256_mul_ps);
    binary!(Div, div, _mm256_div_ps);

    impl BitAnd for M8 {
        type Output = M8;
        #[inline(always)]
        fn bitand(self, other: M8) -> M8 {
            // SAFETY: see `F8`.
            M8(unsafe { _mm256_and_ps(self.0, other.0) })
        }
    }

    impl Lanes<8> for F8 {
        type Mask = M8;

        #[inline(always)]
        fn splat(v: f32) -> F8 {
            // SAFETY: see `F8`.
            F8(unsafe { _mm256_set1_ps(v) })
        }

        #[inline(always)]
        fn from_array(a: [f32; 8]) -> F8 {
            // SAFETY: see `F8`; `a` is eight floats.
            F8(unsafe { _mm256_loadu_ps(a.as_ptr()) })
        }

        #[inline(always)]
        fn to_array(self) -> [f32; 8] {
            let mut a = [0.0; 8];
            // SAFETY: see `F8`; `a` is eight floats.
            unsafe { _mm256_storeu_ps(a.as_mut_ptr(), self.0) };
            a
        }

        #[inline(always)]
        fn min(self, other: F8) -> F8 {
            // SAFETY: see `F8`.
            F8(unsafe { _mm256_min_ps(self.0, other.0) })
        }

        #[inline(always)]
        fn max(self, other: F8) -> F8 {
            // SAFETY: see `F8`.
            F8(unsafe { _mm256_max_ps(self.0, other.0) })
        }

        #[inline(always)]
        fn min_element(self) -> f32 {
            self.to_array().into_iter().fold(f32::INFINITY, f32::min)
        }

        #[inline(always)]
        fn max_element(self) -> f32 {
            // SAFETY: see `F8`. Halves, then quarters, then the last two lanes.
            unsafe {
                let m = _mm_max_ps(_mm256_castps256_ps128(self.0), _mm256_extractf128_ps::<1>(self.0));
                let m = _mm_max_ps(m, _mm_movehl_ps(m, m));
                _mm_cvtss_f32(_mm_max_ss(m, _mm_shuffle_ps::<1>(m, m)))
            }
        }

        #[inline(always)]
        fn cmple(self, other: F8) -> M8 {
            // SAFETY: see `F8`.
            M8(unsafe { _mm256_cmp_ps::<_CMP_LE_OQ>(self.0, other.0) })
        }

        #[inline(always)]
        fn cmpge(self, other: F8) -> M8 {
            // SAFETY: see `F8`.
            M8(unsafe { _mm256_cmp_ps::<_CMP_GE_OQ>(self.0, other.0) })
        }

        #[inline(always)]
        fn cmpne(self, other: F8) -> M8 {
            // SAFETY: see `F8`. Unordered, as SSE's cmpneqps.
            M8(unsafe { _mm256_cmp_ps::<_CMP_NEQ_UQ>(self.0, other.0) })
        }

        #[inline(always)]
        fn is_finite_mask(self) -> M8 {
            // |x| < infinity, as glam's: false for infinities and NaN.
            // SAFETY: see `F8`.
            M8(unsafe {
                let abs = _mm256_andnot_ps(_mm256_set1_ps(-0.0), self.0);
                _mm256_cmp_ps::<_CMP_LT_OQ>(abs, _mm256_set1_ps(f32::INFINITY))
            })
        }

        #[inline(always)]
        fn select(mask: M8, a: F8, b: F8) -> F8 {
            // SAFETY: see `F8`.
            F8(unsafe { _mm256_blendv_ps(b.0, a.0, mask.0) })
        }

        #[inline(always)]
        fn bitmask(mask: M8) -> u32 {
            // SAFETY: see `F8`.
            unsafe { _mm256_movemask_ps(mask.0) as u32 }
        }

        /// Eight children's planes a vector at a time (the scalar decode's floats).
        #[inline(always)]
        fn planes(node: &Node) -> Planes {
            let mut planes = [[[glam::Vec4::ZERO; 2]; 3]; 2];
            for (side, axes) in planes.iter_mut().enumerate() {
                for (axis, lanes) in axes.iter_mut().enumerate() {
                    // SAFETY: see `F8`; `lanes` is eight floats in a row.
                    unsafe { _mm256_storeu_ps(lanes.as_mut_ptr().cast(), plane(node, side, axis)) };
                }
            }
            planes
        }
    }
}
