//! Size rules for pointer arguments whose size the registry gives as COMPSIZE(...): each is named
//! in gl-spec/sizes.txt and called by the generated recorder with those arguments.

use super::{bound_buffer, Recorder, GL_ELEMENT_ARRAY_BUFFER_BINDING, GL_PIXEL_UNPACK_BUFFER_BINDING};
use crate::real;

/// How much memory a pointer argument reads.
pub enum Mem {
    Elements(usize),
    Bytes(usize),
    /// The pointer is an offset into a bound buffer object.
    Offset,
}

/// The product of the terms (a count, or count*4); negative counts read nothing.
pub fn product(terms: &[i64]) -> Mem {
    Mem::Elements(terms.iter().fold(1usize, |acc, t| acc.saturating_mul((*t).max(0) as usize)))
}

/// COMPSIZE(count): as many elements as the argument says.
pub fn elements(_: &mut Recorder, a: &[i64]) -> Mem {
    product(a)
}

/// Values a glLight/glMaterial/glFog/glTexEnv/glTexGen/glTexParameter/glLightModel/
/// glPointParameter pname takes.
fn pname_values(pname: i64) -> usize {
    match pname {
        0x1200 | 0x1201 | 0x1202 | 0x1203 | 0x1600 | 0x1602 => 4, // AMBIENT..POSITION, EMISSION, AMBIENT_AND_DIFFUSE
        0x1204 | 0x1603 => 3,                                     // SPOT_DIRECTION, COLOR_INDEXES
        0x0B53 | 0x0B66 | 0x2201 | 0x1004 | 0x2501 | 0x2502 | 0x8E46 => 4, // LIGHT_MODEL_AMBIENT, FOG_COLOR, TEXTURE_ENV_COLOR, BORDER_COLOR, OBJECT/EYE_PLANE, SWIZZLE_RGBA
        0x8129 => 3,                                                       // POINT_DISTANCE_ATTENUATION
        _ => 1,
    }
}

pub fn pname_count(_: &mut Recorder, a: &[i64]) -> Mem {
    Mem::Elements(pname_values(a[0]))
}

pub fn pname_count_2(_: &mut Recorder, a: &[i64]) -> Mem {
    Mem::Elements(pname_values(a[1]))
}

pub fn indices(_: &mut Recorder, a: &[i64]) -> Mem {
    if bound_buffer(GL_ELEMENT_ARRAY_BUFFER_BINDING) != 0 {
        return Mem::Offset;
    }
    Mem::Bytes((a[0].max(0) as usize).saturating_mul(glray_core::gltypes::value_bytes(a[1] as u32) as usize))
}

pub fn call_lists(_: &mut Recorder, a: &[i64]) -> Mem {
    // A bad type records 4 bytes a name; the real GL raises GL_INVALID_ENUM.
    let size = glray_capture::lists::name_size(a[1] as u32).unwrap_or(4);
    Mem::Bytes((a[0].max(0) as usize).saturating_mul(size))
}

/// Bytes per pixel of a format/type pair (packed types count once per pixel).
fn pixel_bytes(format: i64, ty: i64) -> usize {
    let comps = match format {
        0x1907 | 0x80E0 | 0x8D98 | 0x8D9A => 3, // RGB, BGR, RGB_INTEGER, BGR_INTEGER
        0x1908 | 0x80E1 | 0x8D99 | 0x8D9B | 0x8000 | 0x8001 => 4, // RGBA, BGRA, *_INTEGER, ABGR/CMYK
        0x190A | 0x8227 | 0x84F9 | 0x8228 => 2, // LUMINANCE_ALPHA, RG, DEPTH_STENCIL, RG_INTEGER
        _ => 1,
    };
    match ty {
        0x1400 | 0x1401 => comps,
        0x1402 | 0x1403 | 0x140B => comps * 2,
        0x8032 | 0x8362 | 0x8033 | 0x8365 | 0x8034 | 0x8366 | 0x8363 | 0x8364 => {
            2 - (ty == 0x8032 || ty == 0x8362) as usize
        } // packed 8/16-bit
        0x8035 | 0x8367 | 0x8036 | 0x8368 | 0x84FA | 0x8C3B | 0x8C3E => 4, // packed 32-bit, 24_8, 10F_11F_11F, 5_9_9_9
        0x8DAD => 8,                                                       // FLOAT_32_UNSIGNED_INT_24_8_REV
        0x1A00 => 1,                                                       // BITMAP (rounded up below)
        _ => comps * 4,
    }
}

fn unpack(pname: u32) -> i64 {
    real::get_int(pname) as i64
}

/// Bytes of a width x height x depth image read with the current unpack state (row length,
/// alignment, skips, image height), the way GL walks it.
fn image(a_format: i64, ty: i64, w: i64, h: i64, d: i64) -> Mem {
    if bound_buffer(GL_PIXEL_UNPACK_BUFFER_BINDING) != 0 {
        return Mem::Offset;
    }
    if w <= 0 || h <= 0 || d <= 0 {
        return Mem::Bytes(0);
    }
    let (row_length, alignment, skip_rows, skip_pixels, image_height, skip_images) = (
        unpack(0x0CF2),        // UNPACK_ROW_LENGTH
        unpack(0x0CF5).max(1), // UNPACK_ALIGNMENT
        unpack(0x0CF3),        // UNPACK_SKIP_ROWS
        unpack(0x0CF4),        // UNPACK_SKIP_PIXELS
        unpack(0x806E),        // UNPACK_IMAGE_HEIGHT
        unpack(0x806D),        // UNPACK_SKIP_IMAGES
    );
    let px = pixel_bytes(a_format, ty) as i64;
    let width = if row_length > 0 { row_length } else { w };
    let row = if ty == 0x1A00 { (width + 7) / 8 } else { width * px };
    let row = (row + alignment - 1) / alignment * alignment;
    let rows_per_image = if image_height > 0 { image_height } else { h };
    let total =
        (skip_images + d - 1) * rows_per_image * row + (skip_rows + h - 1) * row + (skip_pixels + w) * px.max(1);
    Mem::Bytes(total.max(0) as usize)
}

pub fn image_1d(_: &mut Recorder, a: &[i64]) -> Mem {
    image(a[0], a[1], a[2], 1, 1)
}

pub fn image_2d(_: &mut Recorder, a: &[i64]) -> Mem {
    image(a[0], a[1], a[2], a[3], 1)
}

pub fn image_3d(_: &mut Recorder, a: &[i64]) -> Mem {
    image(a[0], a[1], a[2], a[3], a[4])
}

pub fn bitmap(_: &mut Recorder, a: &[i64]) -> Mem {
    image(0x1900 /* COLOR_INDEX */, 0x1A00 /* BITMAP */, a[0], a[1], 1)
}

pub fn pixel(_: &mut Recorder, a: &[i64]) -> Mem {
    Mem::Bytes(pixel_bytes(a[0], a[1]))
}

pub fn polygon_stipple(_: &mut Recorder, _: &[i64]) -> Mem {
    image(0x1900, 0x1A00, 32, 32, 1)
}

/// Components of one control point of an evaluator target.
fn map_components(target: i64) -> i64 {
    match target {
        0x0D93 | 0x0DB3 => 1,                   // MAP1/2_INDEX
        0x0D92 | 0x0DB2 | 0x0D94 | 0x0DB4 => 1, // TEXTURE_COORD_1
        0x0D95 | 0x0DB5 => 2,                   // TEXTURE_COORD_2
        0x0D96 | 0x0DB6 | 0x0D97 | 0x0DB7 => 3, // TEXTURE_COORD_3, VERTEX_3
        0x0D98 | 0x0DB8 => 4,                   // TEXTURE_COORD_4 / VERTEX_4
        0x0D90 | 0x0DB0 => 4,                   // COLOR_4
        0x0D91 | 0x0DB1 => 3,                   // NORMAL
        _ => 4,
    }
}

pub fn map_1(_: &mut Recorder, a: &[i64]) -> Mem {
    let (target, stride, order) = (a[0], a[1], a[2]);
    if order <= 0 || stride < 0 {
        return Mem::Elements(0);
    }
    Mem::Elements(((order - 1) * stride + map_components(target)) as usize)
}

pub fn map_2(_: &mut Recorder, a: &[i64]) -> Mem {
    let (target, us, uo, vs, vo) = (a[0], a[1], a[2], a[3], a[4]);
    if uo <= 0 || vo <= 0 || us < 0 || vs < 0 {
        return Mem::Elements(0);
    }
    Mem::Elements(((uo - 1) * us + (vo - 1) * vs + map_components(target)) as usize)
}
