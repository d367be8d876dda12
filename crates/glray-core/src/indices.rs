//! The smallest and largest value of an array of GL indices.
//!
//! The recorder reads every index of a glDrawElements from client memory to know which vertices
//! the draw reads, at every draw of every frame: 30M indices for a 10M-triangle mesh. Compared one
//! by one (a branch-free chain of `cmov`s on one running pair) that took ~50 ms a frame, a sixth
//! of such a frame under glray; here sixteen lanes are kept apart, so that the compiler turns
//! the loop into SIMD minimums and maximums (with AVX2 where the CPU has it, chosen at run
//! time: the library must run on any x86-64) and the scan goes at the speed memory gives it;
//! a big array is scanned in pieces on glray's threads (`threads`).

use crate::threads::{PIECE, SPLIT_FROM};

/// An index type: GL_UNSIGNED_BYTE, GL_UNSIGNED_SHORT or GL_UNSIGNED_INT (an integer: any bits
/// are a value, so one can be read from any bytes).
trait Index: Copy + Ord + Into<u32> {
    /// Bytes of one value.
    const BYTES: usize = std::mem::size_of::<Self>();
    const MIN: Self;
    const MAX: Self;
}

macro_rules! index_types {
    ($($t:ty),*) => {$(
        impl Index for $t {
            const MIN: $t = <$t>::MIN;
            const MAX: $t = <$t>::MAX;
        }
    )*};
}

index_types!(u8, u16, u32);

/// Lanes kept apart: a 512-bit register's worth of 32-bit values, two AVX2 registers.
const LANES: usize = 16;

/// Indices of `size` bytes (1, 2 or 4; anything else is read as 4) in native byte order, read
/// from `bytes` (a partial index at the end is not one): their smallest and largest value, or
/// None when there is none.
pub fn min_max(bytes: &[u8], size: usize) -> Option<(u32, u32)> {
    let size = if matches!(size, 1 | 2) { size } else { 4 };
    let scan = match size {
        1 => scan::<u8>,
        2 => scan::<u16>,
        _ => scan::<u32>,
    };
    if bytes.len() < SPLIT_FROM {
        return scan(bytes);
    }
    // Big arrays in pieces on glray's threads: one core alone gets a fraction of the memory's
    // bandwidth. Pieces hold whole indices; a partial one at the end is none.
    let whole = bytes.len() - bytes.len() % size;
    let pieces = crate::threads::map_pieces(&bytes[..whole], PIECE, scan);
    pieces.into_iter().flatten().reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
}

fn scan<T: Index>(bytes: &[u8]) -> Option<(u32, u32)> {
    if bytes.len() < T::BYTES {
        return None;
    }
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked just now).
        return Some(unsafe { scan_avx2::<T>(bytes) });
    }
    Some(lanes::<T>(bytes))
}

/// `lanes` compiled for AVX2: the same comparisons, eight 32-bit lanes to an instruction.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn scan_avx2<T: Index>(bytes: &[u8]) -> (u32, u32) {
    lanes::<T>(bytes)
}

/// The scan, `LANES` running minimums and maximums side by side, joined at the end. `bytes`
/// holds at least one index.
#[inline(always)]
fn lanes<T: Index>(bytes: &[u8]) -> (u32, u32) {
    let mut lo = [T::MAX; LANES];
    let mut hi = [T::MIN; LANES];
    let mut blocks = bytes.chunks_exact(T::BYTES * LANES);
    for block in &mut blocks {
        // SAFETY: the block holds `LANES` values of `T` (an integer: any bits are one), read
        // whole wherever it starts (a draw's indices need not be aligned).
        let values = unsafe { (block.as_ptr() as *const [T; LANES]).read_unaligned() };
        for (k, v) in values.into_iter().enumerate() {
            lo[k] = lo[k].min(v);
            hi[k] = hi[k].max(v);
        }
    }
    for index in blocks.remainder().chunks_exact(T::BYTES) {
        // SAFETY: as above, one value.
        let v = unsafe { (index.as_ptr() as *const T).read_unaligned() };
        lo[0] = lo[0].min(v);
        hi[0] = hi[0].max(v);
    }
    // Lanes no block reached still hold MAX and MIN: neither wins against a lane that did.
    let lo = lo.into_iter().min().unwrap_or(T::MAX);
    let hi = hi.into_iter().max().unwrap_or(T::MIN);
    (lo.into(), hi.into())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The values one by one, as the recorder compared them before.
    fn one_by_one(bytes: &[u8], size: usize) -> Option<(u32, u32)> {
        let values: Vec<u32> = bytes
            .chunks_exact(size)
            .map(|c| match size {
                1 => c[0] as u32,
                2 => u16::from_ne_bytes([c[0], c[1]]) as u32,
                _ => u32::from_ne_bytes([c[0], c[1], c[2], c[3]]),
            })
            .collect();
        Some((*values.iter().min()?, *values.iter().max()?))
    }

    #[test]
    fn the_lanes_find_what_comparing_one_by_one_finds() {
        // A pseudo-random walk, so that the smallest and largest fall in any lane, and lengths
        // around the block of sixteen (a remainder, a partial index at the end, none at all).
        let mut seed = 12345u32;
        let mut next = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            seed
        };
        for size in [1usize, 2, 4] {
            for len in
                [0usize, 1, 2, 3, 5, 15, 16, 17, 31, 32, 33, 64 * size + 3, 1000, 4099, SPLIT_FROM + 5 * size + 1]
            {
                let bytes: Vec<u8> = (0..len).map(|_| (next() >> 13) as u8).collect();
                assert_eq!(min_max(&bytes, size), one_by_one(&bytes, size), "size {size}, {len} bytes");
            }
        }
    }

    #[test]
    fn extremes_in_the_last_block_or_the_remainder_are_found() {
        for n in [16usize, 17, 40] {
            for at in (0..n).filter(|&at| at != n - 1 - at) {
                let mut v = vec![7u32; n];
                v[at] = u32::MAX;
                v[n - 1 - at] = 0;
                let bytes: Vec<u8> = v.iter().flat_map(|i| i.to_ne_bytes()).collect();
                assert_eq!(min_max(&bytes, 4), Some((0, u32::MAX)), "{n} indices, extremes at {at}");
            }
        }
    }
}
