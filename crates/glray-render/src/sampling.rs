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
    let side = grid_side(n);
    let (cx, cy) = grid_cell(i, side);
    Vec2::new((cx as f32 + u.x) / side as f32, (cy as f32 + u.y) / side as f32)
}

/// The side of the square grid `n` stratified samples share (the least that holds them all).
fn grid_side(n: u32) -> u32 {
    (n as f32).sqrt().ceil().max(1.0) as u32
}

/// Sample `i`'s cell (column, row) in a grid of `side` x `side`, row by row.
fn grid_cell(i: u32, side: u32) -> (u32, u32) {
    (i % side, (i / side) % side)
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

/// A point's `count` cosine-weighted directions about +z (`cosine_local` of each), stratified:
/// sample i takes cell i of a side x side grid over the unit square (side = ceil(sqrt(count)),
/// as `stratified`), at the cell's centre shifted by one random offset for the point, wrapping
/// around (Cranley-Patterson rotation). Each direction is still cosine-distributed, and
/// together they cover the hemisphere evenly (less noise than independent directions). The
/// grid's columns share a radius and its rows an angle: a point's 16 directions take four
/// sines and cosines and eight square roots, where independent ones took sixteen and
/// thirty-two (`sincosf` was 4% of an AO pass's samples).
pub struct Strata {
    count: u32,
    side: u32,
    offset: Vec2,
    /// Per column (when side <= `TABLE`): the radius on the disk and the height, sqrt(u) and
    /// sqrt(1 - u); per row: the angle's cosine and sine.
    r: [f32; TABLE],
    z: [f32; TABLE],
    cos: [f32; TABLE],
    sin: [f32; TABLE],
    next: u32,
}

/// Grid sides up to this (counts up to its square) are worked out per row and column.
const TABLE: usize = 16;

impl Strata {
    /// The directions of one point, its offset `u` (uniform in the unit square).
    pub fn new(count: u32, u: Vec2) -> Strata {
        let side = grid_side(count);
        let mut s = Strata {
            count,
            side,
            offset: u,
            r: [0.0; TABLE],
            z: [0.0; TABLE],
            cos: [0.0; TABLE],
            sin: [0.0; TABLE],
            next: 0,
        };
        if side as usize <= TABLE {
            for c in 0..side as usize {
                let (x, angle) = (s.column(c as u32), s.row(c as u32));
                (s.r[c], s.z[c]) = (x.sqrt(), (1.0 - x).max(0.0).sqrt());
                (s.sin[c], s.cos[c]) = angle.sin_cos();
            }
        }
        s
    }

    /// Column `c`'s u.x: its centre shifted, wrapped into [0, 1).
    fn column(&self, c: u32) -> f32 {
        let x = (c as f32 + 0.5) / self.side as f32 + self.offset.x;
        if x >= 1.0 {
            x - 1.0
        } else {
            x
        }
    }

    /// Row `c`'s angle (2 pi u.y; the wrap of u.y is a whole turn).
    fn row(&self, c: u32) -> f32 {
        std::f32::consts::TAU * ((c as f32 + 0.5) / self.side as f32 + self.offset.y)
    }

    /// The next of the point's directions (after `count`, they start over).
    #[inline]
    pub fn direction(&mut self) -> Vec3 {
        let i = self.next % self.count.max(1);
        self.next += 1;
        let (cx, cy) = grid_cell(i, self.side);
        if self.side as usize <= TABLE {
            let (cx, cy) = (cx as usize, cy as usize);
            return Vec3::new(self.r[cx] * self.cos[cy], self.r[cx] * self.sin[cy], self.z[cx]);
        }
        self.worked(cx, cy)
    }

    /// The direction of cell (cx, cy), worked out alone (what the tables hold, for sides
    /// beyond them).
    fn worked(&self, cx: u32, cy: u32) -> Vec3 {
        let (x, angle) = (self.column(cx), self.row(cy));
        let (sin, cos) = angle.sin_cos();
        let r = x.sqrt();
        Vec3::new(r * cos, r * sin, (1.0 - x).max(0.0).sqrt())
    }
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

    #[test]
    fn a_points_strata_are_cosine_weighted_and_take_every_cell_once() {
        // Over many points (random offsets), directions are cosine-weighted: unit, above the
        // disk, E[cos] = 2/3; with 16 rays and 300 (past the tables: worked out per ray).
        let mut s = Sampler::new(&[11]);
        for count in [16u32, 300] {
            let (mut mean_cos, mut n) = (0.0f64, 0);
            for _ in 0..2000 {
                let mut strata = Strata::new(count, s.next2());
                for _ in 0..count {
                    let d = strata.direction();
                    assert!(d.z >= 0.0 && (d.length() - 1.0).abs() < 1e-5, "{d}");
                    mean_cos += d.z as f64;
                    n += 1;
                }
            }
            let mean_cos = mean_cos / n as f64;
            assert!((mean_cos - 2.0 / 3.0).abs() < 0.005, "{count} rays: {mean_cos}");
        }
        // One point's 16 directions, back on the unit square (u.x = r^2, u.y = angle / 2 pi),
        // fall one in each cell of the 4 x 4 grid shifted by the point's offset.
        let offset = Vec2::new(0.37, 0.81);
        let mut strata = Strata::new(16, offset);
        let mut cells = [0u32; 16];
        for _ in 0..16 {
            let d = strata.direction();
            let u = Vec2::new(d.x * d.x + d.y * d.y, d.y.atan2(d.x) / std::f32::consts::TAU);
            let back = (u - offset + Vec2::splat(2.0)).fract();
            let (cx, cy) = ((back.x * 4.0).floor() as usize % 4, (back.y * 4.0).floor() as usize % 4);
            cells[cy * 4 + cx] += 1;
        }
        assert_eq!(cells, [1; 16]);
        // The tables give what each cell's direction worked out alone gives, cell by cell.
        let mut strata = Strata::new(12, offset);
        for i in 0..12 {
            let d = strata.direction();
            assert_eq!(d, strata.worked(i % 4, i / 4), "sample {i}");
        }
    }
}
