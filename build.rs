//! Generates libglray.so's exported API from the Khronos XML registry and gl-spec/, through
//! glray-spec (crates/glray-spec: the model, and one generator per file). Outputs in OUT_DIR:
//! commands.rs, real.rs, exports.rs, record.rs (the library), replay.rs and params.rs (the
//! `glray` command). See docs/design.md, "The API as data".

use glray_spec::gen;

/// A generator: the model to a file's text.
type Generator = fn(&glray_spec::Spec) -> String;

fn main() {
    let spec_dir = glray_spec::spec_dir();
    glray_spec::rerun_if_changed(&spec_dir);
    println!("cargo:rerun-if-changed=build.rs");
    let spec = glray_spec::load(&spec_dir);
    let out = std::path::PathBuf::from(std::env::var("OUT_DIR").unwrap());
    let outputs: [(&str, Generator); 6] = [
        ("commands.rs", gen::commands::generate),
        ("real.rs", gen::real::generate),
        ("exports.rs", gen::exports::generate),
        ("record.rs", gen::record::generate),
        ("replay.rs", gen::replay::generate),
        ("params.rs", gen::params::generate),
    ];
    for (file, generate) in outputs {
        glray_spec::write(&out.join(file), &generate(&spec));
    }

    // The glvnd layout that every loader accepts (see docs/design.md): SONAME libGL.so.1, and
    // glvnd's libGLX and libOpenGL as dependencies so that dlsym(handle, name) on our handle
    // falls through to them for anything we do not define. `-l:` needs no -dev packages.
    println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libGL.so.1");
    println!("cargo:rustc-cdylib-link-arg=-Wl,--no-as-needed");
    println!("cargo:rustc-cdylib-link-arg=-l:libGLX.so.0");
    println!("cargo:rustc-cdylib-link-arg=-l:libOpenGL.so.0");
    println!("cargo:rustc-cdylib-link-arg=-Wl,--as-needed");
    // Our own calls to our own exports bind inside the library, never to a host's symbol of the
    // same name (apitrace's lesson: hosts with globals named like GL functions).
    println!("cargo:rustc-cdylib-link-arg=-Wl,-Bsymbolic-functions");
}
