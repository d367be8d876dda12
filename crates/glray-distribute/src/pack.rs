//! What big fields of messages travel as: their bytes shuffled and compressed, losslessly
//! (`mpi_compression`; docs/distributed.md has the measurements the default comes from).
//!
//! Shuffling (Blosc's filter) groups the bytes of fixed-size values by their position in the
//! value: the first byte of every pixel's depth, then every second byte, ... Neighbouring
//! pixels' floats share their sign, exponent and high mantissa bytes, so the shuffled bytes
//! hold long runs a compressor finds, where the floats as they lie in memory look random to
//! it. A pixel record (`AoPixel`, 44 bytes) is shuffled as one value of 44 bytes.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

/// Time this process spent packing and unpacking, in nanoseconds (on whichever thread: the
/// host's, the MPI thread), for the statistics' `pack_ms` and `unpack_ms`.
static PACKING: AtomicU64 = AtomicU64::new(0);
static UNPACKING: AtomicU64 = AtomicU64::new(0);

/// Time spent packing and unpacking so far in this process.
pub fn spent() -> (Duration, Duration) {
    (Duration::from_nanos(PACKING.load(Ordering::Relaxed)), Duration::from_nanos(UNPACKING.load(Ordering::Relaxed)))
}

fn count(counter: &AtomicU64, since: Instant) {
    counter.fetch_add(since.elapsed().as_nanos() as u64, Ordering::Relaxed);
}

/// How message fields are compressed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Compression {
    /// As they are (a fast network and little CPU to spare).
    None,
    /// LZ4 (lz4_flex): ~1 GB/s a core each way, about half the bytes of a frame's layers.
    #[default]
    Lz4,
    /// Zstandard at `level`: fewer bytes than LZ4 at a few times its CPU time.
    Zstd(i32),
}

impl Compression {
    /// The setting's value (`none`, `lz4`, `zstd`), as the settings check allows it.
    pub fn from_setting(value: &str) -> Option<Compression> {
        match value {
            "none" => Some(Compression::None),
            "lz4" => Some(Compression::Lz4),
            "zstd" => Some(Compression::Zstd(ZSTD_LEVEL)),
            _ => None,
        }
    }
}

/// Zstandard's level: 1, its fastest (level 3, its default, took 60% more time here for 4% fewer
/// bytes on a frame's tiles).
pub const ZSTD_LEVEL: i32 = 1;

/// A field's bytes as they travel: how they were packed, the size of the values they were
/// shuffled as (1: not shuffled), how many bytes they unpack to, and the packed bytes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Packed {
    how: u8,
    value_size: u16,
    raw: u64,
    #[serde(with = "serde_bytes")]
    bytes: Vec<u8>,
}

const RAW: u8 = 0;
const LZ4: u8 = 1;
const ZSTD: u8 = 2;

impl Packed {
    /// `bytes` (values of `value_size` bytes each) packed as `how` says. Fields smaller than
    /// `SMALL` go as they are: compressing them saves nothing worth the time.
    pub fn new(bytes: &[u8], value_size: usize, how: Compression) -> Packed {
        let since = Instant::now();
        let packed = Self::pack(bytes, value_size, how);
        count(&PACKING, since);
        packed
    }

    fn pack(bytes: &[u8], value_size: usize, how: Compression) -> Packed {
        let raw = bytes.len() as u64;
        if bytes.len() < SMALL || how == Compression::None {
            return Packed { how: RAW, value_size: 1, raw, bytes: bytes.to_vec() };
        }
        let value_size = if value_size > 1 && bytes.len() % value_size == 0 { value_size } else { 1 };
        let shuffled;
        let input = if value_size > 1 {
            shuffled = shuffle(bytes, value_size);
            &shuffled[..]
        } else {
            bytes
        };
        let (kind, packed) = match how {
            Compression::None => unreachable!("handled above"),
            Compression::Lz4 => (LZ4, lz4_flex::block::compress(input)),
            Compression::Zstd(level) => match zstd::bulk::compress(input, level) {
                Ok(p) => (ZSTD, p),
                // (Compressing into memory fails only on allocation; send the bytes as they are.)
                Err(_) => (RAW, input.to_vec()),
            },
        };
        if packed.len() >= input.len() {
            // Incompressible: as they are (unshuffled, and read without a step).
            return Packed { how: RAW, value_size: 1, raw, bytes: bytes.to_vec() };
        }
        Packed { how: kind, value_size: value_size as u16, raw, bytes: packed }
    }

    /// How it is packed, the size of its values, its raw size, and its bytes: for a message that
    /// lays a big field out itself (a scene).
    pub fn into_parts(self) -> (u8, u16, u64, Vec<u8>) {
        (self.how, self.value_size, self.raw, self.bytes)
    }

    /// The inverse of `into_parts` (what comes from another rank: `unpack` checks it).
    pub fn from_parts(how: u8, value_size: u16, raw: u64, bytes: Vec<u8>) -> Packed {
        Packed { how, value_size, raw, bytes }
    }

    /// The bytes it unpacks to, and the bytes it travels as.
    pub fn sizes(&self) -> (u64, u64) {
        (self.raw, self.bytes.len() as u64)
    }

    /// The original bytes, or why they cannot be had (a damaged message).
    pub fn unpack(self) -> Result<Vec<u8>, String> {
        let since = Instant::now();
        let out = self.unpacked();
        count(&UNPACKING, since);
        out
    }

    fn unpacked(self) -> Result<Vec<u8>, String> {
        let raw = usize::try_from(self.raw).map_err(|_| format!("a field of {} bytes", self.raw))?;
        // The room for it is asked for, not taken: a damaged size is an error, never an abort.
        let room = |raw: usize| -> Result<Vec<u8>, String> {
            let mut out = Vec::new();
            out.try_reserve_exact(raw).map_err(|_| format!("a field of {raw} bytes (no room for it)"))?;
            out.resize(raw, 0);
            Ok(out)
        };
        let out = match self.how {
            RAW => self.bytes,
            LZ4 => {
                let mut out = room(raw)?;
                let n = lz4_flex::block::decompress_into(&self.bytes, &mut out)
                    .map_err(|e| format!("an LZ4 field: {e}"))?;
                out.truncate(n);
                out
            }
            ZSTD => {
                let mut out = room(raw)?;
                let n = zstd::bulk::decompress_to_buffer(&self.bytes, &mut out[..])
                    .map_err(|e| format!("a zstd field: {e}"))?;
                out.truncate(n);
                out
            }
            other => return Err(format!("a field packed in an unknown way ({other})")),
        };
        if out.len() != raw {
            return Err(format!("a field of {} bytes where {raw} were sent", out.len()));
        }
        let value_size = usize::from(self.value_size);
        Ok(if value_size > 1 && out.len() % value_size == 0 { unshuffle(&out, value_size) } else { out })
    }
}

/// Below this many bytes a field is not compressed.
const SMALL: usize = 256;

/// `bytes` (whole values of `size` bytes) with byte k of every value together, for k = 0, 1, ...
pub fn shuffle(bytes: &[u8], size: usize) -> Vec<u8> {
    let n = bytes.len() / size;
    let mut out = vec![0u8; bytes.len()];
    for (k, plane) in out.chunks_exact_mut(n.max(1)).enumerate().take(size) {
        for (o, v) in plane.iter_mut().zip(bytes.chunks_exact(size)) {
            *o = v[k];
        }
    }
    out
}

/// The inverse of `shuffle`.
pub fn unshuffle(bytes: &[u8], size: usize) -> Vec<u8> {
    let n = bytes.len() / size;
    let mut out = vec![0u8; bytes.len()];
    for (k, plane) in bytes.chunks_exact(n.max(1)).enumerate().take(size) {
        for (v, b) in out.chunks_exact_mut(size).zip(plane) {
            v[k] = *b;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_come_back_as_they_went_however_packed() {
        // Depths of a smooth surface, a record of 44 bytes, a short field, nothing.
        let depth: Vec<u8> = (0..4096).flat_map(|k| (0.9 + k as f32 * 1e-5).to_le_bytes()).collect();
        let records: Vec<u8> = (0..44 * 300).map(|k| (k * 7 % 251) as u8).collect();
        for how in [Compression::None, Compression::Lz4, Compression::Zstd(ZSTD_LEVEL)] {
            for (bytes, size) in [(&depth[..], 4), (&records[..], 44), (&depth[..10], 4), (&[][..], 4), (&depth[..], 3)]
            {
                let p = Packed::new(bytes, size, how);
                assert_eq!(p.sizes().0, bytes.len() as u64);
                assert_eq!(p.clone().unpack().unwrap(), bytes, "{how:?}, {} bytes of {size}", bytes.len());
            }
            // A smooth float field packs to well under its size, once shuffled.
            if how != Compression::None {
                let (raw, sent) = Packed::new(&depth, 4, how).sizes();
                assert!(sent * 3 < raw, "{how:?}: {sent} of {raw}");
            }
        }
        assert_eq!(unshuffle(&shuffle(&records, 44), 44), records);
        assert_eq!(shuffle(&[1, 2, 3, 4, 5, 6, 7, 8], 4), [1, 5, 2, 6, 3, 7, 4, 8]);
        // Damage is refused, never a panic.
        let mut p = Packed::new(&depth, 4, Compression::Lz4);
        p.bytes.truncate(p.bytes.len() / 2);
        assert!(p.unpack().is_err());
        let bad = Packed { how: 9, value_size: 1, raw: 3, bytes: vec![1, 2, 3] };
        assert!(bad.unpack().is_err());
        let short = Packed { how: RAW, value_size: 1, raw: 5, bytes: vec![1, 2, 3] };
        let huge = Packed { how: LZ4, value_size: 1, raw: u64::MAX, bytes: vec![1, 2, 3] };
        assert!(huge.unpack().is_err(), "a size no buffer is made for");
        assert!(short.unpack().is_err());
    }
}
