//! The byte encoding of a frame's scene: what crosses MPI ranks, and what a test can hold up to
//! the frame it came from. A message is a header (magic, version, byte order) and two postcard
//! values: first the meshes and textures the receiver does not hold yet, then the frame, which
//! names every mesh and texture by its id (a mesh's `id`, a texture's `version`). A program that
//! draws the same display lists every frame therefore sends its geometry once and then only
//! instances, camera, lights and surfaces. Big arrays (positions, triangles, texels) travel as
//! their bytes (`pod_vec`): in the sender's byte order, which the header names, and a receiver
//! of the other order refuses the message.
//!
//! postcard (a documented, stable wire format) keeps the encoding independent of Rust's layout;
//! `VERSION` changes whenever a type in the scene changes shape, and a message of another
//! version is refused with both versions named.

use std::cell::RefCell;
use std::collections::HashMap;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::frame::Frame;
use crate::mesh::Mesh;
use crate::texture::Texture;

/// The first bytes of every message.
pub const MAGIC: &[u8; 8] = b"GLRAYSCN";
/// The encoding's version: raise it whenever a type of the scene changes shape.
pub const VERSION: u16 = 1;
/// The byte order of the arrays sent as bytes: 1 little-endian, 2 big-endian.
const ORDER: u8 = if cfg!(target_endian = "little") { 1 } else { 2 };
const HEADER: usize = MAGIC.len() + 2 + 1;

/// Why a message could not be read.
#[derive(Debug, Clone, PartialEq)]
pub enum DecodeError {
    /// It does not start with `MAGIC`.
    NotAScene,
    /// It was written by another version of the encoding.
    Version { found: u16, expected: u16 },
    /// It was written on a machine of the other byte order.
    ByteOrder,
    /// Its frame names a mesh or texture the receiver has not been sent.
    Missing { what: &'static str, id: u64 },
    /// postcard could not read it (cut short, or damaged), at about this byte.
    Damaged { at: usize, why: String },
}

impl std::fmt::Display for DecodeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DecodeError::NotAScene => write!(f, "not a glray scene message (no GLRAYSCN header)"),
            DecodeError::Version { found, expected } => {
                write!(f, "scene encoding version {found}, this glray reads version {expected}")
            }
            DecodeError::ByteOrder => write!(f, "scene written on a machine of the other byte order"),
            DecodeError::Missing { what, id } => write!(f, "the frame names {what} {id}, which was never sent"),
            DecodeError::Damaged { at, why } => write!(f, "damaged scene message near byte {at}: {why}"),
        }
    }
}

impl std::error::Error for DecodeError {}

/// What a receiver holds of the meshes and textures sent to it, by id; and what a sender knows
/// its receivers hold. A mesh capture no longer draws is forgotten by `retain`.
#[derive(Default)]
pub struct Shared {
    meshes: HashMap<u64, Arc<Mesh>>,
    textures: HashMap<u64, Arc<Texture>>,
}

impl Shared {
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

    /// Keeps only what `frame` draws with.
    pub fn retain_drawn(&mut self, frame: &Frame) {
        let meshes: std::collections::HashSet<u64> = frame.instances.iter().map(|i| i.mesh.id).collect();
        let textures: std::collections::HashSet<u64> =
            frame.surfaces.iter().filter_map(|s| s.texturing.as_ref()).map(|t| t.texture.version).collect();
        self.meshes.retain(|id, _| meshes.contains(id));
        self.textures.retain(|v, _| textures.contains(v));
    }
}

#[derive(Serialize, Deserialize)]
struct Objects {
    meshes: Vec<Mesh>,
    textures: Vec<Texture>,
}

/// `frame` as a message for a receiver that already holds what `sent` holds: the meshes and
/// textures it lacks go with it (and are noted in `sent`, which must then be the receiver's
/// `Shared` as it will be).
pub fn encode(frame: &Frame, sent: &mut Shared) -> Vec<u8> {
    let mut meshes = Vec::new();
    for i in &frame.instances {
        if let std::collections::hash_map::Entry::Vacant(e) = sent.meshes.entry(i.mesh.id) {
            e.insert(i.mesh.clone());
            meshes.push(&*i.mesh);
        }
    }
    let mut textures = Vec::new();
    for t in frame.surfaces.iter().filter_map(|s| s.texturing.as_ref()) {
        if let std::collections::hash_map::Entry::Vacant(e) = sent.textures.entry(t.texture.version) {
            e.insert(t.texture.clone());
            textures.push(&*t.texture);
        }
    }
    #[derive(Serialize)]
    struct ObjectsOut<'a> {
        meshes: Vec<&'a Mesh>,
        textures: Vec<&'a Texture>,
    }
    let mut out = Vec::with_capacity(HEADER + 1024);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.push(ORDER);
    // Writing to a Vec cannot fail; the scene's types all serialize.
    out = postcard::to_extend(&ObjectsOut { meshes, textures }, out).expect("a scene's meshes encode");
    postcard::to_extend(frame, out).expect("a frame encodes")
}

/// A frame from a message, its meshes and textures taken from (and added to) `shared`.
pub fn decode(bytes: &[u8], shared: &mut Shared) -> Result<Frame, DecodeError> {
    if bytes.len() < HEADER || &bytes[..MAGIC.len()] != MAGIC {
        return Err(DecodeError::NotAScene);
    }
    let found = u16::from_le_bytes([bytes[8], bytes[9]]);
    if found != VERSION {
        return Err(DecodeError::Version { found, expected: VERSION });
    }
    if bytes[10] != ORDER {
        return Err(DecodeError::ByteOrder);
    }
    let body = &bytes[HEADER..];
    let damaged =
        |rest: &[u8], e: postcard::Error| DecodeError::Damaged { at: bytes.len() - rest.len(), why: e.to_string() };
    let (objects, rest) = postcard::take_from_bytes::<Objects>(body).map_err(|e| damaged(body, e))?;
    for m in objects.meshes {
        shared.meshes.insert(m.id, Arc::new(m));
    }
    for t in objects.textures {
        shared.textures.insert(t.version, Arc::new(t));
    }
    let frame = DECODING.with(|d| {
        *d.borrow_mut() = Some(std::mem::take(shared));
        let frame = postcard::from_bytes::<Frame>(rest);
        *shared = d.borrow_mut().take().expect("set above");
        frame
    });
    frame.map_err(|e| match MISSING.with(|m| m.take()) {
        Some((what, id)) => DecodeError::Missing { what, id },
        None => damaged(rest, e),
    })
}

thread_local! {
    /// The meshes and textures a frame being decoded on this thread names (serde's derives
    /// take no context: the shared objects reach `shared_mesh` and `shared_texture` here).
    static DECODING: RefCell<Option<Shared>> = const { RefCell::new(None) };
    /// The object a decode missed, for its error.
    static MISSING: std::cell::Cell<Option<(&'static str, u64)>> = const { std::cell::Cell::new(None) };
}

/// An `Arc<Mesh>` field encoded as the mesh's id.
pub mod shared_mesh {
    use super::*;

    pub fn serialize<S: serde::Serializer>(mesh: &Arc<Mesh>, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_u64(mesh.id)
    }

    pub fn deserialize<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Arc<Mesh>, D::Error> {
        let id = u64::deserialize(d)?;
        let found = DECODING.with(|s| s.borrow().as_ref().and_then(|s| s.meshes.get(&id).cloned()));
        found.ok_or_else(|| {
            MISSING.with(|m| m.set(Some(("mesh", id))));
            serde::de::Error::custom(format!("mesh {id} was never sent"))
        })
    }
}

/// An `Arc<Texture>` field encoded as the texture's version.
pub mod shared_texture {
    use super::*;

    pub fn serialize<S: serde::Serializer>(texture: &Arc<Texture>, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_u64(texture.version)
    }

    pub fn deserialize<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Arc<Texture>, D::Error> {
        let version = u64::deserialize(d)?;
        let found = DECODING.with(|s| s.borrow().as_ref().and_then(|s| s.textures.get(&version).cloned()));
        found.ok_or_else(|| {
            MISSING.with(|m| m.set(Some(("texture", version))));
            serde::de::Error::custom(format!("texture {version} was never sent"))
        })
    }
}

/// A `Vec` of plain numbers encoded as its bytes (one copy, not a value at a time).
pub mod pod_vec {
    use std::marker::PhantomData;

    use bytemuck::Pod;
    use serde::de::{SeqAccess, Visitor};

    pub fn serialize<T: Pod, S: serde::Serializer>(v: &[T], s: S) -> Result<S::Ok, S::Error> {
        s.serialize_bytes(bytemuck::cast_slice(v))
    }

    pub fn deserialize<'de, T: Pod, D: serde::Deserializer<'de>>(d: D) -> Result<Vec<T>, D::Error> {
        struct Bytes<T>(PhantomData<T>);
        impl<'de, T: Pod> Visitor<'de> for Bytes<T> {
            type Value = Vec<T>;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                write!(f, "the bytes of an array of {}-byte values", std::mem::size_of::<T>())
            }

            fn visit_bytes<E: serde::de::Error>(self, b: &[u8]) -> Result<Vec<T>, E> {
                if b.len() % std::mem::size_of::<T>() != 0 {
                    return Err(E::custom(format!("{} bytes is not a whole number of values", b.len())));
                }
                Ok(bytemuck::pod_collect_to_vec(b))
            }

            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<T>, A::Error> {
                let mut bytes = Vec::new();
                while let Some(b) = seq.next_element::<u8>()? {
                    bytes.push(b);
                }
                self.visit_bytes(&bytes)
            }
        }
        d.deserialize_bytes(Bytes(PhantomData))
    }
}
