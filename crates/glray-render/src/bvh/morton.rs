//! The fast build (`Quality::Fast`): a linear BVH (Lauterbach et al., 2009). Each triangle's
//! centroid is quantized to 10 bits per axis within the box of all centroids and its bits
//! interleaved (a Morton code); the triangles are sorted by code (a stable radix sort: equal
//! codes stay in index order, so the tree never depends on the number of threads); a range
//! splits where the highest bit in which its first and last codes differ turns from 0 to 1
//! (a binary search), a node's children splitting so, the fullest first, until it has `WIDTH`.
//! Boxes come bottom-up, from each leaf's triangles' corners (read again when the leaves'
//! blocks are made, by the SAH build's own code).
//!
//! No binning and no partitioning, and 8 bytes a triangle where the SAH build's records take
//! 32: the build in a fraction of the SAH build's time, for a tree the walks take longer
//! through (docs/performance.md), meant for trees built again every frame (`bvh_choice`).

use std::sync::Mutex;

use glam::{Vec3, Vec3A};
use glray_core::pages;
use rayon::prelude::*;

use super::build::{make_leaves, number_leaves, pending, whole, Bounds, Built, NodesOut};
use super::node::Node;
use super::{LEAF, LEAF_SIZE, MAX_BLOCKS, WIDTH};

/// A triangle's code in the low 32 bits, its index in the high ones.
type Keyed = u64;

/// The code of a triangle with a corner not finite, above every 30-bit code: sorted last.
const LEFT_OUT: u32 = u32::MAX;

fn code(k: Keyed) -> u32 {
    k as u32
}

fn index(k: Keyed) -> u32 {
    (k >> 32) as u32
}

/// `v`'s low ten bits (a quantized axis) spread out to every third bit.
fn spread(v: u32) -> u32 {
    let mut x = v & 0x3ff;
    x = (x | x << 16) & 0x0300_00ff;
    x = (x | x << 8) & 0x0300_f00f;
    x = (x | x << 4) & 0x030c_30c3;
    (x | x << 2) & 0x0924_9249
}

/// The Morton code of a point quantized to ten bits per axis (`q` in 0..1024).
fn interleave(q: [u32; 3]) -> u32 {
    spread(q[0]) << 2 | spread(q[1]) << 1 | spread(q[2])
}

fn centroid([a, b, c]: [Vec3; 3]) -> Vec3A {
    Vec3A::from(a + b + c)
}

fn finite(t: &[Vec3; 3]) -> bool {
    t.iter().all(|v| v.is_finite())
}

/// Sorts `keys` by their codes, stably (LSD radix, a byte at a time over the 30 bits), in a
/// chunk per thread.
fn sort(keys: &mut Vec<Keyed>) {
    let chunks = if keys.len() < SORT_CHUNK { 1 } else { rayon::current_num_threads().max(1) };
    sort_in(keys, chunks);
}

/// Keys fewer than this are sorted on one thread.
const SORT_CHUNK: usize = 1 << 16;

/// `sort` with the keys cut into `chunks` runs: each pass counts each run's bytes, and each
/// run's keys go to their bucket's part for that run, after those of the runs before it (in
/// parts of the other array split off in that order: no two runs write the same place), so the
/// order of equal bytes stays, and the result is the same for any number of runs.
fn sort_in(keys: &mut Vec<Keyed>, chunks: usize) {
    let len = keys.len();
    let run = len.div_ceil(chunks.max(1)).max(1);
    let mut other: Vec<Keyed> = vec![0; len];
    for shift in [0, 8, 16, 24] {
        let byte = |k: Keyed| (code(k) >> shift) as usize & 255;
        let counts: Vec<[usize; 256]> = keys
            .par_chunks(run)
            .map(|c| {
                let mut n = [0usize; 256];
                for &k in c {
                    n[byte(k)] += 1;
                }
                n
            })
            .collect();
        let total = |b: usize| counts.iter().map(|n| n[b]).sum::<usize>();
        if (0..256).any(|b| total(b) == len) {
            // Every code has the same byte here: the order stays.
            continue;
        }
        // Each run's part of each bucket, bucket by bucket and run by run within a bucket.
        let mut parts: Vec<Vec<&mut [Keyed]>> = (0..counts.len()).map(|_| Vec::with_capacity(256)).collect();
        let mut rest: &mut [Keyed] = &mut other;
        for b in 0..256 {
            for (r, n) in counts.iter().enumerate() {
                let (part, after) = std::mem::take(&mut rest).split_at_mut(n[b]);
                parts[r].push(part);
                rest = after;
            }
        }
        keys.par_chunks(run).zip(parts).for_each(|(c, mut parts)| {
            let mut at = [0usize; 256];
            for &k in c {
                let b = byte(k);
                parts[b][at[b]] = k;
                at[b] += 1;
            }
        });
        std::mem::swap(keys, &mut other);
    }
}

/// Where `keys` (sorted, more than one) splits: after the last key whose code has a 0 in the
/// highest bit where the first and last codes differ; in the middle when all codes are equal.
fn split_at(keys: &[Keyed]) -> usize {
    let (first, last) = (code(keys[0]), code(keys[keys.len() - 1]));
    if first == last {
        return keys.len() / 2;
    }
    let bit = 31 - (first ^ last).leading_zeros();
    keys.partition_point(|&k| code(k) >> bit & 1 == 0)
}

/// A child made: its reference (a leaf's as `LEAF | its first key`, its length in the node's
/// `lens`), box, and the most subtrees a walk below it can leave pending.
type Made = (u32, Bounds, usize);

/// The box of the triangles of `keys`.
fn bounds_of(keys: &[Keyed], corners: &impl Fn(usize) -> [Vec3; 3]) -> Bounds {
    keys.iter().fold(Bounds::EMPTY, |b, &k| corners(index(k) as usize).iter().fold(b, |b, &v| b.with(v)))
}

/// A node's children's key ranges: `WIDTH` slots, the first `len` used (arrays, not vectors:
/// a node's two vectors were an allocation and a free each, ~4% of a 10M build).
struct Kids {
    ranges: [(usize, usize); WIDTH],
    len: usize,
}

impl Kids {
    fn used(&self) -> &[(usize, usize)] {
        &self.ranges[..self.len]
    }
}

/// A node over `keys` (sorted, more than a leaf's worth): its children's ranges (the fullest
/// split until there are `WIDTH`), and the lengths of those made leaves (up to `MAX_BLOCKS`
/// blocks; 0 for the others).
fn children(keys: &[Keyed]) -> (Kids, [u8; WIDTH]) {
    let mut kids = Kids { ranges: [(0, 0); WIDTH], len: 1 };
    kids.ranges[0] = (0, keys.len());
    while kids.len < WIDTH {
        let Some((k, _)) = kids
            .used()
            .iter()
            .enumerate()
            .filter(|(_, &(s, e))| e - s > LEAF_SIZE as usize)
            .max_by_key(|&(k, &(s, e))| (e - s, usize::MAX - k))
        else {
            break;
        };
        let (s, e) = kids.ranges[k];
        let mid = s + split_at(&keys[s..e]);
        kids.ranges.copy_within(k + 1..kids.len, k + 2);
        kids.ranges[k] = (s, mid);
        kids.ranges[k + 1] = (mid, e);
        kids.len += 1;
    }
    let mut lens = [0u8; WIDTH];
    for (lane, &(s, e)) in kids.used().iter().enumerate() {
        if e - s <= (LEAF_SIZE * MAX_BLOCKS) as usize {
            lens[lane] = (e - s) as u8;
        }
    }
    (kids, lens)
}

/// Puts the node over `made` children at `index` of `out`: its box and pending count.
fn finish(out: &mut NodesOut, index: usize, made: &[Made]) -> (Bounds, usize) {
    let mut node = Node::new(made.iter().map(|m| (m.1.lo, m.1.hi)));
    for (lane, m) in made.iter().enumerate() {
        node.child[lane] = m.0;
    }
    out.nodes[index] = node;
    let below = made.iter().map(|m| m.2).max().unwrap_or(0);
    (made.iter().fold(Bounds::EMPTY, |b, m| b.union(m.1)), pending(made.len(), below))
}

/// The subtree over `keys` (see `children`) into `out` on this thread.
fn subtree(keys: &[Keyed], first: usize, corners: &impl Fn(usize) -> [Vec3; 3], out: &mut NodesOut) -> Made {
    let (kids, lens) = children(keys);
    let index = out.nodes.len();
    out.nodes.push(Node::new([]));
    out.lens.push(lens);
    let mut made = [(0, Bounds::EMPTY, 0); WIDTH];
    for ((m, &(s, e)), len) in made.iter_mut().zip(kids.used()).zip(lens) {
        *m = match len {
            0 => subtree(&keys[s..e], first + s, corners, out),
            _ => (LEAF | (first + s) as u32, bounds_of(&keys[s..e], corners), 0),
        };
    }
    let (bounds, most) = finish(out, index, &made[..kids.len]);
    (index as u32, bounds, most)
}

/// The subtree over `keys` into the tree all threads share: ranges of `whole` keys or more
/// make their node there and build their children in parallel; smaller ones are built whole on
/// one thread and appended in one step (as the SAH build's `shared_subtree`).
fn shared_subtree(
    keys: &[Keyed],
    first: usize,
    corners: &(impl Fn(usize) -> [Vec3; 3] + Sync),
    whole: usize,
    shared: &Mutex<NodesOut>,
) -> Made {
    let lock = || shared.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    if keys.len() < whole {
        let mut local = NodesOut::for_records(keys.len());
        let (root, bounds, most) = subtree(keys, first, corners, &mut local);
        return (lock().append(local, root), bounds, most);
    }
    let (kids, lens) = children(keys);
    let index = {
        let mut out = lock();
        out.nodes.push(Node::new([]));
        out.lens.push(lens);
        out.nodes.len() - 1
    };
    let made: Vec<Made> = kids
        .used()
        .par_iter()
        .zip(lens)
        .map(|(&(s, e), len)| match len {
            0 => shared_subtree(&keys[s..e], first + s, corners, whole, shared),
            _ => (LEAF | (first + s) as u32, bounds_of(&keys[s..e], corners), 0),
        })
        .collect();
    let (bounds, most) = finish(&mut lock(), index, &made);
    (index as u32, bounds, most)
}

/// The tree over triangles `0..count` whose corners `corners` gives (`count` within what a
/// tree indexes), those with a corner not finite left out (never hit).
pub(super) fn build(count: usize, corners: impl Fn(usize) -> [Vec3; 3] + Sync) -> Built {
    let box_of = |i: usize| {
        let t = corners(i);
        let c = centroid(t);
        if finite(&t) {
            Bounds { lo: c, hi: c }
        } else {
            Bounds::EMPTY
        }
    };
    let all = (0..count).into_par_iter().with_min_len(4096).map(box_of).reduce(|| Bounds::EMPTY, Bounds::union);
    let extent = all.hi - all.lo;
    if !extent.is_finite() {
        return Built::small(&[], corners);
    }
    let scale = Vec3A::select(extent.cmpgt(Vec3A::ZERO), Vec3A::splat(1024.0 * 0.9999) / extent, Vec3A::ZERO);
    let keyed = |i: usize| {
        let t = corners(i);
        let code = match finite(&t) {
            true => {
                let q = ((centroid(t) - all.lo) * scale).clamp(Vec3A::ZERO, Vec3A::splat(1023.0));
                interleave([q.x as u32, q.y as u32, q.z as u32])
            }
            false => LEFT_OUT,
        };
        u64::from(code) | (i as u64) << 32
    };
    // Every triangle keyed in place (a filtered parallel collect would gather each thread's
    // keys in vectors of its own first, and copy them), those left out sorted last and cut.
    let mut keys: Vec<Keyed> = pages::huge_vec(count);
    (0..count).into_par_iter().with_min_len(4096).map(keyed).collect_into_vec(&mut keys);
    sort(&mut keys);
    keys.truncate(keys.partition_point(|&k| code(k) != LEFT_OUT));
    if keys.len() <= LEAF_SIZE as usize {
        let ids: Vec<u32> = keys.iter().map(|&k| index(k)).collect();
        return Built::small(&ids, corners);
    }
    let shared = Mutex::new(NodesOut::for_records(keys.len()));
    let (root, _, most_pending) = shared_subtree(&keys, 0, &corners, whole(keys.len()), &shared);
    let mut out = shared.into_inner().unwrap_or_else(|poisoned| poisoned.into_inner());
    let (ids, counts) = number_leaves(&mut out, |k| index(keys[k]));
    drop(keys);
    let leaves = make_leaves(&ids, &counts, corners);
    Built { nodes: out.nodes, leaves, root, most_pending }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_code_interleaves_the_axes_bits_x_highest() {
        assert_eq!(interleave([1, 0, 0]), 0b100);
        assert_eq!(interleave([0, 1, 0]), 0b010);
        assert_eq!(interleave([0, 0, 1]), 0b001);
        assert_eq!(interleave([1023, 1023, 1023]), (1 << 30) - 1);
        assert_eq!(interleave([2, 0, 1]), 0b100_001);
    }

    #[test]
    fn the_sort_orders_by_code_and_keeps_equal_codes_in_index_order() {
        let mut state = 0x9e37_79b9_u32;
        let mut keys: Vec<Keyed> = (0..5000u64)
            .map(|i| {
                state ^= state << 13;
                state ^= state >> 17;
                state ^= state << 5;
                // Few distinct codes, spread over all four bytes: many equal ones.
                u64::from(((state % 7) * 0x0101_0101) & 0x3fff_ffff) | i << 32
            })
            .collect();
        let mut want = keys.clone();
        want.sort_by_key(|&k| (code(k), index(k)));
        for chunks in [1, 2, 3, 7] {
            let mut sorted = keys.clone();
            sort_in(&mut sorted, chunks);
            assert!(sorted == want, "{chunks} runs");
        }
        sort(&mut keys);
        assert!(keys == want);
    }

    #[test]
    fn the_build_counts_the_pending_subtrees_a_walk_of_its_tree_can_leave() {
        for n in [9, 1000, 60_000] {
            let tris = super::super::tests::soup(n);
            let built = build(tris.len(), |i| tris[i]);
            let walked = super::super::stack::most_pending(&built.nodes, built.root);
            assert_eq!(built.most_pending, walked, "{n} triangles");
            assert!(n < 1000 || walked > 10, "{n} triangles: a tree that deep leaves more pending");
        }
    }

    #[test]
    fn a_range_splits_where_its_highest_differing_bit_turns() {
        let keys: Vec<Keyed> = [0b0001u32, 0b0011, 0b0100, 0b0110, 0b0111].iter().map(|&c| u64::from(c)).collect();
        assert_eq!(split_at(&keys), 2, "bit 2 turns after the second");
        let same = vec![5u64; 9];
        assert_eq!(split_at(&same), 4, "equal codes: halves");
    }
}
