//! glray's GL state machine, in pure Rust: what the capture layer (DESIGN.md: "capture") keeps
//! of a context, with GL's error rules, so that it can be tested without any GL. The live
//! library and `glray replay --renderer glray` both feed it recorded calls (`events`).
//!
//! - `events`: recorded events (a trace's or the live recorder's) into per-thread contexts;
//! - `ops`: which commands capture follows, by name, and the type their pointers point to;
//! - `args`: reading a recorded call's arguments as GL numbers and arrays;
//! - `context`: one context's state machine and the commands it follows;
//! - `state`: the state glPushAttrib saves, by attribute bit;
//! - `vertex`: the vertex stage (transform, lighting of both faces, texture coordinates);
//! - `arrays`: client arrays and buffer objects, array draws resolved to vertices;
//! - `client_draws`: meshes of big draws from client memory, kept by a hash of what they read;
//! - `draw`: a draw's vertices into the frame's triangles (facing, culling, polygon modes, flat
//!   shading, lines and points as quads);
//! - `mesh_builder`: meshes made from GL calls (a list's glBegin/glEnd, an array draw), compiled
//!   once into the scene's `Mesh`;
//! - `texture`: client pixels decoded into texels, glTexParameter's sampling state;
//! - `error`: GL error codes and the error flag glGetError reads;
//! - `matrix`: the matrix stacks and every operation on them, as Mesa implements them;
//! - `immediate`: the current vertex attributes and glBegin/glEnd;
//! - `list_effects`: the state (beside the matrices) a list leaves changed, for the real GL;
//! - `lists`: display lists with Mesa's rules (generic over what a list holds);
//! - `primitive`: assembling vertex streams into points, lines and triangles, with the provoking
//!   vertex flat shading uses.
//!
//! What a frame hands the tracer (`Frame`, meshes, instances, lighting, textures) is the
//! scene's (crates/glray-scene): capture produces it, and never sees the tracer.

pub mod args;
mod arrays;
mod client_draws;
pub mod context;
mod draw;
pub mod error;
pub mod events;
pub mod immediate;
mod immediate_meshes;
pub mod list_effects;
pub mod lists;
pub mod matrix;
pub mod mesh_builder;
pub mod ops;
pub mod primitive;
mod state;
pub mod texture;
mod vertex;
