//! libglray.so: a libGL.so.1 that forwards every GL, GLX, EGL and OSMesa call to the real
//! implementation, follows what programs draw and puts a ray-traced picture in its place.
//!
//! Laid out as the calls flow (docs/design.md has the diagram):
//! - `abi`: the exports programs bind to, dispatch to the real GL, the handlers, the dlopen
//!   hook and the panic guard;
//! - `calls`: the one stream of calls the exports hand over, under one lock, with the memory
//!   they read, to its two sinks:
//! - `record`: the trace file (the trace writer only);
//! - `feed`: the live feed: capture follows the calls, and at a frame's trigger the frame is
//!   ray traced;
//! - `present`: the ray-traced picture put into the real framebuffer;
//! - `distribute`: in an MPI rank, frames shared with the other ranks (image-parallel), MPI's
//!   start and end interposed, glray's MPI edge loaded on demand;
//! - `start`: at load, the settings are read and the sinks started.
#![allow(non_snake_case, clippy::missing_safety_doc, clippy::too_many_arguments)]

pub mod abi;
mod calls;
mod distribute;
mod feed;
mod panel;
mod present;
mod record;
mod start;
