//! Big allocations kept from one frame for the next. A program that gives a new mesh every
//! frame (a viewer stepping through a simulation's time steps) has glray copy its buffers, make
//! a mesh and build a BVH of about the same sizes frame after frame: over a gigabyte at 10M
//! triangles. glibc maps each allocation of more than 32 MiB afresh and unmaps it when it is
//! freed, so every frame's arrays were new pages, which the kernel zeroes as they are first
//! touched: a quarter of such a frame's time on this machine (docs/performance.md).
//!
//! While the program replaces its meshes so (the renderer says when: `keep_freed`), a freed
//! block of `BIG` bytes or more is kept instead, through the rest of the frame it was freed in
//! and the next one; an allocation of about its size takes it, pages in place, and one a little
//! bigger grows the biggest kept block below it (`take_to_grow`). What no allocation took by
//! then goes back to the C allocator (`frame_begins`). Otherwise nothing is kept: a program
//! that loads its data once peaks at the memory it did before.
//!
//! On Linux (glibc or musl: `malloc_usable_size`); elsewhere `reuse` keeps nothing (lib.rs).
//! Every block comes from the C allocator (malloc, calloc, posix_memalign: what std's `System`
//! uses on Unix) and goes back to it with free; a kept block's size is what
//! `malloc_usable_size` says it holds. A fresh big block is asked for an eighth bigger than
//! needed: the next time step's array is seldom exactly the size of this one's, and pages never
//! touched cost no memory, only address space. Where that or the kept blocks do not fit (short
//! of memory, or of address space under `ulimit -v`), the kept blocks go back and the block is
//! asked for as it is: keeping never fails an allocation the C allocator would make.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Mutex;

/// Allocations of at least this many bytes are kept when freed; smaller ones are left to the C
/// allocator, whose own free lists already serve them again.
pub const BIG: usize = 4 << 20;
/// glibc maps every block of more than this many bytes on its own (its dynamic mmap threshold's
/// ceiling on 64-bit targets), and so grows it by remapping, without a copy.
const MAPPED: usize = 32 << 20;
/// How many freed blocks are kept at most (a time step frees a dozen or so arrays).
const SLOTS: usize = 32;
/// The most alignment malloc gives without being asked (glibc on 64-bit targets).
const MALLOC_ALIGN: usize = 16;

/// A freed block: where it starts (0: an empty slot), how many bytes it holds, and the frame
/// it was freed in.
#[derive(Clone, Copy)]
struct Block {
    at: usize,
    size: usize,
    frame: u64,
}

const EMPTY: Block = Block { at: 0, size: 0, frame: 0 };

/// The allocator: the C allocator's, with freed big blocks kept for a frame.
pub struct Reusing {
    kept: Mutex<[Block; SLOTS]>,
    frame: AtomicU64,
    /// Whether freed big blocks are kept (`keep_freed`).
    keeping: AtomicBool,
}

impl Default for Reusing {
    fn default() -> Self {
        Reusing::new()
    }
}

/// `size` and an eighth more: room for the next frame's array of about the same size.
fn padded(size: usize) -> usize {
    size.saturating_add(size / 8)
}

impl Reusing {
    pub const fn new() -> Reusing {
        Reusing { kept: Mutex::new([EMPTY; SLOTS]), frame: AtomicU64::new(0), keeping: AtomicBool::new(false) }
    }

    /// Whether big blocks freed from now on are kept for the next frame. Off, the kept ones go
    /// back at once.
    pub fn keep_freed(&self, on: bool) {
        if !self.keeping.swap(on, Ordering::Relaxed) || on {
            return;
        }
        self.give_back_all();
    }

    /// Every kept block back to the C allocator.
    fn give_back_all(&self) {
        let all = std::mem::replace(&mut *self.lock(), [EMPTY; SLOTS]);
        all.iter().for_each(|b| give_back(b.at));
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, [Block; SLOTS]> {
        // Nothing panics while the lock is held; a poisoned lock still holds valid blocks.
        self.kept.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// A kept block for `layout`: aligned for it, at least its size and at most half as big
    /// again (a small array must not take the block a bigger one of the same frame needs), the
    /// smallest such.
    fn take(&self, layout: Layout) -> Option<*mut u8> {
        let (size, align) = (layout.size(), layout.align());
        let fits = |b: &Block| b.at % align == 0 && b.size >= size && b.size - size <= size / 2;
        self.claim(fits, |b| std::cmp::Reverse(b.size))
    }

    /// Empties the slot of the kept block that `suits` and has the greatest `rank`, and hands
    /// the block out.
    fn claim<R: Ord>(&self, suits: impl Fn(&Block) -> bool, rank: impl Fn(&Block) -> R) -> Option<*mut u8> {
        let mut kept = self.lock();
        let best = kept.iter_mut().filter(|b| b.at != 0 && suits(b)).max_by_key(|b| rank(b))?;
        Some(std::mem::replace(best, EMPTY).at as *mut u8)
    }

    /// The biggest kept block that is too small for `layout` and big enough that the C
    /// allocator maps it on its own (`MAPPED`), to be grown to it: growing remaps its pages
    /// without copying them and adds only the missing ones, where a fresh block would take new
    /// pages for all of it. None for alignments beyond malloc's (realloc keeps only those).
    fn take_to_grow(&self, layout: Layout) -> Option<*mut u8> {
        if layout.align() > MALLOC_ALIGN {
            return None;
        }
        self.claim(|b| b.size >= MAPPED && b.size < layout.size(), |b| b.size)
    }

    /// A big block for `layout`, zeroed if asked: a kept one that fits, else a kept one grown,
    /// else a fresh one. Null only where the C allocator alone would fail too.
    ///
    /// # Safety
    /// `layout` has a non-zero size.
    unsafe fn big(&self, layout: Layout, zeroed: bool) -> *mut u8 {
        let kept = self.take(layout).or_else(|| {
            let ptr = self.take_to_grow(layout)?;
            // SAFETY: a kept block is the C allocator's and no one else's.
            let grown: *mut u8 = unsafe { libc::realloc(ptr.cast(), padded(layout.size())) }.cast();
            if grown.is_null() {
                // A failed realloc leaves the block as it was.
                give_back(ptr as usize);
            }
            (!grown.is_null()).then_some(grown)
        });
        if let Some(ptr) = kept {
            if zeroed {
                // SAFETY: a kept or grown block holds at least the layout's size.
                unsafe { std::ptr::write_bytes(ptr, 0, layout.size()) };
            }
            return ptr;
        }
        // SAFETY: the caller's non-zero size.
        let ptr = unsafe { fresh(layout, padded(layout.size()), zeroed) };
        if !ptr.is_null() {
            return ptr;
        }
        // Short of memory, or of address space under `ulimit -v`: the kept blocks go back and
        // the block is asked for without room to grow, so that keeping never fails an
        // allocation the C allocator would have made.
        self.give_back_all();
        // SAFETY: as above.
        unsafe { fresh(layout, layout.size(), zeroed) }
    }

    /// Keeps the big block at `ptr` for the frames to come, giving back the oldest kept block
    /// when every slot is full.
    ///
    /// # Safety
    /// `ptr` is a live block of the C allocator that nothing uses any more.
    unsafe fn keep(&self, ptr: *mut u8) {
        // SAFETY: the caller's block, from the C allocator.
        let size = unsafe { libc::malloc_usable_size(ptr.cast()) };
        let block = Block { at: ptr as usize, size, frame: self.frame.load(Ordering::Relaxed) };
        let evicted = {
            let mut kept = self.lock();
            let slot = match kept.iter().position(|b| b.at == 0) {
                Some(empty) => empty,
                None => (0..SLOTS).min_by_key(|&k| (kept[k].frame, kept[k].size)).expect("slots"),
            };
            std::mem::replace(&mut kept[slot], block)
        };
        give_back(evicted.at);
    }

    /// A new frame begins: blocks freed before the last frame began, and taken by nothing since,
    /// go back to the C allocator.
    pub fn frame_begins(&self) {
        let now = self.frame.fetch_add(1, Ordering::Relaxed) + 1;
        let mut stale = [0usize; SLOTS];
        {
            let mut kept = self.lock();
            for (b, s) in kept.iter_mut().zip(&mut stale) {
                if b.at != 0 && b.frame + 2 <= now {
                    *s = b.at;
                    *b = EMPTY;
                }
            }
        }
        stale.into_iter().for_each(give_back);
    }

    /// How many bytes the kept blocks hold.
    pub fn kept_bytes(&self) -> usize {
        self.lock().iter().filter(|b| b.at != 0).map(|b| b.size).sum()
    }

    /// Whether the block at `ptr` is kept.
    pub fn holds(&self, ptr: *const u8) -> bool {
        self.lock().iter().any(|b| b.at != 0 && b.at == ptr as usize)
    }
}

/// Gives the block at `at` (0: none) back to the C allocator.
fn give_back(at: usize) {
    if at != 0 {
        // SAFETY: only blocks the allocator holds and no one else uses come here (kept ones,
        // or one a failed realloc left as it was).
        unsafe { libc::free(at as *mut libc::c_void) };
    }
}

/// A fresh block of `size` bytes (at least `layout`'s) for `layout`, from the C allocator;
/// zeroed if asked (calloc's fresh pages are zero already).
///
/// # Safety
/// `layout` has a non-zero size, and `size` is at least that.
unsafe fn fresh(layout: Layout, size: usize, zeroed: bool) -> *mut u8 {
    if layout.align() <= MALLOC_ALIGN {
        // SAFETY: plain C allocations of a non-zero size.
        return unsafe {
            if zeroed {
                libc::calloc(1, size)
            } else {
                libc::malloc(size)
            }
        }
        .cast();
    }
    let mut out: *mut libc::c_void = std::ptr::null_mut();
    // SAFETY: the alignment is a power of two and a multiple of the pointer size (Layout's own
    // rules, and above MALLOC_ALIGN).
    if unsafe { libc::posix_memalign(&mut out, layout.align(), size) } != 0 {
        return std::ptr::null_mut();
    }
    if zeroed {
        // SAFETY: `out` holds `size` bytes.
        unsafe { std::ptr::write_bytes(out.cast::<u8>(), 0, layout.size()) };
    }
    out.cast()
}

// SAFETY: every block handed out holds at least its layout's size at its alignment (fresh ones
// from the C allocator, kept ones chosen by `take` for both), and is handed out once: `take`
// empties the slot under the lock, and a block is kept only once the program freed it.
unsafe impl GlobalAlloc for Reusing {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if layout.size() < BIG {
            // SAFETY: the caller's layout, as GlobalAlloc demands.
            return unsafe { System.alloc(layout) };
        }
        // SAFETY: a big layout's size is not zero.
        unsafe { self.big(layout, false) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if layout.size() < BIG {
            // SAFETY: the caller's layout.
            return unsafe { System.alloc_zeroed(layout) };
        }
        // SAFETY: a big layout's size is not zero.
        unsafe { self.big(layout, true) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        if layout.size() < BIG {
            // SAFETY: the caller's block and layout.
            unsafe { System.dealloc(ptr, layout) };
        } else if self.keeping.load(Ordering::Relaxed) {
            // SAFETY: a big block came from the C allocator (`fresh`, or realloc).
            unsafe { self.keep(ptr) };
        } else {
            // SAFETY: the caller's block, from the C allocator.
            unsafe { libc::free(ptr.cast()) };
        }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if layout.size() < BIG && new_size < BIG {
            // SAFETY: the caller's block, layout and size.
            return unsafe { System.realloc(ptr, layout, new_size) };
        }
        if layout.size() >= BIG {
            // SAFETY: a big block came from the C allocator.
            let holds = unsafe { libc::malloc_usable_size(ptr.cast()) };
            // A block grown within its padding (or a kept block's extra) stays where it is;
            // one shrunk to under half is moved, so that the memory goes.
            if new_size <= holds && new_size >= holds / 2 {
                return ptr;
            }
        }
        if layout.align() <= MALLOC_ALIGN {
            let size = if new_size >= BIG { padded(new_size) } else { new_size };
            // SAFETY: the block is the C allocator's (`System` uses malloc at this alignment).
            let moved: *mut u8 = unsafe { libc::realloc(ptr.cast(), size) }.cast();
            if !moved.is_null() || size == new_size {
                return moved;
            }
            // As in `big`: a failed realloc leaves the block as it was; without the kept
            // blocks and the room to grow, it may still be made.
            self.give_back_all();
            // SAFETY: as above.
            return unsafe { libc::realloc(ptr.cast(), new_size) }.cast();
        }
        // SAFETY: GlobalAlloc's own rules for a new layout of the same alignment.
        let new_layout = unsafe { Layout::from_size_align_unchecked(new_size, layout.align()) };
        // SAFETY: as for `alloc`.
        let moved = unsafe { self.alloc(new_layout) };
        if !moved.is_null() {
            // SAFETY: both blocks hold at least the smaller size, and are distinct.
            unsafe {
                std::ptr::copy_nonoverlapping(ptr, moved, layout.size().min(new_size));
                self.dealloc(ptr, layout);
            }
        }
        moved
    }
}

/// Every Rust allocation in glray (the library, the command, the tests) goes through this.
#[global_allocator]
static ALLOCATOR: Reusing = Reusing::new();

/// Whether big blocks freed from now on are kept for the next frame (`Reusing::keep_freed`):
/// the renderer keeps them while the program replaces its meshes frame after frame.
pub fn keep_freed(on: bool) {
    ALLOCATOR.keep_freed(on);
}

/// A new frame begins (`Reusing::frame_begins`).
pub fn frame_begins() {
    ALLOCATOR.frame_begins();
}

/// How many bytes freed big blocks hold, waiting for the next frame.
pub fn kept_bytes() -> usize {
    ALLOCATOR.kept_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;

    const MB: usize = 1 << 20;

    fn layout(size: usize) -> Layout {
        Layout::from_size_align(size, 16).expect("layout")
    }

    fn keeping() -> Reusing {
        let a = Reusing::new();
        a.keep_freed(true);
        a
    }

    #[test]
    fn a_freed_big_block_is_what_the_next_allocation_of_about_its_size_gets() {
        let a = keeping();
        unsafe {
            let p = a.alloc(layout(64 * MB));
            p.write_bytes(7, 64 * MB);
            a.dealloc(p, layout(64 * MB));
            assert!(a.holds(p) && a.kept_bytes() >= 64 * MB);
            // Far smaller: not this block.
            let small = a.alloc(layout(20 * MB));
            assert_ne!(small, p);
            // A little bigger, within the padding: this block, zeroed when asked.
            let q = a.alloc_zeroed(layout(66 * MB));
            assert_eq!(q, p);
            assert!(!a.holds(p));
            let bytes = std::slice::from_raw_parts(q, 66 * MB);
            assert!(bytes.iter().all(|&b| b == 0));
            a.dealloc(q, layout(66 * MB));
            a.dealloc(small, layout(20 * MB));
            a.frame_begins();
            a.frame_begins();
            assert_eq!(a.kept_bytes(), 0);
        }
    }

    #[test]
    fn a_kept_block_goes_back_after_the_frame_after_the_one_it_was_freed_in() {
        let a = keeping();
        unsafe {
            let p = a.alloc(layout(8 * MB));
            a.dealloc(p, layout(8 * MB));
            a.frame_begins();
            assert!(a.holds(p), "kept through the next frame");
            a.frame_begins();
            assert!(!a.holds(p) && a.kept_bytes() == 0, "given back after it");
            // Small blocks are never kept.
            let s = a.alloc(layout(BIG - 1));
            a.dealloc(s, layout(BIG - 1));
            assert_eq!(a.kept_bytes(), 0);
        }
    }

    #[test]
    fn with_every_slot_full_the_oldest_block_goes() {
        let a = keeping();
        unsafe {
            // Twice the size of the others: none of them takes it.
            let first = a.alloc(layout(2 * BIG));
            a.dealloc(first, layout(2 * BIG));
            a.frame.fetch_add(1, Ordering::Relaxed);
            let rest: Vec<*mut u8> = (0..SLOTS).map(|_| a.alloc(layout(BIG))).collect();
            assert!(rest.iter().all(|&p| p != first));
            for &p in &rest {
                a.dealloc(p, layout(BIG));
            }
            assert!(!a.holds(first), "the oldest given back");
            assert_eq!(rest.iter().filter(|&&p| a.holds(p)).count(), SLOTS);
            a.frame_begins();
            a.frame_begins();
            a.frame_begins();
            assert_eq!(a.kept_bytes(), 0);
        }
    }

    #[test]
    fn a_block_grows_in_place_within_its_room_and_keeps_its_contents_when_it_moves() {
        let a = keeping();
        unsafe {
            let p = a.alloc(layout(16 * MB));
            for k in 0..16 * MB {
                *p.add(k) = (k % 251) as u8;
            }
            let q = a.realloc(p, layout(16 * MB), 17 * MB);
            assert_eq!(q, p, "within the padding");
            let r = a.realloc(q, layout(17 * MB), 64 * MB);
            let moved = std::slice::from_raw_parts(r, 16 * MB);
            assert!(moved.iter().enumerate().all(|(k, &b)| b == (k % 251) as u8));
            // Aligned beyond malloc's own: moved by hand, aligned still.
            let big_align = Layout::from_size_align(8 * MB, 4096).expect("layout");
            let s = a.alloc(big_align);
            assert_eq!(s as usize % 4096, 0);
            *s = 42;
            let t = a.realloc(s, big_align, 32 * MB);
            assert_eq!((t as usize % 4096, *t), (0, 42));
            a.dealloc(t, Layout::from_size_align(32 * MB, 4096).expect("layout"));
            a.dealloc(r, layout(64 * MB));
        }
    }

    #[test]
    fn nothing_is_kept_unless_asked_and_the_kept_go_when_it_stops() {
        let a = Reusing::new();
        unsafe {
            let p = a.alloc(layout(8 * MB));
            a.dealloc(p, layout(8 * MB));
            assert_eq!(a.kept_bytes(), 0, "not asked to keep");
            a.keep_freed(true);
            let q = a.alloc(layout(8 * MB));
            a.dealloc(q, layout(8 * MB));
            assert!(a.holds(q));
            a.keep_freed(true);
            assert!(a.holds(q), "asked again: still kept");
            a.keep_freed(false);
            assert_eq!(a.kept_bytes(), 0, "stopped: given back at once");
        }
    }

    #[test]
    fn a_block_too_small_for_an_allocation_is_grown_to_it() {
        let a = keeping();
        unsafe {
            let p = a.alloc(layout(40 * MB));
            a.dealloc(p, layout(40 * MB));
            // Too small to take as it is, big enough to grow: taken, and holds the new size.
            let q = a.alloc_zeroed(layout(100 * MB));
            assert!(!a.holds(p) && a.kept_bytes() == 0, "grown, not left kept");
            assert!(libc::malloc_usable_size(q.cast()) >= 100 * MB);
            assert!(std::slice::from_raw_parts(q, 100 * MB).iter().all(|&b| b == 0));
            a.dealloc(q, layout(100 * MB));
            // Under `MAPPED`, blocks are not grown (glibc might copy them).
            let small = a.alloc(layout(8 * MB));
            a.dealloc(small, layout(8 * MB));
            let r = a.alloc(layout(20 * MB));
            assert!(a.holds(small));
            a.dealloc(r, layout(20 * MB));
        }
    }

    /// Set in the copy of the test binary that runs under an address-space limit.
    const UNDER_LIMIT: &str = "REUSE_TEST_UNDER_ADDRESS_LIMIT";

    /// The process's address space in bytes (`VmSize`).
    fn address_space() -> usize {
        let bytes = crate::memory::status_bytes("VmSize:") as usize;
        assert!(bytes > 0, "VmSize in /proc/self/status");
        bytes
    }

    /// `ulimit -v` at `extra` bytes more than the process holds now.
    fn limit_address_space(extra: usize) {
        let limit = (address_space() + extra) as libc::rlim_t;
        let r = libc::rlimit { rlim_cur: limit, rlim_max: limit };
        // SAFETY: a plain system call on a valid struct.
        assert_eq!(unsafe { libc::setrlimit(libc::RLIMIT_AS, &r) }, 0, "setrlimit");
    }

    /// An allocation the C allocator would make is made: without the eighth of room a fresh
    /// block is asked for, and with the kept blocks given back, when there is not room for them
    /// (here an address-space limit, as `ulimit -v` sets on many clusters' login nodes). Run
    /// in a copy of the test binary, so that the limit binds nothing else.
    #[test]
    fn under_a_memory_limit_keeping_fails_no_allocation_the_c_allocator_would_make() {
        let name = "reuse::tests::under_a_memory_limit_keeping_fails_no_allocation_the_c_allocator_would_make";
        if std::env::var_os(UNDER_LIMIT).is_none() {
            let exe = std::env::current_exe().expect("the test binary");
            let out = std::process::Command::new(exe)
                .args(["--exact", name, "--test-threads=1"])
                .env(UNDER_LIMIT, "1")
                .output()
                .expect("the test binary runs");
            let said = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
            assert!(out.status.success() && said.contains("1 passed"), "under the limit: {said}");
            return;
        }
        let a = keeping();
        unsafe {
            // A fresh block: its eighth of room does not fit under the limit, the block does.
            limit_address_space(1700 * MB);
            let p = a.alloc(layout(1600 * MB));
            assert!(!p.is_null(), "1600 MB under a limit of 1700 MB more");
            p.write_bytes(1, MB);
            a.dealloc(p, layout(1600 * MB));
            assert!(a.kept_bytes() >= 1600 * MB);
            // The kept block fills the room a new one needs: it goes back for it.
            let aligned = Layout::from_size_align(1000 * MB, 4096).expect("layout");
            let q = a.alloc(aligned);
            assert!(!q.is_null(), "the kept block given back for it");
            assert_eq!(a.kept_bytes(), 0);
            q.write_bytes(2, MB);
            a.dealloc(q, aligned);
            a.give_back_all();
            // A block grown by realloc: the same, without the room.
            let r = a.alloc(layout(100 * MB));
            let grown = a.realloc(r, layout(100 * MB), 1600 * MB);
            assert!(!grown.is_null(), "grown to 1600 MB under a limit of 1700 MB more");
            a.dealloc(grown, layout(1600 * MB));
        }
    }

    #[test]
    fn glray_allocates_through_it() {
        ALLOCATOR.keep_freed(true);
        // A size no other test of this crate asks for.
        let v: Vec<u8> = vec![1; 100 * MB + 12_345];
        let at = v.as_ptr();
        drop(v);
        let held = ALLOCATOR.holds(at);
        let again: Vec<u8> = Vec::with_capacity(100 * MB);
        let same = again.as_ptr() == at;
        drop(again);
        ALLOCATOR.keep_freed(false);
        assert!(held && same);
        assert_eq!(kept_bytes(), 0);
    }
}
