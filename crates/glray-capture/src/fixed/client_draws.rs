//! Meshes of big array draws from client memory, kept by what they read.
//!
//! A program that draws its data from client arrays (glVertexPointer on its own memory, then
//! glDrawElements) hands GL the same bytes frame after frame, and GL cannot know that they are
//! the same. Taken as new triangles every frame, 10M of them cost glray ~20 s of vertex stage
//! and a BVH build per frame, where llvmpipe takes 1.4 s. ListArg by a hash of every byte the draw
//! reads (`Context::client_draw_key`), the draw becomes one mesh drawn as an instance, like a
//! buffer object's, and its BVH is built once.
//!
//! Only draws that read client memory alone (no buffer object) are kept: what they read is all
//! in the key, so nothing else can make a kept mesh stale. Only what the last frame drew is
//! kept: a program whose arrays change every frame makes a new mesh each frame, and the old one
//! goes at the frame's end instead of filling memory.

use std::collections::HashMap;
use std::sync::Arc;

use crate::fixed::arrays::BufferDraw;
use crate::fixed::mesh_builder::Compiled;

#[derive(Default)]
pub(crate) struct ClientDraws {
    /// Each mesh, with the number of the frame that last drew it.
    meshes: HashMap<BufferDraw, (Arc<Compiled>, u64)>,
    /// The number of the frame being drawn.
    frame: u64,
}

impl ClientDraws {
    /// The mesh of a draw that read the same bytes before.
    pub(crate) fn get(&self, key: &BufferDraw) -> Option<Arc<Compiled>> {
        self.meshes.get(key).map(|(mesh, _)| mesh.clone())
    }

    /// A draw's mesh, drawn in this frame.
    pub(crate) fn insert(&mut self, key: BufferDraw, mesh: Arc<Compiled>) {
        self.meshes.insert(key, (mesh, self.frame));
    }

    /// The frame is over: meshes it did not draw are let go.
    pub(crate) fn frame_ended(&mut self) {
        let frame = self.frame;
        self.meshes.retain(|_, (_, drawn)| *drawn == frame);
        self.frame += 1;
    }

    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.meshes.len()
    }
}
