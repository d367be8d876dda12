//! The stacks a walk keeps the subtrees it will visit later on. A walk pushes all but one of
//! the children a ray meets at each node, so a tree bounds how many entries can ever be
//! pending at once (`most_pending`, which the build works out as it goes); every tree but a
//! pathological one fits `Fixed`, a plain array whose length stays in a register, and only
//! the others take `Spilling`, which grows into a Vec. (With one spilling stack for all, its
//! length lived in memory and its spill was asked at every pop: 17% of the any-hit walk's
//! instructions, ~5% of an AO pass.)

use std::mem::MaybeUninit;

#[cfg(test)]
use super::{Node, EMPTY, LEAF};

/// What a walk needs of its stack.
pub(super) trait Pending<T: Copy> {
    fn new() -> Self;
    fn push(&mut self, entry: T);
    fn pop(&mut self) -> Option<T>;
}

/// Entries `Fixed` holds: trees with at most this many pending (a tree of eight-wide nodes
/// at most eighteen deep) walk with it.
pub(super) const FIXED: usize = 128;

/// An array of `FIXED` entries, for trees that never have more pending. Its pushes are
/// bounds-checked all the same (a predicted branch), so a wrong bound would panic, not write
/// past the array.
pub(super) struct Fixed<T> {
    items: [MaybeUninit<T>; FIXED],
    len: usize,
}

impl<T: Copy> Pending<T> for Fixed<T> {
    #[inline(always)]
    fn new() -> Fixed<T> {
        Fixed { items: [const { MaybeUninit::uninit() }; FIXED], len: 0 }
    }

    #[inline(always)]
    fn push(&mut self, entry: T) {
        self.items[self.len].write(entry);
        self.len += 1;
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<T> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: entries below `len` were written by `push` and not popped since.
        Some(unsafe { self.items[self.len].assume_init() })
    }
}

/// A fixed array, spilling into a Vec past it: for the rare tree `Fixed` cannot hold.
pub(super) struct Spilling<T> {
    items: Fixed<T>,
    spill: Vec<T>,
}

impl<T: Copy> Pending<T> for Spilling<T> {
    #[inline(always)]
    fn new() -> Spilling<T> {
        Spilling { items: Fixed::new(), spill: Vec::new() }
    }

    #[inline(always)]
    fn push(&mut self, entry: T) {
        if self.items.len < FIXED {
            self.items.push(entry);
        } else {
            self.spill.push(entry);
        }
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<T> {
        self.spill.pop().or_else(|| self.items.pop())
    }
}

/// The most entries a walk of the tree from `root` can have pending: over every path from the
/// root, the children left behind at each node (all met but one, at most all but one). The
/// build works this out as it makes the tree (`build::Built::most_pending`); this walk of the
/// finished tree is what the tests hold it to.
#[cfg(test)]
pub(super) fn most_pending(nodes: &[Node], root: u32) -> usize {
    let mut most = 0;
    let mut todo = vec![(root, 0usize)];
    while let Some((c, above)) = todo.pop() {
        if c == EMPTY || c & LEAF != 0 {
            most = most.max(above);
            continue;
        }
        let children = nodes[c as usize].child.iter().filter(|&&k| k != EMPTY);
        let here = above + children.clone().count().saturating_sub(1);
        todo.extend(children.map(|&k| (k, here)));
    }
    most
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_spilling_stack_spills_past_its_array_and_still_pops_last_in_first_out() {
        let mut stack: Spilling<(u32, f32)> = Spilling::new();
        for k in 0..500u32 {
            stack.push((k, k as f32));
        }
        for k in (0..500u32).rev() {
            assert_eq!(stack.pop(), Some((k, k as f32)));
        }
        assert_eq!(stack.pop(), None);
        // And again after a spill: the array is reused.
        stack.push((7, 0.5));
        assert_eq!(stack.pop(), Some((7, 0.5)));
        assert_eq!(stack.pop(), None);
    }

    #[test]
    #[should_panic]
    fn the_fixed_stack_panics_rather_than_write_past_its_array() {
        let mut stack: Fixed<u32> = Fixed::new();
        for k in 0..=FIXED as u32 {
            stack.push(k);
        }
    }
}
