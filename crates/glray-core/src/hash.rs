//! What glray knows a block of memory by: 128 bits of xxh3, a big block hashed in pieces on
//! glray's threads and the pieces' hashes hashed (a 10M-triangle draw's indices and arrays are
//! 240 MB read every frame, more than one core's share of the memory's bandwidth). Capture keys
//! kept meshes by it; a BVH knows the shape it fits by it.

use xxhash_rust::xxh3::xxh3_128;

use crate::threads::{map_pieces, PIECE, SPLIT_FROM};

/// The hash of `bytes`, as two words.
pub fn content_hash(bytes: &[u8]) -> [i64; 2] {
    let h = if bytes.len() < SPLIT_FROM {
        xxh3_128(bytes)
    } else {
        let pieces = map_pieces(bytes, PIECE, xxh3_128);
        xxh3_128(&pieces.iter().flat_map(|h| h.to_ne_bytes()).collect::<Vec<u8>>())
    };
    [h as i64, (h >> 64) as i64]
}
