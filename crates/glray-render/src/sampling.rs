//! Deterministic random numbers and the directions drawn from them. A sample is a function of
//! where it is used (pixel, sample number, purpose, bounce), never of the thread or the order
//! the work runs in, so that an image is the same for any number of threads (DESIGN.md rule 2).

use glam::{Affine3A, Vec2, Vec3};

/// A well-mixed 32-bit hash of a few words (the PCG output permutation over a running state).
pub fn hash(words: &[u32]) -> u32 {
    let mut h: u32 = 0x9E37_79B9;
    for &w in words {
        h = h.wrapping_add(w).wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
        let word = ((h >> ((h >> 28) + 4)) ^ h).wrapping_mul(277_803_737);
        h = (word >> 22) ^ word;
    }
    h
}

/// A stream of uniform numbers in [0, 1), seeded from a hash.
#[derive(Debug, Clone, Copy)]
pub struct Sampler {
    state: u32,
}

impl Sampler {
    pub fn new(seed: &[u32]) -> Sampler {
        Sampler { state: hash(seed) }
    }

    pub fn uniform(&mut self) -> f32 {
        self.state = hash(&[self.state]);
        // 24 bits: exactly representable, strictly below 1.
        (self.state >> 8) as f32 / (1u32 << 24) as f32
    }

    pub fn next2(&mut self) -> Vec2 {
        Vec2::new(self.uniform(), self.uniform())
    }
}

/// Sample `i` of `n` stratified over the unit square (a jittered grid), with `u` the jitter.
pub fn stratified(i: u32, n: u32, u: Vec2) -> Vec2 {
    let side = (n as f32).sqrt().ceil().max(1.0) as u32;
    let (cx, cy) = (i % side, (i / side) % side);
    Vec2::new((cx as f32 + u.x) / side as f32, (cy as f32 + u.y) / side as f32)
}

/// Two unit vectors that make an orthonormal basis with unit `n` (Duff et al. 2017).
pub fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), Vec3::new(b, sign + n.y * n.y * a, -n.y))
}

/// The hemisphere around a unit normal, with its basis made once for the many directions a
/// point's ambient occlusion takes.
#[derive(Debug, Clone, Copy)]
pub struct Hemisphere {
    t: Vec3,
    b: Vec3,
    n: Vec3,
}

impl Hemisphere {
    pub fn around(n: Vec3) -> Hemisphere {
        let (t, b) = basis(n);
        Hemisphere { t, b, n }
    }

    /// A cosine-weighted direction (Malley's method: a uniform point on the disk, lifted). Unit
    /// length by construction: x^2 + y^2 + z^2 = u.x + (1 - u.x).
    #[inline]
    pub fn cosine(&self, u: Vec2) -> Vec3 {
        self.at(cosine_local(u))
    }

    /// The direction whose coordinates along the basis (tangent, bitangent, normal) are `l`.
    #[inline]
    pub fn at(&self, l: Vec3) -> Vec3 {
        self.t * l.x + self.b * l.y + self.n * l.z
    }

    /// The hemisphere's basis taken through the linear map `m`: `at` then gives `m` applied to
    /// the direction this hemisphere's `at` gives (no longer unit or orthogonal, unless `m`
    /// is a rotation), for walking a ray in the object space of an instance.
    pub fn mapped(&self, m: &Affine3A) -> Hemisphere {
        let map = |v: Vec3| m.transform_vector3(v);
        Hemisphere { t: map(self.t), b: map(self.b), n: map(self.n) }
    }
}

/// A cosine-weighted direction about +z (see `Hemisphere::cosine`).
#[inline]
pub fn cosine_local(u: Vec2) -> Vec3 {
    let r = u.x.sqrt();
    let (sin, cos) = (std::f32::consts::TAU * u.y).sin_cos();
    let z = (1.0 - u.x).max(0.0).sqrt();
    Vec3::new(r * cos, r * sin, z)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_are_uniform_and_repeatable() {
        let mut a = Sampler::new(&[1, 2, 3]);
        let mut b = Sampler::new(&[1, 2, 3]);
        let xs: Vec<f32> = (0..10_000).map(|_| a.uniform()).collect();
        assert!(xs.iter().all(|x| (0.0..1.0).contains(x)));
        assert_eq!(xs[..10], (0..10).map(|_| b.uniform()).collect::<Vec<_>>()[..]);
        let mean = xs.iter().sum::<f32>() / xs.len() as f32;
        assert!((mean - 0.5).abs() < 0.01, "{mean}");
        assert_ne!(hash(&[1, 2, 3]), hash(&[1, 2, 4]));
        assert_ne!(hash(&[0, 1]), hash(&[1, 0]));
    }

    #[test]
    fn hemisphere_directions_are_cosine_weighted_around_the_normal() {
        let n = Vec3::new(0.3, -0.5, 0.8).normalize();
        let (t, b) = basis(n);
        assert!(t.dot(n).abs() < 1e-6 && b.dot(n).abs() < 1e-6 && t.dot(b).abs() < 1e-6);
        let mut s = Sampler::new(&[7]);
        let around = Hemisphere::around(n);
        let mut mean_cos = 0.0;
        for _ in 0..20_000 {
            let d = around.cosine(s.next2());
            assert!(d.dot(n) >= -1e-5 && (d.length() - 1.0).abs() < 1e-4);
            mean_cos += d.dot(n);
        }
        // E[cos] under a cosine-weighted hemisphere is 2/3.
        mean_cos /= 20_000.0;
        assert!((mean_cos - 2.0 / 3.0).abs() < 0.01, "{mean_cos}");
        let grid: Vec<Vec2> = (0..4).map(|i| stratified(i, 4, Vec2::splat(0.5))).collect();
        assert_eq!(
            grid,
            vec![Vec2::new(0.25, 0.25), Vec2::new(0.75, 0.25), Vec2::new(0.25, 0.75), Vec2::new(0.75, 0.75)]
        );
    }
}
