//! Sizes of GL data types, shared by the recorder (how much memory a draw reads) and the
//! replayer (where the elements of recorded arrays start).

use glray_gl::{
    GL_BGRA, GL_BYTE, GL_DOUBLE, GL_HALF_FLOAT, GL_INT_2_10_10_10_REV, GL_SHORT, GL_UNSIGNED_BYTE,
    GL_UNSIGNED_INT_10F_11F_11F_REV, GL_UNSIGNED_INT_2_10_10_10_REV, GL_UNSIGNED_SHORT,
};

/// Bytes of one value of a GL data type (GL_FLOAT, GL_UNSIGNED_SHORT, ...).
pub fn value_bytes(ty: u32) -> u64 {
    match ty {
        GL_BYTE | GL_UNSIGNED_BYTE => 1,
        GL_SHORT | GL_UNSIGNED_SHORT | GL_HALF_FLOAT => 2,
        GL_DOUBLE => 8,
        _ => 4, // INT, UNSIGNED_INT, FLOAT, FIXED
    }
}

/// Bytes of one element of a vertex array of `size` components of type `ty` (GL_BGRA as the
/// size means 4 components; the packed 2_10_10_10 and 10F_11F_11F types are one word).
pub fn array_element_bytes(size: i32, ty: u32) -> u64 {
    match ty {
        GL_INT_2_10_10_10_REV | GL_UNSIGNED_INT_2_10_10_10_REV | GL_UNSIGNED_INT_10F_11F_11F_REV => 4,
        t => {
            let comps = if size == GL_BGRA as i32 { 4 } else { size.max(1) as u64 };
            comps * value_bytes(t)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glray_gl::GL_FLOAT;

    #[test]
    fn element_sizes() {
        assert_eq!(array_element_bytes(3, GL_FLOAT), 12);
        assert_eq!(array_element_bytes(GL_BGRA as i32, GL_UNSIGNED_BYTE), 4);
        assert_eq!(array_element_bytes(4, GL_INT_2_10_10_10_REV), 4);
        assert_eq!(array_element_bytes(2, GL_DOUBLE), 16);
        assert_eq!(value_bytes(GL_UNSIGNED_SHORT), 2);
    }
}
