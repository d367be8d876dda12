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

/// `f` of each piece of `bytes` (`piece` bytes long, the last shorter), in order: on glray's
/// threads where a pool is published, else one by one on the caller's thread.
pub fn map_pieces<T: Send>(bytes: &[u8], piece: usize, f: impl Fn(&[u8]) -> T + Sync) -> Vec<T> {
    match pool() {
        Some(pool) => pool.install(|| bytes.par_chunks(piece).map(&f).collect()),
        None => bytes.chunks(piece).map(f).collect(),
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
}
