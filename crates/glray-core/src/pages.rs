//! Huge pages for the big arrays a walk reads at random: a 10M-triangle tree is ~660 MB, and
//! with 4 KiB pages nearly every node a deep walk reaches is also a TLB miss and a page walk.
//! Linux backs a range with 2 MiB pages when asked (`MADV_HUGEPAGE`; Debian's default
//! `transparent_hugepage=madvise` does so only when asked); elsewhere this is a no-op.

/// Below this many bytes an array stays on ordinary pages: a huge page is 2 MiB, and small
/// trees fit the TLB as they are.
const LEAST: usize = 8 << 20;

/// An empty vector with room for `capacity` values, whose memory the kernel is asked to back
/// with huge pages when it is big enough. Ask before writing: pages already faulted in as
/// 4 KiB stay so until the kernel's background thread gets to them.
pub fn huge_vec<T>(capacity: usize) -> Vec<T> {
    let v: Vec<T> = Vec::with_capacity(capacity);
    advise(v.as_ptr().cast(), capacity.saturating_mul(std::mem::size_of::<T>()));
    v
}

#[cfg(target_os = "linux")]
fn advise(start: *const u8, bytes: usize) {
    if bytes < LEAST {
        return;
    }
    // madvise wants a page-aligned start: advise the whole pages inside the allocation.
    const PAGE: usize = 4096;
    let first = (start as usize).div_ceil(PAGE) * PAGE;
    let end = (start as usize + bytes) / PAGE * PAGE;
    if end > first {
        // SAFETY: the range lies inside an allocation this process owns; MADV_HUGEPAGE only
        // changes how the kernel backs it (its contents and mapping stay), and a kernel
        // without transparent huge pages answers EINVAL, which is ignored: it is a hint.
        unsafe { libc::madvise(first as *mut libc::c_void, end - first, libc::MADV_HUGEPAGE) };
    }
}

#[cfg(not(target_os = "linux"))]
fn advise(_start: *const u8, _bytes: usize) {}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    /// The flags the kernel lists for the mapping holding `at` (/proc/self/smaps' VmFlags).
    fn flags_at(at: usize) -> Vec<String> {
        let smaps = std::fs::read_to_string("/proc/self/smaps").expect("/proc/self/smaps");
        let mut inside = false;
        for line in smaps.lines() {
            let range = line.split_whitespace().next().and_then(|r| r.split_once('-'));
            if let Some((lo, hi)) = range
                .and_then(|(lo, hi)| Some((usize::from_str_radix(lo, 16).ok()?, usize::from_str_radix(hi, 16).ok()?)))
            {
                inside = (lo..hi).contains(&at);
            } else if let Some(flags) = line.strip_prefix("VmFlags:").filter(|_| inside) {
                return flags.split_whitespace().map(str::to_owned).collect();
            }
        }
        panic!("no mapping holds {at:#x}")
    }

    #[test]
    fn a_big_vector_is_marked_for_huge_pages_and_a_small_one_is_not() {
        let big: Vec<u64> = huge_vec(4 * LEAST / 8);
        // The first whole page inside the allocation (the advised range starts there).
        let page = (big.as_ptr() as usize).div_ceil(4096) * 4096;
        assert!(flags_at(page).iter().any(|f| f == "hg"), "{:?}", flags_at(page));
        let small: Vec<u64> = huge_vec(1024);
        let at = small.as_ptr() as usize;
        assert!(!flags_at(at).iter().any(|f| f == "hg"), "{:?}", flags_at(at));
        assert!(big.capacity() >= 4 * LEAST / 8 && small.capacity() >= 1024);
    }
}
