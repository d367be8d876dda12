//! The master's tile queue (the paper's two-level load balancing, first level): each rank gets a
//! first batch, then chunks from a shared queue as it asks, smaller as the queue empties
//! (guided self-scheduling), each rank's share sized by how fast it traced the last frame. A
//! tile goes back to the rank that traced it last frame unless that rank was the slowest, so
//! that what a rank holds for a tile (paging's caches, next) stays warm. The second level is
//! each rank's threads sharing its chunks (rayon, in the renderer).

use std::collections::VecDeque;

/// Of the frame's tiles, the part handed out in first batches (the rest is the queue).
const FIRST_SHARE: f64 = 0.5;

pub struct Master {
    ranks: usize,
    /// Which rank traced each tile last frame.
    owner: Vec<Option<u32>>,
    /// Each rank's speed last frame, in tiles a second (None before the first frame).
    speed: Vec<Option<f64>>,
    queue: VecDeque<u32>,
    /// Tiles handed out this frame, per rank.
    given: Vec<Vec<u32>>,
    /// Ranks that trace nothing (a dedicated master).
    idle: Vec<bool>,
}

impl Master {
    pub fn new(ranks: usize) -> Master {
        Master {
            ranks,
            owner: Vec::new(),
            speed: vec![None; ranks],
            queue: VecDeque::new(),
            given: vec![Vec::new(); ranks],
            idle: vec![false; ranks],
        }
    }

    /// Rank `rank` traces nothing: it only hands out and gathers (a dedicated master and
    /// display). Not when it is the only rank.
    pub fn leave_out(&mut self, rank: usize) {
        if self.ranks > 1 && rank < self.ranks {
            self.idle[rank] = true;
        }
    }

    /// Whether `rank` traces tiles.
    pub fn traces(&self, rank: usize) -> bool {
        self.idle.get(rank) != Some(&true)
    }

    /// Each rank's share of the work by last frame's speeds (equal before any).
    fn shares(&self) -> Vec<f64> {
        let speeds: Vec<f64> = self
            .speed
            .iter()
            .zip(&self.idle)
            .map(|(s, &idle)| if idle { 0.0 } else { s.unwrap_or(1.0).max(1e-9) })
            .collect();
        let total: f64 = speeds.iter().sum();
        speeds.iter().map(|s| s / total).collect()
    }

    /// A new frame of `tiles` tiles: the first batch of each rank.
    pub fn begin(&mut self, tiles: u32) -> Vec<Vec<u32>> {
        if self.owner.len() != tiles as usize {
            // Another window size: last frame's tiles are not this frame's.
            self.owner = vec![None; tiles as usize];
        }
        let shares = self.shares();
        let working = (0..self.ranks).filter(|&r| !self.idle[r]);
        let slowest = (self.speed.iter().all(Option::is_some) && self.ranks > 1)
            .then(|| working.min_by(|&a, &b| shares[a].total_cmp(&shares[b])))
            .flatten();
        let quota: Vec<usize> = shares.iter().map(|s| (s * FIRST_SHARE * f64::from(tiles)).floor() as usize).collect();
        let mut batches: Vec<Vec<u32>> = vec![Vec::new(); self.ranks];
        let mut taken = vec![false; tiles as usize];
        // Tiles back to last frame's rank, within its quota (not to the slowest rank).
        for t in 0..tiles {
            if let Some(r) = self.owner[t as usize].map(|r| r as usize).filter(|&r| r < self.ranks) {
                if Some(r) != slowest && batches[r].len() < quota[r] {
                    batches[r].push(t);
                    taken[t as usize] = true;
                }
            }
        }
        // First frames: each rank a band of rows of its own, in rank order.
        let mut free = (0..tiles).filter(|&t| !taken[t as usize]);
        for (r, batch) in batches.iter_mut().enumerate() {
            while batch.len() < quota[r] {
                match free.next() {
                    Some(t) => batch.push(t),
                    None => break,
                }
            }
        }
        let mut queue: VecDeque<u32> = free.collect();
        // What a batch did not take of its own tiles is queued in order.
        queue.make_contiguous().sort_unstable();
        self.queue = queue;
        self.given = batches.clone();
        batches
    }

    /// The next chunk for `rank`: a share of what is left by its speed, halved (so that the
    /// last chunks are small and every rank ends near the same time); empty when all is out.
    pub fn next(&mut self, rank: usize) -> Vec<u32> {
        if self.idle.get(rank) == Some(&true) {
            return Vec::new();
        }
        let left = self.queue.len();
        let share = self.shares()[rank.min(self.ranks - 1)];
        let n = ((left as f64 * share / 2.0).ceil() as usize).clamp(1.min(left), left);
        let chunk: Vec<u32> = self.queue.drain(..n).collect();
        if let Some(g) = self.given.get_mut(rank) {
            g.extend(&chunk);
        }
        chunk
    }

    /// Tiles handed out so far this frame, per rank.
    pub fn given(&self) -> &[Vec<u32>] {
        &self.given
    }

    /// The frame ended: each rank traced its tiles in `seconds[rank]` (None: not known). Last
    /// frame's owners and speeds are what the next frame's batches go by.
    pub fn end(&mut self, seconds: &[Option<f64>]) {
        for (r, tiles) in self.given.iter().enumerate() {
            for &t in tiles {
                if let Some(o) = self.owner.get_mut(t as usize) {
                    *o = Some(r as u32);
                }
            }
            self.speed[r] = match seconds.get(r).copied().flatten() {
                Some(s) if !tiles.is_empty() => Some(tiles.len() as f64 / s.max(1e-6)),
                _ => None,
            };
        }
    }
}

/// The load imbalance of a frame: the slowest rank's time over the mean (1.0: even).
pub fn imbalance(seconds: &[f64]) -> f64 {
    let mean = seconds.iter().sum::<f64>() / seconds.len().max(1) as f64;
    if mean <= 0.0 {
        return 1.0;
    }
    seconds.iter().copied().fold(0.0, f64::max) / mean
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all_given(m: &mut Master, batches: Vec<Vec<u32>>, tiles: u32) -> Vec<u32> {
        let mut seen: Vec<u32> = batches.into_iter().flatten().collect();
        let mut r = 0;
        loop {
            if !m.traces(r % m.ranks) {
                r += 1;
                continue;
            }
            let chunk = m.next(r % m.ranks);
            if chunk.is_empty() {
                break;
            }
            seen.extend(chunk);
            r += 1;
        }
        seen.sort_unstable();
        assert_eq!(seen, (0..tiles).collect::<Vec<_>>(), "every tile handed out once");
        seen
    }

    #[test]
    fn every_tile_is_handed_out_once_in_shrinking_chunks() {
        for (ranks, tiles) in [(1, 1), (1, 40), (3, 40), (4, 7), (2, 300)] {
            let mut m = Master::new(ranks);
            let batches = m.begin(tiles);
            assert!(batches.iter().all(|b| b.len() <= tiles as usize / (2 * ranks) + 1));
            all_given(&mut m, batches, tiles);
        }
        let mut m = Master::new(2);
        m.begin(200);
        let sizes: Vec<usize> = (0..6).map(|k| m.next(k % 2).len()).collect();
        assert!(sizes.windows(2).all(|w| w[1] <= w[0]), "chunks shrink: {sizes:?}");
    }

    #[test]
    fn a_faster_rank_gets_more_and_tiles_stay_where_they_were() {
        let mut m = Master::new(2);
        let first = m.begin(100);
        all_given(&mut m, first, 100);
        // Rank 1 traced three times as fast.
        let (g0, g1) = (m.given()[0].len() as f64, m.given()[1].len() as f64);
        m.end(&[Some(g0 / 10.0), Some(g1 / 30.0)]);
        let last: Vec<Vec<u32>> = m.given().to_vec();
        let batches = m.begin(100);
        assert!(batches[1].len() > 2 * batches[0].len(), "{} vs {}", batches[1].len(), batches[0].len());
        // The fast rank's first batch is made of tiles it traced last frame.
        assert!(batches[1].iter().all(|t| last[1].contains(t)), "affinity: {:?}", batches[1]);
        all_given(&mut m, batches, 100);
        // A dedicated master traces nothing; the others share all.
        let mut m = Master::new(3);
        m.leave_out(0);
        let batches = m.begin(60);
        assert!(batches[0].is_empty() && m.next(0).is_empty());
        all_given(&mut m, batches, 60);
        let mut alone = Master::new(1);
        alone.leave_out(0);
        assert_eq!(alone.begin(4)[0].len(), 2, "the only rank traces");
        assert!((imbalance(&[1.0, 1.0]) - 1.0).abs() < 1e-9 && (imbalance(&[1.0, 3.0]) - 1.5).abs() < 1e-9);
    }
}
