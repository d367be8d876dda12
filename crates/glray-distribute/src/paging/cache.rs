//! A rank's cache of other ranks' blocks: a byte budget, CLOCK replacement (second chance: a
//! block used since the hand last passed it is passed over once), blocks in use pinned.
//!
//! A block is in use while a tracer thread holds it (`Arc<Block>`: the cache's own reference
//! and the thread's); the hand never evicts one, so a walk or a shading never loses its block.
//! When every block is pinned and the budget is full, the new block goes in all the same
//! (counted in `over`): a frame whose threads hold more than the budget at once is not refused.
//! A rank's own blocks never enter (they are resident).

use std::collections::HashMap;
use std::sync::Arc;

use glray_render::paged::Block;

struct Slot {
    key: u64,
    block: Arc<Block>,
    bytes: u64,
    referenced: bool,
    /// Used since `take_touched` was last called (it is then in `touched`).
    touched: bool,
}

#[derive(Default)]
pub struct Cache {
    capacity: u64,
    used: u64,
    slots: Vec<Option<Slot>>,
    free: Vec<usize>,
    index: HashMap<u64, usize>,
    hand: usize,
    /// The blocks used since `take_touched` was last called, in the order of their first use
    /// (one entry each: what a frame's rays needed, for prefetching it the next frame).
    touched: Vec<u64>,
    /// Blocks taken in over the budget (every block pinned).
    pub over: u64,
}

impl Cache {
    /// A cache of `capacity` bytes.
    pub fn new(capacity: u64) -> Cache {
        Cache { capacity, ..Cache::default() }
    }

    pub fn capacity(&self) -> u64 {
        self.capacity
    }

    /// Bytes of the blocks it holds.
    pub fn used(&self) -> u64 {
        self.used
    }

    pub fn len(&self) -> usize {
        self.index.len()
    }

    pub fn is_empty(&self) -> bool {
        self.index.is_empty()
    }

    /// A new budget; blocks over it go as the next blocks come in.
    pub fn set_capacity(&mut self, capacity: u64) {
        self.capacity = capacity;
    }

    /// Block `key`, marked used, if held.
    pub fn get(&mut self, key: u64) -> Option<Arc<Block>> {
        let slot = self.slots[*self.index.get(&key)?].as_mut().expect("indexed slots are full");
        slot.referenced = true;
        if !slot.touched {
            slot.touched = true;
            self.touched.push(key);
        }
        Some(slot.block.clone())
    }

    /// Takes `block` in (`bytes` of it), evicting what CLOCK picks to stay within the budget;
    /// how many blocks it evicted.
    pub fn insert(&mut self, key: u64, block: Arc<Block>, bytes: u64) -> u32 {
        if self.index.contains_key(&key) {
            return 0;
        }
        let mut evicted = 0;
        // Two turns of the hand clear every mark and find every unpinned block.
        let mut steps = 2 * self.slots.len();
        while self.used + bytes > self.capacity && !self.index.is_empty() && steps > 0 {
            steps -= 1;
            self.hand = (self.hand + 1) % self.slots.len();
            let Some(slot) = self.slots[self.hand].as_mut() else { continue };
            if slot.referenced {
                slot.referenced = false;
                continue;
            }
            if Arc::strong_count(&slot.block) > 1 {
                continue;
            }
            let slot = self.slots[self.hand].take().expect("looked at");
            self.index.remove(&slot.key);
            self.used -= slot.bytes;
            self.free.push(self.hand);
            evicted += 1;
        }
        if self.used + bytes > self.capacity {
            self.over += 1;
        }
        self.touched.push(key);
        let slot = Slot { key, block, bytes, referenced: true, touched: true };
        let at = match self.free.pop() {
            Some(at) => {
                self.slots[at] = Some(slot);
                at
            }
            None => {
                self.slots.push(Some(slot));
                self.slots.len() - 1
            }
        };
        self.index.insert(key, at);
        self.used += bytes;
        evicted
    }

    /// Forgets block `key` (its mesh is gone).
    pub fn remove(&mut self, key: u64) {
        if let Some(at) = self.index.remove(&key) {
            let slot = self.slots[at].take().expect("indexed slots are full");
            self.used -= slot.bytes;
            self.free.push(at);
        }
    }

    /// The blocks used since this was last called, first used first (those evicted since
    /// included), and a new count from now.
    pub fn take_touched(&mut self) -> Vec<u64> {
        let touched = std::mem::take(&mut self.touched);
        for k in &touched {
            if let Some(&at) = self.index.get(k) {
                self.slots[at].as_mut().expect("indexed slots are full").touched = false;
            }
        }
        touched
    }

    /// Whether block `key` is held (not marked used).
    pub fn holds(&self, key: u64) -> bool {
        self.index.contains_key(&key)
    }

    /// The keys it holds.
    pub fn keys(&self) -> Vec<u64> {
        self.index.keys().copied().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use glray_scene::mesh::Mesh;

    fn block() -> Arc<Block> {
        let mesh = Mesh::indexed(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![Vec3::Z; 3], vec![[0, 1, 2]]).unwrap();
        Arc::new(Block::new(mesh))
    }

    #[test]
    fn clock_evicts_the_blocks_not_used_since_the_hand_passed_and_never_a_pinned_one() {
        let mut c = Cache::new(300);
        for k in 0..3 {
            assert_eq!(c.insert(k, block(), 100), 0);
        }
        assert_eq!((c.len(), c.used()), (3, 300));
        // Every block is marked as it comes in: the hand clears the marks, then takes the
        // first unmarked one after it.
        assert_eq!(c.insert(3, block(), 100), 1);
        assert_eq!((c.len(), c.used()), (3, 300));
        let held: Vec<u64> = (0..4).filter(|&k| c.index.contains_key(&k)).collect();
        assert_eq!(held.len(), 3);
        // A block used since is passed over once; a pinned one (a thread holds it) always.
        let pinned = c.get(held[0]).unwrap();
        let pinned2 = c.get(held[1]).unwrap();
        assert_eq!(c.insert(4, block(), 100), 1);
        assert!(c.index.contains_key(&held[0]) && c.index.contains_key(&held[1]), "pinned blocks stay");
        assert!(!c.index.contains_key(&held[2]));
        // Everything pinned: the block goes in over the budget, counted.
        let pinned3 = c.get(4).unwrap();
        assert_eq!(c.insert(5, block(), 100), 0);
        assert_eq!((c.over, c.used()), (1, 400));
        drop((pinned, pinned2, pinned3));
        // Unpinned, the next block brings it back under the budget.
        assert!(c.insert(6, block(), 100) >= 2);
        assert!(c.used() <= 300, "{}", c.used());
        c.remove(6);
        assert!(c.get(6).is_none());
    }

    #[test]
    fn the_blocks_used_since_last_asked_come_once_each_first_used_first_evicted_ones_too() {
        let mut c = Cache::new(200);
        c.insert(1, block(), 100);
        c.insert(2, block(), 100);
        c.get(2);
        c.get(1);
        assert_eq!(c.take_touched(), vec![1, 2]);
        assert!(c.take_touched().is_empty(), "a new count after each call");
        c.get(2);
        c.get(2);
        // Block 3 evicts one of them: it was used all the same.
        c.insert(3, block(), 100);
        c.get(1);
        let touched = c.take_touched();
        assert_eq!(&touched[..2], &[2, 3]);
        assert_eq!(touched.len(), if c.holds(1) { 3 } else { 2 });
    }
}
