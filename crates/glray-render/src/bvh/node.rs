//! An inner node of the tree: `WIDTH` (eight) children and their boxes, quantized.
//!
//! Each child's box is stored as 8-bit steps from the node's own minimum corner, one step
//! per axis a power of two (Embree's compressed nodes, CWBVH's boxes): 128 bytes, two cache
//! lines, where boxes in floats took 256. A big tree's walks wait on memory, not arithmetic
//! (a 10M tree's AO pass spent a third of its time in prefetches stalled on full fill
//! buffers), and half the bytes per node is half the lines each visit waits for.
//!
//! A box is decoded as `origin + q * step` in single precision: `q * step` is exact (eight
//! bits times a power of two), so the sum is rounded once, the same way by every walk (the
//! scalar decode here, the AVX one in `boxes`), and the builder rounds each box outwards
//! until its decoded planes hold the box it was given: a decoded box never loses what its
//! subtree holds.

use glam::{Vec3A, Vec4};

use super::{EMPTY, GROUPS, WIDTH};

/// A node's box planes, decoded: `[side][axis][group]`, side 0 the minimum corners and 1 the
/// maximum, one child per lane in groups of four (`WIDTH` floats in a row).
pub(super) type Planes = [[[Vec4; GROUPS]; 3]; 2];

/// `WIDTH` children: `q[side][axis][k]` child k's box along `axis` in steps (side 0 its
/// minimum, 1 its maximum); the children fill the slots from the first, unused ones (`EMPTY`)
/// last, and `occupied` has a bit per used slot (an unused slot's box is not a box: walks mask
/// it out). Aligned so that a node is whole cache lines.
#[derive(Clone, Copy)]
#[repr(C, align(64))]
pub(super) struct Node {
    q: [[[u8; WIDTH]; 3]; 2],
    /// Where step 0 lies on each axis (the node's minimum corner), and one step's length.
    pub origin: [f32; 3],
    pub step: [f32; 3],
    pub occupied: u32,
    pub child: [u32; WIDTH],
}

const _: () = assert!(std::mem::size_of::<Node>() == 128, "two cache lines");

/// A node's bytes on the wire (`wire`): its fields, little-endian, without the padding.
pub(super) const NODE_BYTES: usize = 2 * 3 * WIDTH + 4 * (3 + 3 + 1 + WIDTH);

impl Node {
    /// Appends the node's fields (`NODE_BYTES`).
    pub fn put(&self, out: &mut Vec<u8>) {
        out.extend(self.q.iter().flatten().flatten());
        out.extend(self.origin.iter().chain(&self.step).flat_map(|f| f.to_le_bytes()));
        out.extend(std::iter::once(&self.occupied).chain(&self.child).flat_map(|u| u.to_le_bytes()));
    }

    /// The node `put` wrote (`NODE_BYTES` of them).
    pub fn take(b: &[u8]) -> Node {
        let word = |k: usize| {
            let at = 2 * 3 * WIDTH + 4 * k;
            [b[at], b[at + 1], b[at + 2], b[at + 3]]
        };
        let mut q = [[[0u8; WIDTH]; 3]; 2];
        for (k, v) in q.iter_mut().flatten().flatten().enumerate() {
            *v = b[k];
        }
        Node {
            q,
            origin: std::array::from_fn(|k| f32::from_le_bytes(word(k))),
            step: std::array::from_fn(|k| f32::from_le_bytes(word(3 + k))),
            occupied: u32::from_le_bytes(word(6)),
            child: std::array::from_fn(|k| u32::from_le_bytes(word(7 + k))),
        }
    }
}

impl Node {
    /// A node over children with boxes `boxes` (at most `WIDTH`, finite: minimum and maximum
    /// corners), in slots from the first; their references are set afterwards (`child`,
    /// `EMPTY` until then).
    pub fn new(boxes: impl IntoIterator<Item = (Vec3A, Vec3A)>) -> Node {
        // Every lane made of x, y and z: the builder's boxes carry a triangle index's bits in
        // their fourth lane, a subnormal float, and each SIMD operation on one takes a
        // microcode assist (it tripled this function's time).
        let xyz = |v: Vec3A| Vec3A::new(v.x, v.y, v.z);
        let mut clean = [(Vec3A::ZERO, Vec3A::ZERO); WIDTH];
        let mut count = 0;
        for (lo, hi) in boxes {
            clean[count] = (xyz(lo), xyz(hi));
            count += 1;
        }
        let boxes = &clean[..count];
        let mut node = Node {
            q: [[[255; WIDTH]; 3], [[0; WIDTH]; 3]],
            origin: [0.0; 3],
            step: [1.0; 3],
            occupied: (1u32 << count) - 1,
            child: [EMPTY; WIDTH],
        };
        if boxes.is_empty() {
            return node;
        }
        let origin = boxes.iter().fold(Vec3A::INFINITY, |m, b| m.min(b.0));
        let top = boxes.iter().fold(Vec3A::NEG_INFINITY, |m, b| m.max(b.1));
        let step = Vec3A::from_array(std::array::from_fn(|axis| step_for(origin[axis], top[axis])));
        node.origin = origin.to_array();
        node.step = step.to_array();
        // Three axes at once: the estimate in single precision is within a step of the
        // answer, one correction each way makes it conservative and tight; where it is not
        // conservative even so (a span beyond the float range), the scalar search decides.
        let inverse = step.recip();
        let decode = |q: Vec3A| origin + q * step;
        let (zero, one, most) = (Vec3A::ZERO, Vec3A::ONE, Vec3A::splat(255.0));
        for (k, &(lo, hi)) in boxes.iter().enumerate() {
            let mut down = ((lo - origin) * inverse).floor().clamp(zero, most);
            down = Vec3A::select(decode(down).cmpgt(lo), (down - one).max(zero), down);
            let further = (down + one).min(most);
            down = Vec3A::select(decode(further).cmple(lo), further, down);
            let mut up = ((hi - origin) * inverse).ceil().clamp(zero, most);
            up = Vec3A::select(decode(up).cmplt(hi), (up + one).min(most), up);
            let nearer = (up - one).max(zero);
            up = Vec3A::select(decode(nearer).cmpge(hi), nearer, up);
            let holds = decode(down).cmple(lo) & decode(up).cmpge(hi);
            for axis in 0..3 {
                let (o, s) = (origin[axis], step[axis]);
                let fits = holds.test(axis);
                node.q[0][axis][k] = if fits { down[axis] as u8 } else { self::down(o, s, lo[axis]) };
                node.q[1][axis][k] = if fits { up[axis] as u8 } else { self::up(o, s, hi[axis]) };
            }
        }
        node
    }

    /// Side `side` (0: minimum, 1: maximum) of child `k`'s box along `axis`.
    #[inline(always)]
    pub fn bound(&self, side: usize, axis: usize, k: usize) -> f32 {
        decode(self.origin[axis], self.step[axis], self.q[side][axis][k])
    }

    /// Every child's box, decoded (the baseline's way: the AVX walk decodes in `boxes`).
    #[inline(always)]
    pub fn planes(&self) -> Planes {
        std::array::from_fn(|side| {
            std::array::from_fn(|axis| {
                std::array::from_fn(|g| Vec4::from_array(std::array::from_fn(|l| self.bound(side, axis, 4 * g + l))))
            })
        })
    }

    /// The steps of `side` along `axis`, one child per byte (for the AVX decode).
    #[inline(always)]
    pub fn steps(&self, side: usize, axis: usize) -> &[u8; WIDTH] {
        &self.q[side][axis]
    }
}

/// Step `q` from `origin`: exact product, one rounding in the sum.
#[inline(always)]
fn decode(origin: f32, step: f32, q: u8) -> f32 {
    origin + q as f32 * step
}

/// The least power of two such that 255 steps from `lo` reach `hi` (decoded, in single
/// precision), at least the spacing of the floats there and the least normal float.
fn step_for(lo: f32, hi: f32) -> f32 {
    let extent = (hi as f64 - lo as f64) / 255.0;
    // The power of two at or above: the exponent's bits, one more when there is a fraction.
    let bits = extent.to_bits();
    let exponent = ((bits >> 52) & 0x7ff) as i32 - 1023 + i32::from(bits & ((1 << 52) - 1) != 0);
    let mut step = if extent > 0.0 { f32::from_bits(((exponent.clamp(-126, 127) + 127) as u32) << 23) } else { 0.0 };
    // No finer than the floats there: every step then decodes to a float of its own, exactly
    // (which keeps `Node::new`'s one correction each way enough).
    let least = spacing(lo.abs().max(hi.abs())).max(f32::MIN_POSITIVE);
    step = step.max(least);
    // The division by 255 rounds: the decode itself decides.
    while step / 2.0 >= least && decode(lo, step / 2.0, 255) >= hi {
        step /= 2.0;
    }
    while decode(lo, step, 255) < hi {
        step *= 2.0;
    }
    step
}

/// The distance from a positive float `v` to the next one down its binade (its last bit's
/// worth), a power of two; zero below the normal range.
fn spacing(v: f32) -> f32 {
    f32::from_bits((v.to_bits() & 0x7F80_0000).saturating_sub(23 << 23))
}

/// How many steps `v` lies from `origin` (a step is a power of two: its reciprocal is exact,
/// and so is this in double precision but for the last bits of very distant values, which
/// `down` and `up` mend by decoding).
fn steps_from(origin: f32, step: f32, v: f32) -> f64 {
    (v as f64 - origin as f64) * (1.0 / step as f64)
}

/// The largest step count whose plane lies at or below `v`.
fn down(origin: f32, step: f32, v: f32) -> u8 {
    let mut q = steps_from(origin, step, v).floor().clamp(0.0, 255.0) as u8;
    while q > 0 && decode(origin, step, q) > v {
        q -= 1;
    }
    while q < 255 && decode(origin, step, q + 1) <= v {
        q += 1;
    }
    q
}

/// The least step count whose plane lies at or above `v`.
fn up(origin: f32, step: f32, v: f32) -> u8 {
    let mut q = steps_from(origin, step, v).ceil().clamp(0.0, 255.0) as u8;
    while q < 255 && decode(origin, step, q) < v {
        q += 1;
    }
    while q > 0 && decode(origin, step, q - 1) >= v {
        q -= 1;
    }
    q
}

#[cfg(test)]
mod tests {
    use super::*;

    fn random(k: u32) -> f32 {
        super::super::tests::random(k)
    }

    #[test]
    fn decoded_boxes_hold_the_boxes_given_and_are_tight_to_a_step() {
        // Boxes of every scale: near the origin, far from it (large origins, tiny extents),
        // flat on an axis, a single point, negative and mixed signs.
        let mut cases: Vec<Vec<(Vec3A, Vec3A)>> = Vec::new();
        for (c, scale, offset) in [(0, 1.0, 0.0), (1, 1e-6, 1e4), (2, 1e5, -3e5), (3, 1e-30, 1.0), (4, 3e37, -1e38)] {
            let boxes = (0..c + 4)
                .map(|k| {
                    let v = |j: u32| offset + random(c * 1000 + k * 6 + j) * scale;
                    let (a, b) = (Vec3A::new(v(0), v(1), v(2)), Vec3A::new(v(3), v(4), v(5)));
                    (a.min(b), a.max(b))
                })
                .collect();
            cases.push(boxes);
        }
        cases.push(vec![(Vec3A::new(1.0, 2.0, 3.0), Vec3A::new(1.0, 2.0, 3.0)); 2]);
        cases.push(vec![
            (Vec3A::new(-1.0, 5.0, 0.0), Vec3A::new(1.0, 5.0, 0.0)),
            (Vec3A::ZERO, Vec3A::new(0.5, 5.0, 0.0)),
        ]);
        for (c, boxes) in cases.iter().enumerate() {
            let node = Node::new(boxes.iter().copied());
            assert_eq!(node.occupied, (1 << boxes.len()) - 1);
            for (k, (lo, hi)) in boxes.iter().enumerate() {
                for axis in 0..3 {
                    let (dlo, dhi) = (node.bound(0, axis, k), node.bound(1, axis, k));
                    assert!(
                        dlo <= lo[axis] && dhi >= hi[axis],
                        "case {c} child {k} axis {axis}: {dlo}..{dhi} misses {lo}..{hi}"
                    );
                    // Tight: a step further in would lose part of the box.
                    let q = node.steps(0, axis)[k];
                    assert!(
                        q == 255 || decode(node.origin[axis], node.step[axis], q + 1) > lo[axis],
                        "case {c} k {k} axis {axis} q {q} {} {} {}",
                        node.origin[axis],
                        node.step[axis],
                        lo[axis]
                    );
                    let q = node.steps(1, axis)[k];
                    assert!(
                        q == 0 || decode(node.origin[axis], node.step[axis], q - 1) < hi[axis],
                        "case {c} k {k} axis {axis} q {q} {} {} {}",
                        node.origin[axis],
                        node.step[axis],
                        hi[axis]
                    );
                }
            }
            // The SIMD decode of all planes is the scalar one.
            let planes = node.planes();
            for (side, axis, k) in (0..2).flat_map(|s| (0..3).flat_map(move |a| (0..WIDTH).map(move |k| (s, a, k)))) {
                assert_eq!(planes[side][axis][k / 4][k % 4].to_bits(), node.bound(side, axis, k).to_bits());
            }
        }
    }

    #[test]
    fn steps_are_powers_of_two_that_span_the_node() {
        for (lo, hi) in [(0.0f32, 1.0f32), (-7.5, 1e-3), (1e4, 1e4 + 1e-3), (3.0, 3.0), (-3e38, 3e38)] {
            let step = step_for(lo, hi);
            assert_eq!(step.to_bits() & 0x007F_FFFF, 0, "{step} a power of two");
            assert!(decode(lo, step, 255) >= hi, "{lo}..{hi}: 255 steps of {step} fall short");
            assert!(
                step <= spacing(lo.abs().max(hi.abs()))
                    || step == f32::MIN_POSITIVE
                    || decode(lo, step / 2.0, 255) < hi,
                "{lo}..{hi}: {step} not the least"
            );
        }
    }
}
