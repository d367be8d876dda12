//! glray's GL state machine, in pure Rust: what the capture layer (DESIGN.md: "capture") keeps
//! of a context, with GL's error rules, so that it can be tested without any GL. The live
//! library and `glray replay --renderer glray` both feed it recorded calls (`events`).
//!
//! - `events`: recorded events (a trace's or the live recorder's) into per-thread contexts;
//! - `ops`: which commands capture follows, by name, and the type their pointers point to;
//! - `args`: reading a recorded call's arguments as GL numbers and arrays;
//! - `fixed`: the fixed-function machine: one context's state, by concern (matrices, lighting
//!   and materials, rasterization and fragment state, texturing, display lists, arrays and
//!   buffer objects, immediate mode), each with the commands it follows, and a frame of what
//!   the context draws;
//! - `programs`: the shader-program layer beside it: programs by their inputs' names, uniforms,
//!   vertex arrays, and the profiles (VTK 9's) that say what a program's draw is;
//! - `texture`: client pixels decoded into texels, glTexParameter's sampling state;
//! - `error`: GL error codes and the error flag glGetError reads;
//! - `primitive`: assembling vertex streams into points, lines and triangles, with the provoking
//!   vertex flat shading uses.
//!
//! What a frame hands the tracer (`Frame`, meshes, instances, lighting, textures) is the
//! scene's (crates/glray-scene): capture produces it, and never sees the tracer.

pub mod args;
pub mod error;
pub mod events;
pub mod fixed;
pub mod ops;
pub mod primitive;
pub mod programs;
pub mod texture;
