//! The GL side of textures: client pixels decoded into RGBA texels with the unpack state
//! (glTexImage2D, glTexSubImage2D), the base internal format GL keeps, and glTexParameter's
//! sampling state. The texture objects themselves, and sampling them, are the scene's
//! (`glray_scene::texture`).

use glam::Vec4;
use glray_gl::{
    GL_ALPHA, GL_ALPHA16, GL_ALPHA4, GL_BGR, GL_BGRA, GL_FLOAT, GL_INTENSITY, GL_INTENSITY16, GL_INTENSITY4,
    GL_LUMINANCE, GL_LUMINANCE16, GL_LUMINANCE16_ALPHA16, GL_LUMINANCE4, GL_LUMINANCE4_ALPHA4, GL_LUMINANCE_ALPHA,
    GL_R3_G3_B2, GL_RED, GL_RGB, GL_RGB16, GL_RGB4, GL_RGBA, GL_SRGB8, GL_TEXTURE_LOD_BIAS, GL_TEXTURE_MAG_FILTER,
    GL_TEXTURE_MAX_LOD, GL_TEXTURE_MIN_FILTER, GL_TEXTURE_MIN_LOD, GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T,
    GL_UNSIGNED_BYTE, GL_UNSIGNED_BYTE_2_3_3_REV, GL_UNSIGNED_BYTE_3_3_2, GL_UNSIGNED_INT_10_10_10_2,
    GL_UNSIGNED_INT_2_10_10_10_REV, GL_UNSIGNED_INT_8_8_8_8, GL_UNSIGNED_INT_8_8_8_8_REV,
    GL_UNSIGNED_SHORT_1_5_5_5_REV, GL_UNSIGNED_SHORT_4_4_4_4, GL_UNSIGNED_SHORT_4_4_4_4_REV, GL_UNSIGNED_SHORT_5_5_5_1,
    GL_UNSIGNED_SHORT_5_6_5, GL_UNSIGNED_SHORT_5_6_5_REV,
};
use glray_scene::texture::{BaseFormat, Filter, Texture, Wrap};

use crate::args;
use crate::error::{GlError, GlResult};

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

/// Sets glTexParameter's `pname` to `value` on `t`'s sampling state (filters, wraps, level of
/// detail); None for a `pname` glray does not follow, Err for a value GL refuses (the state is
/// left as it was).
pub fn set_parameter(t: &mut Texture, pname: u32, value: f64) -> Option<GlResult> {
    let v = value as u32;
    let set = match pname {
        GL_TEXTURE_MIN_FILTER => Filter::from_gl(v).map(|f| t.min_filter = f),
        GL_TEXTURE_MAG_FILTER => {
            Filter::from_gl(v).filter(|f| matches!(f, Filter::Nearest | Filter::Linear)).map(|f| t.mag_filter = f)
        }
        GL_TEXTURE_WRAP_S => Wrap::from_gl(v).map(|w| t.wrap_s = w),
        GL_TEXTURE_WRAP_T => Wrap::from_gl(v).map(|w| t.wrap_t = w),
        GL_TEXTURE_LOD_BIAS => {
            t.lod.bias = value as f32;
            Some(())
        }
        GL_TEXTURE_MIN_LOD => {
            t.lod.min = value as f32;
            Some(())
        }
        GL_TEXTURE_MAX_LOD => {
            t.lod.max = value as f32;
            Some(())
        }
        _ => return None,
    };
    Some(set.ok_or(GlError::InvalidEnum))
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
pub fn base_format(internal: u32) -> BaseFormat {
    match internal {
        1 | GL_LUMINANCE | GL_LUMINANCE4..=GL_LUMINANCE16 => BaseFormat::Luminance,
        2 | GL_LUMINANCE_ALPHA | GL_LUMINANCE4_ALPHA4..=GL_LUMINANCE16_ALPHA16 => BaseFormat::LuminanceAlpha,
        GL_ALPHA | GL_ALPHA4..=GL_ALPHA16 => BaseFormat::Alpha,
        GL_INTENSITY | GL_INTENSITY4..=GL_INTENSITY16 => BaseFormat::Intensity,
        3 | GL_RGB | GL_R3_G3_B2 | GL_RGB4..=GL_RGB16 | GL_SRGB8 => BaseFormat::Rgb,
        _ => BaseFormat::Rgba,
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
pub fn to_base(c: Vec4, base: BaseFormat) -> Vec4 {
    match base {
        BaseFormat::Luminance => Vec4::new(c.x, c.x, c.x, 1.0),
        BaseFormat::LuminanceAlpha => Vec4::new(c.x, c.x, c.x, c.w),
        BaseFormat::Alpha => Vec4::new(0.0, 0.0, 0.0, c.w),
        BaseFormat::Intensity => Vec4::splat(c.x),
        BaseFormat::Rgb => c.truncate().extend(1.0),
        BaseFormat::Rgba => c,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const UBYTE: u32 = GL_UNSIGNED_BYTE;

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
}
