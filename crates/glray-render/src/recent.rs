//! What was made of the triangles recent camera rays hit (`Recent`), kept a few at a time for
//! the neighbouring pixels that hit them again.

use glray_scene::frame::TriangleId;

/// What was made of the triangles recent camera rays hit, in a few slots chosen by id:
/// neighbouring pixels mostly hit the same triangles, in both rows of the blocks a thread
/// shades (a single "last triangle" lost each one at every change of row), and an instance's
/// triangle is made (lit, faced) only when it is needed. Lent, not copied (a triangle with its
/// lighting is a few hundred bytes).
///
/// The ids and the values are apart, so that a value is made where it is kept (in a tuple
/// with its id a triangle was copied twice more, a few percent of a frame).
pub(crate) struct Recent<T> {
    ids: [Option<TriangleId>; RECENT],
    values: [Option<T>; RECENT],
}

/// Slots in `Recent`.
const RECENT: usize = 16;

impl<T> Default for Recent<T> {
    fn default() -> Self {
        Recent { ids: [None; RECENT], values: std::array::from_fn(|_| None) }
    }
}

impl<T> Recent<T> {
    /// What was made of triangle `id`, made by `make` if its slot holds another's.
    #[inline]
    pub fn get(&mut self, id: TriangleId, make: impl FnOnce() -> Option<T>) -> Option<&T> {
        // Fibonacci hashing: neighbouring indices (a mesh's neighbouring triangles) spread
        // over the slots, the top bits of the product choosing one.
        let key = id.index ^ id.instance.rotate_left(16);
        let slot = (key.wrapping_mul(0x9E37_79B1) >> (32 - RECENT.trailing_zeros())) as usize;
        if self.ids[slot] != Some(id) {
            self.ids[slot] = Some(id);
            self.values[slot] = make();
        }
        self.values[slot].as_ref()
    }
}
