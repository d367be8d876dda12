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

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::frame::Frame;
use crate::mesh::Mesh;
pub use crate::objects::ObjectStore;
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

#[derive(Serialize, Deserialize)]
struct Objects {
    meshes: Vec<Mesh>,
    textures: Vec<Texture>,
}

/// `frame` as a message for a receiver that already holds what `sent` holds: the meshes and
/// textures it lacks go with it (and are noted in `sent`, which must then be the receiver's
/// `ObjectStore` as it will be).
pub fn encode(frame: &Frame, sent: &mut ObjectStore) -> Vec<u8> {
    let mut meshes = Vec::new();
    for i in &frame.instances {
        if sent.add_mesh(&i.mesh) {
            meshes.push(&*i.mesh);
        }
    }
    let mut textures = Vec::new();
    for t in frame.surfaces.iter().filter_map(|s| s.texturing.as_ref()) {
        if sent.add_texture(&t.texture) {
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
pub fn decode(bytes: &[u8], shared: &mut ObjectStore) -> Result<Frame, DecodeError> {
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
        shared.add_mesh(&Arc::new(m));
    }
    for t in objects.textures {
        shared.add_texture(&Arc::new(t));
    }
    let (frame, missing) = shared.reading(|| postcard::from_bytes::<Frame>(rest));
    frame.map_err(|e| match missing {
        Some((what, id)) => DecodeError::Missing { what, id },
        None => damaged(rest, e),
    })
}
