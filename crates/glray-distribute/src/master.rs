//! The master's tile queue (the paper's two-level load balancing, first level): each rank gets a
//! first batch, then chunks as it asks, smaller as the tiles left run out (guided
//! self-scheduling), each rank's share sized by how fast it traced the last frame. Every tile
//! has a home, the rank whose band of rows it is in (`bands`): a rank is given its own band's
//! tiles first, and another's only once its own are out (taken from the far end of the band
//! with the most left), so that a tile is mostly traced where its band is added up and
//! denoised, and crosses no link, and what a rank holds for its tiles (paging's caches, next)
//! stays warm from frame to frame. The second level is each rank's threads sharing its chunks
//! (rayon, in the renderer).

use std::collections::VecDeque;

/// Of the frame's tiles, the part handed out in first batches (the rest is the queue).
const FIRST_SHARE: f64 = 0.5;

pub struct Master {
    ranks: usize,
    /// Each rank's speed last frame, in tiles a second (None before the first frame).
    speed: Vec<Option<f64>>,
    /// Each rank's own tiles not handed out yet, in order.
    queues: Vec<VecDeque<u32>>,
    /// Tiles handed out this frame, per rank.
    given: Vec<Vec<u32>>,
    /// Ranks that trace nothing (a dedicated master).
    idle: Vec<bool>,
}

impl Master {
    pub fn new(ranks: usize) -> Master {
        Master {
            ranks,
            speed: vec![None; ranks],
            queues: vec![VecDeque::new(); ranks],
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

    /// The ranks that trace, in order.
    pub fn tracing(&self) -> Vec<usize> {
        (0..self.ranks).filter(|&r| self.traces(r)).collect()
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

    /// A new frame whose tile `t` has its home on rank `homes[t]`: the first batch of each rank,
    /// of its own tiles.
    pub fn begin(&mut self, homes: &[usize]) -> Vec<Vec<u32>> {
        let tiles = homes.len();
        let shares = self.shares();
        self.queues = vec![VecDeque::new(); self.ranks];
        for (t, &home) in homes.iter().enumerate() {
            // (A home that traces nothing, or no rank: the first rank that traces takes it.)
            let home = if home < self.ranks && self.traces(home) { home } else { self.tracing()[0] };
            self.queues[home].push_back(t as u32);
        }
        let batches: Vec<Vec<u32>> = (0..self.ranks)
            .map(|r| {
                let quota = (shares[r] * FIRST_SHARE * tiles as f64).floor() as usize;
                let n = quota.min(self.queues[r].len());
                self.queues[r].drain(..n).collect()
            })
            .collect();
        self.given = batches.clone();
        batches
    }

    /// The next chunk for `rank`: a share of what is left by its speed, halved (so that the
    /// last chunks are small and every rank ends near the same time), of its own tiles first,
    /// then from the far end of the band with the most left; empty when all is out.
    pub fn next(&mut self, rank: usize) -> Vec<u32> {
        if rank >= self.ranks || self.idle[rank] {
            return Vec::new();
        }
        let left: usize = self.queues.iter().map(VecDeque::len).sum();
        let share = self.shares()[rank];
        let n = ((left as f64 * share / 2.0).ceil() as usize).clamp(1.min(left), left);
        let own = n.min(self.queues[rank].len());
        let mut chunk: Vec<u32> = self.queues[rank].drain(..own).collect();
        while chunk.len() < n {
            let Some(most) = (0..self.ranks).max_by_key(|&r| (self.queues[r].len(), std::cmp::Reverse(r))) else {
                break;
            };
            let Some(t) = self.queues[most].pop_back() else { break };
            chunk.push(t);
        }
        self.given[rank].extend(&chunk);
        chunk
    }

    /// Tiles handed out so far this frame, per rank.
    pub fn given(&self) -> &[Vec<u32>] {
        &self.given
    }

    /// The frame ended: each rank traced its tiles in `seconds[rank]` (None: not known). Last
    /// frame's speeds are what the next frame's shares go by.
    pub fn end(&mut self, seconds: &[Option<f64>]) {
        for (r, tiles) in self.given.iter().enumerate() {
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

    /// Tiles 0..tiles, in bands of the first ranks (`tiles / ranks` each).
    fn homes(tiles: u32, ranks: usize) -> Vec<usize> {
        (0..tiles as usize).map(|t| t * ranks / tiles as usize).collect()
    }

    #[test]
    fn every_tile_is_handed_out_once_in_shrinking_chunks_its_own_first() {
        for (ranks, tiles) in [(1, 1), (1, 40), (3, 40), (4, 7), (2, 300)] {
            let mut m = Master::new(ranks);
            let batches = m.begin(&homes(tiles, ranks));
            assert!(batches.iter().all(|b| b.len() <= tiles as usize / (2 * ranks) + 1));
            all_given(&mut m, batches, tiles);
        }
        let mut m = Master::new(2);
        let batches = m.begin(&homes(200, 2));
        assert!(batches[0].iter().all(|&t| t < 100) && batches[1].iter().all(|&t| t >= 100), "own tiles first");
        let sizes: Vec<usize> = (0..6).map(|k| m.next(k % 2).len()).collect();
        assert!(sizes.windows(2).all(|w| w[1] <= w[0]), "chunks shrink: {sizes:?}");
        // Asking in turn (as ranks of the same speed do), all but the last few tiles stay at
        // home.
        let mut m = Master::new(2);
        let batches = m.begin(&homes(100, 2));
        all_given(&mut m, batches, 100);
        let away = m.given()[0].iter().filter(|&&t| t >= 50).count() + m.given()[1].iter().filter(|&&t| t < 50).count();
        assert!(away <= 5, "{away} tiles away from home: {:?}", m.given());
    }

    #[test]
    fn a_faster_rank_gets_more_taken_from_the_far_end_of_another_band() {
        let mut m = Master::new(2);
        let first = m.begin(&homes(100, 2));
        all_given(&mut m, first, 100);
        // Rank 1 traced three times as fast.
        let (g0, g1) = (m.given()[0].len() as f64, m.given()[1].len() as f64);
        m.end(&[Some(g0 / 10.0), Some(g1 / 30.0)]);
        let batches = m.begin(&homes(100, 2));
        assert!(batches[1].len() > 2 * batches[0].len(), "{} vs {}", batches[1].len(), batches[0].len());
        let given = all_given(&mut m, batches, 100);
        assert_eq!(given.len(), 100);
        // Rank 1 ran out of its own and took rank 0's last tiles (the far end of its band).
        let stolen: Vec<u32> = m.given()[1].iter().copied().filter(|&t| t < 50).collect();
        assert!(!stolen.is_empty() && stolen.iter().all(|&t| t >= 25), "{stolen:?}");
        // A dedicated master traces nothing; the others share all, its band's tiles too.
        let mut m = Master::new(3);
        m.leave_out(0);
        let batches = m.begin(&homes(60, 3));
        assert!(batches[0].is_empty() && m.next(0).is_empty());
        all_given(&mut m, batches, 60);
        let mut alone = Master::new(1);
        alone.leave_out(0);
        assert_eq!(alone.begin(&homes(4, 1))[0].len(), 2, "the only rank traces");
        assert!((imbalance(&[1.0, 1.0]) - 1.0).abs() < 1e-9 && (imbalance(&[1.0, 3.0]) - 1.5).abs() < 1e-9);
    }
}
