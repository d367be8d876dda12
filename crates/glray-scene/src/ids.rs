//! Ids of meshes and texture versions, unique across the ranks of an MPI job: a rank's objects
//! travel to every other rank (`encode`), and the tracer keeps each mesh's BVH by its id, so
//! two ranks must never make the same one. Each process counts from 1 in its own space, set
//! from its rank before it makes any object (`set_space`); a process that is no MPI rank keeps
//! space 0, the ids it always had.

use std::sync::atomic::{AtomicU64, Ordering};

/// The bits of an id that count within a space: 2^40 objects a process.
const COUNT_BITS: u32 = 40;

static SPACE: AtomicU64 = AtomicU64::new(0);
static NEXT: AtomicU64 = AtomicU64::new(1);

/// Makes the ids from here on those of `space` (a rank + 1: space 0 is a lone process's).
pub fn set_space(space: u32) {
    SPACE.store(u64::from(space) << COUNT_BITS, Ordering::Relaxed);
}

/// A new id, never given before in this process's space.
pub fn next() -> u64 {
    SPACE.load(Ordering::Relaxed) | (NEXT.fetch_add(1, Ordering::Relaxed) & ((1 << COUNT_BITS) - 1))
}

/// The space an id was made in.
pub fn space_of(id: u64) -> u32 {
    (id >> COUNT_BITS) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_of_two_spaces_never_meet() {
        let a = next();
        set_space(3);
        let b = next();
        set_space(0);
        assert_ne!(a, b);
        assert_eq!((space_of(a), space_of(b)), (0, 3));
        assert!(next() > a, "counting goes on in space 0");
    }
}
