//! What libglray.so and the `glray` command share: the settings, logging, and finding the real
//! GL, GLX, EGL and OSMesa libraries without ever finding glray itself.

pub mod config;
pub mod gltypes;
pub mod hash;
pub mod image;
pub mod indices;
pub mod log;
pub mod memory;
pub mod pages;
pub mod prefetch;
pub mod reallib;
#[cfg(target_os = "linux")]
pub mod reuse;
/// Elsewhere glray allocates through the system's allocator, and keeps nothing.
#[cfg(not(target_os = "linux"))]
pub mod reuse {
    pub fn frame_begins() {}
    pub fn keep_freed(_on: bool) {}
    pub fn kept_bytes() -> usize {
        0
    }
}
pub mod threads;
pub mod trace;

pub const VERSION: &str = env!("CARGO_PKG_VERSION");
