//! The meshes and textures a frame draws with, shared by id: what a receiver holds of those
//! sent to it (`ObjectStore`), and the serde helpers that write an `Arc<Mesh>` or `Arc<Texture>`
//! field as its id and read it back from the `ObjectStore` of the message being read (`encode`).

use std::cell::{Cell, RefCell};
use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use serde::Deserialize;

use crate::mesh::Mesh;
use crate::texture::Texture;

/// What a receiver holds of the meshes and textures sent to it, by id (a mesh's `id`, a
/// texture's `version`); and what a sender knows its receiver holds.
#[derive(Default)]
pub struct ObjectStore {
    meshes: HashMap<u64, Arc<Mesh>>,
    textures: HashMap<u64, Arc<Texture>>,
}

impl ObjectStore {
    pub fn mesh(&self, id: u64) -> Option<&Arc<Mesh>> {
        self.meshes.get(&id)
    }

    pub fn has_mesh(&self, id: u64) -> bool {
        self.meshes.contains_key(&id)
    }

    pub fn has_texture(&self, version: u64) -> bool {
        self.textures.contains_key(&version)
    }

    /// How many meshes and textures it holds.
    pub fn len(&self) -> (usize, usize) {
        (self.meshes.len(), self.textures.len())
    }

    pub fn is_empty(&self) -> bool {
        self.meshes.is_empty() && self.textures.is_empty()
    }

    /// Adds `mesh`; false if one of its id was held already.
    pub fn add_mesh(&mut self, mesh: &Arc<Mesh>) -> bool {
        self.meshes.insert(mesh.id, mesh.clone()).is_none()
    }

    /// Adds `texture`; false if one of its version was held already.
    pub fn add_texture(&mut self, texture: &Arc<Texture>) -> bool {
        self.textures.insert(texture.version, texture.clone()).is_none()
    }

    /// Keeps only the meshes and textures named (what the frames to come still draw with).
    pub fn retain(&mut self, meshes: &HashSet<u64>, textures: &HashSet<u64>) {
        self.meshes.retain(|id, _| meshes.contains(id));
        self.textures.retain(|v, _| textures.contains(v));
    }

    /// `read` with the `Arc` fields it deserializes taken from this store; and, if one named
    /// an object the store lacks, which (`("mesh", id)` or `("texture", version)`).
    pub fn reading<T>(&mut self, read: impl FnOnce() -> T) -> (T, Option<(&'static str, u64)>) {
        MISSING.with(|m| m.set(None));
        READING.with(|r| *r.borrow_mut() = Some(std::mem::take(self)));
        let out = read();
        *self = READING.with(|r| r.borrow_mut().take()).unwrap_or_default();
        (out, MISSING.with(|m| m.take()))
    }
}

thread_local! {
    /// The store a message being read on this thread takes its objects from (serde's derives
    /// take no context: the shared objects reach `shared_mesh` and `shared_texture` here).
    static READING: RefCell<Option<ObjectStore>> = const { RefCell::new(None) };
    /// The object a read missed, for its error.
    static MISSING: Cell<Option<(&'static str, u64)>> = const { Cell::new(None) };
}

/// The object of the store being read from, or the error naming the missing one.
fn found<T, E: serde::de::Error>(
    what: &'static str,
    id: u64,
    get: impl FnOnce(&ObjectStore) -> Option<Arc<T>>,
) -> Result<Arc<T>, E> {
    let found = READING.with(|r| r.borrow().as_ref().and_then(get));
    found.ok_or_else(|| {
        MISSING.with(|m| m.set(Some((what, id))));
        E::custom(format!("{what} {id} was never sent"))
    })
}

/// An `Arc<Mesh>` field written as the mesh's id.
pub mod shared_mesh {
    use super::*;

    pub fn serialize<S: serde::Serializer>(mesh: &Arc<Mesh>, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_u64(mesh.id)
    }

    pub fn deserialize<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Arc<Mesh>, D::Error> {
        let id = u64::deserialize(d)?;
        found("mesh", id, |s| s.meshes.get(&id).cloned())
    }
}

/// An `Arc<Texture>` field written as the texture's version.
pub mod shared_texture {
    use super::*;

    pub fn serialize<S: serde::Serializer>(texture: &Arc<Texture>, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_u64(texture.version)
    }

    pub fn deserialize<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Arc<Texture>, D::Error> {
        let version = u64::deserialize(d)?;
        found("texture", version, |s| s.textures.get(&version).cloned())
    }
}
