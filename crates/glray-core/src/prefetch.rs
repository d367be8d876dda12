//! Cache prefetch hints: loading memory a walk or a shading pass will read soon, so that
//! its misses overlap other work instead of stalling one after another (big meshes and
//! their trees miss on nearly every access).

/// Starts loading the cache line at `p`, without waiting for it.
#[inline(always)]
pub fn line<T>(p: *const T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: _mm_prefetch only hints the cache (SSE, the x86-64 baseline); it reads nothing
    // the program sees and does not fault on any address.
    unsafe {
        std::arch::x86_64::_mm_prefetch(p.cast::<i8>(), std::arch::x86_64::_MM_HINT_T0)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// Starts loading every cache line of `*value`.
#[inline(always)]
pub fn all<T>(value: &T) {
    let at = (value as *const T).cast::<u8>();
    let size = std::mem::size_of::<T>();
    let mut offset = 0;
    while offset < size {
        line(at.wrapping_add(offset));
        offset += 64;
    }
    // The last line, when the value does not start on a line boundary.
    if size > 0 {
        line(at.wrapping_add(size - 1));
    }
}
