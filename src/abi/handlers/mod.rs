//! glray's handlers: the commands gl-spec/classes.txt marks `handler` come here (under a panic
//! guard) instead of going straight to the real implementation. Each handler has the name and
//! parameters of its command; the build fails if one is missing.

mod context;
mod errors;
mod lookup;

pub use context::*;
pub use errors::*;
pub use lookup::*;
