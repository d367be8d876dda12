//! How a frame's pixels are split into work: pieces of the image, each a band of rows and a
//! segment of columns, that threads render in any order; and the order of the 4x2 blocks of
//! camera rays within a piece.
//!
//! Frames with secondary rays go in tiles: neighbouring points' ambient-occlusion and shadow
//! rays walk much the same nodes below the top of the tree, and in 8x8 tiles a pixel's
//! neighbours above and below were traced just before it, not a row of the image ago, so their
//! nodes are still in the cache (a 10M AO pass 11-18% faster than in pairs of rows, 1M 5%;
//! docs/performance.md). Camera rays alone gain nothing from tiles and go a pair of rows at a
//! time. Either way the pieces are small enough for many threads to share a frame evenly:
//! 1,800 of 8 rows by 64 columns at 1280x720, 360 pairs of rows.

use glam::Vec4;

use crate::denoise::AoPixel;

/// The side of the square tiles that frames with secondary rays are traced in.
pub const TILE: usize = 8;

/// The columns of a piece of a frame with secondary rays: eight tiles.
pub const SEGMENT: usize = 8 * TILE;

/// A rectangle of the image that one thread renders: its rows' colours, depths and, when
/// samples are added up, linear colours, each row a slice of the image's own row.
pub(crate) struct Piece<'a> {
    /// The image's row and column at the piece's top left.
    pub y0: usize,
    pub x0: usize,
    pub rgba: Vec<&'a mut [u8]>,
    pub depth: Vec<&'a mut [f32]>,
    pub colors: Option<Vec<&'a mut [Vec4]>>,
    /// The AO kept apart for the denoiser, when it is.
    pub ao: Option<Vec<&'a mut [AoPixel]>>,
}

impl Piece<'_> {
    /// The image's rows the piece covers (first and last).
    pub fn rows(&self) -> std::ops::RangeInclusive<usize> {
        self.y0..=self.y0 + self.depth.len() - 1
    }

    /// The image's columns the piece covers.
    pub fn columns(&self) -> std::ops::Range<usize> {
        self.x0..self.x0 + self.depth[0].len()
    }
}

/// A `width`-pixel-wide image's rows split into pieces: with secondary rays, bands of `TILE`
/// rows and segments of `segment` columns (a multiple of `TILE`, at most `SEGMENT`: `SEGMENT`
/// for a whole frame, the side of the tiles image-parallel ranks are handed, so that a piece
/// lies in one tile); without (None), whole pairs of rows. A pixel comes out the same whatever
/// piece it is traced in.
pub(crate) fn split<'a>(
    rgba: &'a mut [u8],
    depth: &'a mut [f32],
    colors: Option<&'a mut [Vec4]>,
    ao: Option<&'a mut [AoPixel]>,
    width: usize,
    segment: Option<usize>,
) -> Vec<Piece<'a>> {
    let (band, segment) = match segment {
        Some(s) => (TILE, s.clamp(TILE, SEGMENT) / TILE * TILE),
        None => (2, width),
    };
    let mut pieces = Vec::new();
    if width == 0 {
        // A window with no columns (minimised) has no pixels, and no rows to cut.
        return pieces;
    }
    let mut colors = colors.map(|c| c.chunks_mut(width));
    let mut ao = ao.map(|c| c.chunks_mut(width));
    for (y, (rgba_row, depth_row)) in rgba.chunks_mut(4 * width).zip(depth.chunks_mut(width)).enumerate() {
        let colors_row = colors.as_mut().and_then(|c| c.next());
        let ao_row = ao.as_mut().and_then(|c| c.next());
        if y % band == 0 {
            // A new band: its pieces, from the left.
            let columns = (0..width).step_by(segment);
            pieces.extend(columns.map(|x0| Piece {
                y0: y,
                x0,
                rgba: Vec::with_capacity(band),
                depth: Vec::with_capacity(band),
                colors: colors_row.is_some().then(|| Vec::with_capacity(band)),
                ao: ao_row.is_some().then(|| Vec::with_capacity(band)),
            }));
        }
        let first = pieces.len() - width.div_ceil(segment);
        let band = &mut pieces[first..];
        for (p, row) in band.iter_mut().zip(rgba_row.chunks_mut(4 * segment)) {
            p.rgba.push(row);
        }
        for (p, row) in band.iter_mut().zip(depth_row.chunks_mut(segment)) {
            p.depth.push(row);
        }
        if let Some(c) = colors_row {
            for (p, row) in band.iter_mut().zip(c.chunks_mut(segment)) {
                p.colors.as_mut().expect("colours in every piece").push(row);
            }
        }
        if let Some(c) = ao_row {
            for (p, row) in band.iter_mut().zip(c.chunks_mut(segment)) {
                p.ao.as_mut().expect("AO in every piece").push(row);
            }
        }
    }
    pieces
}

/// Calls `block` with each 4x2 block of the pixels `columns` x `rows`, tile by tile (`TILE`
/// columns wide) from the left, each tile's blocks a pair of rows at a time from the top:
/// (first column, upper row, lower row); a last row without a pair is its own lower row.
/// Plain loops: as a chain of `flat_map`s over `step_by`s, the walk cost ~230 instructions a
/// block (callgrind), 1% of a GL-look frame.
pub fn for_each_block(
    columns: std::ops::Range<usize>,
    rows: std::ops::RangeInclusive<usize>,
    mut block: impl FnMut(usize, usize, usize),
) {
    let (top, last) = (*rows.start(), *rows.end());
    let mut tile = columns.start;
    while tile < columns.end {
        let end = columns.end.min(tile + TILE);
        let mut y = top;
        while y <= last {
            let mut x = tile;
            while x < end {
                block(x, y, (y + 1).min(last));
                x += 4;
            }
            y += 2;
        }
        tile += TILE;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    #[test]
    fn blocks_cover_every_pixel_once_tile_by_tile() {
        for (columns, rows) in [(0..8, 0..=7), (1..19, 0..=12), (3..4, 5..=5), (0..13, 8..=14), (2..30, 0..=1)] {
            let mut seen = HashMap::new();
            let mut tiles = Vec::new();
            for_each_block(columns.clone(), rows.clone(), |x, ya, yb| {
                assert!(yb == ya + 1 || (yb == ya && ya == *rows.end()), "rows {ya}, {yb} of {rows:?}");
                let tile = (x - columns.start) / TILE;
                assert!(tiles.last().is_none_or(|&t| t <= tile), "tile {tile} after {tiles:?}");
                tiles.push(tile);
                for y in ya..=yb {
                    for px in x..(x + 4).min(columns.end) {
                        *seen.entry((px, y)).or_insert(0) += 1;
                    }
                }
            });
            let all = columns.len() * rows.clone().count();
            assert_eq!(seen.len(), all, "{columns:?} x {rows:?}");
            assert!(seen.keys().all(|(x, y)| columns.contains(x) && rows.contains(y)));
            assert!(seen.values().all(|&n| n == 1), "{columns:?} x {rows:?}: a pixel in two blocks");
        }
    }

    #[test]
    fn pieces_hold_every_pixel_once_where_it_lies() {
        for (w, h, tiled) in [(1280, 720, true), (1280, 720, false), (131, 19, true), (7, 5, true), (7, 5, false)] {
            // Each pixel's three values name it, so that a piece's rows can be checked in place.
            let mut rgba: Vec<u8> = (0..w * h).flat_map(|i| (i as u32).to_le_bytes()).collect();
            let mut depth: Vec<f32> = (0..w * h).map(|i| i as f32).collect();
            let mut colors: Vec<Vec4> = (0..w * h).map(|i| Vec4::splat(i as f32)).collect();
            let pieces = split(&mut rgba, &mut depth, Some(&mut colors), None, w, tiled.then_some(SEGMENT));
            let mut seen = vec![0u8; w * h];
            for p in &pieces {
                let (rows, columns) = (p.rows(), p.columns());
                assert!(rows.clone().count() <= if tiled { TILE } else { 2 });
                assert!(columns.len() <= if tiled { SEGMENT } else { w });
                for (k, y) in rows.enumerate() {
                    let colors = &p.colors.as_ref().expect("asked for")[k];
                    assert_eq!(
                        (p.rgba[k].len(), p.depth[k].len(), colors.len()),
                        (4 * columns.len(), columns.len(), columns.len())
                    );
                    for (j, x) in columns.clone().enumerate() {
                        let i = y * w + x;
                        assert_eq!(p.rgba[k][4 * j..4 * j + 4], (i as u32).to_le_bytes(), "({x}, {y})");
                        assert_eq!((p.depth[k][j], colors[j].x), (i as f32, i as f32), "({x}, {y})");
                        seen[i] += 1;
                    }
                }
            }
            assert!(seen.iter().all(|&n| n == 1), "{w}x{h}: every pixel in exactly one piece");
            if (w, h) == (1280, 720) {
                assert_eq!(pieces.len(), if tiled { 1800 } else { 360 }, "enough pieces for many threads");
            }
        }
        for tiled in [true, false] {
            let tiled = tiled.then_some(SEGMENT);
            assert!(split(&mut [], &mut [], None, None, 0, tiled).is_empty(), "a window without columns has no pieces");
        }
    }
}
