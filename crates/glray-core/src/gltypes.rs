//! Sizes of GL data types, shared by the recorder (how much memory a draw reads) and the
//! replayer (where the elements of recorded arrays start).

/// Bytes of one value of a GL data type (GL_FLOAT, GL_UNSIGNED_SHORT, ...).
pub fn value_bytes(ty: u32) -> u64 {
    match ty {
        0x1400 | 0x1401 => 1,          // BYTE, UNSIGNED_BYTE
        0x1402 | 0x1403 | 0x140B => 2, // SHORT, UNSIGNED_SHORT, HALF_FLOAT
        0x140A => 8,                   // DOUBLE
        _ => 4,                        // INT, UNSIGNED_INT, FLOAT, FIXED
    }
}

/// Bytes of one element of a vertex array of `size` components of type `ty` (GL_BGRA as the
/// size means 4 components; the packed 2_10_10_10 and 10F_11F_11F types are one word).
pub fn array_element_bytes(size: i32, ty: u32) -> u64 {
    const GL_BGRA: i32 = 0x80E1;
    match ty {
        0x8D9F | 0x8368 | 0x8C3B => 4,
        t => {
            let comps = if size == GL_BGRA { 4 } else { size.max(1) as u64 };
            comps * value_bytes(t)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn element_sizes() {
        assert_eq!(array_element_bytes(3, 0x1406), 12);
        assert_eq!(array_element_bytes(0x80E1, 0x1401), 4);
        assert_eq!(array_element_bytes(4, 0x8D9F), 4);
        assert_eq!(array_element_bytes(2, 0x140A), 16);
        assert_eq!(value_bytes(0x1403), 2);
    }
}
