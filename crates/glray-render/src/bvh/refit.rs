//! A tree refitted to its triangles' new corners: the same nodes, leaves and triangles in each
//! leaf, every box made again bottom-up around where the triangles are now.
//!
//! A program stepping through a simulation's time often gives the same mesh again with its
//! vertices moved, or not moved at all (only its colours are new; VTK puts a changed dataset's
//! points into a new buffer even so). A refit reads each triangle once where a build sorts them
//! all; the tree stays as good as the motion lets it (`cost` says how good, and the scene
//! builds anew when it has grown too far: `scene::Meshes`). Triangles that did not move leave
//! their leaves bit for bit as they were, and a tree none of whose triangles moved is the tree
//! a build would make.

use glam::{Vec3, Vec3A};
use rayon::prelude::*;

use super::build::Bounds;
use super::{leaf_blocks, Node, Tri4, TriBvh, EMPTY, LEAF, WIDTH};

/// Blocks refitted in a run on one thread.
const RUN: usize = 4096;
/// How many blocks ahead a block's corners are loaded (its indices twice as far ahead).
const AHEAD: usize = 8;

/// A block made again: its triangles' box, how many triangles it holds, whether any moved.
#[derive(Clone, Copy)]
struct LeafBlock {
    bounds: Bounds,
    triangles: u32,
    moved: bool,
}

impl TriBvh {
    /// This tree over `count` triangles whose corners are now `corners`, refitted, and whether
    /// any triangle moved. None where a refit cannot give a tree over all of them: the tree
    /// does not hold `count` triangles (its build left out those with corners that were not
    /// finite, or it was built over another mesh), or a corner is not finite now. The tree is
    /// taken either way: a refit that fails part of the way leaves it of no use. `load(i,
    /// corners)` starts loading what `corners(i)` reads: first (`corners` false) what says
    /// where triangle i's corners are, then (true) the corners.
    pub fn refit(
        mut self,
        count: usize,
        corners: impl Fn(usize) -> [Vec3; 3] + Sync,
        load: impl Fn(usize, bool) + Sync,
    ) -> Option<(TriBvh, bool)> {
        // Leaves are in the tree's order, their triangles' corners wherever the mesh has them:
        // a miss or two for each (a 10M refit's leaves took twice as long without the loads
        // started ahead, the corners' a few blocks after the indices').
        let mut blocks: Vec<Option<LeafBlock>> = vec![None; self.leaves.len()];
        self.leaves.par_chunks_mut(RUN).zip(blocks.par_chunks_mut(RUN)).for_each(|(tris, out)| {
            let live = |t: &Tri4| t.id.into_iter().take_while(|&i| i != EMPTY && (i as usize) < count);
            for j in 0..tris.len() {
                if let Some(t) = tris.get(j + 2 * AHEAD) {
                    live(t).for_each(|i| load(i as usize, false));
                }
                if let Some(t) = tris.get(j + AHEAD) {
                    live(t).for_each(|i| load(i as usize, true));
                }
                out[j] = refit_block(&mut tris[j], count, &corners);
            }
        });
        let mut held = 0usize;
        let mut moved = false;
        for b in &blocks {
            let b = b.as_ref()?;
            held += b.triangles as usize;
            moved |= b.moved;
        }
        if held != count {
            return None;
        }
        if !moved || self.root & LEAF != 0 || self.root == EMPTY {
            // Nothing moved (the nodes hold as they are), or no node to refit.
            return Some((self, moved));
        }
        let leaf_bounds = |c: u32| {
            let (first, n) = leaf_blocks(c);
            blocks[first..first + n].iter().flatten().fold(Bounds::EMPTY, |b, k| b.union(k.bounds))
        };
        // The nodes level by level from the root (each level found in parallel: one thread
        // took 19 ms at 10M).
        let mut levels = vec![vec![self.root]];
        loop {
            let next: Vec<u32> = levels[levels.len() - 1]
                .par_iter()
                .flat_map_iter(|&n| self.nodes[n as usize].child.into_iter().filter(|&c| c != EMPTY && c & LEAF == 0))
                .collect();
            if next.is_empty() {
                break;
            }
            levels.push(next);
        }
        // No node twice among the levels (a tree's nodes each have one parent): each is made by
        // one thread alone below.
        let mut seen = vec![false; self.nodes.len()];
        for &n in levels.iter().flatten() {
            if std::mem::replace(&mut seen[n as usize], true) {
                return None;
            }
        }
        drop(seen);
        // Each level from the deepest up, in parallel: a node made again over its children's
        // new boxes (a leaf's from its blocks, an inner child's worked out with the level
        // below), its children where they were, and its own box kept for the level above.
        // One pass: a pass for the boxes and then one for the nodes read every leaf's blocks
        // twice (the two were ~45% of a deformed 10M step's refit).
        let mut node_bounds = vec![Bounds::EMPTY; self.nodes.len()];
        let nodes = Slots::new(&mut self.nodes);
        let boxes = Slots::new(&mut node_bounds);
        for level in levels.iter().rev() {
            level.par_iter().for_each(|&n| {
                let n = n as usize;
                // SAFETY (the three blocks below): node n is this level's once (checked
                // above), so this thread alone reads and writes its slots now; its children's
                // boxes were written by the level below, whose threads have all finished
                // (rayon's `for_each` returns after they have), and nothing writes them now.
                let child = unsafe { nodes.get(n) }.child;
                let used = child.iter().take_while(|&&c| c != EMPTY);
                let child_box = |c: u32| if c & LEAF != 0 { leaf_bounds(c) } else { unsafe { boxes.get(c as usize) } };
                let mut whole = Bounds::EMPTY;
                let mut node = Node::new(used.map(|&c| {
                    let b = child_box(c);
                    whole = whole.union(b);
                    (b.lo, b.hi)
                }));
                node.child = child;
                unsafe {
                    nodes.set(n, node);
                    boxes.set(n, whole);
                }
            });
        }
        Some((self, true))
    }

    /// The tree's cost as its SAH build weighs it, relative to its root's box: the area of
    /// every child's box (the chance a ray through the root meets it), a leaf's once for each
    /// of its blocks. A refit tree whose triangles moved far from where it was built costs
    /// more than it did; one built again would cost about what it first did.
    pub fn cost(&self) -> f32 {
        if self.root == EMPTY || self.root & LEAF != 0 {
            return 1.0;
        }
        let child_box = |node: &Node, k: usize| -> Bounds {
            let corner = |side: usize| Vec3A::from_array(std::array::from_fn(|axis| node.bound(side, axis, k)));
            Bounds { lo: corner(0), hi: corner(1) }
        };
        let root = &self.nodes[self.root as usize];
        let used = |node: &Node| (0..WIDTH).take_while(|&k| node.child[k] != EMPTY).collect::<Vec<_>>();
        let whole = used(root).into_iter().fold(Bounds::EMPTY, |b, k| b.union(child_box(root, k))).half_area();
        if whole <= 0.0 || !whole.is_finite() {
            return 1.0;
        }
        let sum: f64 = self
            .nodes
            .par_iter()
            .map(|node| {
                (0..WIDTH)
                    .take_while(|&k| node.child[k] != EMPTY)
                    .map(|k| {
                        let c = node.child[k];
                        let weight = if c & LEAF != 0 { leaf_blocks(c).1 as f64 } else { 1.0 };
                        weight * child_box(node, k).half_area() as f64
                    })
                    .sum::<f64>()
            })
            .sum();
        (sum / whole as f64) as f32
    }
}

/// The slots of a slice that the threads of one refit level read and write at once, each
/// thread only its own nodes' (the levels hold each node once) and the level below's, which
/// nobody writes any more. A slice cannot be lent to threads in pieces that are not ranges:
/// a level's nodes lie anywhere in the tree's array.
struct Slots<'a, T> {
    at: *mut T,
    len: usize,
    _lent: std::marker::PhantomData<&'a mut [T]>,
}

// SAFETY: the slots are `T`s sent between threads; who touches which is `get`'s and `set`'s
// callers' promise.
unsafe impl<T: Send> Sync for Slots<'_, T> {}

impl<'a, T: Copy> Slots<'a, T> {
    fn new(slice: &'a mut [T]) -> Slots<'a, T> {
        Slots { at: slice.as_mut_ptr(), len: slice.len(), _lent: std::marker::PhantomData }
    }

    /// Slot `i`. Panics past the end.
    ///
    /// # Safety
    /// No other thread writes slot `i` meanwhile.
    unsafe fn get(&self, i: usize) -> T {
        assert!(i < self.len);
        // SAFETY: within the slice, which `'a` keeps lent; no write races this read (above).
        unsafe { self.at.add(i).read() }
    }

    /// Puts `value` in slot `i`. Panics past the end.
    ///
    /// # Safety
    /// No other thread reads or writes slot `i` meanwhile.
    unsafe fn set(&self, i: usize, value: T) {
        assert!(i < self.len);
        // SAFETY: within the slice; this thread alone touches slot `i` now (above).
        unsafe { self.at.add(i).write(value) }
    }
}

/// LeafBlock `tri` made again from its triangles' corners now (`refit`); None where a corner is
/// not finite or a triangle is not one of the mesh's `count`.
fn refit_block(tri: &mut Tri4, count: usize, corners: &(impl Fn(usize) -> [Vec3; 3] + Sync)) -> Option<LeafBlock> {
    let id = tri.id;
    let ids = &id[..id.iter().take_while(|&&i| i != EMPTY).count()];
    let mut bounds = Bounds::EMPTY;
    for &i in ids {
        if i as usize >= count {
            return None;
        }
        for v in corners(i as usize) {
            if !v.is_finite() {
                return None;
            }
            bounds = bounds.with(v);
        }
    }
    let made = Tri4::new(ids, |i| corners(i as usize));
    let moved = bits(&made) != bits(tri);
    *tri = made;
    Some(LeafBlock { bounds, triangles: ids.len() as u32, moved })
}

/// A block's corner and edges, bit for bit.
fn bits(t: &Tri4) -> [[[u32; 4]; 3]; 3] {
    [t.v0, t.e1, t.e2].map(|v| v.map(|l| l.to_array().map(f32::to_bits)))
}

#[cfg(test)]
mod tests {
    use super::super::tests::{brute, random, soup};
    use super::super::{Quality, BUNDLE};
    use super::*;
    use obvhs::ray::Ray;

    type Triangle = [Vec3; 3];

    /// `tris` each moved by up to `reach` on every axis.
    fn moved(tris: &[Triangle], reach: f32) -> Vec<Triangle> {
        let k = |i: usize, a: usize| reach * (2.0 * random((i * 3 + a) as u32 + 7_000_000) - 1.0);
        tris.iter().enumerate().map(|(i, t)| t.map(|p| p + Vec3::new(k(i, 0), k(i, 1), k(i, 2)))).collect()
    }

    fn refit(bvh: TriBvh, tris: &[Triangle]) -> Option<(TriBvh, bool)> {
        bvh.refit(tris.len(), |i| tris[i], |_, _| {})
    }

    /// Every walk of `bvh` finds what testing each of `tris` finds.
    fn walks_agree(bvh: &TriBvh, tris: &[Triangle], what: &str) {
        for k in 0..400u32 {
            let o = Vec3A::new(random(k * 7 + 100_000) * 1.4 - 0.2, random(k * 7 + 100_001) * 1.4 - 0.2, 3.0);
            let target = Vec3A::new(random(k * 7 + 100_002), random(k * 7 + 100_003), 0.0);
            let ray = Ray::new(o, (target - o).normalize(), 0.0, f32::INFINITY);
            let want = brute(tris, &ray);
            assert_eq!(bvh.closest(&ray, |_, _| true).map(|h| (h.index, h.t)), want, "{what}: ray {k}");
            assert_eq!(bvh.occluded(&ray), want.is_some(), "{what}: ray {k}");
            let packet = bvh.packet_hits(&[ray; 8], |_, _| true);
            assert!(packet.iter().all(|h| h.map(|h| (h.index, h.t)) == want), "{what}: ray {k}");
            let hidden = bvh.occluded_from(o, &[ray.direction; BUNDLE], f32::INFINITY, 0);
            assert_eq!(hidden != 0, want.is_some(), "{what}: ray {k}");
        }
    }

    #[test]
    fn a_refit_tree_finds_what_testing_every_moved_triangle_finds() {
        for quality in [Quality::Sah, Quality::Fast] {
            let tris = soup(3000);
            let mut bvh = TriBvh::build_as(tris.len(), |i| tris[i], quality);
            // Moved a little, then far (boxes grow and overlap: slower walks, the same hits).
            for (step, reach) in [0.01, 0.02, 0.5].into_iter().enumerate() {
                let now = moved(&tris, reach);
                let (refit, any) = refit(bvh, &now).expect("the same triangles, moved");
                assert!(any, "{quality:?}: moved");
                walks_agree(&refit, &now, &format!("{quality:?} step {step}"));
                bvh = refit;
            }
        }
    }

    #[test]
    fn a_tree_whose_triangles_did_not_move_is_the_tree_a_build_makes() {
        let tris = soup(3000);
        let fresh = TriBvh::build(tris.len(), |i| tris[i]);
        let once = refit(TriBvh::build(tris.len(), |i| tris[i]), &moved(&tris, 0.05)).expect("moved").0;
        let (back, any) = refit(once, &tris).expect("moved back");
        assert!(any);
        let (same, any) = refit(back, &tris).expect("not moved");
        assert!(!any, "nothing moved");
        let leaves = |b: &TriBvh| b.leaves.iter().map(|t| (bits(t), t.id)).collect::<Vec<_>>();
        let nodes = |b: &TriBvh| {
            let boxes = |n: &Node| std::array::from_fn::<f32, 48, _>(|j| n.bound(j / 24, (j / 8) % 3, j % 8));
            b.nodes.iter().map(|n| (n.child, n.occupied, boxes(n).map(f32::to_bits))).collect::<Vec<_>>()
        };
        assert!(leaves(&same) == leaves(&fresh) && same.root == fresh.root);
        assert!(nodes(&same) == nodes(&fresh), "moved and moved back: the build's boxes again");
        assert_eq!(same.cost(), fresh.cost());
    }

    #[test]
    fn a_tree_is_not_refit_to_a_corner_not_finite_or_to_another_mesh() {
        let tris = soup(500);
        let build = || TriBvh::build(tris.len(), |i| tris[i]);
        let mut bad = tris.clone();
        bad[123][1].y = f32::NAN;
        assert!(refit(build(), &bad).is_none(), "a corner not finite");
        assert!(refit(build(), &tris[..499]).is_none(), "fewer triangles");
        assert!(refit(build(), &soup(501)).is_none(), "more triangles");
        // Built with the triangle not finite: a tree that left it out cannot hold it now; one
        // whose build kept it (its box's minimum and maximum may drop the NaN) is refit.
        let left_out = TriBvh::build(bad.len(), |i| bad[i]);
        let held = left_out.leaves.iter().flat_map(|t| t.id).filter(|&i| i != EMPTY).count();
        match refit(left_out, &tris) {
            Some((tree, _)) => {
                assert_eq!(held, tris.len(), "refit, yet a triangle left out");
                walks_agree(&tree, &tris, "refit after a corner that was not finite");
            }
            None => assert_eq!(held, tris.len() - 1, "not refit, yet every triangle held"),
        }
        let mut none = TriBvh::build(3, |i| tris[i]);
        none.leaves[0].id[2] = EMPTY;
        assert!(refit(none, &tris[..3]).is_none(), "a triangle the tree does not hold");
        assert!(refit(build(), &tris).is_some_and(|(_, any)| !any));
    }

    #[test]
    fn a_tree_refit_to_triangles_moved_far_costs_more_than_a_new_build() {
        let tris = soup(3000);
        let bvh = TriBvh::build(tris.len(), |i| tris[i]);
        let built = bvh.cost();
        let (near, _) = refit(bvh, &moved(&tris, 0.002)).expect("moved");
        assert!(near.cost() < built * 1.1, "moved a little: {} against {built}", near.cost());
        let far = moved(&tris, 0.5);
        let (refit, _) = refit(near, &far).expect("moved");
        let rebuilt = TriBvh::build(far.len(), |i| far[i]).cost();
        assert!(refit.cost() > rebuilt * 2.0, "refit {} against built {rebuilt}", refit.cost());
    }
}
