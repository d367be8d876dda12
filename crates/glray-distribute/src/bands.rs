//! Which rank finishes which rows of a shared frame: the window cut into a band of rows per
//! rank that traces (`Bands`). A rank adds up its band's passes and denoises its AO, from the
//! band's own tiles and the rows around it the denoiser reads (`Band::layer_rows`), wherever
//! those were traced; then it sends each rank the part of the band that rank's data covers.
//! Nothing of a frame is finished on one rank alone, and a tile traced where its band lives
//! (the master hands each rank its own band's tiles first) crosses no link.

use std::ops::Range;

use glray_render::denoise::Band;
use glray_render::tiles::TileGrid;

/// The bands of a `width` x `height` window, one per rank that traces (in rank order), each
/// `height / n` rows or one more.
#[derive(Debug, Clone, PartialEq)]
pub struct Bands {
    width: usize,
    height: usize,
    /// (rank, its rows).
    bands: Vec<(usize, Range<usize>)>,
}

impl Bands {
    pub fn new(width: usize, height: usize, ranks: &[usize]) -> Bands {
        let n = ranks.len().max(1);
        let bands = ranks.iter().enumerate().map(|(k, &r)| (r, k * height / n..(k + 1) * height / n)).collect();
        Bands { width, height, bands }
    }

    /// Rank `rank`'s band (None: it traces nothing, or its band has no rows).
    pub fn of(&self, rank: usize) -> Option<Band> {
        let (_, rows) = self.bands.iter().find(|(r, rows)| *r == rank && !rows.is_empty())?;
        Some(Band { rows: rows.clone(), width: self.width, height: self.height })
    }

    /// The rank whose band holds row `y`.
    pub fn owner(&self, y: usize) -> Option<usize> {
        self.bands.iter().find(|(_, rows)| rows.contains(&y)).map(|(r, _)| *r)
    }

    /// Each tile's home: the rank whose band holds the tile's middle row.
    pub fn homes(&self, grid: &TileGrid) -> Vec<usize> {
        (0..grid.count())
            .map(|t| {
                let (_, y0, _, h) = grid.rect(t);
                self.owner(y0 + h / 2).unwrap_or(0)
            })
            .collect()
    }

    /// Where rows `rows` of a traced tile go: for each rank, the rows of them in its band
    /// (sent whole) and, when AO is denoised, those of the rows around its band its denoising
    /// reads (sent as their AO alone), as (rank, rows, whole).
    pub fn destinations(&self, rows: Range<usize>, denoised: bool) -> Vec<(usize, Range<usize>, bool)> {
        let mut out = Vec::new();
        for (rank, _) in &self.bands {
            let Some(band) = self.of(*rank) else { continue };
            let reads = if denoised { band.layer_rows() } else { band.rows.clone() };
            let cut = |r: &Range<usize>| rows.start.max(r.start)..rows.end.min(r.end);
            let (around, own) = (cut(&reads), cut(&band.rows));
            if around.is_empty() {
                continue;
            }
            // Above and below the band's own rows: their AO alone.
            if around.start < own.start.min(around.end) {
                out.push((*rank, around.start..own.start.min(around.end), false));
            }
            if !own.is_empty() {
                out.push((*rank, own.clone(), true));
            }
            let after = own.end.max(around.start);
            if after < around.end {
                out.push((*rank, after..around.end, false));
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_row_has_one_band_and_goes_where_it_is_read() {
        let bands = Bands::new(100, 720, &[0, 1, 2]);
        assert_eq!(bands.of(1).unwrap().rows, 240..480);
        assert_eq!((bands.owner(0), bands.owner(479), bands.owner(480)), (Some(0), Some(1), Some(2)));
        assert_eq!(bands.of(5), None);
        // A tile's rows 200..264 with AO denoised: rank 0 its band's rows 200..240 whole; rank
        // 1 the rows 240..264 whole, and the rows its denoising reads above (206..240) as AO;
        // rank 0 reads 240..264 below its band (its band ends at 240: 34 rows more).
        let d = bands.destinations(200..264, true);
        assert!(d.contains(&(0, 200..240, true)) && d.contains(&(0, 240..264, false)), "{d:?}");
        assert!(d.contains(&(1, 206..240, false)) && d.contains(&(1, 240..264, true)), "{d:?}");
        assert_eq!(d.len(), 4, "{d:?}");
        // Without denoising, only the bands' own rows.
        assert_eq!(bands.destinations(200..264, false), vec![(0, 200..240, true), (1, 240..264, true)]);
        // Each row of the window reaches its band once, whole.
        for denoised in [false, true] {
            let mut whole = vec![0; 720];
            for t in (0..720).step_by(64) {
                for (rank, rows, full) in bands.destinations(t..(t + 64).min(720), denoised) {
                    if full {
                        rows.clone().for_each(|y| whole[y] += 1);
                        assert!(rows.clone().all(|y| bands.owner(y) == Some(rank)));
                    }
                }
            }
            assert!(whole.iter().all(|&n| n == 1));
        }
        // More ranks than rows: some have no band.
        let few = Bands::new(8, 2, &[0, 1, 2, 3]);
        assert_eq!(few.of(0), None);
        assert!(few.of(1).is_some() && few.of(3).is_some());
        let grid = TileGrid::new(200, 150);
        assert_eq!(Bands::new(200, 150, &[0, 1]).homes(&grid), vec![0, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1]);
    }
}
