//! Reading a recorded call's arguments (glray-core's `Value`s) as the numbers GL commands take:
//! scalars, and the memory of pointer arguments as arrays of GL types. A value of the wrong kind
//! reads as 0 (or an empty array): the trace reader has already checked the encoding, and GL
//! itself would take garbage; capture must never panic on a bad trace.

use glam::DVec4;
use glray_core::trace::Value;
use glray_gl::{
    GL_BYTE, GL_DOUBLE, GL_FLOAT, GL_HALF_FLOAT, GL_INT, GL_SHORT, GL_UNSIGNED_BYTE, GL_UNSIGNED_INT, GL_UNSIGNED_SHORT,
};

pub fn int(a: &[Value], i: usize) -> i64 {
    a.get(i).map_or(0, Value::as_int)
}

pub fn uint(a: &[Value], i: usize) -> u32 {
    int(a, i) as u32
}

pub fn float(a: &[Value], i: usize) -> f64 {
    match a.get(i) {
        Some(Value::F32(x)) => *x as f64,
        Some(Value::F64(x)) => *x,
        Some(v) => v.as_int() as f64,
        None => 0.0,
    }
}

/// The recorded memory of a pointer argument (empty for null or unrecorded pointers).
pub fn bytes<'a>(a: &[Value<'a>], i: usize) -> &'a [u8] {
    match a.get(i) {
        Some(Value::Blob(b)) | Some(Value::Str(b)) => b,
        _ => &[],
    }
}

/// Size in bytes of one element of a GL type; None for types glray does not read.
pub fn type_size(ty: u32) -> Option<usize> {
    Some(match ty {
        GL_BYTE | GL_UNSIGNED_BYTE => 1,
        GL_SHORT | GL_UNSIGNED_SHORT | GL_HALF_FLOAT => 2,
        GL_INT | GL_UNSIGNED_INT | GL_FLOAT => 4,
        GL_DOUBLE => 8,
        _ => return None,
    })
}

/// Element `i` of type `ty` in `b` (native byte order), as f64, without normalisation;
/// None past the end.
pub fn element(b: &[u8], ty: u32, i: usize) -> Option<f64> {
    let mut v = [0.0];
    (elements(b.get(i * type_size(ty)?..)?, ty, &mut v) == 1).then_some(v[0])
}

/// The elements of type `ty` at the start of `b` (native byte order) into `out`, as f64
/// without normalisation, as many as both hold; how many (0 for a type glray does not read).
/// The type is decided once for them all, not element by element: attribute vectors
/// (glVertex3fv, glNormal3fv: millions in a big display list) and vertex arrays are read so.
#[inline]
pub fn elements(b: &[u8], ty: u32, out: &mut [f64]) -> usize {
    #[inline(always)]
    fn each<const S: usize>(b: &[u8], out: &mut [f64], convert: impl Fn([u8; S]) -> f64) -> usize {
        let mut n = 0;
        for (o, s) in out.iter_mut().zip(b.chunks_exact(S)) {
            *o = convert(s.try_into().expect("chunks of S bytes"));
            n += 1;
        }
        n
    }
    match ty {
        GL_BYTE => each(b, out, |s: [u8; 1]| s[0] as i8 as f64),
        GL_UNSIGNED_BYTE => each(b, out, |s: [u8; 1]| s[0] as f64),
        GL_SHORT => each(b, out, |s| i16::from_ne_bytes(s) as f64),
        GL_UNSIGNED_SHORT => each(b, out, |s| u16::from_ne_bytes(s) as f64),
        GL_HALF_FLOAT => each(b, out, |s| half_to_f64(u16::from_ne_bytes(s))),
        GL_INT => each(b, out, |s| i32::from_ne_bytes(s) as f64),
        GL_UNSIGNED_INT => each(b, out, |s| u32::from_ne_bytes(s) as f64),
        GL_FLOAT => each(b, out, |s| f32::from_ne_bytes(s) as f64),
        GL_DOUBLE => each(b, out, f64::from_ne_bytes),
        _ => 0,
    }
}

/// GL's conversion of a normalised integer component to [-1, 1] or [0, 1] (OpenGL 2.1,
/// table 2.9); floats pass unchanged.
pub fn normalize(v: f64, ty: u32) -> f64 {
    match ty {
        GL_BYTE => (2.0 * v + 1.0) / 255.0,
        GL_UNSIGNED_BYTE => v / 255.0,
        GL_SHORT => (2.0 * v + 1.0) / 65535.0,
        GL_UNSIGNED_SHORT => v / 65535.0,
        GL_INT => (2.0 * v + 1.0) / 4294967295.0,
        GL_UNSIGNED_INT => v / 4294967295.0,
        _ => v,
    }
}

/// The first `n` elements of a pointer argument as f64 (fewer if less memory was recorded).
pub fn array(b: &[u8], ty: u32, n: usize) -> Vec<f64> {
    // No more room than the memory holds elements (a corrupt count asks for no huge allocation).
    let mut v = vec![0.0; n.min(b.len() / type_size(ty).unwrap_or(1))];
    let got = elements(b, ty, &mut v);
    v.truncate(got);
    v
}

/// The values of argument `i`: a recorded array of `n` values of type `ty` (a `v` command's
/// pointer), or the one scalar it is.
pub fn floats(a: &[Value], i: usize, ty: u32, n: usize) -> Vec<f64> {
    match a.get(i) {
        Some(Value::Blob(b)) => array(b, ty, n),
        Some(_) => vec![float(a, i)],
        None => Vec::new(),
    }
}

/// A colour argument: integer forms map the integer range to [-1, 1].
pub fn color_param(a: &[Value], i: usize, ty: u32) -> DVec4 {
    let v = floats(a, i, ty, 4);
    let get = |k: usize| {
        let x = v.get(k).copied().unwrap_or(0.0);
        if ty == GL_INT {
            x / 2147483647.0
        } else {
            x
        }
    };
    DVec4::new(get(0), get(1), get(2), get(3))
}

fn half_to_f64(h: u16) -> f64 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = ((h >> 10) & 0x1f) as i32;
    let frac = (h & 0x3ff) as f64;
    sign * match exp {
        0 => frac * 2f64.powi(-24),
        31 => {
            if frac == 0.0 {
                f64::INFINITY
            } else {
                f64::NAN
            }
        }
        _ => (1.0 + frac / 1024.0) * 2f64.powi(exp - 15),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elements_and_normalisation() {
        let b = [0xffu8, 0x7f];
        assert_eq!(element(&b, GL_BYTE, 0), Some(-1.0));
        assert_eq!(element(&b, GL_UNSIGNED_BYTE, 1), Some(127.0));
        assert_eq!(element(&b, GL_UNSIGNED_BYTE, 2), None);
        assert_eq!(normalize(255.0, GL_UNSIGNED_BYTE), 1.0);
        assert_eq!(normalize(-128.0, GL_BYTE), -1.0);
        assert_eq!(normalize(127.0, GL_BYTE), 1.0);
        assert_eq!(half_to_f64(0x3c00), 1.0);
        assert_eq!(array(&1.5f32.to_ne_bytes(), GL_FLOAT, 4), vec![1.5]);
    }

    #[test]
    fn elements_of_every_type_read_what_their_memory_holds() {
        let bytes = |v: &[f64], ty: u32| -> Vec<u8> {
            v.iter()
                .flat_map(|&x| match ty {
                    GL_BYTE => (x as i8).to_ne_bytes().to_vec(),
                    GL_UNSIGNED_BYTE => (x as u8).to_ne_bytes().to_vec(),
                    GL_SHORT => (x as i16).to_ne_bytes().to_vec(),
                    GL_UNSIGNED_SHORT => (x as u16).to_ne_bytes().to_vec(),
                    GL_HALF_FLOAT => 0x3c00u16.to_ne_bytes().to_vec(), // 1.0, the only value used
                    GL_INT => (x as i32).to_ne_bytes().to_vec(),
                    GL_UNSIGNED_INT => (x as u32).to_ne_bytes().to_vec(),
                    GL_FLOAT => (x as f32).to_ne_bytes().to_vec(),
                    _ => x.to_ne_bytes().to_vec(),
                })
                .collect()
        };
        let signed = [-3.0, 7.0, 100.0];
        let unsigned = [3.0, 7.0, 200.0];
        for (ty, v) in [
            (GL_BYTE, &signed),
            (GL_UNSIGNED_BYTE, &unsigned),
            (GL_SHORT, &signed),
            (GL_UNSIGNED_SHORT, &unsigned),
            (GL_INT, &signed),
            (GL_UNSIGNED_INT, &unsigned),
            (GL_FLOAT, &[0.5, -2.25, 3.0]),
            (GL_DOUBLE, &[0.1, -2.25, 1e300]),
            (GL_HALF_FLOAT, &[1.0, 1.0, 1.0]),
        ] {
            let b = bytes(v, ty);
            let mut out = [9.0; 4];
            assert_eq!(elements(&b, ty, &mut out), 3, "type {ty:#x}");
            assert_eq!(&out[..3], &v[..], "type {ty:#x}");
            assert_eq!(out[3], 9.0, "type {ty:#x}: past the memory, untouched");
            // Element by element, the same values; memory cut inside the last element: two.
            for (i, x) in v.iter().enumerate() {
                assert_eq!(element(&b, ty, i), Some(*x), "type {ty:#x}, element {i}");
            }
            assert_eq!(element(&b, ty, 3), None);
            assert_eq!(elements(&b[..b.len() - 1], ty, &mut out), 2, "type {ty:#x}");
            assert_eq!(array(&b, ty, 10), v.to_vec(), "type {ty:#x}");
        }
        assert_eq!(elements(&[0; 8], 0x1234, &mut [0.0; 2]), 0, "a type glray does not read");
        assert_eq!(element(&[0; 8], 0x1234, 0), None);
    }
}
