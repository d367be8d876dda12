//! Generic vertex attributes and the vertex array objects that hold them: for each attribute
//! location, whether it is on, where its values are (a buffer object and an offset in it) and
//! how they are laid out. A draw through a program reads its inputs from here.

use std::collections::HashMap;

/// How many generic attributes capture follows (GL guarantees at least 16).
pub const ATTRIBUTES: usize = 16;

/// One generic attribute's array: glVertexAttribPointer's state and glVertexAttribDivisor's.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct AttribArray {
    pub enabled: bool,
    pub size: i32,
    pub ty: u32,
    pub normalized: bool,
    pub stride: i32,
    /// Byte offset into `buffer`.
    pub offset: u64,
    /// The buffer object bound to GL_ARRAY_BUFFER at the glVertexAttribPointer (0: client
    /// memory, which capture does not follow for generic attributes).
    pub buffer: u32,
    /// Instances per value (0: one value per vertex).
    pub divisor: u32,
}

/// A vertex array object's state.
#[derive(Debug, Clone, Default)]
pub struct VertexArray {
    pub attribs: [AttribArray; ATTRIBUTES],
}

/// A context's vertex array objects (not shared between contexts, as GL has it), and the one
/// bound (0: the default one a compatibility context has).
#[derive(Debug, Clone, Default)]
pub struct VertexArrays {
    bound: u32,
    arrays: HashMap<u32, VertexArray>,
}

impl VertexArrays {
    pub fn bind(&mut self, name: u32) {
        self.bound = name;
    }

    pub fn delete(&mut self, names: impl Iterator<Item = u32>) {
        for name in names {
            self.arrays.remove(&name);
            if self.bound == name {
                self.bound = 0;
            }
        }
    }

    /// The bound vertex array's state.
    pub fn current(&self) -> Option<&VertexArray> {
        self.arrays.get(&self.bound)
    }

    /// Attribute `index` of the bound vertex array, to be changed (None: no such index).
    pub fn attrib_mut(&mut self, index: u32) -> Option<&mut AttribArray> {
        let array = self.arrays.entry(self.bound).or_default();
        array.attribs.get_mut(index as usize)
    }

    /// Attribute `index` of the bound vertex array.
    pub fn attrib(&self, index: u32) -> Option<AttribArray> {
        self.current().and_then(|a| a.attribs.get(index as usize).copied())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_vertex_array_keeps_its_own_attributes() {
        let mut v = VertexArrays::default();
        v.bind(3);
        *v.attrib_mut(0).unwrap() = AttribArray { enabled: true, size: 3, buffer: 7, ..Default::default() };
        v.bind(4);
        assert_eq!(v.attrib(0), None, "a vertex array not yet given any attribute");
        v.attrib_mut(0).unwrap().size = 2;
        v.bind(3);
        assert_eq!(v.attrib(0).map(|a| (a.size, a.buffer)), Some((3, 7)));
        assert!(v.attrib_mut(ATTRIBUTES as u32).is_none());
        v.delete([3].into_iter());
        assert_eq!(v.attrib(0), None, "deleting the bound one binds 0");
    }
}
