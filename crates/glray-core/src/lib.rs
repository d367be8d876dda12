//! What libglray.so and the `glray` command share: the settings, logging, and finding the real
//! GL, GLX, EGL and OSMesa libraries without ever finding glray itself.

pub mod config;
pub mod gltypes;
pub mod image;
pub mod indices;
pub mod log;
pub mod pages;
pub mod prefetch;
pub mod reallib;
pub mod reuse;
pub mod threads;
pub mod trace;

pub const VERSION: &str = env!("CARGO_PKG_VERSION");
