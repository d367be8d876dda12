//! Pieces of a frame traced with parking (paging's misses): a piece whose rays reached a block
//! not on this rank is put back as it was and set aside, its blocks asked for, while the thread
//! traces the next pieces; a few pieces later it is tried again (its blocks have come by then,
//! or its rays, now stopped where they should be, reach new ones), and after `TRIES` tries it is
//! traced waiting for whatever is still missing. Misses overlap instead of each holding a thread
//! for a round trip; a piece comes out exactly as it would have without parking (it is traced
//! whole, from its own first values, with every block it reaches).

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

use glam::Vec4;

use crate::denoise::AoPixel;
use crate::paged::Pager;
use crate::pieces::Piece;

/// How many pieces a thread keeps set aside before it tries the oldest again: enough for their
/// blocks to travel while it traces others, few enough that the blocks that came for them are
/// still there (they wait outside the cache until a piece takes them).
const AHEAD: usize = 3;

/// Tries of a piece in parking mode before it is traced waiting for its blocks.
const TRIES: u32 = 3;

/// Traces `pieces` with `process`, on every thread; parks pieces when `pager` parks.
pub(crate) fn trace(pieces: Vec<Piece<'_>>, process: &(dyn Fn(&mut Piece) + Sync), pager: Option<&Arc<dyn Pager>>) {
    use rayon::prelude::*;
    let Some(pager) = pager.filter(|p| p.parks()) else {
        return pieces.into_par_iter().for_each(|mut p| process(&mut p));
    };
    // Pieces in order, taken from the back.
    let queue = Mutex::new(pieces.into_iter().rev().collect::<Vec<_>>());
    let take = || queue.lock().unwrap_or_else(|e| e.into_inner()).pop();
    rayon::broadcast(|_| {
        let mut aside: VecDeque<(Piece, Kept, u32)> = VecDeque::new();
        loop {
            let next = match aside.len() >= AHEAD {
                true => aside.pop_front(),
                false => take()
                    .map(|p| {
                        let kept = Kept::of(&p);
                        (p, kept, 0)
                    })
                    .or_else(|| aside.pop_front()),
            };
            let Some((mut piece, kept, tries)) = next else { break };
            if tries >= TRIES {
                process(&mut piece);
                continue;
            }
            pager.park();
            process(&mut piece);
            if pager.unpark() {
                kept.restore(&mut piece);
                aside.push_back((piece, kept, tries + 1));
            }
        }
    });
}

/// A piece's values before it was traced: tracing starts from them (a pixel known to miss
/// keeps what it held; passes add to what is there).
struct Kept {
    rgba: Vec<Vec<u8>>,
    depth: Vec<Vec<f32>>,
    colors: Option<Vec<Vec<Vec4>>>,
    ao: Option<Vec<Vec<AoPixel>>>,
}

impl Kept {
    fn of(p: &Piece) -> Kept {
        fn rows<T: Copy>(rows: &[&mut [T]]) -> Vec<Vec<T>> {
            rows.iter().map(|r| r.to_vec()).collect()
        }
        Kept {
            rgba: rows(&p.rgba),
            depth: rows(&p.depth),
            colors: p.colors.as_deref().map(rows),
            ao: p.ao.as_deref().map(rows),
        }
    }

    fn restore(&self, p: &mut Piece) {
        fn rows<T: Copy>(to: &mut [&mut [T]], from: &[Vec<T>]) {
            for (t, f) in to.iter_mut().zip(from) {
                t.copy_from_slice(f);
            }
        }
        rows(&mut p.rgba, &self.rgba);
        rows(&mut p.depth, &self.depth);
        if let (Some(to), Some(from)) = (p.colors.as_deref_mut(), &self.colors) {
            rows(to, from);
        }
        if let (Some(to), Some(from)) = (p.ao.as_deref_mut(), &self.ao) {
            rows(to, from);
        }
    }
}
