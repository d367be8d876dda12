//! Building the BVH: top-down binned SAH (the surface area heuristic on 16 bins per axis, as
//! Embree's "medium" build), splitting each node's range in two, then the larger child again,
//! until it has `WIDTH` children; ranges of at most `LEAF_SIZE` triangles are leaves, and
//! ranges of up to `MAX_BLOCKS` times that are leaves where the SAH says so (`as_node`).
//!
//! `Quality::Fast` builds a linear BVH instead (`morton`), sooner and walked more slowly.
//!
//! Lean on purpose (issue 5: build time and peak memory): one 32-byte record per triangle
//! (its box, the triangle's index in the box's spare lane) partitioned in place, no binary tree
//! in between, and the top of the tree built on rayon in parallel.

use std::sync::Mutex;

use glam::{BVec3A, Vec3, Vec3A, Vec4};
use glray_core::pages;
use rayon::prelude::*;

use super::node::Node;
use super::{leaf_ref, Tri4, EMPTY, LEAF, LEAF_SIZE, MAX_BLOCKS, MAX_LEAVES, WIDTH};

/// The x, y and z lanes of a vector (its fourth lane is cleared by `select`).
const XYZ: BVec3A = BVec3A::TRUE;

/// A triangle's box; `lo.w` holds the triangle's index (as bits).
#[derive(Clone, Copy)]
struct Record {
    lo: Vec4,
    hi: Vec4,
}

impl Record {
    /// Triangle `index`'s record, from its corners.
    fn new(index: usize, [a, b, c]: [Vec3; 3]) -> Record {
        let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
        Record { lo: lo.extend(f32::from_bits(index as u32)), hi: hi.extend(0.0) }
    }

    fn index(&self) -> u32 {
        self.lo.w.to_bits()
    }

    /// Twice the centroid (the halving cancels out of the binning), its fourth lane zero: the
    /// index's bits there are a subnormal float (or a tiny normal one past 2^23), and a
    /// multiplication meeting one takes a microcode assist of ~30 ns on Intel cores. Left in,
    /// the binning's scaling met them for a part of a 10M mesh's records (-11% build without).
    #[inline(always)]
    fn centroid2(&self) -> Vec3A {
        Vec3A::select(XYZ, Vec3A::from_vec4(self.lo + self.hi), Vec3A::ZERO)
    }
}

/// A box (grown from records here, from corners in `morton` and `refit`).
#[derive(Clone, Copy, PartialEq)]
pub(super) struct Bounds {
    pub lo: Vec3A,
    pub hi: Vec3A,
}

impl Bounds {
    pub const EMPTY: Bounds = Bounds { lo: Vec3A::INFINITY, hi: Vec3A::NEG_INFINITY };

    /// The box grown to hold point `v`.
    pub fn with(self, v: Vec3) -> Bounds {
        self.union(Bounds { lo: v.into(), hi: v.into() })
    }

    /// The box around a range's triangles.
    fn of(records: &[Record]) -> Bounds {
        records.iter().fold(Bounds::EMPTY, |mut b, r| {
            b.grow(r);
            b
        })
    }

    fn grow(&mut self, r: &Record) {
        self.lo = self.lo.min(Vec3A::from_vec4(r.lo));
        self.hi = self.hi.max(Vec3A::from_vec4(r.hi));
    }

    pub fn union(self, o: Bounds) -> Bounds {
        Bounds { lo: self.lo.min(o.lo), hi: self.hi.max(o.hi) }
    }

    pub fn half_area(&self) -> f32 {
        let d = (self.hi - self.lo).max(Vec3A::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

const BINS: usize = 16;
/// How many records ahead the binning starts loading the records it reads (8 KB): ranges
/// larger than the caches are read from memory at every level near the top of the tree, and
/// the binning waited on those loads for over a third of its time (-15% of a 10M build).
const AHEAD: usize = 256;
/// Ranges at least this long are binned in parallel and make their next splits ahead in
/// parallel; subtrees are built in parallel from a smaller length on (`whole` in `build`).
const PARALLEL: usize = 1 << 15;

#[derive(Clone, Copy)]
struct Bins {
    bounds: [[Bounds; BINS]; 3],
    count: [[u32; BINS]; 3],
}

impl Bins {
    fn new() -> Bins {
        Bins { bounds: [[Bounds::EMPTY; BINS]; 3], count: [[0; BINS]; 3] }
    }

    fn merge(mut self, o: &Bins) -> Bins {
        for axis in 0..3 {
            for b in 0..BINS {
                self.bounds[axis][b] = self.bounds[axis][b].union(o.bounds[axis][b]);
                self.count[axis][b] += o.count[axis][b];
            }
        }
        self
    }
}

/// Maps centroids to bins along each axis.
#[derive(Clone, Copy)]
struct Binning {
    origin: Vec3A,
    scale: Vec3A,
}

impl Binning {
    /// The bins of `r`'s centroid along the three axes. The bins are filled for every record
    /// of every split, the build's largest part: one truncation for the three axes (a scalar
    /// `f32 as i32` is a dozen instructions each, with its NaN and range checks), and the
    /// indices masked into range, which also drops the bins' bounds checks.
    #[inline(always)]
    fn bin(&self, r: &Record) -> [usize; 3] {
        let b = ((r.centroid2() - self.origin) * self.scale).min(Vec3A::splat((BINS - 1) as f32)).max(Vec3A::ZERO);
        let [x, y, z] = truncate(b);
        // In range already (clamped above; the records are finite): the mask only lets the
        // compiler see it.
        [x as usize & (BINS - 1), y as usize & (BINS - 1), z as usize & (BINS - 1)]
    }

    /// Whether a record's bin along `axis` is below `plane` (`bin(r)[axis] < plane`, for a
    /// plane between bins). A bin is the value clamped to 0..BINS - 1 and truncated, so it is
    /// below a plane between 1 and BINS - 1 exactly when the value is: no conversion, no clamp.
    /// The record's lane is read as an array (a `Vec3A` indexed by a run-time axis went through
    /// a jump table, per record).
    fn below(&self, axis: usize, plane: usize) -> impl Fn(&Record) -> bool {
        debug_assert!((1..BINS).contains(&plane));
        let (origin, scale, plane) = (self.origin.to_array()[axis], self.scale.to_array()[axis], plane as f32);
        move |r| (super::lane(&(r.lo + r.hi), axis) - origin) * scale < plane
    }
}

/// `v`'s lanes truncated to integers (`v` in 0..BINS).
#[inline(always)]
fn truncate(v: Vec3A) -> [u32; 3] {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{__m128, __m128i, _mm_cvttps_epi32};
        // SAFETY: SSE2 is part of x86-64's baseline; a __m128i is four plain 32-bit integers.
        let [x, y, z, _]: [u32; 4] = unsafe {
            let t: __m128i = _mm_cvttps_epi32(__m128::from(v));
            std::mem::transmute(t)
        };
        [x, y, z]
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        [v.x as u32, v.y as u32, v.z as u32]
    }
}

/// The box around the centroids (doubled, as `Record::centroid2`) of a range.
#[derive(Clone, Copy)]
struct Centroids {
    lo: Vec3A,
    hi: Vec3A,
}

impl Centroids {
    const EMPTY: Centroids = Centroids { lo: Vec3A::INFINITY, hi: Vec3A::NEG_INFINITY };

    fn with(self, c: Vec3A) -> Centroids {
        Centroids { lo: self.lo.min(c), hi: self.hi.max(c) }
    }

    fn of(records: &[Record]) -> Centroids {
        let grow = |c: Centroids, r: &Record| c.with(r.centroid2());
        if records.len() >= PARALLEL {
            records
                .par_chunks(4096)
                .map(|chunk| chunk.iter().fold(Centroids::EMPTY, grow))
                .reduce(|| Centroids::EMPTY, |a, b| a.with(b.lo).with(b.hi))
        } else {
            records.iter().fold(Centroids::EMPTY, grow)
        }
    }
}

/// Leaves count in blocks of four triangles (one SIMD test each).
fn blocks(n: u32) -> f32 {
    n.div_ceil(LEAF_SIZE) as f32
}

/// One part of a split range: where it ends (the first part) or starts (the second), the box
/// around its triangles, and the box around their centroids.
type Part = (usize, Bounds, Centroids);

/// How a tree is built: by binned SAH here (the tree the walks take fastest), or as a linear
/// BVH (`morton`: the build in about half the time, rays ~13-20% slower; docs/performance.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quality {
    Sah,
    Fast,
}

/// The best split of a range found by binning: the plane, the boxes of its two sides, and its
/// SAH cost (`half_area * blocks` of each side, summed).
#[derive(Clone, Copy)]
struct Choice {
    binning: Binning,
    axis: usize,
    plane: usize,
    bounds: (Bounds, Bounds),
    cost: f32,
}

/// The cheapest split of `records` (whose centroids `centroids` bounds) by binned SAH; None when
/// every centroid is in one place (no plane separates any).
fn choose(records: &[Record], centroids: Centroids) -> Option<Choice> {
    let extent = centroids.hi - centroids.lo;
    let scale = Vec3A::select(extent.cmpgt(Vec3A::ZERO), Vec3A::splat(BINS as f32 * 0.9999) / extent, Vec3A::ZERO);
    let binning = Binning { origin: centroids.lo, scale };
    let add = |bins: &mut Bins, r: &Record| {
        for (axis, b) in binning.bin(r).into_iter().enumerate() {
            bins.bounds[axis][b].grow(r);
            bins.count[axis][b] += 1;
        }
    };
    let fill = |bins: &mut Bins, chunk: &[Record]| {
        if chunk.len() < 256 {
            chunk.iter().for_each(|r| add(bins, r));
            return;
        }
        // Neighbouring records mostly fall in the same bins (partitioning keeps them near):
        // into one set of bins, each would wait for the previous one's store. Two sets,
        // alternately, halve that chain.
        let mut other = Bins::new();
        let mut pairs = chunk.chunks_exact(2);
        for (k, pair) in (&mut pairs).enumerate() {
            // One line (two records) a pair; past the chunk's end the hint reads nothing.
            glray_core::prefetch::line(chunk.as_ptr().wrapping_add(2 * k + AHEAD));
            add(bins, &pair[0]);
            add(&mut other, &pair[1]);
        }
        pairs.remainder().iter().for_each(|r| add(bins, r));
        *bins = bins.merge(&other);
    };
    let bins = if records.len() >= PARALLEL {
        records
            .par_chunks(4096)
            .map(|c| {
                let mut b = Bins::new();
                fill(&mut b, c);
                b
            })
            .reduce(Bins::new, |a, b| a.merge(&b))
    } else {
        let mut b = Bins::new();
        fill(&mut b, records);
        b
    };
    // The cheapest plane over the three axes, A(left) * blocks(left) + A(right) * blocks(right),
    // the first of equal ones. Every plane's cost first, then the least: choosing as it went,
    // the sweep branched on each cost against the best so far, which mispredicted often (the
    // sweep is a split's fixed cost, paid in full by the many small ranges near the leaves).
    let mut costs = [[f32::INFINITY; BINS]; 3];
    for (axis, costs) in costs.iter_mut().enumerate() {
        let bounds = &bins.bounds[axis];
        let count = &bins.count[axis];
        let mut right = [0.0f32; BINS];
        let mut acc = (Bounds::EMPTY, 0u32);
        for b in (1..BINS).rev() {
            acc = (acc.0.union(bounds[b]), acc.1 + count[b]);
            right[b] = if acc.1 == 0 { f32::INFINITY } else { acc.0.half_area() * blocks(acc.1) };
        }
        let mut left = (Bounds::EMPTY, 0u32);
        for b in 1..BINS {
            left = (left.0.union(bounds[b - 1]), left.1 + count[b - 1]);
            let cost = left.0.half_area() * blocks(left.1) + right[b];
            costs[b] = if left.1 == 0 { f32::INFINITY } else { cost };
        }
    }
    let least = costs.as_flattened().iter().fold(f32::INFINITY, |a, &c| a.min(c));
    let at = costs.as_flattened().iter().position(|&c| c == least).filter(|_| least < f32::INFINITY)?;
    let (axis, plane) = (at / BINS, at % BINS);
    let union = |bins: &[Bounds]| bins.iter().fold(Bounds::EMPTY, |acc, &b| acc.union(b));
    let bounds = (union(&bins.bounds[axis][..plane]), union(&bins.bounds[axis][plane..]));
    Some(Choice { binning, axis, plane, bounds, cost: least })
}

/// Splits `records` (whose centroids `centroids` bounds) in two: by `choice`, or in halves
/// without one. Every split leaves both parts non-empty.
fn split_by(records: &mut [Record], choice: Option<Choice>) -> (Part, Part) {
    let Some(Choice { binning, axis, plane, bounds: (lb, rb), .. }) = choice else {
        // Every centroid in one place.
        return halve(records);
    };
    let (i, lc, rc) = partition(records, binning.below(axis, plane));
    if i == 0 || i == records.len() {
        // Cannot happen (the bins counted both sides with the same arithmetic), but an empty
        // side would never end: halve instead.
        return halve(records);
    }
    ((i, lb, lc), (i, rb, rc))
}

/// Splits `records` (whose centroids `centroids` bounds) in two by binned SAH.
fn split(records: &mut [Record], centroids: Centroids) -> (Part, Part) {
    split_by(records, choose(records, centroids))
}

/// The first split of a range a node would give a node of its own (more than `LEAF_SIZE`
/// triangles; as `split_by` takes it), or None when the range is cheaper as one leaf of up to
/// `MAX_BLOCKS` blocks. The SAH as Embree weighs it, a node visit costing what a block's test
/// costs: the leaf's area times its blocks, against its area (the visit) plus its best split's
/// cost. Such leaves save the walks a node visit, and the dependent miss on it, where a split
/// hardly narrows the range (docs/performance.md: camera rays at 10M -3 to -6%, a quarter
/// fewer nodes).
fn as_node(records: &[Record], bounds: Bounds, centroids: Centroids) -> Option<Option<Choice>> {
    let n = records.len() as u32;
    let choice = choose(records, centroids);
    if n > LEAF_SIZE * MAX_BLOCKS {
        return Some(choice);
    }
    let area = bounds.half_area();
    choice.filter(|c| area * blocks(n) > area + c.cost).map(Some)
}

/// Records looked at together by `partition`, from each end.
const BLOCK: usize = 32;
/// How far ahead of each end `partition` starts loading the blocks it reads next, as the
/// binning does (`AHEAD`): the end read downwards is a stream the hardware follows less well
/// (-5% of a 10M build).
const PART_AHEAD: usize = 4 * BLOCK;

/// Starts loading the block of `BLOCK` records from `first` (a line per two records); an
/// address outside the records is only a hint that reads nothing.
#[inline(always)]
fn load_block(first: *const Record) {
    for k in (0..BLOCK).step_by(2) {
        glray_core::prefetch::line(first.wrapping_add(k));
    }
}

/// Partitions `records` in place, those `left` of the plane first: where the second part
/// starts, and the box around each part's centroids.
///
/// Near the top of the tree a record's side is a coin toss, so a loop branching on it
/// mispredicts every other record, each time only once its bin is worked out (that loop was a
/// third of the build's time for a twentieth of its instructions). Instead a block from each
/// end is read without branches, noting where the records on the wrong side are, and those are
/// swapped in pairs (BlockQuicksort: Edelkamp and Weiss, 2016). The middle left at the end,
/// under two blocks, is partitioned through a mask of its records' sides.
fn partition(records: &mut [Record], left: impl Fn(&Record) -> bool) -> (usize, Centroids, Centroids) {
    let mut sides = [Centroids::EMPTY; 2];
    // Each record's centroid goes into its side's box without a branch: into the other one as
    // an empty box. A record read twice (in a block, then in the middle) only goes in twice.
    let note = |sides: &mut [Centroids; 2], r: &Record, is_left: bool| {
        let c = r.centroid2();
        let on = BVec3A::splat(is_left);
        let [left_box, right_box] = sides;
        left_box.lo = left_box.lo.min(Vec3A::select(on, c, Vec3A::INFINITY));
        left_box.hi = left_box.hi.max(Vec3A::select(on, c, Vec3A::NEG_INFINITY));
        right_box.lo = right_box.lo.min(Vec3A::select(on, Vec3A::INFINITY, c));
        right_box.hi = right_box.hi.max(Vec3A::select(on, Vec3A::NEG_INFINITY, c));
    };
    // [lo, hi) is still to be partitioned; `wrong_*[start..start + count]` are the offsets of
    // the misplaced records in the current block at each end (from lo upwards, from hi down).
    let (mut lo, mut hi) = (0, records.len());
    let (mut wrong_lo, mut wrong_hi) = ([0u8; BLOCK], [0u8; BLOCK]);
    let (mut start_lo, mut count_lo, mut start_hi, mut count_hi) = (0, 0, 0, 0);
    while hi - lo >= 2 * BLOCK {
        if count_lo == 0 {
            start_lo = 0;
            load_block(records.as_ptr().wrapping_add(lo + PART_AHEAD));
            for (k, r) in records[lo..lo + BLOCK].iter().enumerate() {
                let is_left = left(r);
                note(&mut sides, r, is_left);
                wrong_lo[count_lo] = k as u8;
                count_lo += usize::from(!is_left);
            }
        }
        if count_hi == 0 {
            start_hi = 0;
            load_block(records.as_ptr().wrapping_add(hi).wrapping_sub(PART_AHEAD + BLOCK));
            for (k, r) in records[hi - BLOCK..hi].iter().rev().enumerate() {
                let is_left = left(r);
                note(&mut sides, r, is_left);
                wrong_hi[count_hi] = k as u8;
                count_hi += usize::from(is_left);
            }
        }
        let pairs = count_lo.min(count_hi);
        for k in 0..pairs {
            records.swap(lo + wrong_lo[start_lo + k] as usize, hi - 1 - wrong_hi[start_hi + k] as usize);
        }
        (start_lo, count_lo, start_hi, count_hi) =
            (start_lo + pairs, count_lo - pairs, start_hi + pairs, count_hi - pairs);
        if count_lo == 0 {
            lo += BLOCK;
        }
        if count_hi == 0 {
            hi -= BLOCK;
        }
    }
    // The middle, under two blocks (and all of most ranges near the leaves): each record's
    // side as one bit, then the right ones before the cut swapped with the left ones after it,
    // found bit by bit.
    let middle = &mut records[lo..hi];
    debug_assert!(middle.len() < 2 * BLOCK && 2 * BLOCK <= 64);
    let mut is_left = 0u64;
    for (k, r) in middle.iter().enumerate() {
        let on = left(r);
        note(&mut sides, r, on);
        is_left |= u64::from(on) << k;
    }
    let cut = is_left.count_ones() as usize;
    let before = (1u64 << cut) - 1;
    let (mut wrong_lo, mut wrong_hi) = (!is_left & before, is_left & !before);
    while wrong_lo != 0 {
        middle.swap(wrong_lo.trailing_zeros() as usize, wrong_hi.trailing_zeros() as usize);
        wrong_lo &= wrong_lo - 1;
        wrong_hi &= wrong_hi - 1;
    }
    let [lc, rc] = sides;
    (lo + cut, lc, rc)
}

/// Splits `records` in two halves by count, whatever their positions.
fn halve(records: &[Record]) -> (Part, Part) {
    let mid = records.len() / 2;
    let (l, r) = records.split_at(mid);
    ((mid, Bounds::of(l), Centroids::of(l)), (mid, Bounds::of(r), Centroids::of(r)))
}

/// The nodes under construction (or those of one subtree, built on another thread). While
/// building, a leaf's reference is `LEAF | its first record` and `lens` holds its length; the
/// leaves themselves are made at the end, when the records are in their final order.
#[derive(Default)]
pub(super) struct NodesOut {
    pub nodes: Vec<Node>,
    pub lens: Vec<[u8; WIDTH]>,
}

impl NodesOut {
    /// Room for the nodes over `records` records: trees here have about one node per 13
    /// triangles (eight children, leaves of 3.6 on average), so the vectors do not copy their
    /// nodes as they grow. Pages reserved and never written cost no memory.
    pub fn for_records(records: usize) -> NodesOut {
        let nodes = records / 8 + 1;
        NodesOut { nodes: pages::huge_vec(nodes), lens: Vec::with_capacity(nodes) }
    }

    /// Appends a subtree built elsewhere; returns its root's reference here.
    pub fn append(&mut self, sub: NodesOut, root: u32) -> u32 {
        let n0 = self.nodes.len() as u32;
        let moved = |c: u32| if c & LEAF != 0 { c } else { c + n0 };
        self.nodes.extend(sub.nodes.into_iter().map(|mut n| {
            n.child = n.child.map(moved);
            n
        }));
        self.lens.extend(sub.lens);
        moved(root)
    }
}

/// A range of records still to be made a node: where it starts among all records, the box
/// around its centroids, and its first split when already chosen (`as_node`).
#[derive(Clone, Copy)]
struct Todo {
    first: usize,
    centroids: Centroids,
    split: Option<Option<Choice>>,
}

/// A node over a range (`Todo`), its children's leaf lengths (0: inner), and the ranges of its
/// inner children, still to be built, with their lanes.
type Made<'r> = (Node, [u8; WIDTH], Vec<(usize, &'r mut [Record], Todo)>);

/// The splits of `ranges` (disjoint, in order, as (start, end, centroids) in `records`), each
/// on its own slice, in parallel: None for a range of a leaf's worth, which is not split.
fn splits_of(records: &mut [Record], ranges: &[(usize, usize, Centroids)]) -> Vec<Option<(Part, Part)>> {
    let mut slices = Vec::with_capacity(ranges.len());
    let (mut rest, mut at) = (records, 0);
    for &(s, e, c) in ranges {
        let (_, tail) = std::mem::take(&mut rest).split_at_mut(s - at);
        let (part, tail) = tail.split_at_mut(e - s);
        slices.push((part, c));
        (rest, at) = (tail, e);
    }
    slices.into_par_iter().map(|(part, c)| (part.len() as u32 > LEAF_SIZE).then(|| split(part, c))).collect()
}

fn node(records: &mut [Record], todo: Todo) -> Made<'_> {
    let Todo { first, centroids, split: known } = todo;
    // Children as (start, end, bounds, centroids) in `records`, in order; split the one with
    // the largest surface (of those with more than a leaf's worth) until there are WIDTH.
    let mut kids: Vec<(usize, usize, Bounds, Centroids)> = Vec::with_capacity(WIDTH);
    let choice = known.unwrap_or_else(|| choose(records, centroids));
    let ((mid, lb, lc), (_, rb, rc)) = split_by(records, choice);
    kids.push((0, mid, lb, lc));
    kids.push((mid, records.len(), rb, rc));
    // A big range's next two levels of splits are made ahead, two and then four at a time in
    // parallel (one after another, the top node's seven partitions were the build's longest
    // stretch on one thread). The choice below still takes them in its own order; one it never
    // takes only left its range partitioned, which the child's own build does not mind. What
    // is made ahead depends on the range's length alone, so the tree does not depend on the
    // number of threads.
    let mut ahead: Vec<((usize, usize), (Part, Part))> = Vec::new();
    if records.len() >= PARALLEL {
        let mut level: Vec<(usize, usize, Centroids)> = kids.iter().map(|&(s, e, _, c)| (s, e, c)).collect();
        for _ in 0..2 {
            let made = splits_of(records, &level);
            let mut next = Vec::new();
            for (&(s, e, _), made) in level.iter().zip(made) {
                let Some(split) = made else { continue };
                let ((mid, _, lc), (_, _, rc)) = split;
                next.push((s, s + mid, lc));
                next.push((s + mid, e, rc));
                ahead.push(((s, e), split));
            }
            level = next;
        }
    }
    while kids.len() < WIDTH {
        let Some((k, _)) = kids
            .iter()
            .enumerate()
            .filter(|(_, c)| (c.1 - c.0) as u32 > LEAF_SIZE)
            .max_by(|a, b| a.1 .2.half_area().total_cmp(&b.1 .2.half_area()))
        else {
            break;
        };
        let (s, e, _, c) = kids[k];
        let made = ahead.iter().find(|(range, _)| *range == (s, e)).map(|(_, split)| *split);
        let ((mid, lb, lc), (_, rb, rc)) = made.unwrap_or_else(|| split(&mut records[s..e], c));
        kids[k] = (s, s + mid, lb, lc);
        kids.insert(k + 1, (s + mid, e, rb, rc));
    }
    let mut node = Node::new(kids.iter().map(|k| (k.2.lo, k.2.hi)));
    let mut lens = [0u8; WIDTH];
    let mut splits = [None; WIDTH];
    for (lane, &(s, e, b, c)) in kids.iter().enumerate() {
        splits[lane] = if (e - s) as u32 <= LEAF_SIZE { None } else { as_node(&records[s..e], b, c) };
        if splits[lane].is_none() {
            node.child[lane] = LEAF | (first + s) as u32;
            lens[lane] = (e - s) as u8;
        }
    }
    // The inner children's ranges, as disjoint slices.
    let mut parts = Vec::with_capacity(WIDTH);
    let mut rest = records;
    let mut at = 0;
    for (lane, &(s, e, _, centroids)) in kids.iter().enumerate() {
        debug_assert_eq!(s, at);
        let (part, tail) = rest.split_at_mut(e - at);
        if let Some(split) = splits[lane] {
            parts.push((lane, part, Todo { first: first + s, centroids, split: Some(split) }));
        }
        rest = tail;
        at = e;
    }
    (node, lens, parts)
}

/// How many of a node's children are leaves (their lengths in `lens`; 0: inner or none).
fn leaf_children(lens: &[u8; WIDTH]) -> usize {
    lens.iter().filter(|&&len| len > 0).count()
}

/// How many blocks the leaves among a node's children have (their lengths in `lens`).
fn blocks_of_leaves(lens: &[u8; WIDTH]) -> u32 {
    lens.iter().map(|&len| u32::from(len).div_ceil(LEAF_SIZE)).sum()
}

/// How many subtrees a walk can leave pending below a node with `children` children, the
/// deepest of which leaves `below` (see `stack::most_pending`): all its children but the one
/// it goes on with, and then what that one's subtree can leave.
pub(super) fn pending(children: usize, below: usize) -> usize {
    children - 1 + below
}

/// Builds the subtree over `records` (see `node`) into `out` on this thread: the reference of
/// its root (an inner node), and the most subtrees a walk of it can leave pending (worked out
/// here, as the tree is made: a pass over the finished tree was 3% of a build).
fn subtree(records: &mut [Record], todo: Todo, out: &mut NodesOut) -> (u32, usize) {
    let (node, lens, parts) = node(records, todo);
    let children = leaf_children(&lens) + parts.len();
    let index = out.nodes.len();
    out.nodes.push(node);
    out.lens.push(lens);
    let mut below = 0;
    for (lane, part, todo) in parts {
        let (child, most) = subtree(part, todo, out);
        out.nodes[index].child[lane] = child;
        below = below.max(most);
    }
    (index as u32, pending(children, below))
}

/// Builds the subtree over `records` (see `node`) into the tree all threads share: ranges of
/// `whole` records or more make their node there and build their children in parallel;
/// smaller ones are built whole on one thread and appended in one step. (Subtrees returning
/// their nodes to their parents instead copied every node once per parallel level, and the
/// vectors' growth left ~100 MB of freed pages in the allocator at 10M triangles: peak memory.)
fn shared_subtree(records: &mut [Record], todo: Todo, whole: usize, shared: &Mutex<NodesOut>) -> (u32, usize) {
    let lock = || shared.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    if records.len() < whole {
        let mut local = NodesOut::for_records(records.len());
        let (root, most) = subtree(records, todo, &mut local);
        return (lock().append(local, root), most);
    }
    let (node, lens, parts) = node(records, todo);
    let children = leaf_children(&lens) + parts.len();
    let index = {
        let mut out = lock();
        out.nodes.push(node);
        out.lens.push(lens);
        out.nodes.len() - 1
    };
    let made: Vec<(usize, (u32, usize))> =
        parts.into_par_iter().map(|(lane, part, todo)| (lane, shared_subtree(part, todo, whole, shared))).collect();
    let mut out = lock();
    let mut below = 0;
    for (lane, (child, most)) in made {
        out.nodes[index].child[lane] = child;
        below = below.max(most);
    }
    (index as u32, pending(children, below))
}

/// A built tree: its nodes, leaves, root, and the most subtrees a walk of it can leave
/// pending (`stack::most_pending`).
pub(super) struct Built {
    pub nodes: Vec<Node>,
    pub leaves: Vec<Tri4>,
    pub root: u32,
    pub most_pending: usize,
}

impl Built {
    /// The tree of at most a leaf's worth of triangles `ids` (none: the empty tree), whose
    /// corners `corners` gives.
    pub fn small(ids: &[u32], corners: impl Fn(usize) -> [Vec3; 3]) -> Built {
        if ids.is_empty() {
            return Built { nodes: Vec::new(), leaves: Vec::new(), root: EMPTY, most_pending: 0 };
        }
        let leaves = vec![Tri4::new(ids, |i| corners(i as usize))];
        Built { nodes: Vec::new(), leaves, root: leaf_ref(0, 1), most_pending: 0 }
    }
}

/// Below how many triangles a subtree is built whole on one thread (by either build): a
/// sixteenth of the mesh, between 8K and `PARALLEL`. A 98K mesh's eight top subtrees (12K
/// each) were too few and too uneven to keep two threads busy (8K there: -8% build); bigger
/// meshes gain nothing from more, smaller tasks (10M: +4%).
pub(super) fn whole(triangles: usize) -> usize {
    (triangles / 16).clamp(1 << 13, PARALLEL)
}

/// How many of `count` triangles one tree holds: past what leaf references can index (2^30
/// blocks), the rest of the mesh is left out, and said so (a mesh that size is ~34 GB of build
/// records alone).
pub(super) fn capped(count: usize) -> usize {
    if count > MAX_LEAVES as usize {
        glray_core::warn!(
            "a mesh of {count} triangles is more than one BVH holds ({MAX_LEAVES}); the triangles past that are not traced"
        );
        MAX_LEAVES as usize
    } else {
        count
    }
}

/// The binned SAH tree over `count` triangles (at most `capped`'s) whose corners `corners`
/// gives.
pub(super) fn sah(count: usize, corners: impl Fn(usize) -> [Vec3; 3] + Sync) -> Built {
    let record = |i: usize| Record::new(i, corners(i));
    let mut records: Vec<Record> = if count >= PARALLEL {
        let mut records = pages::huge_vec(count);
        (0..count).into_par_iter().map(record).collect_into_vec(&mut records);
        records
    } else {
        (0..count).map(record).collect()
    };
    // A triangle with a NaN or infinite corner can never be hit (its determinant is not
    // finite): it stays out, and no NaN or infinity reaches the bins and node bounds (SSE's
    // min and max happen to drop a NaN in one operand order and keep it in the other).
    records.retain(|r| Vec3A::from_vec4(r.lo).is_finite() && Vec3A::from_vec4(r.hi).is_finite());
    if records.len() as u32 <= LEAF_SIZE {
        let ids: Vec<u32> = records.iter().map(Record::index).collect();
        return Built::small(&ids, corners);
    }
    let centroids = Centroids::of(&records);
    let shared = Mutex::new(NodesOut::for_records(records.len()));
    let whole = whole(records.len());
    let todo = Todo { first: 0, centroids, split: None };
    let (root, most_pending) = shared_subtree(&mut records, todo, whole, &shared);
    let mut out = shared.into_inner().unwrap_or_else(|poisoned| poisoned.into_inner());
    let (ids, counts) = number_leaves(&mut out, |k| records[k].index());
    // The records go before the leaves are made (peak memory).
    drop(records);
    let leaves = make_leaves(&ids, &counts, corners);
    Built { nodes: out.nodes, leaves, root, most_pending }
}

/// The leaves of a tree whose leaf children are still `LEAF | first` with lengths in
/// `out.lens`, numbered in node order: each leaf child's reference set to its blocks, and each
/// block's triangles (`index(k)`: the triangle at position k of the build's order) and count.
/// In parallel over runs of nodes, each run numbering on from its first node's first leaf (one
/// thread numbering them all was 4-5% of a build), into vectors of the exact length
/// (collecting a parallel iterator's pieces and joining them raised the 10M peak by 55 MB).
pub(super) fn number_leaves(out: &mut NodesOut, index: impl Fn(usize) -> u32 + Sync) -> (Vec<[u32; 4]>, Vec<u8>) {
    let mut total = 0;
    let firsts: Vec<u32> = out
        .lens
        .iter()
        .map(|lens| {
            let first = total;
            total += blocks_of_leaves(lens);
            first
        })
        .collect();
    let total = total as usize;
    let (mut ids, mut counts) = (vec![[0u32; 4]; total], vec![0u8; total]);
    const RUN: usize = 1024;
    let mut runs = Vec::with_capacity(out.nodes.len().div_ceil(RUN));
    let (mut ids_left, mut counts_left) = (&mut ids[..], &mut counts[..]);
    for start in (0..out.nodes.len()).step_by(RUN) {
        let len = firsts.get(start + RUN).map_or(total, |&f| f as usize) - firsts[start] as usize;
        let (run_ids, rest_ids) = std::mem::take(&mut ids_left).split_at_mut(len);
        let (run_counts, rest_counts) = std::mem::take(&mut counts_left).split_at_mut(len);
        runs.push((firsts[start], run_ids, run_counts));
        (ids_left, counts_left) = (rest_ids, rest_counts);
    }
    out.nodes.par_chunks_mut(RUN).zip(out.lens.par_chunks(RUN)).zip(runs).for_each(|((nodes, lens), run)| {
        let (first, ids, counts) = run;
        let mut k = 0;
        for (node, lens) in nodes.iter_mut().zip(lens) {
            for lane in (0..WIDTH).filter(|&lane| lens[lane] > 0) {
                let start = (node.child[lane] & !LEAF) as usize;
                let len = lens[lane] as usize;
                node.child[lane] = leaf_ref(first + k as u32, len.div_ceil(LEAF_SIZE as usize) as u32);
                for block in (start..start + len).step_by(LEAF_SIZE as usize) {
                    let n = (start + len - block).min(LEAF_SIZE as usize);
                    for (slot, at) in ids[k].iter_mut().zip(block..block + n) {
                        *slot = index(at);
                    }
                    counts[k] = n as u8;
                    k += 1;
                }
            }
        }
    });
    (ids, counts)
}

/// The blocks numbered by `number_leaves`, made from their triangles' corners. In parallel
/// from a few thousand leaves on (each reads its triangles' corners from the mesh: 7% of a 98K
/// build, whose 27K leaves were below `PARALLEL`).
pub(super) fn make_leaves(ids: &[[u32; 4]], counts: &[u8], corners: impl Fn(usize) -> [Vec3; 3] + Sync) -> Vec<Tri4> {
    let make = |(leaf, &n): (&[u32; 4], &u8)| Tri4::new(&leaf[..n as usize], |i| corners(i as usize));
    let mut leaves = pages::huge_vec(ids.len());
    ids.par_iter().zip(counts).with_min_len(2048).map(make).collect_into_vec(&mut leaves);
    leaves
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` records with scattered boxes, numbered 0..n.
    fn records(n: usize) -> Vec<Record> {
        let mut state = 0x2545_f491_u32;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state as f32 / u32::MAX as f32
        };
        (0..n)
            .map(|i| {
                let lo = Vec3::new(next(), next(), next()) * 10.0;
                let hi = lo + Vec3::new(next(), next(), next());
                Record { lo: lo.extend(f32::from_bits(i as u32)), hi: hi.extend(0.0) }
            })
            .collect()
    }

    #[test]
    fn a_centroid_carries_none_of_its_records_index_into_arithmetic() {
        // Indices whose bits are a subnormal float and, past 2^23, a tiny normal one.
        for index in [1, 12_345, (1 << 23) + 5, 10_000_000] {
            let r = Record::new(index, [Vec3::ZERO, Vec3::X, Vec3::Y]);
            assert_eq!(r.index(), index as u32);
            // SAFETY: a Vec3A is four f32 lanes, the fourth hidden.
            let lanes: [f32; 4] = unsafe { std::mem::transmute(r.centroid2()) };
            assert_eq!(lanes.map(f32::to_bits), [1.0f32, 1.0, 0.0, 0.0].map(f32::to_bits), "index {index}");
        }
    }

    #[test]
    fn a_range_a_split_hardly_narrows_stays_one_leaf_of_two_blocks() {
        let tri = |at: Vec3, k: usize| {
            let d = 0.01 * k as f32;
            [at + Vec3::new(d, 0.0, 0.0), at + Vec3::new(1.0, d, 0.0), at + Vec3::new(0.0, 1.0, d)]
        };
        let verdict = |tris: &[[Vec3; 3]]| {
            let rs: Vec<Record> = tris.iter().enumerate().map(|(i, &t)| Record::new(i, t)).collect();
            as_node(&rs, Bounds::of(&rs), Centroids::of(&rs)).is_some()
        };
        // Eight triangles nearly on top of each other: any split leaves two boxes as big as
        // the whole, so a node would cost a visit for nothing.
        let heap: Vec<_> = (0..8).map(|k| tri(Vec3::ZERO, k)).collect();
        assert!(!verdict(&heap), "eight stacked triangles: one leaf");
        // Two heaps of four far apart: a node halves the area each ray meets.
        let apart: Vec<_> = (0..8).map(|k| tri(Vec3::new(if k < 4 { 0.0 } else { 50.0 }, 0.0, 0.0), k)).collect();
        assert!(verdict(&apart), "two heaps apart: a node");
        // Nine stacked triangles would take three blocks: always a node.
        let nine: Vec<_> = (0..9).map(|k| tri(Vec3::ZERO, k)).collect();
        assert!(verdict(&nine), "nine triangles: a node");
        // Eight in one place exactly (no plane separates any centroid): one leaf, not halves.
        assert!(!verdict(&[tri(Vec3::ZERO, 0); 8]));
    }

    #[test]
    fn the_build_counts_the_pending_subtrees_a_walk_of_its_tree_can_leave() {
        // Serial (under PARALLEL records) and parallel builds, and a tree of one leaf.
        for n in [3, 1000, 100_000] {
            let tris = super::super::tests::soup(n);
            let built = sah(tris.len(), |i| tris[i]);
            let walked = super::super::stack::most_pending(&built.nodes, built.root);
            assert_eq!(built.most_pending, walked, "{n} triangles");
            assert!(n < 1000 || walked > 10, "{n} triangles: a tree that deep leaves more pending");
        }
    }

    #[test]
    fn partition_puts_every_left_record_first_keeps_every_record_and_boxes_each_side() {
        // Below, at and past two blocks, and long enough for blocks left over at both ends.
        for n in [0, 1, 2, 31, 63, 64, 65, 127, 200, 1000, 4099] {
            for cut in [0.0, 0.2, 0.5, 0.97, 1.0] {
                let mut rs = records(n);
                let left = |r: &Record| r.centroid2().x < 20.0 * cut + 0.5;
                let (at, lc, rc) = partition(&mut rs, left);
                assert_eq!(at, rs.iter().filter(|r| left(r)).count(), "n {n} cut {cut}");
                assert!(rs[..at].iter().all(left) && !rs[at..].iter().any(left), "n {n} cut {cut}");
                let mut ids: Vec<u32> = rs.iter().map(Record::index).collect();
                ids.sort_unstable();
                assert!(ids.iter().copied().eq(0..n as u32), "n {n} cut {cut}: records lost or doubled");
                for (side, got) in [(&rs[..at], lc), (&rs[at..], rc)] {
                    let want = Centroids::of(side);
                    assert_eq!((got.lo, got.hi), (want.lo, want.hi), "n {n} cut {cut}");
                }
            }
        }
    }
}
