//! libglray.so: a libGL.so.1 that forwards every GL, GLX, EGL and OSMesa call to the real
//! implementation, and hands some of them to glray's handlers first.
//!
//! Layout (one job per module):
//! - `commands`: the generated command table (names, class, display-list rule) from gl-spec/;
//! - `exports`: the generated `extern "C"` functions the loader binds programs to;
//! - `real`: generated typed calls of the real implementation;
//! - `dispatch`: which real function a call goes to (per-thread glvnd or OSMesa), resolved
//!   lazily, lock-free on the hot path;
//! - `runtime`: settings and glray's own identity, read once;
//! - `handlers`: what glray does on the calls gl-spec/classes.txt marks `handler`;
//! - `profile`: what the current context is (version, core or compatibility profile);
//! - `dlopen_hook`: programs that dlopen GL libraries end up in glray;
//! - `ffi_guard`: no panic crosses `extern "C"`.
#![allow(non_snake_case, clippy::missing_safety_doc, clippy::too_many_arguments)]

pub mod commands;
mod dispatch;
mod dlopen_hook;
pub mod exports;
mod ffi_guard;
mod handlers;
mod profile;
mod raytrace;
mod real;
mod record;
mod runtime;
