//! The threads glray's own parallel work runs on, found from anywhere in the library.
//!
//! Frames are traced on glray's own pool of threads rather than rayon's global one, so that a
//! forked child (which has none of its parent's threads) can be given new ones (the live
//! tracer's `forked`). Capture and the recorder have work worth sharing out too (reading a big
//! draw's memory every frame), and must use the same threads: rayon's global pool would hang a
//! forked child. The pool is published here, lock-free (a child forked while another thread
//! held a lock would wait on it forever), and never freed: it is made once, and again only in
//! a forked child, whose parent's pool must not be dropped anyway (that signals threads that
//! are not there).

use std::mem::MaybeUninit;
use std::sync::atomic::{AtomicPtr, Ordering};

use rayon::prelude::*;
use rayon::ThreadPool;

static POOL: AtomicPtr<ThreadPool> = AtomicPtr::new(std::ptr::null_mut());

/// The pieces a big block of memory is read in on glray's threads (a multiple of every GL
/// index size), and the size from which a block is split at all (smaller ones take less time
/// to read than to share out).
pub const PIECE: usize = 4 << 20;
pub const SPLIT_FROM: usize = 4 * PIECE;

/// Makes `pool` the one glray's work runs on from now on, and gives it back.
pub fn publish(pool: ThreadPool) -> &'static ThreadPool {
    let pool: &'static ThreadPool = Box::leak(Box::new(pool));
    POOL.store(pool as *const ThreadPool as *mut ThreadPool, Ordering::Release);
    pool
}

/// The pool published last, if any.
pub fn pool() -> Option<&'static ThreadPool> {
    // SAFETY: a published pool is leaked, never freed: the pointer stays valid.
    unsafe { POOL.load(Ordering::Acquire).as_ref() }
}

/// `f` of each piece of `items` (`piece` items long, the last shorter), in order: on glray's
/// threads where a pool is published, else one by one on the caller's thread.
pub fn map_pieces<T: Sync, R: Send>(items: &[T], piece: usize, f: impl Fn(&[T]) -> R + Sync) -> Vec<R> {
    match pool() {
        Some(pool) => pool.install(|| items.par_chunks(piece).map(&f).collect()),
        None => items.chunks(piece).map(f).collect(),
    }
}

/// `f` of each piece of `items` (`piece` items long, the last shorter) with the index of the
/// piece's first item, in order, where `f` writes the piece: on glray's threads where a pool is
/// published and there is more than one piece, else on the caller's thread (a small mesh's
/// arrays take less time to fill than to share out).
pub fn fill_pieces<T: Send, R: Send>(items: &mut [T], piece: usize, f: impl Fn(usize, &mut [T]) -> R + Sync) -> Vec<R> {
    let piece = piece.max(1);
    match pool().filter(|_| items.len() > piece) {
        Some(pool) => pool.install(|| items.par_chunks_mut(piece).enumerate().map(|(k, p)| f(k * piece, p)).collect()),
        None => items.chunks_mut(piece).enumerate().map(|(k, p)| f(k * piece, p)).collect(),
    }
}

/// A vector of `len` items made in pieces (`piece` items long, the last shorter) on glray's
/// threads, as `fill_pieces` shares them out: `f(first, filler)` gives the piece from item
/// `first` on, each item in turn, through `filler`, and says what else it found (a range, a
/// box). The new items are written once, where a vector of default items would be written
/// twice (one pass of them on the caller's thread). None when some piece was left short
/// (`f` found an item missing).
pub fn collect_pieces<T: Send, R: Send>(
    len: usize,
    piece: usize,
    f: impl Fn(usize, &mut Filler<'_, T>) -> R + Sync,
) -> Option<(Vec<T>, Vec<R>)> {
    let mut out = Vec::with_capacity(len);
    let made = fill_pieces(&mut out.spare_capacity_mut()[..len], piece, |first, slots| {
        let mut filler = Filler { slots, filled: 0 };
        let found = f(first, &mut filler);
        (filler.filled == filler.slots.len()).then_some(found)
    });
    let found: Option<Vec<R>> = made.into_iter().collect();
    let found = found?;
    // SAFETY: every piece's filler wrote each of its slots (`filled` counts the slots written,
    // in order, and equals the piece's length), and the pieces cover `0..len`.
    unsafe { out.set_len(len) };
    Some((out, found))
}

/// A copy of `items`, a big one's made in pieces on glray's threads (a buffer object's data,
/// copied as the program hands it over: at 10M triangles, 60 MB of positions every time step).
pub fn copy_of<T: Copy + Send + Sync>(items: &[T]) -> Vec<T> {
    let made = collect_pieces(items.len(), piece_of::<T>(), |first, piece| {
        let n = piece.room();
        piece.push_slice(&items[first..first + n]);
    });
    made.map_or_else(|| items.to_vec(), |(copy, _)| copy)
}

/// One piece of a `collect_pieces` vector, given its items in order.
pub struct Filler<'a, T> {
    slots: &'a mut [MaybeUninit<T>],
    filled: usize,
}

impl<T> Filler<'_, T> {
    /// The next item. Panics past the piece's end.
    #[inline(always)]
    pub fn push(&mut self, item: T) {
        self.slots[self.filled].write(item);
        self.filled += 1;
    }

    /// The next `items.len()` items. Panics past the piece's end.
    #[inline]
    pub fn push_slice(&mut self, items: &[T])
    where
        T: Copy,
    {
        let slots = &mut self.slots[self.filled..self.filled + items.len()];
        for (slot, &item) in slots.iter_mut().zip(items) {
            slot.write(item);
        }
        self.filled += items.len();
    }

    /// Items the piece still takes.
    #[inline]
    pub fn room(&self) -> usize {
        self.slots.len() - self.filled
    }
}

/// Items per piece of a big array of `T` shared out on glray's threads: about `PIECE` bytes.
pub const fn piece_of<T>() -> usize {
    let size = std::mem::size_of::<T>();
    if size == 0 {
        PIECE
    } else {
        PIECE.div_ceil(size)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_come_back_in_order_with_or_without_a_pool() {
        let bytes: Vec<u8> = (0..1000u32).map(|k| k as u8).collect();
        let expected: Vec<u32> = bytes.chunks(64).map(|p| p.iter().map(|&b| b as u32).sum()).collect();
        let sum = |p: &[u8]| p.iter().map(|&b| b as u32).sum::<u32>();
        assert_eq!(map_pieces(&bytes, 64, sum), expected);
        publish(rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap());
        assert!(pool().is_some());
        assert_eq!(map_pieces(&bytes, 64, sum), expected);
    }

    #[test]
    fn pieces_are_filled_from_their_own_first_item_with_or_without_a_pool() {
        // 1000 items in pieces of 64 (the last shorter): each item its own index, each piece's
        // finding its first item, in order; a piece left short gives nothing; a copy is the
        // items. Both ways: one by one on this thread, then on a pool.
        let check = || {
            let (items, firsts) = collect_pieces(1000, 64, |first, piece| {
                for k in first..first + piece.room() {
                    piece.push(k as u32);
                }
                first
            })
            .expect("every piece filled");
            assert_eq!(items, (0..1000).collect::<Vec<u32>>());
            assert_eq!(firsts, (0..1000).step_by(64).collect::<Vec<usize>>());
            let short = collect_pieces(1000, 64, |first, piece| {
                let n = if first == 640 { piece.room() - 1 } else { piece.room() };
                piece.push_slice(&vec![7u8; n]);
            });
            assert!(short.is_none(), "one item short in one piece");
            let mut filled = vec![0usize; 1000];
            fill_pieces(&mut filled, 64, |first, piece| piece.iter_mut().enumerate().for_each(|(k, v)| *v = first + k));
            assert_eq!(filled, (0..1000).collect::<Vec<usize>>());
            let bytes: Vec<u8> = (0..(9usize << 20) + 5).map(|k| (k * 13 + k / 7919) as u8).collect();
            assert_eq!(copy_of(&bytes), bytes);
        };
        check();
        publish(rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap());
        check();
    }
}
