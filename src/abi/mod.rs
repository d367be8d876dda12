//! The ABI edge: what the loader and programs bind to, and how a call reaches the real GL.
//!
//! - `commands`: the generated command table (names, class, display-list rule, frame role);
//! - `exports`: the generated `extern "C"` functions the loader binds programs to, which hand
//!   each call to the stream of calls (`crate::calls`) when something listens;
//! - `real`: generated typed calls of the real implementation;
//! - `dispatch`: which real function a call goes to (per-thread glvnd or OSMesa), resolved
//!   lazily, lock-free on the hot path;
//! - `runtime`: the settings and glray's own identity, read once; the real libraries;
//! - `handlers`: what glray does on the calls gl-spec/classes.txt marks `handler`;
//! - `profile`: what the current context is (version, core or compatibility profile);
//! - `dlopen_hook`: programs that dlopen GL libraries end up in glray;
//! - `ffi_guard`: no panic crosses `extern "C"`.

pub mod commands;
pub mod dispatch;
pub mod dlopen_hook;
pub mod exports;
pub mod ffi_guard;
pub mod handlers;
pub mod profile;
pub mod real;
pub mod runtime;
