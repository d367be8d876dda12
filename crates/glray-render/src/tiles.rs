//! A frame traced in tiles handed out one chunk at a time (`TileWork`): how image-parallel
//! ranks share a frame. The tiles are squares in a fixed grid over the window (`TileGrid`): 64
//! pixels a side, or 32 or 16 when there are many ranks to share them (`TileGrid::for_ranks`),
//! traced in pieces that lie inside one tile; a pixel comes out the same whichever rank,
//! thread, chunk or tile size traces it.

use glam::Vec4;

use crate::denoise::AoPixel;

/// The side of a tile: eight bands of the pieces frames with secondary rays are traced in, and
/// one segment of their columns (`pieces::TILE`, `pieces::SEGMENT`).
pub const TILE_SIDE: usize = crate::pieces::SEGMENT;

/// The sides a grid may take, largest first: multiples of the pieces' bands of rows.
pub const TILE_SIDES: [usize; 3] = [TILE_SIDE, TILE_SIDE / 2, TILE_SIDE / 4];

/// Tiles a tracing rank is to have at least, for the master's chunks to even the ranks out (at
/// 64x64, a 1280x720 frame has 240 tiles: 3.75 a rank at 64 ranks, and one slow tile is a
/// quarter of a rank's frame).
pub const TILES_PER_RANK: usize = 16;

/// The tiles of a `width` x `height` window, numbered row by row from the bottom left (GL's
/// first row).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TileGrid {
    pub width: u32,
    pub height: u32,
    side: usize,
}

impl TileGrid {
    /// Tiles of `TILE_SIDE`.
    pub fn new(width: u32, height: u32) -> TileGrid {
        TileGrid { width, height, side: TILE_SIDE }
    }

    /// Tiles of the largest of `TILE_SIDES` that gives each of `ranks` tracing ranks
    /// `TILES_PER_RANK` tiles (the smallest side when none does).
    pub fn for_ranks(width: u32, height: u32, ranks: usize) -> TileGrid {
        let side = TILE_SIDES
            .into_iter()
            .find(|&side| TileGrid { width, height, side }.count() as usize >= TILES_PER_RANK * ranks)
            .unwrap_or(TILE_SIDES[TILE_SIDES.len() - 1]);
        TileGrid { width, height, side }
    }

    /// The side of its tiles.
    pub fn side(&self) -> usize {
        self.side
    }

    fn columns(&self) -> usize {
        (self.width as usize).div_ceil(self.side)
    }

    /// How many tiles cover the window.
    pub fn count(&self) -> u32 {
        (self.columns() * (self.height as usize).div_ceil(self.side)) as u32
    }

    /// Tile `tile`'s first column and row, and its width and height (smaller at the right and
    /// top edges).
    pub fn rect(&self, tile: u32) -> (usize, usize, usize, usize) {
        let (tx, ty) = (tile as usize % self.columns(), tile as usize / self.columns());
        let (x0, y0) = (tx * self.side, ty * self.side);
        (x0, y0, self.side.min(self.width as usize - x0), self.side.min(self.height as usize - y0))
    }

    /// The tile holding pixel (x, y).
    pub fn tile_at(&self, x: usize, y: usize) -> u32 {
        ((y / self.side) * self.columns() + x / self.side) as u32
    }

    /// Tile `tile`'s pixels cut out of a whole image's (rows bottom-up, as `Rendered`).
    pub fn cut(&self, tile: u32, image: Layers<'_>) -> TilePixels {
        let Layers { rgba, depth, colors, ao } = image;
        let (x0, y0, w, h) = self.rect(tile);
        let width = self.width as usize;
        let mut out = TilePixels {
            tile,
            rgba: Vec::with_capacity(4 * w * h),
            depth: Vec::with_capacity(w * h),
            colors: Vec::with_capacity(if colors.is_some() { w * h } else { 0 }),
            ao: Vec::with_capacity(if ao.is_some() { w * h } else { 0 }),
        };
        for y in y0..y0 + h {
            let row = y * width + x0;
            out.rgba.extend_from_slice(&rgba[4 * row..4 * (row + w)]);
            out.depth.extend_from_slice(&depth[row..row + w]);
            if let Some(c) = colors {
                out.colors.extend_from_slice(&c[row..row + w]);
            }
            if let Some(a) = ao {
                out.ao.extend_from_slice(&a[row..row + w]);
            }
        }
        out
    }

    /// Puts a tile's pixels into a whole image's. False (and nothing written) when they do not
    /// have the tile's size, or lack a layer the image has: a message from another window size
    /// or a damaged one.
    pub fn paste(&self, t: &TilePixels, image: LayersMut<'_>) -> bool {
        if t.tile >= self.count() {
            return false;
        }
        let LayersMut { rgba, depth, mut colors, mut ao } = image;
        let (x0, y0, w, h) = self.rect(t.tile);
        let sized = |has: bool, len: usize| !has || len == w * h;
        if t.rgba.len() != 4 * w * h
            || t.depth.len() != w * h
            || !sized(colors.is_some(), t.colors.len())
            || !sized(ao.is_some(), t.ao.len())
        {
            return false;
        }
        let width = self.width as usize;
        for (k, y) in (y0..y0 + h).enumerate() {
            let row = y * width + x0;
            rgba[4 * row..4 * (row + w)].copy_from_slice(&t.rgba[4 * k * w..4 * (k + 1) * w]);
            depth[row..row + w].copy_from_slice(&t.depth[k * w..(k + 1) * w]);
            if let Some(c) = colors.as_deref_mut() {
                c[row..row + w].copy_from_slice(&t.colors[k * w..(k + 1) * w]);
            }
            if let Some(a) = ao.as_deref_mut() {
                a[row..row + w].copy_from_slice(&t.ao[k * w..(k + 1) * w]);
            }
        }
        true
    }
}

/// A whole image's layers, as a frame's render holds them: colours, depths, and where kept,
/// colours before rounding and the AO kept apart for the denoiser.
#[derive(Clone, Copy)]
pub struct Layers<'a> {
    pub rgba: &'a [u8],
    pub depth: &'a [f32],
    pub colors: Option<&'a [Vec4]>,
    pub ao: Option<&'a [AoPixel]>,
}

/// `Layers`, to paste tiles into.
pub struct LayersMut<'a> {
    pub rgba: &'a mut [u8],
    pub depth: &'a mut [f32],
    pub colors: Option<&'a mut [Vec4]>,
    pub ao: Option<&'a mut [AoPixel]>,
}

/// One traced tile: its pixels row by row from the bottom, their colours before rounding
/// when samples are added up over passes or the AO is denoised (else empty), and the AO kept
/// apart for the denoiser (else empty).
#[derive(Debug, Clone, PartialEq)]
pub struct TilePixels {
    pub tile: u32,
    pub rgba: Vec<u8>,
    pub depth: Vec<f32>,
    pub colors: Vec<Vec4>,
    pub ao: Vec<AoPixel>,
}

/// Where the tiles a render traces come from and where they go: a rank's share of a frame,
/// asked for chunk by chunk while it traces (`Renderer::render_tiles`).
pub trait TileWork: Sync {
    /// The grid the tiles are numbered in, over a `width` x `height` window.
    fn grid(&self, width: u32, height: u32) -> TileGrid {
        TileGrid::new(width, height)
    }
    /// The next tiles to trace; None when there are no more for this rank this frame.
    fn next(&self) -> Option<Vec<u32>>;
    /// A tile traced.
    fn done(&self, pixels: TilePixels);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_the_window_and_cut_and_paste_back() {
        let grid = TileGrid::new(150, 70);
        assert_eq!(grid.count(), 3 * 2);
        assert_eq!(grid.rect(2), (128, 0, 22, 64));
        assert_eq!(grid.rect(5), (128, 64, 22, 6));
        assert_eq!(grid.tile_at(149, 69), 5);
        let n = 150 * 70;
        let rgba: Vec<u8> = (0..4 * n).map(|i| (i % 251) as u8).collect();
        let depth: Vec<f32> = (0..n).map(|i| i as f32).collect();
        let colors: Vec<Vec4> = (0..n).map(|i| Vec4::splat(i as f32)).collect();
        let ao: Vec<AoPixel> = (0..n).map(|i| AoPixel { object: i as u32, hidden: 0.5, ..AoPixel::NONE }).collect();
        let (mut r2, mut d2, mut c2) = (vec![0u8; 4 * n], vec![0f32; n], vec![Vec4::ZERO; n]);
        let mut a2 = vec![AoPixel::NONE; n];
        let whole = Layers { rgba: &rgba, depth: &depth, colors: Some(&colors), ao: Some(&ao) };
        for t in 0..grid.count() {
            let cut = grid.cut(t, whole);
            let into = LayersMut { rgba: &mut r2, depth: &mut d2, colors: Some(&mut c2), ao: Some(&mut a2) };
            assert!(grid.paste(&cut, into));
        }
        assert!(r2 == rgba && d2 == depth && c2 == colors && a2 == ao);
        let wrong = TilePixels { tile: 0, rgba: vec![0; 4], depth: vec![0.0], colors: vec![], ao: vec![] };
        let into = LayersMut { rgba: &mut r2, depth: &mut d2, colors: None, ao: None };
        assert!(!grid.paste(&wrong, into), "a tile of another size is refused");
        let no_ao = TilePixels { ao: vec![], ..grid.cut(0, whole) };
        let into = LayersMut { rgba: &mut r2, depth: &mut d2, colors: Some(&mut c2), ao: Some(&mut a2) };
        assert!(!grid.paste(&no_ao, into), "a tile without the AO the image keeps is refused");
    }

    #[test]
    fn many_ranks_get_smaller_tiles() {
        let sides: Vec<usize> = [1, 2, 15, 16, 32, 64, 256].map(|n| TileGrid::for_ranks(1280, 720, n).side()).to_vec();
        // 240 tiles of 64 (15 ranks' worth), 920 of 32 (57), 3,600 of 16.
        assert_eq!(sides, [64, 64, 64, 32, 32, 16, 16]);
        let grid = TileGrid::for_ranks(1280, 720, 64);
        assert_eq!((grid.count(), grid.rect(81)), (3600, (16, 16, 16, 16)));
        assert_eq!(grid.tile_at(1279, 719), 3599);
    }
}
