//! Image-parallel ray tracing across ranks (DESIGN.md, "Distribution"; the paper's GLuDRay):
//! every rank traces tiles of the whole image against the whole scene.
//!
//! - `transport`: what the protocol needs of a message layer (MPI, or memory in tests);
//! - `protocol`: the messages, each with its frame number;
//! - `master`: the tile queue: first batches, adaptive chunks, tiles kept where they were;
//! - `node`: one rank's part in a frame: scenes exchanged and merged, tiles traced and
//!   gathered, every wait bounded;
//! - `paging`: `distribute = paged`: each rank's big meshes in blocks, other ranks' blocks
//!   fetched into a bounded cache.

pub mod assembly;
pub mod bands;
pub mod link;
pub mod master;
pub mod node;
pub mod pack;
pub mod paging;
pub mod protocol;
pub mod transport;

pub use node::{Agreement, Fault, FrameReport, Limits, Node};
pub use transport::Transport;
