//! What a rank puts together during a shared frame: its band of the frame from the pieces of
//! tiles traced here and elsewhere (`BandRows`), and the picture it returns to its host from
//! the parts of every band its data covers (`Canvas`).

use glam::Vec4;
use glray_render::denoise::{AoPixel, Band};
use glray_render::Rendered;

use crate::protocol::Rect;

/// Rows of a traced tile as they reach the rank whose band holds or reads them: the tile's
/// columns `x..x + width`, rows `first..first + rows`, whole (depth, colours before rounding or
/// RGBA, AO) or only their AO (rows around the band).
pub struct Piece<'a> {
    pub x: usize,
    pub width: usize,
    pub first: usize,
    pub rows: usize,
    pub whole: bool,
    pub rgba: &'a [u8],
    pub depth: &'a [f32],
    pub colors: &'a [Vec4],
    pub ao: &'a [AoPixel],
}

/// A rank's band as its pieces arrive: its rows' pixels, and the AO of the rows its denoising
/// reads.
pub struct BandRows {
    pub band: Band,
    layer_first: usize,
    rgba: Vec<u8>,
    depth: Vec<f32>,
    colors: Option<Vec<Vec4>>,
    ao: Option<Vec<AoPixel>>,
    /// Pixels arrived and awaited: of the band, and of the rows around it.
    whole: (u64, u64),
    around: (u64, u64),
}

impl BandRows {
    /// `band`, its colours before rounding kept (`linear`) or not, its AO denoised or not.
    pub fn new(band: Band, linear: bool, ao: bool) -> BandRows {
        let (w, own) = (band.width, band.rows.len());
        let layer = if ao { band.layer_rows() } else { band.rows.clone() };
        BandRows {
            layer_first: layer.start,
            rgba: vec![0; 4 * w * own],
            depth: vec![0.0; w * own],
            colors: linear.then(|| vec![Vec4::ZERO; w * own]),
            ao: ao.then(|| vec![AoPixel::NONE; w * layer.len()]),
            whole: (0, (w * own) as u64),
            around: (0, (w * (layer.len() - own)) as u64),
            band,
        }
    }

    /// Puts a piece in place: false (nothing written) when it does not fit the band or lacks a
    /// layer the band keeps.
    pub fn paste(&mut self, p: &Piece) -> bool {
        let w = self.band.width;
        let n = p.width * p.rows;
        let rows = p.first..p.first + p.rows;
        let layer = self.layer_first..self.layer_first + self.ao.as_ref().map_or(self.band.rows.len(), |a| a.len() / w);
        let fits = p.x + p.width <= w
            && if p.whole {
                rows.start >= self.band.rows.start && rows.end <= self.band.rows.end
            } else {
                rows.start >= layer.start
                    && rows.end <= layer.end
                    && (rows.end <= self.band.rows.start || rows.start >= self.band.rows.end)
            };
        let sized = |len: usize, per: usize, kept: bool| !kept || len == per * n;
        let ok = fits
            && (!p.whole
                || (p.depth.len() == n
                    && (self.colors.is_some() || p.rgba.len() == 4 * n)
                    && sized(p.colors.len(), 1, self.colors.is_some())))
            && sized(p.ao.len(), 1, self.ao.is_some());
        if !ok {
            return false;
        }
        for k in 0..p.rows {
            let y = p.first + k;
            let src = k * p.width..(k + 1) * p.width;
            if p.whole {
                let at = (y - self.band.rows.start) * w + p.x;
                self.depth[at..at + p.width].copy_from_slice(&p.depth[src.clone()]);
                match self.colors.as_mut() {
                    Some(c) => {
                        c[at..at + p.width].copy_from_slice(&p.colors[src.clone()]);
                        // (The RGBA of a pixel whose colours are kept: those colours rounded,
                        // as the tracer rounds them; `add_band_pass` makes it anew anyway.)
                        let rgba = glray_render::render::rgba_of(&p.colors[src.clone()]);
                        self.rgba[4 * at..4 * (at + p.width)].copy_from_slice(&rgba);
                    }
                    None => self.rgba[4 * at..4 * (at + p.width)].copy_from_slice(&p.rgba[4 * src.start..4 * src.end]),
                }
            }
            if let Some(ao) = self.ao.as_mut() {
                let at = (y - self.layer_first) * w + p.x;
                ao[at..at + p.width].copy_from_slice(&p.ao[src]);
            }
        }
        if p.whole {
            self.whole.0 += n as u64;
        } else {
            self.around.0 += n as u64;
        }
        true
    }

    /// Whether every pixel of the band and of the rows around it has arrived.
    pub fn complete(&self) -> bool {
        self.whole.0 >= self.whole.1 && self.around.0 >= self.around.1
    }

    /// The AO of the band's `layer_rows`, as it stands.
    pub fn layer(&self) -> Option<&[AoPixel]> {
        self.ao.as_deref()
    }

    /// The band's pass: its pixels, colours before rounding, and AO (of its `layer_rows`).
    pub fn into_pass(self) -> (Band, Rendered, Option<Vec<Vec4>>, Option<Vec<AoPixel>>) {
        let picture = Rendered {
            width: self.band.width as u32,
            height: self.band.rows.len() as u32,
            rgba: self.rgba,
            depth: self.depth,
        };
        (self.band, picture, self.colors, self.ao)
    }
}

/// The picture a rank returns to its host: its background, with the parts of the shared
/// picture its data covers (`want`) put in as they arrive.
pub struct Canvas {
    pub picture: Rendered,
    want: Option<Rect>,
    have: u64,
}

impl Canvas {
    pub fn new(background: Rendered, want: Option<Rect>) -> Canvas {
        Canvas { picture: background, want, have: 0 }
    }

    /// Puts a part of the picture in: false when it is not inside what this rank wants, or
    /// its sizes do not agree.
    pub fn paste(&mut self, rect: Rect, rgba: &[u8], depth: &[f32]) -> bool {
        let Some(want) = self.want else { return false };
        let n = rect.area() as usize;
        let inside = rect.x >= want.x
            && rect.y >= want.y
            && rect.x + rect.width <= want.x + want.width
            && rect.y + rect.height <= want.y + want.height;
        if !inside || rgba.len() != 4 * n || depth.len() != n {
            return false;
        }
        let w = self.picture.width as usize;
        let (x, rw) = (rect.x as usize, rect.width as usize);
        for k in 0..rect.height as usize {
            let at = (rect.y as usize + k) * w + x;
            self.picture.rgba[4 * at..4 * (at + rw)].copy_from_slice(&rgba[4 * k * rw..4 * (k + 1) * rw]);
            self.picture.depth[at..at + rw].copy_from_slice(&depth[k * rw..(k + 1) * rw]);
        }
        self.have += n as u64;
        true
    }

    /// Whether all it wants has arrived.
    pub fn complete(&self) -> bool {
        self.have >= self.want.map_or(0, |r| r.area())
    }
}

/// The part `rect` (within the band's rows) of a band's picture (`band_picture`, its rows
/// from `first`): its RGBA and depths, row by row.
pub fn cut(band_picture: &Rendered, first: usize, rect: Rect) -> (Vec<u8>, Vec<f32>) {
    let w = band_picture.width as usize;
    let (x, rw) = (rect.x as usize, rect.width as usize);
    let mut rgba = Vec::with_capacity(4 * rect.area() as usize);
    let mut depth = Vec::with_capacity(rect.area() as usize);
    for y in rect.y as usize..(rect.y + rect.height) as usize {
        let at = (y - first) * w + x;
        rgba.extend_from_slice(&band_picture.rgba[4 * at..4 * (at + rw)]);
        depth.extend_from_slice(&band_picture.depth[at..at + rw]);
    }
    (rgba, depth)
}
