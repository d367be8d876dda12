//! 2D texture objects as glTexImage2D/glTexSubImage2D/glTexParameter leave them, and sampling
//! them the way GL does (nearest or linear, mipmapped, REPEAT or CLAMP wraps). Texels are kept
//! as RGBA floats expanded from the client's format; the base internal format is kept too,
//! because the texture environment treats LUMINANCE, ALPHA and INTENSITY differently.

use glam::{Vec2, Vec4};
use glray_gl::{
    GL_ALPHA, GL_BGR, GL_BGRA, GL_FLOAT, GL_INTENSITY, GL_LINEAR, GL_LINEAR_MIPMAP_LINEAR, GL_LINEAR_MIPMAP_NEAREST,
    GL_LUMINANCE, GL_LUMINANCE_ALPHA, GL_MIRRORED_REPEAT, GL_NEAREST, GL_NEAREST_MIPMAP_LINEAR,
    GL_NEAREST_MIPMAP_NEAREST, GL_RED, GL_REPEAT, GL_RGB, GL_RGBA, GL_TEXTURE_LOD_BIAS, GL_TEXTURE_MAG_FILTER,
    GL_TEXTURE_MAX_LOD, GL_TEXTURE_MIN_FILTER, GL_TEXTURE_MIN_LOD, GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T,
    GL_UNSIGNED_BYTE, GL_UNSIGNED_BYTE_2_3_3_REV, GL_UNSIGNED_BYTE_3_3_2, GL_UNSIGNED_INT_10_10_10_2,
    GL_UNSIGNED_INT_2_10_10_10_REV, GL_UNSIGNED_INT_8_8_8_8, GL_UNSIGNED_INT_8_8_8_8_REV,
    GL_UNSIGNED_SHORT_1_5_5_5_REV, GL_UNSIGNED_SHORT_4_4_4_4, GL_UNSIGNED_SHORT_4_4_4_4_REV, GL_UNSIGNED_SHORT_5_5_5_1,
    GL_UNSIGNED_SHORT_5_6_5, GL_UNSIGNED_SHORT_5_6_5_REV,
};

use crate::args;

/// glPixelStore's unpack state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Unpack {
    pub alignment: usize,
    pub row_length: usize,
    pub skip_rows: usize,
    pub skip_pixels: usize,
}

impl Default for Unpack {
    fn default() -> Self {
        Unpack { alignment: 4, row_length: 0, skip_rows: 0, skip_pixels: 0 }
    }
}

/// One mipmap level.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Level {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<Vec4>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    pub levels: Vec<Level>,
    /// The base internal format (GL_RGB, GL_RGBA, GL_LUMINANCE, ...).
    pub base_format: u32,
    pub min_filter: u32,
    pub mag_filter: u32,
    pub wrap_s: u32,
    pub wrap_t: u32,
    /// Made by glTexImage1D: one row, sampled by s alone (its level of detail ignores t).
    pub one_d: bool,
    /// How the level of detail is moved and bounded (glTexParameterf's GL_TEXTURE_LOD_BIAS,
    /// GL_TEXTURE_MIN_LOD and GL_TEXTURE_MAX_LOD).
    pub lod: LodRange,
    /// Which state of the texture this is: a number no state of any texture in the process
    /// has had before, renewed at every change (`changed`). The renderer knows a frame's
    /// textures by it (an address would be taken again by a texture made after one is freed,
    /// and a texture no frame holds is changed in place).
    pub version: u64,
}

/// A texture's level-of-detail parameters. GL adds the bias to the level of detail worked out
/// from the pixel's footprint, then clamps the sum to [min, max] (OpenGL 2.1, 3.8.8); the
/// result picks both the levels and whether the texture is magnified or minified. Programs
/// set a small positive bias to soften minified text (xscreensaver's texture fonts: 0.25).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LodRange {
    pub bias: f32,
    pub min: f32,
    pub max: f32,
}

impl Default for LodRange {
    fn default() -> Self {
        LodRange { bias: 0.0, min: -1000.0, max: 1000.0 }
    }
}

impl LodRange {
    /// The level of detail a sample takes, from the one of the pixel's footprint.
    pub fn apply(&self, lod: f32) -> f32 {
        (lod + self.bias).clamp(self.min, self.max.max(self.min))
    }

    /// The parameter glTexParameterf's `pname` sets, if it is one of these.
    pub fn parameter_mut(&mut self, pname: u32) -> Option<&mut f32> {
        Some(match pname {
            GL_TEXTURE_LOD_BIAS => &mut self.bias,
            GL_TEXTURE_MIN_LOD => &mut self.min,
            GL_TEXTURE_MAX_LOD => &mut self.max,
            _ => return None,
        })
    }
}

/// A version no texture has had (`Texture::version`).
fn next_version() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

impl Texture {
    /// Marks a change: the texture is a new state to the renderer.
    pub fn changed(&mut self) {
        self.version = next_version();
    }

    /// The parameter glTexParameter's `pname` sets, of those glray follows.
    pub fn parameter_mut(&mut self, pname: u32) -> Option<&mut u32> {
        Some(match pname {
            GL_TEXTURE_MIN_FILTER => &mut self.min_filter,
            GL_TEXTURE_MAG_FILTER => &mut self.mag_filter,
            GL_TEXTURE_WRAP_S => &mut self.wrap_s,
            GL_TEXTURE_WRAP_T => &mut self.wrap_t,
            _ => return None,
        })
    }

    /// The value of that parameter (read through `parameter_mut` on a copy of the
    /// parameters alone, so that the two never disagree on which field a `pname` is).
    pub fn parameter(&self, pname: u32) -> Option<u32> {
        Texture { levels: Vec::new(), ..*self }.parameter_mut(pname).map(|p| *p)
    }
}

impl Default for Texture {
    fn default() -> Self {
        Texture {
            levels: Vec::new(),
            base_format: GL_RGBA,
            min_filter: GL_NEAREST_MIPMAP_LINEAR,
            mag_filter: GL_LINEAR,
            wrap_s: GL_REPEAT,
            wrap_t: GL_REPEAT,
            one_d: false,
            lod: LodRange::default(),
            version: next_version(),
        }
    }
}

/// Components per pixel of a client format; None for formats glray does not read.
fn components(format: u32) -> Option<usize> {
    Some(match format {
        GL_ALPHA | GL_LUMINANCE | GL_RED | GL_INTENSITY => 1,
        GL_LUMINANCE_ALPHA => 2,
        GL_RGB | GL_BGR => 3,
        GL_RGBA | GL_BGRA => 4,
        _ => return None,
    })
}

/// The base internal format GL derives from glTexImage2D's internalformat argument.
pub fn base_format(internal: u32) -> u32 {
    match internal {
        1 | GL_LUMINANCE | 0x803F..=0x8042 => GL_LUMINANCE,
        2 | GL_LUMINANCE_ALPHA | 0x8043..=0x8048 => GL_LUMINANCE_ALPHA,
        GL_ALPHA | 0x803B..=0x803E => GL_ALPHA,
        GL_INTENSITY | 0x804A..=0x804D => GL_INTENSITY,
        3 | GL_RGB | 0x2A10 | 0x804F..=0x8054 | 0x8C41 => GL_RGB,
        _ => GL_RGBA,
    }
}

/// A packed pixel type (GL 1.2's GL_UNSIGNED_SHORT_5_6_5, GL_UNSIGNED_INT_8_8_8_8_REV, ...):
/// every component of a pixel in one element of `bytes` bytes (native byte order), the
/// format's components in order taking `widths` bits each, the first in the highest bits, or
/// with `reversed` (the `_REV` types) in the lowest.
struct PackedType {
    bytes: usize,
    widths: &'static [u32],
    reversed: bool,
}

impl PackedType {
    fn of(ty: u32) -> Option<PackedType> {
        let (bytes, widths, reversed): (usize, &'static [u32], bool) = match ty {
            GL_UNSIGNED_BYTE_3_3_2 => (1, &[3, 3, 2], false), // GL_UNSIGNED_BYTE_3_3_2
            GL_UNSIGNED_BYTE_2_3_3_REV => (1, &[3, 3, 2], true), // GL_UNSIGNED_BYTE_2_3_3_REV
            GL_UNSIGNED_SHORT_5_6_5 => (2, &[5, 6, 5], false), // GL_UNSIGNED_SHORT_5_6_5
            GL_UNSIGNED_SHORT_5_6_5_REV => (2, &[5, 6, 5], true), // GL_UNSIGNED_SHORT_5_6_5_REV
            GL_UNSIGNED_SHORT_4_4_4_4 => (2, &[4, 4, 4, 4], false), // GL_UNSIGNED_SHORT_4_4_4_4
            GL_UNSIGNED_SHORT_4_4_4_4_REV => (2, &[4, 4, 4, 4], true), // GL_UNSIGNED_SHORT_4_4_4_4_REV
            GL_UNSIGNED_SHORT_5_5_5_1 => (2, &[5, 5, 5, 1], false), // GL_UNSIGNED_SHORT_5_5_5_1
            GL_UNSIGNED_SHORT_1_5_5_5_REV => (2, &[5, 5, 5, 1], true), // GL_UNSIGNED_SHORT_1_5_5_5_REV
            GL_UNSIGNED_INT_8_8_8_8 => (4, &[8, 8, 8, 8], false), // GL_UNSIGNED_INT_8_8_8_8
            GL_UNSIGNED_INT_8_8_8_8_REV => (4, &[8, 8, 8, 8], true), // GL_UNSIGNED_INT_8_8_8_8_REV
            GL_UNSIGNED_INT_10_10_10_2 => (4, &[10, 10, 10, 2], false), // GL_UNSIGNED_INT_10_10_10_2
            GL_UNSIGNED_INT_2_10_10_10_REV => (4, &[10, 10, 10, 2], true), // GL_UNSIGNED_INT_2_10_10_10_REV
            _ => return None,
        };
        Some(PackedType { bytes, widths, reversed })
    }

    /// The components of the pixel at the start of `b`, normalised to [0, 1].
    fn components(&self, b: &[u8]) -> Option<[f32; 4]> {
        let word = match self.bytes {
            1 => *b.first()? as u32,
            2 => u16::from_ne_bytes(b.get(..2)?.try_into().ok()?) as u32,
            _ => u32::from_ne_bytes(b.get(..4)?.try_into().ok()?),
        };
        let total: u32 = self.widths.iter().sum();
        let mut c = [0.0; 4];
        let mut before = 0;
        for (i, &w) in self.widths.iter().enumerate() {
            let shift = if self.reversed { before } else { total - before - w };
            let max = (1u32 << w) - 1;
            c[i] = ((word >> shift) & max) as f32 / max as f32;
            before += w;
        }
        Some(c)
    }
}

/// Decodes client pixels into RGBA texels; None for an unsupported format or type (or a
/// packed type whose component count is not the format's: GL refuses those), or too little
/// memory.
pub fn decode(width: usize, height: usize, format: u32, ty: u32, unpack: &Unpack, data: &[u8]) -> Option<Vec<Vec4>> {
    let mut out = Vec::new();
    decode_into(&mut out, width, height, format, ty, unpack, data)?;
    Some(out)
}

/// `decode` into `out` (cleared first; on None, its contents are unspecified): a program that
/// uploads an image of the same size every frame has it decoded into the last one's memory,
/// where a new 64 MB vector for a 2048x2048 image was a page fault every 4 KiB.
pub fn decode_into(
    out: &mut Vec<Vec4>,
    width: usize,
    height: usize,
    format: u32,
    ty: u32,
    unpack: &Unpack,
    data: &[u8],
) -> Option<()> {
    out.clear();
    let n = components(format)?;
    let packed = PackedType::of(ty);
    let (size, pixel_bytes) = match &packed {
        Some(p) if p.widths.len() == n => (p.bytes, p.bytes),
        Some(_) => return None,
        None => (args::type_size(ty)?, n * args::type_size(ty)?),
    };
    let row_pixels = if unpack.row_length > 0 { unpack.row_length } else { width };
    let align = unpack.alignment.max(1);
    let row_bytes = (row_pixels * pixel_bytes).div_ceil(align) * align;
    out.reserve(width * height);
    // Bytes, the type of nearly every image, read a row at a time through a table of the
    // values `args::normalize` gives (the same floats): element by element through the type's
    // dispatch, a 2048x2048 texture took ~270 ms, every frame a program uploads one.
    let bytes = (packed.is_none() && ty == GL_UNSIGNED_BYTE).then(|| {
        let mut table = [0.0f32; 256];
        for (v, t) in table.iter_mut().enumerate() {
            *t = args::normalize(v as f64, ty).clamp(0.0, 1.0) as f32;
        }
        table
    });
    // Floats (scientific data) likewise, each clamped as it is read.
    let floats = packed.is_none() && ty == GL_FLOAT;
    for y in 0..height {
        let row = (y + unpack.skip_rows) * row_bytes + unpack.skip_pixels * pixel_bytes;
        if floats || bytes.is_some() {
            let pixels = data.get(row..row.checked_add(width * pixel_bytes)?)?;
            match &bytes {
                Some(table) => out.extend(row_texels(pixels, n, 1, format, |b| table[b[0] as usize])),
                None => out.extend(row_texels(pixels, n, 4, format, |b| {
                    f32::from_ne_bytes([b[0], b[1], b[2], b[3]]).clamp(0.0, 1.0)
                })),
            }
            continue;
        }
        for x in 0..width {
            let c = match &packed {
                Some(p) => p.components(data.get(row + x * pixel_bytes..)?)?,
                None => {
                    let first = (row + x * pixel_bytes) / size;
                    let mut c = [0.0f32; 4];
                    for (i, v) in c.iter_mut().enumerate().take(n) {
                        let raw = if row % size == 0 {
                            args::element(data, ty, first + i)?
                        } else {
                            let at = row + (x * n + i) * size;
                            args::element(data.get(at..at + size)?, ty, 0)?
                        };
                        *v = args::normalize(raw, ty).clamp(0.0, 1.0) as f32;
                    }
                    c
                }
            };
            out.push(texel(format, c));
        }
    }
    Some(())
}

/// The texels of a row of pixels of `n` components, `size` bytes each, each component read
/// with `read`.
fn row_texels<'a>(
    pixels: &'a [u8],
    n: usize,
    size: usize,
    format: u32,
    read: impl Fn(&[u8]) -> f32 + 'a,
) -> impl Iterator<Item = Vec4> + 'a {
    pixels.chunks_exact(n * size).map(move |p| {
        let mut c = [0.0f32; 4];
        for (v, b) in c.iter_mut().zip(p.chunks_exact(size)) {
            *v = read(b);
        }
        texel(format, c)
    })
}

/// An RGBA texel from the components a pixel of `format` gives, in their order.
#[inline]
fn texel(format: u32, c: [f32; 4]) -> Vec4 {
    match format {
        GL_ALPHA => Vec4::new(0.0, 0.0, 0.0, c[0]),
        GL_LUMINANCE | GL_INTENSITY => Vec4::new(c[0], c[0], c[0], 1.0),
        GL_RED => Vec4::new(c[0], 0.0, 0.0, 1.0),
        GL_LUMINANCE_ALPHA => Vec4::new(c[0], c[0], c[0], c[1]),
        GL_RGB => Vec4::new(c[0], c[1], c[2], 1.0),
        GL_BGR => Vec4::new(c[2], c[1], c[0], 1.0),
        GL_BGRA => Vec4::new(c[2], c[1], c[0], c[3]),
        _ => Vec4::new(c[0], c[1], c[2], c[3]),
    }
}

/// Converts texels to the base internal format (what GL stores): LUMINANCE keeps red, ALPHA
/// only alpha, INTENSITY red in all four.
pub fn to_base(c: Vec4, base: u32) -> Vec4 {
    match base {
        GL_LUMINANCE => Vec4::new(c.x, c.x, c.x, 1.0),
        GL_LUMINANCE_ALPHA => Vec4::new(c.x, c.x, c.x, c.w),
        GL_ALPHA => Vec4::new(0.0, 0.0, 0.0, c.w),
        GL_INTENSITY => Vec4::splat(c.x),
        GL_RGB => c.truncate().extend(1.0),
        _ => c,
    }
}

impl Texture {
    /// Whether the texture can be sampled (GL: "complete"): level 0 exists, and when the
    /// minification filter uses mipmaps, every level down to 1x1.
    pub fn complete(&self) -> bool {
        let Some(base) = self.levels.first().filter(|l| l.width > 0 && l.height > 0) else {
            return false;
        };
        if !self.mipmapped() {
            return true;
        }
        let (mut w, mut h) = (base.width, base.height);
        for level in &self.levels {
            if level.width != w || level.height != h {
                return false;
            }
            if w == 1 && h == 1 {
                return true;
            }
            w = (w / 2).max(1);
            h = (h / 2).max(1);
        }
        false
    }

    fn mipmapped(&self) -> bool {
        !matches!(self.min_filter, GL_NEAREST | GL_LINEAR)
    }

    fn wrap(mode: u32, i: i64, n: usize) -> usize {
        let n = n as i64;
        let i = match mode {
            GL_REPEAT => i.rem_euclid(n),
            GL_MIRRORED_REPEAT => {
                let m = i.rem_euclid(2 * n);
                if m < n {
                    m
                } else {
                    2 * n - 1 - m
                }
            }
            _ => i.clamp(0, n - 1), // CLAMP, CLAMP_TO_EDGE (no border colour)
        };
        i as usize
    }

    fn texel(&self, l: &Level, x: i64, y: i64) -> Vec4 {
        let x = Self::wrap(self.wrap_s, x, l.width);
        let y = Self::wrap(self.wrap_t, y, l.height);
        l.texels[y * l.width + x]
    }

    fn sample_level(&self, level: usize, uv: Vec2, linear: bool) -> Vec4 {
        let l = &self.levels[level];
        let x = uv.x * l.width as f32;
        let y = uv.y * l.height as f32;
        if !linear {
            return self.texel(l, x.floor() as i64, y.floor() as i64);
        }
        let (x, y) = (x - 0.5, y - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let a = self.texel(l, x0, y0).lerp(self.texel(l, x0 + 1, y0), fx);
        let b = self.texel(l, x0, y0 + 1).lerp(self.texel(l, x0 + 1, y0 + 1), fx);
        a.lerp(b, fy)
    }

    /// Whether `sample` depends on its level of detail: with mipmaps, or with one filter for
    /// magnification and another for minification. Without, the level of detail (worked out
    /// from the triangle's derivatives on the screen at every pixel) can be left out.
    pub fn reads_lod(&self) -> bool {
        self.mipmapped() || (self.mag_filter == GL_LINEAR) != (self.min_filter == GL_LINEAR)
    }

    /// The filtered texel at `uv` for a level of detail `lod` (log2 of texels per pixel).
    pub fn sample(&self, uv: Vec2, lod: f32) -> Vec4 {
        if !self.complete() {
            return Vec4::ONE;
        }
        let lod = self.lod.apply(lod);
        if lod <= 0.0 || !self.mipmapped() {
            let filter = if lod <= 0.0 { self.mag_filter } else { self.min_filter };
            return self.sample_level(0, uv, filter == GL_LINEAR);
        }
        let last = (self.levels.len() - 1) as f32;
        let linear = matches!(self.min_filter, GL_LINEAR_MIPMAP_NEAREST | GL_LINEAR_MIPMAP_LINEAR);
        match self.min_filter {
            GL_NEAREST_MIPMAP_NEAREST | GL_LINEAR_MIPMAP_NEAREST => {
                let level = (lod + 0.5).floor().clamp(0.0, last) as usize;
                self.sample_level(level, uv, linear)
            }
            _ => {
                let lod = lod.min(last);
                let l0 = lod.floor() as usize;
                let l1 = (l0 + 1).min(last as usize);
                self.sample_level(l0, uv, linear).lerp(self.sample_level(l1, uv, linear), lod.fract())
            }
        }
    }
}

/// The default pixel type for the tests below.
#[allow(dead_code)]
const UBYTE: u32 = GL_UNSIGNED_BYTE;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decode_honours_alignment_and_formats() {
        // 1x2 RGB rows padded to 4 bytes.
        let data = [255u8, 0, 0, 9, 0, 0, 255, 9];
        let t = decode(1, 2, GL_RGB, UBYTE, &Unpack::default(), &data).unwrap();
        assert_eq!(t, vec![Vec4::new(1.0, 0.0, 0.0, 1.0), Vec4::new(0.0, 0.0, 1.0, 1.0)]);
        let t = decode(1, 1, GL_BGRA, UBYTE, &Unpack::default(), &[0, 0, 255, 0]).unwrap();
        assert_eq!(t, vec![Vec4::new(1.0, 0.0, 0.0, 0.0)]);
        assert!(decode(2, 2, GL_RGBA, UBYTE, &Unpack::default(), &[0; 15]).is_none());
    }

    #[test]
    fn every_byte_value_decodes_to_its_fraction_of_255_wherever_the_unpack_state_puts_it() {
        // All 256 byte values as 3 x 2 pixels of LUMINANCE_ALPHA, RGB and BGRA, from a region
        // 2 pixels in and 1 row down of rows 5 pixels long (padded to the alignment).
        for (format, n) in [(GL_LUMINANCE_ALPHA, 2usize), (GL_RGB, 3), (GL_BGRA, 4)] {
            let un = Unpack { alignment: 8, row_length: 5, skip_rows: 1, skip_pixels: 2 };
            let row_bytes = (5 * n).div_ceil(8) * 8;
            for start in (0..256).step_by(6 * n) {
                let mut data = vec![0u8; 3 * row_bytes];
                for (k, v) in (start..start + 6 * n).enumerate() {
                    let (y, i) = (k / (3 * n), k % (3 * n));
                    data[(1 + y) * row_bytes + 2 * n + i] = (v % 256) as u8;
                }
                let t = decode(3, 2, format, UBYTE, &un, &data).unwrap();
                let f = |k: usize| ((start + k) % 256) as f32 / 255.0;
                for (p, texel) in t.iter().enumerate() {
                    let k = p * n;
                    let want = match format {
                        GL_LUMINANCE_ALPHA => Vec4::new(f(k), f(k), f(k), f(k + 1)),
                        GL_RGB => Vec4::new(f(k), f(k + 1), f(k + 2), 1.0),
                        _ => Vec4::new(f(k + 2), f(k + 1), f(k), f(k + 3)),
                    };
                    assert_eq!(*texel, want, "{format:#x} pixel {p} from byte {}", start + k);
                }
                assert!(decode(3, 2, format, UBYTE, &un, &data[..2 * row_bytes + 2 * n + 3 * n - 1]).is_none());
            }
        }
    }

    #[test]
    fn float_pixels_decode_clamped_to_0_1_wherever_the_unpack_state_puts_them() {
        // 2 x 2 RGB floats, one pixel in and one row down of rows 3 pixels long; values under
        // 0 and over 1 (and an infinity) clamp as GL clamps a fixed-point texture's.
        let values = [-1.0f32, 0.25, 1.5, 0.5, f32::INFINITY, 0.125, 0.75, 0.0, 1.0, 0.3, 0.6, 0.9];
        let un = Unpack { alignment: 4, row_length: 3, skip_rows: 1, skip_pixels: 1 };
        let mut data = vec![0u8; 3 * 3 * 12];
        for (k, v) in values.iter().enumerate() {
            let (y, i) = (k / 6, k % 6);
            let at = ((1 + y) * 9 + 3 + i) * 4;
            data[at..at + 4].copy_from_slice(&v.to_ne_bytes());
        }
        let t = decode(2, 2, GL_RGB, 0x1406, &un, &data).unwrap();
        let want: Vec<Vec4> =
            values.chunks(3).map(|c| Vec4::new(c[0], c[1], c[2], 1.0).clamp(Vec4::ZERO, Vec4::ONE)).collect();
        assert_eq!(t, want);
        assert!(decode(2, 2, GL_RGB, 0x1406, &un, &data[..data.len() - 13]).is_none(), "too little memory");
    }

    #[test]
    fn packed_pixel_types_decode_as_gl_reads_them() {
        let un = Unpack::default();
        // GL_UNSIGNED_INT_8_8_8_8_REV with RGBA: red in the lowest byte, the same bytes as
        // GL_UNSIGNED_BYTE on a little-endian machine (xscreensaver loads its images so).
        let word: u32 = 0x33 << 24 | 0xff << 8;
        let rev = decode(1, 1, GL_RGBA, 0x8367, &un, &word.to_ne_bytes()).unwrap();
        assert_eq!(rev, vec![Vec4::new(0.0, 1.0, 0.0, 0.2)]);
        // The same word in GL_UNSIGNED_INT_8_8_8_8: red in the highest byte.
        let forward = decode(1, 1, GL_RGBA, 0x8035, &un, &word.to_ne_bytes()).unwrap();
        assert_eq!(forward, vec![Vec4::new(0.2, 0.0, 1.0, 0.0)]);
        // BGRA with _REV: blue lowest (what X images and many loaders give).
        let bgra = decode(1, 1, GL_BGRA, 0x8367, &un, &0x80ff_0000u32.to_ne_bytes()).unwrap();
        assert_eq!(bgra[0].x, 1.0);
        assert!((bgra[0].w - 128.0 / 255.0).abs() < 1e-6 && bgra[0].z == 0.0);
        // 5_6_5: red in the top five bits; _REV: in the bottom five.
        let pixels = [0xf800u16.to_ne_bytes(), 0x001fu16.to_ne_bytes()].concat();
        let t = decode(2, 1, GL_RGB, 0x8363, &un, &pixels).unwrap();
        assert_eq!(t, vec![Vec4::new(1.0, 0.0, 0.0, 1.0), Vec4::new(0.0, 0.0, 1.0, 1.0)]);
        let t = decode(2, 1, GL_RGB, 0x8364, &un, &pixels).unwrap();
        assert_eq!(t, vec![Vec4::new(0.0, 0.0, 1.0, 1.0), Vec4::new(1.0, 0.0, 0.0, 1.0)]);
        // 4_4_4_4 and 5_5_5_1 (alpha the one bit), 3_3_2 and 2_10_10_10_REV.
        let t = decode(1, 1, GL_RGBA, 0x8033, &un, &0x0f00u16.to_ne_bytes()).unwrap();
        assert_eq!(t, vec![Vec4::new(0.0, 1.0, 0.0, 0.0)]);
        let t = decode(1, 1, GL_RGBA, 0x8034, &un, &0x0001u16.to_ne_bytes()).unwrap();
        assert_eq!(t, vec![Vec4::new(0.0, 0.0, 0.0, 1.0)]);
        let t = decode(1, 1, GL_RGB, 0x8032, &un, &[0b1110_0000]).unwrap();
        assert_eq!(t, vec![Vec4::new(1.0, 0.0, 0.0, 1.0)]);
        let t = decode(1, 1, GL_RGBA, 0x8368, &un, &(3u32 << 30 | 0x3ff).to_ne_bytes()).unwrap();
        assert_eq!(t, vec![Vec4::new(1.0, 0.0, 0.0, 1.0)]);
        // Rows of 2-byte pixels padded to the unpack alignment: 3 pixels, 6 bytes, 8 a row.
        let mut rows = vec![0u8; 16];
        rows[8..10].copy_from_slice(&0xf800u16.to_ne_bytes());
        let t = decode(3, 2, GL_RGB, 0x8363, &un, &rows).unwrap();
        assert_eq!(t[3], Vec4::new(1.0, 0.0, 0.0, 1.0));
        // A packed type whose component count is not the format's, and too little memory.
        assert!(decode(1, 1, GL_RGBA, 0x8363, &un, &[0; 2]).is_none());
        assert!(decode(2, 1, GL_RGBA, 0x8367, &un, &[0; 7]).is_none());
    }

    #[test]
    fn sampling_wraps_and_filters() {
        let texels = vec![Vec4::ZERO, Vec4::ONE];
        let t = Texture {
            levels: vec![Level { width: 2, height: 1, texels }],
            min_filter: GL_NEAREST,
            mag_filter: GL_NEAREST,
            ..Texture::default()
        };
        assert_eq!(t.sample(Vec2::new(0.25, 0.5), 0.0), Vec4::ZERO);
        assert_eq!(t.sample(Vec2::new(1.75, 0.5), 0.0), Vec4::ONE, "REPEAT");
        let t = Texture { mag_filter: GL_LINEAR, ..t };
        assert_eq!(t.sample(Vec2::new(0.5, 0.5), 0.0), Vec4::splat(0.5));
        let incomplete = Texture { min_filter: GL_LINEAR_MIPMAP_LINEAR, ..t };
        assert!(!incomplete.complete());
    }

    #[test]
    fn the_level_of_detail_is_read_only_where_it_changes_a_sample() {
        // Two levels: 2x1 (black, white) and 1x1 grey.
        let levels = vec![
            Level { width: 2, height: 1, texels: vec![Vec4::ZERO, Vec4::ONE] },
            Level { width: 1, height: 1, texels: vec![Vec4::splat(0.5)] },
        ];
        let base = Texture { levels, ..Texture::default() };
        let at = Vec2::new(0.4, 0.5);
        let lods = [-3.0, 0.0, 0.5, 1.0, 6.0];
        for (min, mag) in [
            (GL_NEAREST, GL_NEAREST),
            (GL_LINEAR, GL_LINEAR),
            (GL_NEAREST, GL_LINEAR),
            (GL_LINEAR, GL_NEAREST),
            (GL_NEAREST_MIPMAP_NEAREST, GL_NEAREST),
            (GL_LINEAR_MIPMAP_LINEAR, GL_LINEAR),
        ] {
            let t = Texture { min_filter: min, mag_filter: mag, ..base.clone() };
            let samples: Vec<Vec4> = lods.iter().map(|&lod| t.sample(at, lod)).collect();
            let varies = samples.iter().any(|s| *s != samples[0]);
            assert_eq!(t.reads_lod(), varies, "min {min:#x}, mag {mag:#x}: {samples:?}");
        }
    }

    #[test]
    fn the_level_of_detail_is_biased_then_clamped() {
        // Two levels: 1x1 white and 1x1 black (level 1 of a 1x1 texture is not complete, but
        // sampling reads the levels given).
        let levels = vec![
            Level { width: 2, height: 2, texels: vec![Vec4::ONE; 4] },
            Level { width: 1, height: 1, texels: vec![Vec4::ZERO] },
        ];
        let t = Texture { levels, min_filter: GL_LINEAR_MIPMAP_LINEAR, ..Texture::default() };
        let at = Vec2::new(0.5, 0.5);
        assert_eq!(t.sample(at, 0.5), Vec4::splat(0.5));
        let biased = Texture { lod: LodRange { bias: 0.25, ..LodRange::default() }, ..t.clone() };
        assert_eq!(biased.sample(at, 0.5), Vec4::splat(0.25), "half way plus a quarter");
        // A bias past zero makes a magnified sample minified: it reads the mipmaps.
        assert_eq!(biased.sample(at, -0.125), Vec4::splat(0.875));
        let clamped = Texture { lod: LodRange { bias: 0.25, min: 0.0, max: 0.5 }, ..t.clone() };
        assert_eq!(clamped.sample(at, 0.5), Vec4::splat(0.5), "at most max");
        let raised = Texture { lod: LodRange { min: 1.0, ..LodRange::default() }, ..t };
        assert_eq!(raised.sample(at, -3.0), Vec4::ZERO, "at least min");
    }
}
