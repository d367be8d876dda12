//! Size rules for pointer arguments whose size the registry gives as COMPSIZE(...): each is named
//! in gl-spec/sizes.txt and called by the generated recorder with those arguments.

use glray_gl::*;

use super::{bound_buffer, Recorder};
use crate::abi::real;

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
    match pname as u32 {
        GL_AMBIENT | GL_DIFFUSE | GL_SPECULAR | GL_POSITION | GL_EMISSION | GL_AMBIENT_AND_DIFFUSE => 4,
        GL_SPOT_DIRECTION | GL_COLOR_INDEXES => 3,
        GL_LIGHT_MODEL_AMBIENT
        | GL_FOG_COLOR
        | GL_TEXTURE_ENV_COLOR
        | GL_TEXTURE_BORDER_COLOR
        | GL_OBJECT_PLANE
        | GL_EYE_PLANE
        | GL_TEXTURE_SWIZZLE_RGBA => 4,
        GL_POINT_DISTANCE_ATTENUATION => 3,
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
    let size = glray_capture::fixed::lists::name_size(a[1] as u32).unwrap_or(4);
    Mem::Bytes((a[0].max(0) as usize).saturating_mul(size))
}

/// Bytes per pixel of a format/type pair (packed types count once per pixel).
fn pixel_bytes(format: i64, ty: i64) -> usize {
    let comps = match format as u32 {
        GL_RGB | GL_BGR | GL_RGB_INTEGER | GL_BGR_INTEGER => 3,
        GL_RGBA | GL_BGRA | GL_RGBA_INTEGER | GL_BGRA_INTEGER | GL_ABGR_EXT | GL_CMYK_EXT => 4,
        GL_LUMINANCE_ALPHA | GL_RG | GL_DEPTH_STENCIL | GL_RG_INTEGER => 2,
        _ => 1,
    };
    match ty as u32 {
        GL_BYTE | GL_UNSIGNED_BYTE => comps,
        GL_SHORT | GL_UNSIGNED_SHORT | GL_HALF_FLOAT => comps * 2,
        // Packed into 8 bits.
        GL_UNSIGNED_BYTE_3_3_2 | GL_UNSIGNED_BYTE_2_3_3_REV => 1,
        // Packed into 16 bits.
        GL_UNSIGNED_SHORT_4_4_4_4
        | GL_UNSIGNED_SHORT_4_4_4_4_REV
        | GL_UNSIGNED_SHORT_5_5_5_1
        | GL_UNSIGNED_SHORT_1_5_5_5_REV
        | GL_UNSIGNED_SHORT_5_6_5
        | GL_UNSIGNED_SHORT_5_6_5_REV => 2,
        // Packed into 32 bits.
        GL_UNSIGNED_INT_8_8_8_8
        | GL_UNSIGNED_INT_8_8_8_8_REV
        | GL_UNSIGNED_INT_10_10_10_2
        | GL_UNSIGNED_INT_2_10_10_10_REV
        | GL_UNSIGNED_INT_24_8
        | GL_UNSIGNED_INT_10F_11F_11F_REV
        | GL_UNSIGNED_INT_5_9_9_9_REV => 4,
        GL_FLOAT_32_UNSIGNED_INT_24_8_REV => 8,
        GL_BITMAP => 1, // rounded up below
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
        unpack(GL_UNPACK_ROW_LENGTH),
        unpack(GL_UNPACK_ALIGNMENT).max(1),
        unpack(GL_UNPACK_SKIP_ROWS),
        unpack(GL_UNPACK_SKIP_PIXELS),
        unpack(GL_UNPACK_IMAGE_HEIGHT),
        unpack(GL_UNPACK_SKIP_IMAGES),
    );
    let px = pixel_bytes(a_format, ty) as i64;
    let width = if row_length > 0 { row_length } else { w };
    let row = if ty as u32 == GL_BITMAP { (width + 7) / 8 } else { width * px };
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
    image(GL_COLOR_INDEX.into(), GL_BITMAP.into(), a[0], a[1], 1)
}

pub fn pixel(_: &mut Recorder, a: &[i64]) -> Mem {
    Mem::Bytes(pixel_bytes(a[0], a[1]))
}

pub fn polygon_stipple(_: &mut Recorder, _: &[i64]) -> Mem {
    image(GL_COLOR_INDEX.into(), GL_BITMAP.into(), 32, 32, 1)
}

/// Components of one control point of an evaluator target.
fn map_components(target: i64) -> i64 {
    match target as u32 {
        GL_MAP1_INDEX | GL_MAP2_INDEX | GL_MAP1_TEXTURE_COORD_1 | GL_MAP2_TEXTURE_COORD_1 => 1,
        GL_MAP1_TEXTURE_COORD_2 | GL_MAP2_TEXTURE_COORD_2 => 2,
        GL_MAP1_TEXTURE_COORD_3 | GL_MAP2_TEXTURE_COORD_3 | GL_MAP1_VERTEX_3 | GL_MAP2_VERTEX_3 => 3,
        GL_MAP1_TEXTURE_COORD_4 | GL_MAP2_TEXTURE_COORD_4 | GL_MAP1_VERTEX_4 | GL_MAP2_VERTEX_4 => 4,
        GL_MAP1_COLOR_4 | GL_MAP2_COLOR_4 => 4,
        GL_MAP1_NORMAL | GL_MAP2_NORMAL => 3,
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
