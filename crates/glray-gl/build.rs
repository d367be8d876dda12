//! Generates enums.rs (every GL, GLX, EGL and OSMesa enum value) from the Khronos registry and
//! gl-spec/osmesa.txt, through glray-spec.
fn main() {
    let spec_dir = glray_spec::spec_dir();
    glray_spec::rerun_if_changed(&spec_dir);
    let spec = glray_spec::load(&spec_dir);
    let out = std::path::PathBuf::from(std::env::var("OUT_DIR").unwrap());
    glray_spec::write(&out.join("enums.rs"), &glray_spec::gen::enums::generate(&spec));
}
