//! glray's GL API as data, read at build time: the Khronos registry (gl.xml, glx.xml, egl.xml
//! from the pinned `khronos_api`) and glray's own files in gl-spec/ become one model (`Spec`), and
//! each generated file has a generator of its own (`gen`), as Mesa's glapi/gen does. The build
//! scripts of libglray (exports, dispatch, recorder, replay), glray-gl (the GL enum values) and
//! glray-capture (the commands capture follows) call it; nothing of the GL API is written by hand.
//!
//! - `model`: what the model holds (commands with their prototypes and what glray does with
//!   them, enum values, capture's ops);
//! - `registry`: reading the Khronos XML (commands of features and extensions, enum values) and
//!   files of C prototypes (OSMesa, the GLX functions no registry lists);
//! - `files`: reading gl-spec/'s own files (types, exports, classes, sizes, capture's ops);
//! - `gen`: one generator per output.

pub mod files;
pub mod gen;
mod load;
pub mod model;
pub mod registry;

use std::path::Path;

pub use load::load;
pub use model::*;

/// Stops the build with a message naming what is wrong.
pub fn fail(msg: &str) -> ! {
    panic!("glray build: {msg}");
}

/// Writes a generated file.
pub fn write(path: &Path, text: &str) {
    std::fs::write(path, text).unwrap_or_else(|e| fail(&format!("writing {}: {e}", path.display())));
}

/// The gl-spec/ directory of the workspace, from the manifest directory of the crate whose build
/// script runs (the workspace root, or a crate under crates/).
pub fn spec_dir() -> std::path::PathBuf {
    let manifest = std::path::PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("run from a build script"));
    manifest
        .ancestors()
        .map(|d| d.join("gl-spec"))
        .find(|d| d.join("exports.txt").is_file())
        .unwrap_or_else(|| fail(&format!("no gl-spec/ above {}", manifest.display())))
}

/// Tells cargo to run the calling build script again when a gl-spec/ file changes.
pub fn rerun_if_changed(spec: &Path) {
    for f in files::FILES {
        println!("cargo:rerun-if-changed={}", spec.join(f).display());
    }
}
