//! A glArrayElement between glBegin and glEnd, as the immediate-mode calls it stands for.
//!
//! The trace gives the element's memory just before the call (an ARRAYS event), but GL takes no
//! gl*Pointer between glBegin and glEnd (GL_INVALID_OPERATION: the replay kept reading the
//! arrays set before the glBegin, from freed memory). So the replay gives the element as Mesa's
//! own glArrayElement does: every attribute first, then the vertex, each converted as GL
//! converts array elements (colours, secondary colours and normals normalized from integers,
//! generic attributes as their pointer said, the rest as they are).

use glray_core::trace::{array_kind, ArrayData};
use glray_gl::GL_BGRA;

/// One array of an element, owned until the glArrayElement that reads it.
pub struct Array {
    kind: u8,
    index: u32,
    size: i32,
    gl_type: u32,
    stride: i32,
    normalized: bool,
    first: u64,
    bytes: Vec<u8>,
}

impl Array {
    pub fn of(a: &ArrayData) -> Array {
        Array {
            kind: a.kind,
            index: a.index,
            size: a.size,
            gl_type: a.gl_type,
            stride: a.stride,
            normalized: a.normalized,
            first: a.first,
            bytes: a.bytes.to_vec(),
        }
    }

    /// Element `k`'s components (GL's defaults where the array has fewer: 0, 0, 0, 1), and how
    /// many the array has; None where the memory does not hold it.
    fn element(&self, k: u64, normalize: bool) -> Option<([f64; 4], usize)> {
        let bgra = self.size == GL_BGRA as i32;
        let n = if bgra { 4 } else { self.size.clamp(1, 4) as usize };
        let elem = glray_capture::args::type_size(self.gl_type)? * n;
        let stride = if self.stride > 0 { self.stride as usize } else { elem };
        let at = usize::try_from(k.checked_sub(self.first)?).ok()?.checked_mul(stride)?;
        let mut x = [0.0, 0.0, 0.0, 1.0];
        if glray_capture::args::elements(self.bytes.get(at..)?, self.gl_type, &mut x[..n]) < n {
            return None;
        }
        if normalize {
            for c in &mut x[..n] {
                *c = glray_capture::args::normalize(*c, self.gl_type);
            }
        }
        if bgra {
            x.swap(0, 2);
        }
        Some((x, n))
    }
}

/// An immediate-mode call (the double-precision forms: every array type converts to them
/// without loss).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Immediate {
    Color4d([f64; 4]),
    SecondaryColor3d([f64; 3]),
    Normal3d([f64; 3]),
    FogCoordd(f64),
    EdgeFlag(bool),
    /// Texture unit, coordinates.
    MultiTexCoord4d(u32, [f64; 4]),
    /// Attribute index, components.
    VertexAttrib4d(u32, [f64; 4]),
    Vertex4d([f64; 4]),
}

/// The calls element `k` of `arrays` stands for: attributes in the order given, the vertex
/// (the vertex array, or generic attribute 0, which is the vertex in a compatibility context)
/// last. Arrays whose memory lacks the element give nothing (GL would read what is not there).
pub fn calls(arrays: &[Array], k: u64) -> Vec<Immediate> {
    let mut calls = Vec::with_capacity(arrays.len());
    let mut vertex = None;
    for a in arrays {
        let is_vertex = a.kind == array_kind::VERTEX || (a.kind == array_kind::ATTRIB && a.index == 0);
        let normalize = match a.kind {
            array_kind::COLOR | array_kind::SECONDARY_COLOR | array_kind::NORMAL => true,
            array_kind::ATTRIB => a.normalized,
            _ => false,
        };
        let Some((x, _)) = a.element(k, normalize) else { continue };
        let call = match a.kind {
            _ if is_vertex => {
                vertex = Some(Immediate::Vertex4d(x));
                continue;
            }
            array_kind::COLOR => Immediate::Color4d(x),
            array_kind::SECONDARY_COLOR => Immediate::SecondaryColor3d([x[0], x[1], x[2]]),
            array_kind::NORMAL => Immediate::Normal3d([x[0], x[1], x[2]]),
            array_kind::FOG_COORD => Immediate::FogCoordd(x[0]),
            array_kind::EDGE_FLAG => Immediate::EdgeFlag(x[0] != 0.0),
            array_kind::TEXCOORD => Immediate::MultiTexCoord4d(a.index, x),
            array_kind::ATTRIB => Immediate::VertexAttrib4d(a.index, x),
            // Colour indices: no colour-index visuals are replayed.
            _ => continue,
        };
        calls.push(call);
    }
    calls.extend(vertex);
    calls
}

#[cfg(test)]
mod tests {
    use super::*;
    use glray_gl::{GL_FLOAT, GL_UNSIGNED_BYTE};

    fn array(kind: u8, size: i32, gl_type: u32, first: u64, bytes: Vec<u8>) -> Array {
        Array { kind, index: 0, size, gl_type, stride: 0, normalized: false, first, bytes }
    }

    fn floats(v: &[f32]) -> Vec<u8> {
        v.iter().flat_map(|f| f.to_le_bytes()).collect()
    }

    #[test]
    fn an_element_is_its_attributes_then_its_vertex_with_gls_defaults_and_conversions() {
        let arrays = [
            array(array_kind::VERTEX, 2, GL_FLOAT, 3, floats(&[0.5, -1.0])),
            array(array_kind::COLOR, 3, GL_UNSIGNED_BYTE, 3, vec![255, 0, 51]),
            array(array_kind::TEXCOORD, 1, GL_FLOAT, 3, floats(&[0.25])),
        ];
        assert_eq!(
            calls(&arrays, 3),
            [
                Immediate::Color4d([1.0, 0.0, 0.2, 1.0]),
                Immediate::MultiTexCoord4d(0, [0.25, 0.0, 0.0, 1.0]),
                Immediate::Vertex4d([0.5, -1.0, 0.0, 1.0]),
            ]
        );
        // Memory that does not hold the element gives no call for it.
        assert!(calls(&arrays, 4).is_empty());
        assert!(calls(&arrays, 2).is_empty());
    }

    #[test]
    fn bgra_colours_are_swizzled_and_strides_followed() {
        let mut colour = array(array_kind::COLOR, GL_BGRA as i32, GL_UNSIGNED_BYTE, 1, vec![0, 0, 255, 255, 9, 9]);
        colour.stride = 6;
        assert_eq!(calls(&[colour], 1), [Immediate::Color4d([1.0, 0.0, 0.0, 1.0])]);
    }
}
