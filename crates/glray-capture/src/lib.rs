//! glray's GL state machine, in pure Rust: what the capture layer (DESIGN.md: "capture") keeps
//! of a context, with GL's error rules, so that it can be tested without any GL.
//!
//! - `camera`: rays through pixel centres from the projection and viewport, window depth of hits;
//! - `error`: GL error codes and the error flag glGetError reads;
//! - `matrix`: the matrix stacks (modelview, projection, texture, color) and every operation on
//!   them, as Mesa implements them;
//! - `immediate`: the current vertex attributes and glBegin/glEnd;
//! - `lighting`: the fixed-function lighting equation, per vertex, as a rasterizer evaluates it;
//! - `lists`: display lists with Mesa's rules (generic over what a list holds);
//! - `primitive`: assembling glBegin/glEnd and glDrawArrays vertex streams into points, lines and
//!   triangles, with the provoking vertex flat shading uses.
//!
//! Nothing here is wired into libglray.so yet: the capture of issue 4 builds on it.

pub mod args;
pub mod camera;
pub mod context;
pub mod error;
pub mod events;
pub mod frame;
pub mod immediate;
pub mod lighting;
pub mod lists;
pub mod matrix;
pub mod ops;
pub mod primitive;
pub mod texture;
